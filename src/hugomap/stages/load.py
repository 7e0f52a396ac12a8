"""Stage ``load``: drive the piston until the front has travelled the loading distance, and
save the complete state (the checkpoint every scheme at this u_p branches from)."""

from __future__ import annotations

import json
import logging
import math
import os
from pathlib import Path

import xarray as xr

from ..failures import HugomapFailure
from ..methods.piston import History
from ..methods.piston import load_to_target as run_loading
from ..registry import backend as backend_of
from ..states import PistonFrame, Pole
from .files import INFO_ATTR, Clock, failure, history_vars, info_of, is_ok, open_dataset, pole_vars

log = logging.getLogger("hugomap")
LOAD_MARKS = (0.25, 0.5, 0.75)  # fractions of the loading distance that get a progress line


class LoadingProgress:
    """The loading stage's progress lines: one when it starts, one as the front passes each
    fraction of ``LOAD_MARKS`` of the loading distance (step, simulated time, front, ETA), a
    few lines whatever the number of samples. Call it after each sample
    (``methods.piston.run_stage``'s ``on_sample``); ``wall()`` is the job's wall time [s].

    Rates are counted from the first sample on, so the first chunk's one-off costs (numba
    compiling its kernels on a cold cache: tens of seconds) do not enter the ETA nor
    ``wall_per_time``, the wall seconds per unit of simulated time that the piston stage's
    first ETA is made from (``stages.piston.loading_rate``)."""

    def __init__(self, sim, frame: PistonFrame, h: History, wall) -> None:
        self.sim, self.frame, self.h, self.wall = sim, frame, h, wall
        self.marks = list(LOAD_MARKS)
        self.first: tuple[float, float, float] | None = None  # wall, t, fraction done
        self.last: tuple[float, float] | None = None  # wall, t
        log.info(
            "loading: until the front has travelled %.6g from x = %.6g (a sample every %d "
            "steps, a line at %s of the way)",
            frame.load_distance, frame.x_origin, frame.sample_every,
            ", ".join(f"{m:.0%}" for m in LOAD_MARKS),
        )  # fmt: skip

    def wall_per_time(self) -> float | None:
        """Wall seconds per unit of simulated time from the first sample to the last."""
        if self.first is None or self.last is None or self.last[1] <= self.first[1]:
            return None
        return (self.last[0] - self.first[0]) / (self.last[1] - self.first[1])

    def __call__(self) -> None:
        xf = self.h.front[-1] if self.h.front else float("nan")
        if not math.isfinite(xf) or self.frame.load_distance <= 0:
            return
        wall = self.wall()
        done = (xf - self.frame.x_origin) / self.frame.load_distance
        self.last = (wall, float(self.sim.time))
        if self.first is None:
            self.first = (wall, float(self.sim.time), done)
        if not self.marks or done < self.marks[0]:
            return
        while self.marks and done >= self.marks[0]:
            self.marks.pop(0)
        w0, _, d0 = self.first
        eta = "done" if done >= 1.0 else "no ETA yet"
        if done < 1.0 and done > d0:
            eta = f"ETA {(wall - w0) * (1.0 - done) / (done - d0):.0f} s"
        log.info(
            "loading: step %d, t = %.6g, front %.6g, %.0f %% of the loading distance, "
            "%.0f s so far, %s",
            self.sim.steps, self.sim.time, xf, 100.0 * min(done, 1.0), wall, eta,
        )  # fmt: skip


def load_to_target(
    sample: str | os.PathLike, scene: dict, u_p: float, out: str | os.PathLike
) -> Path:
    """From the prepared sample, set the piston going at ``u_p`` (``Backend.start_piston``)
    and drive it (``methods.piston.load_to_target``) until the front has travelled
    ``shock.load_fraction`` of the sample; save the state with its history and pole."""
    b = backend_of(scene)
    clock = Clock()
    attrs = {"stage": "loaded", "u_p": u_p, "scene_config": json.dumps(scene)}
    ds = open_dataset(sample)
    if not is_ok(ds):
        return failure(out, ds.attrs["status"], ds.attrs.get("diagnostic", ""), attrs)
    info = info_of(ds)
    sim = b.load(ds, sample)
    pole = Pole.from_dataset(ds)
    b.start_piston(sim, scene, u_p)
    frame = b.piston_frame(sim, scene, u_p, info)
    profile = b.profile(sim, scene, info)
    h = History()
    step0 = sim.steps
    try:
        progress = LoadingProgress(sim, frame, h, lambda: clock.cost()["wall_s"])
        run_loading(sim, frame, profile, h, on_sample=progress)
    except HugomapFailure as exc:
        return failure(out, exc.status, exc.diagnostic, attrs)
    cost = clock.cost(sim.n_particles * (sim.steps - step0))
    log.info("loaded: t = %.4g, %d samples, front %.4g, %.0f s", sim.time, len(h.t),
             h.front[-1], cost["wall_s"])  # fmt: skip
    extra = xr.merge([history_vars(h), pole_vars(pole, b)])
    rate = progress.wall_per_time()
    if rate is not None:  # for the piston stage's first ETA
        attrs["wall_per_time"] = rate
    return b.save(sim, out, extra, {**attrs, "status": "ok", "cost": json.dumps(cost),
                                     INFO_ATTR: json.dumps(info)})  # fmt: skip
