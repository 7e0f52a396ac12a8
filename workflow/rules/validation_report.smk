# The validation report (docs/validation.md): tables computed from the data files that the
# campaign, the replica studies and the benchmarks leave in docs/figures
# (hugomap.validation_report). Target: `validation_report`, run from the repository root;
# not part of `all`.


rule validation_report:
    input:
        data=expand(
            "docs/figures/{name}",
            name=[
                "campaign_points.csv",
                "campaign_settings.csv",
                "replicas_points.csv",
                "seam_replicas_points.csv",
                "max_average_points.csv",
                "window_cost.jsonl",
                "relaxing_cost_lj_fcc.jsonl",
            ],
        ),
        generator="src/hugomap/validation_report.py",
    output:
        "docs/validation.md",
    log:
        f"{RES}/logs/validation_report.log",
    conda:
        "../envs/hugomap.yaml"
    threads: 1
    resources:
        mem_mb=1024,
        runtime=5,
    params:
        py=PY,
    shell:
        "{params.py} -m hugomap.validation_report --figures docs/figures --out {output}"
        " > {log} 2>&1"
