# Turn the validated config into targets and job parameters.
import json
import math
from pathlib import Path

from hugomap.keys import scene_points

PY = sys.executable
RES = config["results"]  # validated: the default "results" filled in


def up_tag(u):
    """Wildcard text of a piston velocity (e.g. 0.5 -> '0.5', 2.0 -> '2')."""
    return f"{float(u):.6g}"


def scene_json(wildcards):
    scene = dict(config["scenes"][wildcards.scene])
    scene["name"] = wildcards.scene
    return json.dumps(scene, sort_keys=True)


def point_files(wildcards):
    """One point file per scheme and piston velocity of the scene (hugomap.keys.scene_points:
    every scheme at every u_p, or what schemes: [auto] chose at each)."""
    return [
        f"{RES}/{wildcards.scene}/up{up_tag(u)}/{scheme}.nc"
        for scheme, u in scene_points(
            config["scenes"][wildcards.scene], config["schemes"]
        )
    ]


def all_targets():
    out = []
    made = set()  # the campaign's scenes: their history figures only on request
    if "campaign" in config:
        from hugomap.campaign_expand import variants

        made = {v.scene for v in variants(config["campaign"])}
    for scene in config["scenes"]:
        out += [
            f"{RES}/hugoniot/{scene}.nc",
            f"{RES}/figures/{scene}_PV.png",
            f"{RES}/figures/{scene}_D_up.png",
        ]
        if scene in made:
            continue
        out += [
            f"{RES}/figures/{scene}/up{up_tag(u)}_{scheme}_history.png"
            for scheme, u in scene_points(config["scenes"][scene], config["schemes"])
            if scheme not in ("piston", "msst", "nphug")  # no control history
        ]
    if "campaign" in config:  # its dataset and figures (rule campaign)
        out += list(campaign_outputs().values())
    return out


# Cluster resources per job (SLURM profile: workflow/profiles/slurm), from the scene's
# backend cost model (hugomap.backend.Backend.cost: memory and 1-thread CPU seconds). A
# local run ignores mem_mb and runtime unless --resources caps them. Generous on purpose: a
# job killed at its limit costs more than a slot held a little too long; each retry
# (--retries) gets `attempt` times the first request.
STARTUP_MIN = 5  # imports, numba compile when its cache is cold, file writes


def _cost(scene, stage):
    from hugomap.registry import backend
    from hugomap.stages.piston import job_cost

    if stage == "piston":  # a sample grown to meet the target runs in the same job
        return job_cost(scene)
    return backend(scene).cost(scene, stage)


def stage_mem_mb(stage):
    """mem_mb of a stage ("prepare", "load", "piston", "reference")."""

    def mem_mb(wildcards, attempt):
        return attempt * _cost(config["scenes"][wildcards.scene], stage).mem_mb

    return mem_mb


def stage_runtime(stage):
    """runtime [min] of a stage: its CPU seconds over the threads, plus start-up."""

    def runtime(wildcards, threads, attempt):
        cpu_s = _cost(config["scenes"][wildcards.scene], stage).cpu_s
        return attempt * int(math.ceil(STARTUP_MIN + cpu_s / threads / 60.0))

    return runtime


# MPI: a backend whose job asks for ranks > 1 (Resources.ranks: LAMMPS scenes with `ranks`)
# runs under `mpiexec -n ranks` (the mpich wheel's, beside this Python, else the one on
# PATH), one thread a rank, its ranks reserved as the job's threads. The SLURM executor reads
# resources `mpi` (the launcher, also a sign to start the job's command as it is, not in an
# srun step of one task), `tasks` (--ntasks) and `cpus_per_task`.
MPIEXEC = next((str(p) for p in [Path(PY).parent / "mpiexec"] if p.exists()), "mpiexec")


def _ranks(wildcards, stage):
    return _cost(config["scenes"][wildcards.scene], stage).ranks


def stage_threads(stage):
    """Threads of a stage's job: its MPI ranks, or the config's `threads` without MPI."""

    def threads(wildcards):
        ranks = _ranks(wildcards, stage)
        return ranks if ranks > 1 else config["threads"]

    return threads


def stage_tasks(stage):
    """SLURM tasks of a stage's job: its MPI ranks."""
    return lambda wildcards: _ranks(wildcards, stage)


def stage_cpus_per_task(stage):
    """SLURM cpus per task: one per rank under MPI, else the job's threads."""
    return lambda wildcards, threads: 1 if _ranks(wildcards, stage) > 1 else threads


def stage_mpi(stage):
    """The MPI launcher of a stage's job under MPI, else "" (no launcher)."""
    return lambda wildcards: MPIEXEC if _ranks(wildcards, stage) > 1 else ""


def stage_command(wildcards, threads, resources):
    """How a stage's job starts Python: under MPI `NUMBA_NUM_THREADS=1 <mpi> -n <tasks>`,
    else with the job's threads for numba."""
    if resources.mpi:
        return f"NUMBA_NUM_THREADS=1 {resources.mpi} -n {resources.tasks} {PY}"
    return f"NUMBA_NUM_THREADS={threads} {PY}"


