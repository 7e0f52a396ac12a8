"""One function per workflow stage: file in, file out, no physics of its own.

prepare_sample → load_to_target (checkpoint) → piston_point → aggregate → figures, and the
equilibrium reference beside them. A stage whose solver breaks still writes its output, marked
with a ``status`` and a ``diagnostic``, so the aggregate keeps the point, marked failed.
"""

from __future__ import annotations

import json
import logging
import os
import resource
import time
from pathlib import Path

import numpy as np
import xarray as xr

from .analysis.shock import analyse_piston, region_state
from .analysis.stats import block_average
from .failures import CheckpointError, SolverUnstable, StageFailed
from .io.atomic import write_netcdf
from .io.checkpoint import read_checkpoint, verify_checkpoint
from .io.dataset import POLE_VARS, aggregate_points, point_dataset, scalar_vars
from .md.potential import LJParams
from .md.sample import fcc_state
from .md.simulation import MDSimulation
from .window.piston import History, PistonParams, drive, load_to_target, start_piston

log = logging.getLogger("hugomap")
WALL_LAYER = 4.0  # sigma kept clear of a wall when measuring the pole (wall layering)


def _lj(scene: dict) -> LJParams:
    p = scene.get("potential", {})
    return LJParams(rc=p.get("rc", 2.5), shift=p.get("shift", True), skin=p.get("skin", 0.3))


def _cpu() -> float:
    r = resource.getrusage(resource.RUSAGE_SELF)
    return r.ru_utime + r.ru_stime


def _pole_from(ds: xr.Dataset) -> dict[str, float]:
    names = [*POLE_VARS, *(k + "_err" for k in POLE_VARS)]
    return {k: float(ds[k]) for k in names if k in ds}


def prepare_sample(scene: dict, out: str | os.PathLike) -> Path:
    """FCC at (ρ0, T0) between two static walls, thermostatted (CSVR) for ``equilibrate_time``,
    then run without thermostat for ``pole_time`` while the pole is measured away from the
    walls: ρ0, P0 = P_xx, E0, T0 (block averages with standard errors)."""
    if scene.get("solver") == "csph":  # contact SPH (SI units): pipeline_sph
        from . import pipeline_sph

        return pipeline_sph.prepare_sample(scene, out)
    s = scene["sample"]
    lj = _lj(scene)
    state = fcc_state(tuple(s["cells"]), s["rho0"], s["T0"], s["seed"], periodic_x=False)
    sim = MDSimulation(
        state, lj, s["dt"], T_bath=s["T0"], tau_bath=s["thermostat_tau"], seed=s["seed"]
    )
    sim.advance(int(round(s["equilibrate_time"] / s["dt"])))
    sim.T_bath = None
    width = scene["shock"]["bin_width"]
    area = float(state.L[1] * state.L[2])
    every = 25
    nsamples = max(int(round(s["pole_time"] / (s["dt"] * every))), 16)
    keys = {"n": "rho0", "Pxx": "P0", "e": "E0", "T": "T0", "Pyy": "Pyy0"}
    series = {k: [] for k in keys}
    edges = np.arange(int(np.floor(state.L[0] / width + 1e-9)) + 1) * width
    for _ in range(nsamples):
        sim.advance(every)
        st = region_state(sim.profile_sums(width), edges, WALL_LAYER, state.L[0] - WALL_LAYER, area)
        for k in keys:
            series[k].append(st[k])
    pole = {}
    for k, name in keys.items():
        pole[name], pole[name + "_err"] = block_average(np.asarray(series[k]))
    log.info("pole: %s", json.dumps(pole))
    extra = xr.Dataset(scalar_vars(pole, POLE_VARS))
    return sim.save(
        out,
        extra=extra,
        attrs={"stage": "sample", "status": "ok", "scene_config": json.dumps(scene)},
    )


def _piston_params(scene: dict, u_p: float, sim: MDSimulation) -> PistonParams:
    sh = scene["shock"]
    L = sim.state.L
    return PistonParams(
        u_p=u_p,
        bin_width=sh["bin_width"],
        sample_every=sh["sample_every"],
        load_distance=sh["load_fraction"] * float(L[0]),
        rear_margin=sh["rear_margin"],
        max_time=sh["max_time"],
        area=float(L[1] * L[2]),
    )


def _failure(out: str | os.PathLike, status: str, diagnostic: str, attrs: dict) -> Path:
    log.error("%s: %s", status, diagnostic)
    ds = xr.Dataset(attrs={**attrs, "status": status, "diagnostic": diagnostic})
    return write_netcdf(ds, out)


