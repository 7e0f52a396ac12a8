"""Stage ``piston``: continue the piston from the loading checkpoint until the front nears
the far end, then measure the Hugoniot point (``analysis.shock.measure_point``).

A periodic checkpoint ``<out>.part.nc`` (every ``shock.checkpoint_every`` samples) lets a
killed job resume where it stopped; one that fails its checks (format, checksum, the same
loading checkpoint) is logged and ignored, and the run starts again from the loading
checkpoint.
"""

from __future__ import annotations

import json
import logging
import os
import shutil
import time
from pathlib import Path

import netCDF4
import numpy as np
import xarray as xr

from ..analysis.shock import measure_point
from ..failures import CheckpointError, HugomapFailure
from ..methods.piston import History, drive, steady_track
from ..methods.target import ErrorTarget, judge
from ..registry import backend as backend_of
from ..states import PistonFrame, Pole, Resources
from .files import (
    INFO_ATTR,
    Clock,
    history_of,
    history_vars,
    info_of,
    is_ok,
    open_dataset,
    pole_vars,
    write_extras,
    write_point,
)
from .load import load_to_target
from .sample import prepare_sample

log = logging.getLogger("hugomap")
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


def save_partial(
    b, sim, h: History, pole: Pole, cost: dict[str, float], loaded: xr.Dataset,
    part: str | os.PathLike,
) -> Path:  # fmt: skip
    """Write the periodic checkpoint ``part`` of a running piston point: the state, its
    history and pole, the cost so far, and the checksum of the loading checkpoint it descends
    from (``parent_checksum``: a partial checkpoint left by a run from another loading
    checkpoint, e.g. before a config change, is not resumed)."""
    extra = xr.merge([history_vars(h), pole_vars(pole, b)])
    attrs = {
        "stage": "drive", "status": "ok", "cost": json.dumps(cost),
        "parent_checksum": str(loaded.attrs.get("checksum", "")),
        INFO_ATTR: loaded.attrs.get(INFO_ATTR, "{}"),
    }  # fmt: skip
    return b.save(sim, part, extra, attrs)


def _resume_partial(b, part: Path, loaded: xr.Dataset) -> tuple[xr.Dataset, object, History] | None:
    """The partial checkpoint ``part`` of a killed run (dataset, simulation, history), if
    there is one that can be resumed; else None (logged): a missing file, an unreadable,
    foreign or altered one (``CheckpointError``), or one from another loading checkpoint."""
    if not part.exists():
        return None
    try:
        dp = b.read_checkpoint(part)  # format and checksum verified
        if dp.attrs.get("parent_checksum") != loaded.attrs.get("checksum"):
            raise CheckpointError(
                str(part),
                "it descends from another loading checkpoint (parent_checksum "
                f"{dp.attrs.get('parent_checksum')!r}, loaded {loaded.attrs.get('checksum')!r})",
            )
        resumed = dp, b.load(dp, part), history_of(dp)
    except (CheckpointError, OSError, ValueError, KeyError) as exc:
        log.warning(
            "ignoring partial checkpoint %s, restarting from the loaded state: %s", part, exc
        )
        return None
    log.info("resuming from %s at t = %.6g (step %d)", part, resumed[1].time, resumed[1].steps)
    return resumed


def loading_rate(
    h: History, cost: dict, wall_per_time: float | None = None
) -> tuple[float, float] | None:
    """How fast the loading stage went: (the speed at which the gap between the front and the
    far end closed, from a line through the second half of its samples; the wall seconds per
    unit of simulated time: the loading checkpoint's ``wall_per_time`` where it has one (its
    samples after the first, without the first chunk's compile time), else its whole
    ``cost`` over its simulated time), or None where it cannot tell (fewer than 4 samples
    with a front, a gap that did not close, no wall time)."""
    a = h.arrays()
    m = (a["stage"] == 0) & np.isfinite(a["front"])
    t, gap = a["t"][m], a["x_right"][m] - a["front"][m]
    if t.size < 4:
        return None
    half = t.size // 2
    speed = -float(np.polyfit(t[half:], gap[half:], 1)[0])
    if wall_per_time is None or not wall_per_time > 0:
        span = float(t[-1] - t[0]) * t.size / (t.size - 1)  # t.size sample intervals
        wall_per_time = float(cost.get("wall_s", 0.0)) / span if span > 0 else 0.0
    if not (speed > 0 and wall_per_time > 0):
        return None
    return speed, float(wall_per_time)


def _gap(sim, h: History, frame: PistonFrame) -> tuple[float, float] | None:
    """(front, what the front still has to close: the far end less ``rear_margin``)."""
    xf = next((f for f in reversed(h.front) if np.isfinite(f)), float("nan"))
    if not np.isfinite(xf):
        return None
    xr = frame.far_end if frame.far_end is not None else sim.wall_positions()[1]
    return xf, xr - xf - frame.rear_margin


