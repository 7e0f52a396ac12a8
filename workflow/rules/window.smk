# Moving-window schemes: the window checkpoint, AMW and MW points, and the dichotomy as a
# data-dependent loop (one checkpoint job per iteration, each bisection step a short run
# restarted from the same window checkpoint).


wildcard_constraints:
    k="[0-9]+",
    i="[0-9]+",


rule window_start:
    input:
        f"{RES}/{{scene}}/up{{up}}/loaded.nc",
    output:
        f"{RES}/{{scene}}/up{{up}}/window.nc",
    log:
        f"{RES}/logs/{{scene}}/up{{up}}/window.log",
    conda:
        "../envs/hugomap.yaml"
    threads: stage_threads("window")
    resources:
        tasks=stage_tasks("window"),
        cpus_per_task=stage_cpus_per_task("window"),
        mpi=stage_mpi("window"),
    params:
        run=stage_command,
        scene=scene_json,
    shell:
        "{params.run} -m hugomap window --scene-name {wildcards.scene}"
        " --scene-json {params.scene:q} --loaded {input} --u-p {wildcards.up}"
        " --out {output} > {log} 2>&1"


rule control_point:
    input:
        f"{RES}/{{scene}}/up{{up}}/window.nc",
    output:
        f"{RES}/{{scene}}/up{{up}}/{{scheme}}.nc",
    log:
        f"{RES}/logs/{{scene}}/up{{up}}/{{scheme}}.log",
    wildcard_constraints:
        scheme="amw|mw",
    conda:
        "../envs/hugomap.yaml"
    threads: stage_threads("control")
    resources:
        tasks=stage_tasks("control"),
        cpus_per_task=stage_cpus_per_task("control"),
        mpi=stage_mpi("control"),
    params:
        run=stage_command,
        scene=scene_json,
    shell:
        "{params.run} -m hugomap {wildcards.scheme}"
        " --scene-name {wildcards.scene} --scene-json {params.scene:q} --window {input}"
        " --u-p {wildcards.up} --out {output} > {log} 2>&1"


checkpoint dichotomy_state:
    input:
        unpack(dichotomy_state_inputs),
    output:
        f"{RES}/{{scene}}/up{{up}}/dichotomy/state{{k}}.json",
    log:
        f"{RES}/logs/{{scene}}/up{{up}}/dichotomy_state{{k}}.log",
    conda:
        "../envs/hugomap.yaml"
    threads: 1
    params:
        py=PY,
        scene=scene_json,
        previous=lambda w, input: (
            f"--previous {input.previous}" if "previous" in input.keys() else ""
        ),
        trials=lambda w, input: (
            " ".join(input.trials) if "trials" in input.keys() else ""
        ),
    shell:
        "{params.py} -m hugomap dichotomy-state --scene-name {wildcards.scene}"
        " --scene-json {params.scene:q} --window {input.window} --k {wildcards.k}"
        " {params.previous} --out {output} {params.trials} > {log} 2>&1"


rule dichotomy_trial:
    input:
        window=f"{RES}/{{scene}}/up{{up}}/window.nc",
        state=f"{RES}/{{scene}}/up{{up}}/dichotomy/state{{k}}.json",
    output:
        f"{RES}/{{scene}}/up{{up}}/dichotomy/trial{{k}}_{{i}}.json",
    log:
        f"{RES}/logs/{{scene}}/up{{up}}/dichotomy_trial{{k}}_{{i}}.log",
    conda:
        "../envs/hugomap.yaml"
    threads: stage_threads("dichotomy")
    resources:
        tasks=stage_tasks("dichotomy"),
        cpus_per_task=stage_cpus_per_task("dichotomy"),
        mpi=stage_mpi("dichotomy"),
    params:
        run=stage_command,
        scene=scene_json,
    shell:
        "{params.run} -m hugomap dichotomy-trial"
        " --scene-name {wildcards.scene} --scene-json {params.scene:q} --window {input.window}"
        " --state {input.state} --index {wildcards.i} --out {output} > {log} 2>&1"


rule dichotomy_point:
    input:
        unpack(dichotomy_final),
    output:
        f"{RES}/{{scene}}/up{{up}}/dichotomy.nc",
    log:
        f"{RES}/logs/{{scene}}/up{{up}}/dichotomy.log",
    conda:
        "../envs/hugomap.yaml"
    threads: stage_threads("dichotomy")
    resources:
        tasks=stage_tasks("dichotomy"),
        cpus_per_task=stage_cpus_per_task("dichotomy"),
        mpi=stage_mpi("dichotomy"),
    params:
        run=stage_command,
        scene=scene_json,
        # from params, not {input.*}: a dry run (-n) formats this command before the loop's
        # states exist, when the input function could not yet name them
        window=lambda w: f"{RES}/{w.scene}/up{w.up}/window.nc",
        state=lambda w, input: input.state if "state" in input.keys() else "",
        trials=lambda w, input: (
            " ".join(input.trials) if "trials" in input.keys() else ""
        ),
    shell:
        "{params.run} -m hugomap dichotomy-point"
        " --scene-name {wildcards.scene} --scene-json {params.scene:q} --window {params.window}"
        " --u-p {wildcards.up} --state {params.state} --out {output} {params.trials} > {log} 2>&1"
