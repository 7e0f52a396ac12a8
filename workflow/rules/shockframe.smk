# The shock-frame schemes msst and nphug (solver lammps: LAMMPS's fix msst and fix nphug on a
# periodic box of the material at the sample's measured pole; hugomap.lammps.shockframe):
# one job a point, from the prepared sample alone (no loading, no window).


rule shockframe_point:
    input:
        f"{RES}/{{scene}}/sample.nc",
    output:
        f"{RES}/{{scene}}/up{{up}}/{{scheme}}.nc",
    log:
        f"{RES}/logs/{{scene}}/up{{up}}/{{scheme}}.log",
    wildcard_constraints:
        scheme="msst|nphug",
    conda:
        "../envs/hugomap.yaml"
    threads: 1
    resources:
        mem_mb=stage_mem_mb("shockframe"),
        runtime=stage_runtime("shockframe"),
    params:
        py=PY,
        scene=scene_json,
    shell:
        "{params.py} -m hugomap shockframe --scene-name {wildcards.scene}"
        " --scene-json {params.scene:q} --scheme {wildcards.scheme} --sample {input}"
        " --u-p {wildcards.up} --out {output} > {log} 2>&1"