def _history_extra(h: History) -> xr.Dataset:
    a = h.arrays()
    nb = a["sums"].shape[1] if a["sums"].ndim == 3 else 0
    return xr.Dataset(
        {
            "hist_t": (("sample",), a["t"]),
            "hist_x_left": (("sample",), a["x_left"]),
            "hist_x_right": (("sample",), a["x_right"]),
            "hist_front": (("sample",), a["front"]),
            "hist_stage": (("sample",), a["stage"]),
            "hist_sums": (("sample", "bin", "field"), a["sums"].reshape(len(a["t"]), nb, -1)),
        }
    )


def _history_from(ds: xr.Dataset) -> History:
    return History.from_arrays({k[5:]: ds[k].values for k in ds.data_vars if k.startswith("hist_")})


def load_to_target_stage(
    sample: str | os.PathLike, scene: dict, u_p: float, out: str | os.PathLike
) -> Path:
    """From the prepared sample, drive a piston at ``u_p`` until the front has travelled
    ``load_fraction`` of the sample; save the complete state (the branching checkpoint)."""
    if scene.get("solver") == "csph":
        from . import pipeline_sph

        return pipeline_sph.load_to_target_stage(sample, scene, u_p, out)
    t0, c0 = time.perf_counter(), _cpu()
    with xr.open_dataset(sample, engine="netcdf4") as ds:
        ds.load()
    pole = _pole_from(ds)
    sim = MDSimulation.from_dataset(ds)
    sim.dt = scene["shock"]["dt"]
    sim.T_bath = None
    p = _piston_params(scene, u_p, sim)
    start_piston(sim, u_p)
    h = History()
    step0 = sim.state.step
    attrs = {"stage": "loaded", "u_p": u_p, "scene_config": json.dumps(scene)}
    try:
        load_to_target(sim, p, h)
    except (SolverUnstable, StageFailed) as exc:
        return _failure(out, exc.status, exc.diagnostic, attrs)
    cost = {
        "wall_s": time.perf_counter() - t0,
        "cpu_s": _cpu() - c0,
        "atom_steps": float(sim.state.n * (sim.state.step - step0)),
    }
    extra = xr.merge([_history_extra(h), xr.Dataset(scalar_vars(pole, POLE_VARS))])
    return sim.save(out, extra=extra, attrs={**attrs, "status": "ok", "cost": json.dumps(cost)})


def save_partial(
    sim: MDSimulation,
    h: History,
    pole: dict[str, float],
    cost: dict[str, float],
    loaded: xr.Dataset,
    part: str | os.PathLike,
) -> Path:
    """Write the periodic checkpoint ``part`` of a running piston point: the state, its
    history and pole, the cost so far, and the checksum of the loading checkpoint it descends
    from (``parent_checksum``: a partial checkpoint left by a run from another loading
    checkpoint, e.g. before a config change, is not resumed)."""
    extra = xr.merge([_history_extra(h), xr.Dataset(scalar_vars(pole, POLE_VARS))])
    attrs = {
        "stage": "drive",
        "status": "ok",
        "cost": json.dumps(cost),
        "parent_checksum": str(loaded.attrs.get("checksum", "")),
    }
    return sim.save(part, extra=extra, attrs=attrs)


STALE_TMP_S = 60.0  # a temporary file not written to for this long was left by a killed write


def _remove_stale_temporaries(out: Path) -> None:
    """Remove the temporary files (``io.atomic``) of ``out`` and of its partial checkpoint
    that a killed write left behind; one written to in the last ``STALE_TMP_S`` seconds may
    belong to a write in progress (a second sweep in the same folder) and is kept."""
    now = time.time()
    for tmp in out.parent.glob(f".{out.name}.*.tmp"):
        try:
            if now - tmp.stat().st_mtime >= STALE_TMP_S:
                log.info("removing %s, left by a killed write", tmp)
                tmp.unlink()
        except FileNotFoundError:
            pass


def _resume_partial(
    part: Path, loaded: xr.Dataset
) -> tuple[xr.Dataset, MDSimulation, History] | None:
    """The partial checkpoint ``part`` of a killed run (dataset, simulation, history), if
    there is one that can be resumed; else None (logged): a missing file, an unreadable,
    foreign or altered one (``CheckpointError``), or one from another loading checkpoint."""
    if not part.exists():
        return None
    try:
        dp = read_checkpoint(part)  # format version and checksum verified
        if dp.attrs.get("parent_checksum") != loaded.attrs.get("checksum"):
            raise CheckpointError(
                str(part),
                "it descends from another loading checkpoint (parent_checksum "
                f"{dp.attrs.get('parent_checksum')!r}, loaded {loaded.attrs.get('checksum')!r})",
            )
        resumed = dp, MDSimulation.from_dataset(dp, part), _history_from(dp)
    except (CheckpointError, OSError, ValueError, KeyError) as exc:
        log.warning(
            "ignoring partial checkpoint %s, restarting from the loaded state: %s", part, exc
        )
        return None
    log.info("resuming from %s at t = %s (step %s)", part, dp.attrs["time"], dp.attrs["step"])
    return resumed


