# Aggregation across piston velocities and the figures. The figures go into
# `snakemake --report report.html` with their captions (workflow/report/).


report: "../report/workflow.rst"


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
        pv=report(
            f"{RES}/figures/{{scene}}_PV.png",
            caption="../report/pv.rst",
            category="Hugoniots",
            subcategory="{scene}",
            labels={"scene": "{scene}", "figure": "P-V"},
        ),
        dup=report(
            f"{RES}/figures/{{scene}}_D_up.png",
            caption="../report/d_up.rst",
            category="Hugoniots",
            subcategory="{scene}",
            labels={"scene": "{scene}", "figure": "D-u_p"},
        ),
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
        report(
            f"{RES}/figures/{{scene}}/up{{up}}_{{scheme}}_history.png",
            caption="../report/history.rst",
            category="Window control histories",
            subcategory="{scene}",
            labels={"scene": "{scene}", "u_p": "{up}", "scheme": "{scheme}"},
        ),
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
