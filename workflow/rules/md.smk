# Molecular-dynamics stages: sample, loading checkpoint, piston point, reference.


wildcard_constraints:
    scene="[A-Za-z][A-Za-z0-9_]*",
    up="[0-9.eE+-]+",


rule prepare_sample:
    output:
        f"{RES}/{{scene}}/sample.nc",
    params:
        scene=scene_json,
    threads: config["threads"]
    log:
        f"{RES}/logs/{{scene}}/prepare.log",
    shell:
        "NUMBA_NUM_THREADS={threads} {PY} -m hugomap prepare --scene-name {wildcards.scene}"
        " --scene-json {params.scene:q} --out {output} > {log} 2>&1"


rule load_to_target:
    input:
        f"{RES}/{{scene}}/sample.nc",
    output:
        f"{RES}/{{scene}}/up{{up}}/loaded.nc",
    params:
        scene=scene_json,
    threads: config["threads"]
    log:
        f"{RES}/logs/{{scene}}/up{{up}}/load.log",
    shell:
        "NUMBA_NUM_THREADS={threads} {PY} -m hugomap load --scene-name {wildcards.scene}"
        " --scene-json {params.scene:q} --sample {input} --u-p {wildcards.up}"
        " --out {output} > {log} 2>&1"


rule piston_point:
    input:
        f"{RES}/{{scene}}/up{{up}}/loaded.nc",
    output:
        f"{RES}/{{scene}}/up{{up}}/piston.nc",
    params:
        scene=scene_json,
    threads: config["threads"]
    log:
        f"{RES}/logs/{{scene}}/up{{up}}/piston.log",
    shell:
        "NUMBA_NUM_THREADS={threads} {PY} -m hugomap piston --scene-name {wildcards.scene}"
        " --scene-json {params.scene:q} --loaded {input} --u-p {wildcards.up}"
        " --out {output} > {log} 2>&1"


rule reference:
    output:
        f"{RES}/{{scene}}/reference.nc",
    params:
        scene=scene_json,
    threads: 1
    log:
        f"{RES}/logs/{{scene}}/reference.log",
    shell:
        "NUMBA_NUM_THREADS=1 {PY} -m hugomap reference --scene-name {wildcards.scene}"
        " --scene-json {params.scene:q} --out {output} > {log} 2>&1"