def _log_progress(sim, h, p, x_start: list, wall: float) -> None:
    """A progress line: step, simulated time, front, fraction of the drive done, ETA.

    The drive ends when the front is ``rear_margin`` from the far wall; the fraction is how
    much of that gap (front to far wall, both moving) has closed since the first progress
    line, the ETA that fraction's wall rate."""
    xf = next((f for f in reversed(h.front) if np.isfinite(f)), float("nan"))
    if not np.isfinite(xf):
        return
    xl, xr = sim.wall_positions()
    gap = xr - xf - p.rear_margin  # what the front still has to close (the wall comes too)
    if x_start[0] is None:
        x_start[0] = (gap, wall)
    gap0, w0 = x_start[0]
    done = 1.0 - gap / gap0 if gap0 > 0 else 1.0
    eta = (wall - w0) * (1.0 - done) / done if done > 0 else float("nan")
    log.info(
        "progress: step %d, t = %.3f tau, front %.2f sigma, %.0f %% of the drive, ETA %.0f s",
        sim.state.step, sim.time, xf, 100.0 * min(max(done, 0.0), 1.0), eta,
    )  # fmt: skip


def piston_point(
    loaded: str | os.PathLike,
    scene: dict,
    u_p: float,
    out: str | os.PathLike,
    scheme: str = "piston",
) -> Path:
    """Continue the piston from the loading checkpoint until the front nears the far wall,
    then measure the Hugoniot point. A periodic checkpoint ``<out>.part.nc`` (every
    ``shock.checkpoint_every`` samples) lets a killed job resume where it stopped; one that
    fails its checks (format version, checksum, same loading checkpoint) is logged and
    ignored, and the run starts again from the loading checkpoint."""
    if scene.get("solver") == "csph":
        from . import pipeline_sph

        return pipeline_sph.piston_point(loaded, scene, u_p, out, scheme)
    t0, c0 = time.perf_counter(), _cpu()
    sh = scene["shock"]
    name = scene.get("name", "")
    with xr.open_dataset(loaded, engine="netcdf4") as ds:
        ds.load()
    status = ds.attrs.get("status", "ok")
    base_values = {"piston_velocity": u_p}
    if status != "ok":
        ds_out = point_dataset(
            base_values, {}, None, scheme, name, status, ds.attrs.get("diagnostic", ""), scene
        )
        return write_netcdf(ds_out, out)
    verify_checkpoint(ds, loaded)  # its pole is used whichever state the run resumes from
    part = Path(str(out) + ".part.nc")
    _remove_stale_temporaries(Path(out))
    resumed = _resume_partial(part, ds)
    if resumed is None:
        src, sim, h = ds, MDSimulation.from_dataset(ds, loaded), _history_from(ds)
    else:
        src, sim, h = resumed
    pole = _pole_from(ds)
    cost = json.loads(src.attrs.get("cost", ds.attrs.get("cost", "{}")))
    p = _piston_params(scene, u_p, sim)
    step0 = sim.state.step
    n_since = [0]

    x_start = [None]

    def checkpoint() -> None:
        n_since[0] += 1
        if n_since[0] % sh["checkpoint_every"] == 0:
            _log_progress(sim, h, p, x_start, time.perf_counter() - t0)
            c = dict(cost)
            c["wall_s"] = c.get("wall_s", 0) + time.perf_counter() - t0
            c["cpu_s"] = c.get("cpu_s", 0) + _cpu() - c0
            c["atom_steps"] = c.get("atom_steps", 0) + sim.state.n * (sim.state.step - step0)
            save_partial(sim, h, pole, c, ds, part)

    status, diagnostic = "ok", ""
    try:
        drive(sim, p, h, on_sample=checkpoint)
    except (SolverUnstable, StageFailed) as exc:
        status, diagnostic = exc.status, exc.diagnostic
        log.error("%s: %s", status, diagnostic)
    values = dict(base_values)
    values["wall_s"] = cost.get("wall_s", 0) + time.perf_counter() - t0
    values["cpu_s"] = cost.get("cpu_s", 0) + _cpu() - c0
    values["atom_steps"] = cost.get("atom_steps", 0) + sim.state.n * (sim.state.step - step0)
    if status == "ok":
        r = analyse_piston(
            h.arrays(), pole, p.area, p.bin_width, sh["gap"],
            residual_tol=sh["residual_tol"], avg_length=sh["avg_length"],
            u_upstream=-u_p, u_piston=0.0,
        )  # fmt: skip
        # u_p is exact here (the nominal piston speed, the dataset's u_p coordinate).
        r.pop("u_p"), r.pop("u_p_err")
        values.update(r)
        status = str(r["status"])
        if status != "ok":
            diagnostic = "jump residuals: " + ", ".join(
                f"{k} {values['residual_' + k]:+.3%}" for k in ("mass", "momentum", "energy")
            )
    ds_out = point_dataset(values, pole, h.arrays(), scheme, name, status, diagnostic, scene)
    path = write_netcdf(ds_out, out)
    part.unlink(missing_ok=True)
    return path