def log_drive_start(
    sim, h: History, frame: PistonFrame, rate: tuple[float, float] | None, x_start: list
) -> None:
    """The drive's first line: where the front is, what it has to go, and an ETA from the
    loading stage's rate (``loading_rate``); sets ``x_start`` (the gap and wall time at the
    start, for ``log_progress``)."""
    g = _gap(sim, h, frame)
    if g is None:
        log.info("drive: step %d, t = %.6g, no front yet", sim.steps, sim.time)
        return
    xf, gap = g
    x_start[0] = (gap, 0.0)
    eta = "no ETA yet (the loading stage's rate is unknown)"
    if rate is not None:
        speed, wall_per_t = rate
        eta = (f"ETA {max(gap, 0.0) / speed * wall_per_t:.0f} s from the loading stage (gap "
               f"closing at {speed:.4g} per unit time, {wall_per_t:.3g} s of wall per unit time)")  # fmt: skip
    log.info("drive: step %d, t = %.6g, front %.6g, %.6g to go, %s",
             sim.steps, sim.time, xf, gap, eta)  # fmt: skip


def log_progress(
    sim, h: History, frame: PistonFrame, x_start: list, wall: float,
    rate: tuple[float, float] | None = None,
) -> None:  # fmt: skip
    """A progress line: step, simulated time, front, fraction of the drive done, ETA.

    The drive ends when the front is ``rear_margin`` from the far end; the fraction is how
    much of that gap (front to far end, both may move) has closed since the drive began
    (``x_start[0]``: the gap and wall time then, set by ``log_drive_start`` or on the first
    call), the ETA that fraction's wall rate; before any progress, the loading stage's
    ``rate`` (``loading_rate``) where it is known, else it says so rather than guess."""
    g = _gap(sim, h, frame)
    if g is None:
        return
    xf, gap = g
    if x_start[0] is None:
        x_start[0] = (gap, wall)
    gap0, w0 = x_start[0]
    done = 1.0 - gap / gap0 if gap0 > 0 else 1.0
    if done > 0:
        eta = f"ETA {(wall - w0) * (1.0 - done) / done:.0f} s"
    elif rate is not None:
        eta = f"ETA {max(gap, 0.0) / rate[0] * rate[1]:.0f} s (loading stage's rate)"
    else:
        eta = "ETA after the next line"
    log.info(
        "progress: step %d, t = %.6g, front %.6g, %.0f %% of the drive, %s",
        sim.steps, sim.time, xf, 100.0 * min(max(done, 0.0), 1.0), eta,
    )  # fmt: skip


# A re-run's drive is the one the first run's error law asks for, with this margin: an
# 8-block error is itself uncertain by ~27 % (methods.target), and a sample that falls short
# again costs a third run the user did not ask for.
SIZE_MARGIN = 1.2
# target.max_sample_factor where the target does not give it: a second run costs at most
# about 4 times the first
MAX_SAMPLE_FACTOR = 2.0


def max_sample_factor(scene: dict) -> float:
    """The scene's ``target.max_sample_factor`` (1 without a target: nothing to grow to)."""
    t = scene.get("target") or {}
    return float(t.get("max_sample_factor", MAX_SAMPLE_FACTOR)) if t else 1.0


def piston_point(
    loaded: str | os.PathLike, scene: dict, u_p: float, out: str | os.PathLike,
    scheme: str = "piston",
) -> Path:  # fmt: skip
    """The piston's point (``drive_point``); one that misses its error target (status
    ``target_not_reached``) is run once more on a sample the factor ``grow_to_target``
    chose longer (``Backend.longer_sample``: prepared, loaded and driven in the folder
    ``<out stem>_sized``, the first run kept there as ``pilot.nc``). The second run's point
    counts the first's CPU and the longer sample's preparation in its cost and records the
    factor and the first run's relative errors (``sample_factor``, ``pilot_D_rel_err``,
    ``pilot_P_rel_err``). A killed job resumes: a finished first run,
    sample or loading is not run again."""
    out = Path(out)
    room = out.with_name(f"{out.stem}_sized")
    pilot = room / "pilot.nc"
    b = backend_of(scene)
    first = _kept_first_run(room, scene, b)
    if first is None:
        drive_point(loaded, scene, u_p, out, scheme)
        first = open_dataset(out)
        if not float(first.get("sample_factor", 1.0)) > 1.0:
            return out
        room.mkdir(exist_ok=True)
        os.replace(out, pilot)
    factor = float(first["sample_factor"])
    longer = b.longer_sample(scene, factor)
    log.info(
        "re-running on a sample %.3g times as long: %s", factor, str(first["diagnostic"].values)
    )
    sample, loaded2 = room / "sample.nc", room / "loaded.nc"
    spent = room / "spent.json"  # the first run's cost and the longer sample's preparation
    if not sample.exists():
        clock = Clock({k: float(first[k]) for k in ("wall_s", "cpu_s", "atom_steps") if k in first})
        prepare_sample(longer, sample)
        spent.write_text(json.dumps(clock.cost()))
    prior = json.loads(spent.read_text()) if spent.exists() else {}
    if not loaded2.exists():
        load_to_target(sample, longer, u_p, loaded2)
    rel = {q: float(first[f"{q}_rel_err"]) for q in ("D", "P") if f"{q}_rel_err" in first}
    return drive_point(loaded2, longer, u_p, out, scheme, prior=prior,
                       extra={"sample_factor": factor, **{f"pilot_{q}_rel_err": v
                                                          for q, v in rel.items()}})  # fmt: skip


