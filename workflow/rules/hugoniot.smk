# Aggregation across piston velocities and the figures.


rule aggregate:
    input:
        points=point_files,
        reference=f"{RES}/{{scene}}/reference.nc",
    output:
        f"{RES}/hugoniot/{{scene}}.nc",
    log:
        f"{RES}/logs/{{scene}}/aggregate.log",
    conda:
        "../envs/hugomap.yaml"
    threads: 1
    resources:
        mem_mb=2048,
        runtime=summary_runtime,
    params:
        py=PY,
        config=lambda wildcards: json.dumps(config, sort_keys=True),
    shell:
        "{params.py} -m hugomap aggregate --scene-name {wildcards.scene} --config-json {params.config:q}"
        " --reference {input.reference} --out {output} {input.points} > {log} 2>&1"


rule figures:
    input:
        f"{RES}/hugoniot/{{scene}}.nc",
    output:
        pv=f"{RES}/figures/{{scene}}_PV.png",
        dup=f"{RES}/figures/{{scene}}_D_up.png",
    log:
        f"{RES}/logs/{{scene}}/figures.log",
    conda:
        "../envs/hugomap.yaml"
    threads: 1
    resources:
        mem_mb=2048,
        runtime=summary_runtime,
    params:
        py=PY,
    shell:
        "{params.py} -m hugomap figures {input} --pv {output.pv} --dup {output.dup} > {log} 2>&1"


rule history_figure:
    input:
        f"{RES}/{{scene}}/up{{up}}/{{scheme}}.nc",
    output:
        f"{RES}/figures/{{scene}}/up{{up}}_{{scheme}}_history.png",
    log:
        f"{RES}/logs/{{scene}}/up{{up}}/{{scheme}}_history.log",
    wildcard_constraints:
        scheme="amw|mw|dichotomy",
    conda:
        "../envs/hugomap.yaml"
    threads: 1
    params:
        py=PY,
    shell:
        "{params.py} -m hugomap history {input} --out {output} > {log} 2>&1"
