# The validation campaign (config key `campaign`, hugomap.campaign): its variants are
# ordinary scenes (expanded before validation); this rule joins their aggregates into one
# dataset and draws the speed-accuracy chart, the stability map and every point's pull
# against its reference (with a replica study's chi-square). Target: `campaign`.


rule campaign:
    input:
        campaign_aggregates,
    output:
        nc=campaign_outputs()["nc"],
        chart=report(
            campaign_outputs()["chart"],
            caption="../report/speed_accuracy.rst",
            category="Validation campaign",
            labels={"figure": "speed against accuracy"},
        ),
        map=report(
            campaign_outputs()["map"],
            caption="../report/stability.rst",
            category="Validation campaign",
            labels={"figure": "stability map"},
        ),
        pulls=report(
            campaign_outputs()["pulls"],
            caption="../report/pulls.rst",
            category="Validation campaign",
            labels={"figure": "pulls against the reference"},
        ),
    log:
        f"{RES}/logs/campaign.log",
    conda:
        "../envs/hugomap.yaml"
    threads: 1
    resources:
        mem_mb=2048,
        runtime=10,
    params:
        py=PY,
        config=lambda wildcards: json.dumps(
            # in the config's order: an axis's first key is its coordinate
            {k: v for k, v in config.items() if k != "scenes"}
        ),
    shell:
        "{params.py} -m hugomap campaign --config-json {params.config:q} --out {output.nc}"
        " --chart {output.chart} --map {output.map} --pulls {output.pulls} {input} > {log} 2>&1"