def _same_scene(made: str, scene: dict) -> bool:
    """Whether a file's ``scene_config`` attribute (``made``) is ``scene``."""
    return json.dumps(json.loads(made), sort_keys=True) == json.dumps(scene, sort_keys=True)


def _kept_first_run(room: Path, scene: dict, b) -> xr.Dataset | None:
    """The first run kept in ``room`` (a second run's folder, ``pilot.nc``), or None; a
    room holding what was made for another scene (a config changed between a killed job
    and its rerun: a first run of another scene, or a sample or loading other than the
    longer sample its factor asks for) is emptied, and None."""
    pilot = room / "pilot.nc"
    first = open_dataset(pilot) if pilot.exists() else None
    ok = first is not None and _same_scene(first.attrs.get("scene_config", "null"), scene)
    if ok:
        longer = b.longer_sample(scene, float(first["sample_factor"]))
        for f in (room / "sample.nc", room / "loaded.nc"):
            if ok and f.exists():
                with netCDF4.Dataset(f) as nc:
                    ok = _same_scene(getattr(nc, "scene_config", "null"), longer)
    if ok:
        return first
    if room.exists():
        if first is not None:
            log.warning("%s holds a run of another scene: starting again", room)
        shutil.rmtree(room)
    return None


def grow_to_target(
    need: float, cpu_s: float, target: ErrorTarget, max_factor: float
) -> tuple[float, str]:  # fmt: skip
    """How much longer a piston's sample grows after missing its target, and why: ``need``
    is the drive the error law asks for over the drive it had (the sample grows as the
    drive, its CPU as the square: atoms times steps); the factor is ``need`` x SIZE_MARGIN,
    refused (1.0) above ``max_factor`` (``target.max_sample_factor``) or where the second
    run, about factor² x ``cpu_s`` (the first run's), would overrun ``target.cpu_s`` with
    the first's spent."""
    factor = need * SIZE_MARGIN
    if not factor > 1.0:
        return 1.0, ""
    tried = f"; not run again: {factor:.3g} times with a {SIZE_MARGIN - 1:.0%} margin"
    if factor > max_factor:
        return 1.0, f"{tried}, above target.max_sample_factor = {max_factor:g}"
    if target.cpu_s is not None and cpu_s * (1.0 + factor**2) > target.cpu_s:
        return 1.0, (f"{tried} would cost about {cpu_s * factor**2:.3g} s more, above "
                     f"target.cpu_s = {target.cpu_s:g} s")  # fmt: skip
    return factor, f"; run again on a sample {factor:.3g} times as long"


def job_cost(scene: dict) -> Resources:
    """A piston job's resources (``Backend.cost``): its first run's, and where its target
    may grow the sample (``target.max_sample_factor`` F > 1) the longer sample's
    preparation, loading and drive beside it; its memory the longer sample's."""
    b = backend_of(scene)
    first = b.cost(scene, "piston")
    factor = max_sample_factor(scene)
    longer = b.longer_sample(scene, factor) if factor > 1.0 else None
    if longer is None:
        return first
    grown = [b.cost(longer, stage) for stage in ("prepare", "load", "piston")]
    return Resources(max(first.mem_mb, *(g.mem_mb for g in grown)),
                     first.cpu_s + sum(g.cpu_s for g in grown), first.ranks)  # fmt: skip


