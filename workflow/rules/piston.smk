# The stages every backend runs: sample, loading checkpoint, piston point, reference.


wildcard_constraints:
    scene="[A-Za-z][A-Za-z0-9_]*",
    up="[0-9.eE+-]+",


rule prepare_sample:
    output:
        f"{RES}/{{scene}}/sample.nc",
    log:
        f"{RES}/logs/{{scene}}/prepare.log",
    conda:
        "../envs/hugomap.yaml"
    threads: stage_threads("prepare")
    resources:
        mem_mb=stage_mem_mb("prepare"),
        runtime=stage_runtime("prepare"),
        tasks=stage_tasks("prepare"),
        cpus_per_task=stage_cpus_per_task("prepare"),
        mpi=stage_mpi("prepare"),
    params:
        run=stage_command,
        scene=scene_json,
    shell:
        "{params.run} -m hugomap prepare --scene-name {wildcards.scene}"
        " --scene-json {params.scene:q} --out {output} > {log} 2>&1"


# Priorities (higher first when cores free up): a loading checkpoint unlocks every point at
# its u_p, and a piston job is the longest of a sweep where it runs a second time, so
# starting both early keeps a core from idling at the end.
rule load_to_target:
    input:
        f"{RES}/{{scene}}/sample.nc",
    output:
        f"{RES}/{{scene}}/up{{up}}/loaded.nc",
    log:
        f"{RES}/logs/{{scene}}/up{{up}}/load.log",
    priority: 2
    conda:
        "../envs/hugomap.yaml"
    threads: stage_threads("load")
    resources:
        mem_mb=stage_mem_mb("load"),
        runtime=stage_runtime("load"),
        tasks=stage_tasks("load"),
        cpus_per_task=stage_cpus_per_task("load"),
        mpi=stage_mpi("load"),
    params:
        run=stage_command,
        scene=scene_json,
    shell:
        "{params.run} -m hugomap load --scene-name {wildcards.scene}"
        " --scene-json {params.scene:q} --sample {input} --u-p {wildcards.up}"
        " --out {output} > {log} 2>&1"


rule piston_point:
    input:
        f"{RES}/{{scene}}/up{{up}}/loaded.nc",
    output:
        f"{RES}/{{scene}}/up{{up}}/piston.nc",
    log:
        f"{RES}/logs/{{scene}}/up{{up}}/piston.log",
    priority: 1
    conda:
        "../envs/hugomap.yaml"
    threads: stage_threads("piston")
    resources:
        mem_mb=stage_mem_mb("piston"),
        runtime=stage_runtime("piston"),
        tasks=stage_tasks("piston"),
        cpus_per_task=stage_cpus_per_task("piston"),
        mpi=stage_mpi("piston"),
    params:
        run=stage_command,
        scene=scene_json,
    shell:
        "{params.run} -m hugomap piston --scene-name {wildcards.scene}"
        " --scene-json {params.scene:q} --loaded {input} --u-p {wildcards.up}"
        " --out {output} > {log} 2>&1"


rule shared_reference:
    input:
        sample=shared_reference_sample,
    output:
        f"{RES}/references/{{key}}.nc",
    log:
        f"{RES}/logs/references/{{key}}.log",
    wildcard_constraints:
        key="[a-z]+_[0-9a-f]{12}",
    conda:
        "../envs/hugomap.yaml"
    threads: 1
    resources:
        mem_mb=shared_reference_mem_mb,
        runtime=shared_reference_runtime,
    params:
        py=PY,
        inputs=shared_reference_json,
        sample=lambda wildcards, input: (
            f"--sample {input.sample}" if input.sample else ""
        ),
    shell:
        "NUMBA_NUM_THREADS=1 {params.py} -m hugomap reference --scene-json {params.inputs:q}"
        " {params.sample} --out {output} > {log} 2>&1"


rule reference:
    input:
        shared=shared_reference_file,
        sample=reference_sample_file,
    output:
        f"{RES}/{{scene}}/reference.nc",
    log:
        f"{RES}/logs/{{scene}}/reference.log",
    conda:
        "../envs/hugomap.yaml"
    threads: 1
    resources:
        mem_mb=stage_mem_mb("reference"),
        runtime=scene_reference_runtime,
    params:
        py=PY,
        scene=scene_json,
        shared=lambda wildcards, input: (
            f"--shared {input.shared}" if input.shared else ""
        ),
        sample=lambda wildcards, input: (
            f"--sample {input.sample}" if input.sample else ""
        ),
    shell:
        "NUMBA_NUM_THREADS=1 {params.py} -m hugomap reference --scene-name {wildcards.scene}"
        " --scene-json {params.scene:q} {params.shared} {params.sample} --out {output}"
        " > {log} 2>&1"