# A reference that is a run of its own (equilibrium MD) is computed once per distinct set
# of the inputs it depends on (Backend.reference_inputs) and copied into each scene's folder;
# an MD reference is computed at the pole its scene's sample measured, so both reference
# rules read the sample file too.
# Keys per scene (None where the backend computes its reference per scene) and, per key, the
# first scene (config order) with those inputs: once, when the workflow is parsed.
def _reference_keys():
    from hugomap.stages.reference import reference_key

    return {name: reference_key(scene) for name, scene in config["scenes"].items()}


REFERENCE_KEYS = _reference_keys()
SHARED_REFERENCES = {}
for _scene, _key in REFERENCE_KEYS.items():
    if _key is not None:
        SHARED_REFERENCES.setdefault(_key, _scene)


def shared_reference_file(wildcards):
    """The shared reference a scene copies (none where computed per scene)."""
    key = REFERENCE_KEYS[wildcards.scene]
    return [] if key is None else [f"{RES}/references/{key}.nc"]


def reference_sample_file(wildcards):
    """The scene's sample file when its reference is computed at the pole the sample
    measured (Backend.reference_from_sample: MD), else none."""
    from hugomap.stages.reference import needs_sample

    if needs_sample(config["scenes"][wildcards.scene]):
        return [f"{RES}/{wildcards.scene}/sample.nc"]
    return []


def shared_reference_sample(wildcards):
    """The sample of the scene whose reference the shared file is."""
    return reference_sample_file(_reference_wildcards(wildcards))


def _reference_wildcards(wildcards):
    from types import SimpleNamespace

    return SimpleNamespace(scene=SHARED_REFERENCES[wildcards.key])


def shared_reference_json(wildcards):
    """The first scene with the key's inputs: its reference is the one computed."""
    scene = dict(config["scenes"][SHARED_REFERENCES[wildcards.key]])
    scene["name"] = SHARED_REFERENCES[wildcards.key]
    return json.dumps(scene, sort_keys=True)


def shared_reference_mem_mb(wildcards, attempt):
    return stage_mem_mb("reference")(_reference_wildcards(wildcards), attempt)


def shared_reference_runtime(wildcards, threads, attempt):
    return stage_runtime("reference")(_reference_wildcards(wildcards), threads, attempt)


def scene_reference_runtime(wildcards, threads, attempt):
    """A scene computes its own reference (seconds) or copies the shared one."""
    return attempt * STARTUP_MIN


def summary_runtime(wildcards, attempt):
    """runtime [min] of aggregate / figures: a few seconds per 100 point files."""
    return attempt * (5 + len(config["scenes"][wildcards.scene]["shock"]["u_p"]) // 100)


# The dichotomy's data-dependent loop (workflow/rules/window.smk).
def dichotomy_dir(w):
    return f"{RES}/{w.scene}/up{w.up}/dichotomy"


def dichotomy_pending(w, k):
    """The u_out values iteration k proposed (read from its state file: a checkpoint)."""
    state = checkpoints.dichotomy_state.get(scene=w.scene, up=w.up, k=k).output[0]
    with open(state) as f:
        return json.load(f)["pending"]


def dichotomy_trials(w, k):
    """The trial files run on iteration k's proposals."""
    n = len(dichotomy_pending(w, k))
    return [f"{dichotomy_dir(w)}/trial{k}_{i}.json" for i in range(n)]


def dichotomy_state_inputs(w):
    k = int(w.k)
    if k == 0:
        return {"window": f"{RES}/{w.scene}/up{w.up}/window.nc"}
    return {
        "window": f"{RES}/{w.scene}/up{w.up}/window.nc",
        "previous": f"{dichotomy_dir(w)}/state{k - 1}.json",
        "trials": dichotomy_trials(w, k - 1),
    }


def dichotomy_final(w):
    """Walk the iterations until a state says done; its file and every trial so far."""
    k, trials = 0, []
    while True:
        state = checkpoints.dichotomy_state.get(scene=w.scene, up=w.up, k=k).output[0]
        with open(state) as f:
            if json.load(f)["done"]:
                return {
                    "window": f"{RES}/{w.scene}/up{w.up}/window.nc",
                    "state": state,
                    "trials": trials,
                }
        trials += dichotomy_trials(w, k)
        k += 1


def campaign_aggregates(wildcards):
    """The aggregates of every scene the campaign made."""
    from hugomap.campaign_expand import variants

    if "campaign" not in config:
        raise WorkflowError(
            "this config has no campaign block: give --configfile config/campaign.yaml"
        )
    return [f"{RES}/hugoniot/{v.scene}.nc" for v in variants(config["campaign"])]


def campaign_outputs():
    """The campaign dataset and its three figures, named by campaign.name."""
    name = config.get("campaign", {}).get("name", "validation")
    return {
        "nc": f"{RES}/campaign/{name}.nc",
        "chart": f"{RES}/campaign/{name}_speed_accuracy.png",
        "map": f"{RES}/campaign/{name}_stability.png",
        "pulls": f"{RES}/campaign/{name}_pulls.png",
    }