def drive_point(
    loaded: str | os.PathLike, scene: dict, u_p: float, out: str | os.PathLike,
    scheme: str = "piston", prior: dict | None = None, extra: dict | None = None,
) -> Path:  # fmt: skip
    """Continue the piston from ``loaded`` (or its partial checkpoint) until the front is
    ``rear_margin`` from the far end (``methods.piston.drive``), measure the point over the
    drive samples, write the backend's extras (snapshots) and the point file (with the
    ``extra`` values; its cost the loading's, this drive's and ``prior``'s). A first run
    (``prior`` None) that misses its target records in ``sample_factor`` the factor
    ``grow_to_target`` chose (1: no second run)."""
    b = backend_of(scene)
    sh = scene["shock"]
    ds = open_dataset(loaded)
    base = {"piston_velocity": u_p}
    if not is_ok(ds):
        return write_point(out, b, scene, scheme, base, {}, None, ds.attrs["status"],
                           ds.attrs.get("diagnostic", ""))  # fmt: skip
    info = info_of(ds)
    part = Path(str(out) + ".part.nc")
    _remove_stale_temporaries(Path(out))
    resumed = _resume_partial(b, part, ds)
    loaded_history = history_of(ds)
    if resumed is None:
        src, sim, h = ds, b.load(ds, loaded), loaded_history  # verified on load
    else:
        b.read_checkpoint(loaded)  # verified too: its pole is used whichever state resumes
        src, sim, h = resumed
    pole = Pole.from_dataset(ds)
    clock = Clock(json.loads(src.attrs.get("cost", ds.attrs.get("cost", "{}"))), prior or {})
    frame = b.piston_frame(sim, scene, u_p, info)
    profile = b.profile(sim, scene, info)
    step0 = sim.steps
    n_since, x_start = [0], [None]
    rate = loading_rate(loaded_history, json.loads(ds.attrs.get("cost", "{}")),
                        ds.attrs.get("wall_per_time"))  # fmt: skip
    log_drive_start(sim, h, frame, rate, x_start)

    def checkpoint() -> None:
        n_since[0] += 1
        if n_since[0] % sh["checkpoint_every"] == 0:
            wall = clock.cost()["wall_s"] - clock.prior["wall_s"]
            log_progress(sim, h, frame, x_start, wall, rate)
            save_partial(b, sim, h, pole, clock.cost(sim.n_particles * (sim.steps - step0)),
                         ds, part)  # fmt: skip

    status, diagnostic = "ok", ""
    try:
        drive(sim, frame, profile, h, on_sample=checkpoint)
    except HugomapFailure as exc:
        status, diagnostic = exc.status, exc.diagnostic
        log.error("%s: %s", status, diagnostic)
    values = {**base, "sample_factor": 1.0, **(extra or {}),
              **clock.cost(sim.n_particles * (sim.steps - step0))}  # fmt: skip
    a = h.arrays()
    if status == "ok":
        d = a["stage"] == 1
        track = steady_track(a, frame)
        r = measure_point(
            {k: a[k][d] for k in ("t", "front", "x_left", "x_right", "sums")}, profile, pole,
            frame.u_behind, frame.u_ahead,
            sh["gap"] if frame.gap is None else frame.gap,
            sh["avg_length"] if frame.avg_length is None else frame.avg_length,
            sh["residual_tol"],
            left_gap=frame.piston_gap,
            track=track,
            ahead_gap=frame.ahead_gap,
        )  # fmt: skip
        r.pop("u_p"), r.pop("u_p_err")  # u_p is exact: the dataset's coordinate
        # a piston cannot run on once its front nears the far end: it is judged on its
        # steady track's span, and told the span it would need (methods.target), on the slow
        # law T^(-1/2) (K_DEFAULT) so that the span it states is not short: its D is the
        # slope of a front that wanders (a random walk's slope error falls as T^(-1/2),
        # white noise about the line's as T^(-3/2)), its P the mean of a slab of fixed length.
        span = float(np.ptp(track[0])) if len(track[0]) else 0.0
        target = ErrorTarget.of_scene(scene)
        status, diagnostic = judge(target, r, str(r.pop("status")), str(r.pop("diagnostic")),
                                   span, P0=pole.P0, what="drive",
                                   unit=f" {b.units.axes['time']}")  # fmt: skip
        if status == "target_not_reached" and span > 0:
            # the steady track grows with the sample: its length is what to change
            need = r["time_to_target"] / span
            diagnostic += f"; a drive that long needs a sample about {need:.2g} times as long"
            if prior is None:
                factor, note = grow_to_target(need, values["cpu_s"], target,
                                              max_sample_factor(scene))  # fmt: skip
                if factor > 1.0 and b.longer_sample(scene, factor) is None:
                    factor, note = 1.0, "; not run again: the sample's length is its file's"
                diagnostic += note
                values["sample_factor"] = factor
        values.update(r)
        log.info("point: D = %.6g +- %.2g, u_p %.6g (measured %.6g), P = %.6g +- %.2g, %s",
                 r["D"], r["D_err"], u_p, r["u_p_measured"], r["P"], r["P_err"], status)  # fmt: skip
    write_extras(b.extras, sim, Path(out), scene, u_p, info)
    path = write_point(out, b, scene, scheme, values, pole.as_dict(),
                       {k: a[k] for k in ("t", "front", "stage")}, status, diagnostic)  # fmt: skip
    part.unlink(missing_ok=True)
    return path
