# Turn the validated config into targets and job parameters.
import json
import math

PY = sys.executable
RES = "results"


def up_tag(u):
    """Wildcard text of a piston velocity (e.g. 0.5 -> '0.5', 2.0 -> '2')."""
    return f"{float(u):.6g}"


def scene_json(wildcards):
    scene = dict(config["scenes"][wildcards.scene])
    scene["name"] = wildcards.scene
    return json.dumps(scene, sort_keys=True)


def point_files(wildcards):
    """One point file per scheme of the config and piston velocity of the scene."""
    ups = config["scenes"][wildcards.scene]["shock"]["u_p"]
    return [
        f"{RES}/{wildcards.scene}/up{up_tag(u)}/{scheme}.nc"
        for scheme in config["scenes"][wildcards.scene].get(
            "schemes", config["schemes"]
        )
        for u in ups
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
        schemes = config["scenes"][scene].get("schemes", config["schemes"])
        out += [
            f"{RES}/figures/{scene}/up{up_tag(u)}_{scheme}_history.png"
            for scheme in schemes
            if scheme != "piston"
            for u in config["scenes"][scene]["shock"]["u_p"]
        ]
    if "campaign" in config:  # its dataset and figures (rule campaign)
        out += list(campaign_outputs().values())
    return out


# Cluster resources per job (SLURM profile: workflow/profiles/slurm), from the scene
# size. A local run ignores mem_mb and runtime unless --resources caps them. Generous on
# purpose: a job killed at its limit costs more than a slot held a little too long; each
# retry (--retries) gets `attempt` times the first request.
MD_BASE_MB = 1024  # Python + numba + xarray/netCDF: about 350 MB resident, measured
# state ~0.2 kB + full Verlet list ~0.8 kB (int32 rows, rho* <= 1.5), x4 margin
MD_BYTES_PER_ATOM = 4096
MD_S_PER_ATOM_STEP = 1.0e-6  # 1-core kernel ~3e-7 s (FACTS.md), x3: sampling, I/O
MD_STARTUP_MIN = 5  # imports, numba compile when its cache is cold, file writes
REF_POLE_FACTOR, REF_MAX_ITER = 4, 10  # analysis.reference.reference_hugoniot defaults


def _n_atoms(scene):
    nx, ny, nz = scene["sample"]["cells"]
    return 4 * nx * ny * nz  # FCC


def _profile_bytes(scene):
    """Profile history of one shock stage: samples x bins x 11 sums (float64)."""
    s, sh = scene["sample"], scene["shock"]
    length = s["cells"][0] * (4.0 / s["rho0"]) ** (1.0 / 3.0)
    n_samples = sh["max_time"] / sh["dt"] / sh["sample_every"]
    return n_samples * (length / sh["bin_width"] + 1) * 11 * 8


def _atom_steps(scene, stage):
    """Upper bound of atoms x steps of an MD stage."""
    s, sh = scene["sample"], scene["shock"]
    if stage == "prepare":
        return _n_atoms(scene) * (s["equilibrate_time"] + s["pole_time"]) / s["dt"]
    if stage in ("load", "piston"):  # each stage stops at shock.max_time
        return _n_atoms(scene) * sh["max_time"] / sh["dt"]
    # reference: the pole (REF_POLE_FACTOR x production), then NVT runs per compression
    r = scene["reference"]
    run = r["equilibrate_steps"] + r["production_steps"]
    steps = r["equilibrate_steps"] + REF_POLE_FACTOR * r["production_steps"]
    steps += REF_MAX_ITER * len(r["compressions"]) * run
    return 4 * r["cells"] ** 3 * steps


# CSPH scenes (solver: csph, SI units): particles x steps at a measured-rate bound.
SPH_S_PER_PARTICLE_STEP = 3.0e-6  # 1D ~1e-6 s, 2D porous ~2e-6 s on one core, x1.5-3
# state, pair list (~30 neighbours in 2D), profile history
SPH_BYTES_PER_PARTICLE = 8192


def _sph_particles(scene):
    s = scene["sample"]
    n = s["length"] / s["dx"]
    return n * (s["width"] / s["dx"] if scene["dim"] == 2 else 1.0)


def _sph_steps(scene):
    """Upper bound of the steps of a piston stage: the front crosses the sample at its
    slowest speed (porous: the snowplow D = u_p alpha/(alpha - 1)) while dt is cfl dx over
    the fastest signal (c0 + s u_p)."""
    s, e, sh = scene["sample"], scene["material"]["eos"], scene["shock"]
    u_lo, u_hi = min(sh["u_p"]), max(sh["u_p"])
    d_min = e["c0"] + e["s"] * u_lo
    if "porous" in s:
        a = s["porous"]["distention"]
        d_min = min(d_min, u_lo * a / max(a - 1.0, 1e-9))
    dt = scene.get("numerics", {}).get("cfl", 0.3) * s["dx"] / (e["c0"] + e["s"] * u_hi)
    return s["length"] / d_min / dt


def md_mem_mb(stage):
    """mem_mb of an MD stage ("prepare", "load", "piston", "reference")."""

    def mem_mb(wildcards, attempt):
        scene = config["scenes"][wildcards.scene]
        if scene["solver"] == "csph":
            n = _sph_particles(scene)
            return attempt * int(MD_BASE_MB + n * SPH_BYTES_PER_PARTICLE / 2**20)
        if stage == "reference":
            n, extra = 4 * scene["reference"]["cells"] ** 3, 0
        else:
            n, extra = _n_atoms(scene), _profile_bytes(scene) * (stage != "prepare")
        # the profile history is held, then copied once into the dataset that is written
        return attempt * int(MD_BASE_MB + (n * MD_BYTES_PER_ATOM + 2 * extra) / 2**20)

    return mem_mb


def md_runtime(stage):
    """runtime [min] of an MD stage: atom-steps at the 1-core rate over the threads."""

    def runtime(wildcards, threads, attempt):
        scene = config["scenes"][wildcards.scene]
        if scene["solver"] == "csph":
            steps = 0 if stage in ("prepare", "reference") else _sph_steps(scene)
            steps *= _sph_particles(scene)
            minutes = MD_STARTUP_MIN + steps * SPH_S_PER_PARTICLE_STEP / threads / 60.0
            return attempt * int(math.ceil(minutes))
        steps = _atom_steps(scene, stage)
        minutes = MD_STARTUP_MIN + steps * MD_S_PER_ATOM_STEP / threads / 60.0
        return attempt * int(math.ceil(minutes))

    return runtime


# The MD reference Hugoniot is computed once per distinct set of the inputs it depends on
# (hugomap.config.reference_inputs) and copied into each scene's folder. Keys per scene
# (None for CSPH) and, per key, the first MD scene (config order) with those inputs: once,
# when the workflow is parsed (the config is final by then).
def _reference_keys():
    from hugomap.config import reference_key

    return {name: reference_key(scene) for name, scene in config["scenes"].items()}


REFERENCE_KEYS = _reference_keys()
SHARED_REFERENCES = {}
for _scene, _key in REFERENCE_KEYS.items():
    if _key is not None:
        SHARED_REFERENCES.setdefault(_key, _scene)


def shared_reference_file(wildcards):
    """The shared reference an MD scene copies (none for CSPH: computed per scene)."""
    key = REFERENCE_KEYS[wildcards.scene]
    return [] if key is None else [f"{RES}/references/{key}.nc"]


def _reference_wildcards(wildcards):
    from types import SimpleNamespace

    return SimpleNamespace(scene=SHARED_REFERENCES[wildcards.key])


def shared_reference_json(wildcards):
    from hugomap.config import reference_inputs

    scene = config["scenes"][SHARED_REFERENCES[wildcards.key]]
    return json.dumps(reference_inputs(scene), sort_keys=True)


def shared_reference_mem_mb(wildcards, attempt):
    return md_mem_mb("reference")(_reference_wildcards(wildcards), attempt)


def shared_reference_runtime(wildcards, threads, attempt):
    return md_runtime("reference")(_reference_wildcards(wildcards), threads, attempt)


def scene_reference_runtime(wildcards, threads, attempt):
    """A CSPH scene computes its reference (seconds); an MD scene copies the shared one."""
    return attempt * MD_STARTUP_MIN


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
    """The campaign dataset and its two figures, named by campaign.name."""
    name = config.get("campaign", {}).get("name", "validation")
    return {
        "nc": f"{RES}/campaign/{name}.nc",
        "chart": f"{RES}/campaign/{name}_speed_accuracy.png",
        "map": f"{RES}/campaign/{name}_stability.png",
    }
