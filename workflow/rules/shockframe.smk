# The shock-frame schemes msst and nphug (solver lammps: LAMMPS's fix msst and fix nphug on a
# periodic box of the material at the sample's measured pole; hugomap.lammps.shockframe):
# one job a point, from the prepared sample alone (no loading, no window); on the scene's
# MPI ranks like the other LAMMPS stages (the box is read through global quantities only).


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
    threads: stage_threads("shockframe")
    resources:
        mem_mb=stage_mem_mb("shockframe"),
        runtime=stage_runtime("shockframe"),
        tasks=stage_tasks("shockframe"),
        cpus_per_task=stage_cpus_per_task("shockframe"),
        mpi=stage_mpi("shockframe"),
    params:
        run=stage_command,
        scene=scene_json,
    shell:
        "{params.run} -m hugomap shockframe --scene-name {wildcards.scene}"
        " --scene-json {params.scene:q} --scheme {wildcards.scheme} --sample {input}"
        " --u-p {wildcards.up} --out {output} > {log} 2>&1"
