"""Stage ``load``: drive the piston until the front has travelled the loading distance, and
save the complete state (the checkpoint every scheme at this u_p branches from)."""

from __future__ import annotations

import json
import logging
import os
from pathlib import Path

import xarray as xr

from ..failures import HugomapFailure
from ..registry import backend as backend_of
from ..states import Pole
from ..window.piston import History
from ..window.piston import load_to_target as run_loading
from .files import INFO_ATTR, Clock, failure, history_vars, info_of, is_ok, open_dataset, pole_vars

log = logging.getLogger("hugomap")


def load_to_target(
    sample: str | os.PathLike, scene: dict, u_p: float, out: str | os.PathLike
) -> Path:
    """From the prepared sample, set the piston going at ``u_p`` (``Backend.start_piston``)
    and drive it (``window.piston.load_to_target``) until the front has travelled
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
        run_loading(sim, frame, profile, h)
    except HugomapFailure as exc:
        return failure(out, exc.status, exc.diagnostic, attrs)
    cost = clock.cost(sim.n_particles * (sim.steps - step0))
    log.info("loaded: t = %.4g, %d samples, front %.4g", sim.time, len(h.t), h.front[-1])
    extra = xr.merge([history_vars(h), pole_vars(pole, b)])
    return b.save(sim, out, extra, {**attrs, "status": "ok", "cost": json.dumps(cost),
                                     INFO_ATTR: json.dumps(info)})  # fmt: skip