def reference_stage(
    scene: dict, out: str | os.PathLike, shared: str | os.PathLike | None = None
) -> Path:
    """The equilibrium-MD reference Hugoniot of the scene's pole and potential (a CSPH
    scene: its material model's Hugoniot, ``pipeline_sph.reference_stage``).

    MD: computed from ``config.reference_inputs(scene)`` (stored as the ``reference_inputs``
    attribute), or, with ``shared``, copied from a reference computed for the same inputs
    (``results/references/<key>.nc``); a shared file made from other inputs is refused."""
    if scene.get("solver") == "csph":
        from . import pipeline_sph

        return pipeline_sph.reference_stage(scene, out)
    from .config import reference_inputs

    want = json.dumps(reference_inputs(scene), sort_keys=True)
    if shared is not None:
        with xr.open_dataset(shared, engine="netcdf4") as r:
            ds = r.load()
        got = ds.attrs.get("reference_inputs")
        if got != want:
            raise ValueError(
                f"{shared}: this reference was computed for {got}, not for scene "
                f"{scene.get('name', '?')!r} ({want}); delete the file and rerun"
            )
    else:
        from .analysis.reference import reference_hugoniot  # numba kernels: not for a copy

        s, r = scene["sample"], scene["reference"]
        ds = reference_hugoniot(
            s["rho0"], s["T0"], _lj(scene),
            compressions=r["compressions"], cells=(r["cells"],) * 3, dt=r["dt"],
            n_equil=r["equilibrate_steps"], n_prod=r["production_steps"], seed=s["seed"],
        )  # fmt: skip
        ds.attrs["reference_inputs"] = want
    ds.attrs["scene_config"] = json.dumps(scene)
    return write_netcdf(ds, out)


def aggregate(
    points: list[str],
    reference: str | None,
    config: dict,
    scene: str,
    out: str | os.PathLike,
    scheme: str = "piston",
) -> Path:
    """All points of a scene → ``results/hugoniot/<scene>.nc`` (dims scheme × u_p).

    Points are grouped by the ``scheme`` attribute of their files (``scheme`` is the default
    for files without one), each group is joined along u_p, and the groups along scheme."""
    import netCDF4

    ref = None
    if reference:
        with xr.open_dataset(reference, engine="netcdf4") as r:
            ref = r.load()
    groups: dict[str, list[str]] = {}
    for p in points:
        with netCDF4.Dataset(p) as nc:
            name = getattr(nc, "scheme", scheme)
        groups.setdefault(str(name), []).append(p)
    parts = [
        aggregate_points(ps, name, ref, config, scene).sortby("u_p") for name, ps in groups.items()
    ]
    # A variable that one scheme's points never produced (all failed) is NaN there.
    names = {k for part in parts for k, v in part.data_vars.items() if "scheme" in v.dims}
    for i, part in enumerate(parts):
        for k in names - set(part.data_vars):
            src = next(q[k] for q in parts if k in q)
            fill = np.full((1, part.sizes["u_p"]), np.nan if src.dtype.kind == "f" else 0,
                           dtype=src.dtype if src.dtype.kind != "O" else object)  # fmt: skip
            parts[i] = parts[i].assign({k: (("scheme", "u_p"), fill, src.attrs)})
    ds = xr.concat(parts, dim="scheme", data_vars="minimal", coords="minimal", compat="override",
                   join="outer", combine_attrs="override")  # fmt: skip
    return write_netcdf(ds.load(), out)
