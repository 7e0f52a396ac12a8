"""Stage ``window``: cut the moving window out of the loading checkpoint and save it (the
state AMW, MW and the dichotomy branch from)."""

from __future__ import annotations

import json
import logging
import os
from pathlib import Path

import numpy as np

from ..analysis.stats import line_fit
from ..failures import HugomapFailure
from ..registry import backend as backend_of
from ..states import Pole
from .files import INFO_ATTR, Clock, failure, history_of, info_of, is_ok, open_dataset

log = logging.getLogger("hugomap")


def window_start(
    loaded: str | os.PathLike, scene: dict, u_p: float, out: str | os.PathLike
) -> Path:
    """D is first guessed from the loading stage's front speed (a line fit over its second
    half, relative to the upstream material), the backend cuts and settles the window in
    that frame (``Backend.open_window``), and the window is saved with its ω normalisation
    and pole. With ``window.start_offset`` ε ≠ 0 every velocity then gets ε D_guess: the saved
    frame is off by that much, the front runs at about ε D, and each scheme must find D
    itself (stability maps). The cost so far (loading, this set-up) travels with it."""
    b = backend_of(scene)
    attrs = {"stage": "window", "u_p": u_p, "scene_config": json.dumps(scene)}
    ds = open_dataset(loaded)
    if not is_ok(ds):
        return failure(out, ds.attrs["status"], ds.attrs.get("diagnostic", ""), attrs)
    clock = Clock(json.loads(ds.attrs.get("cost", "{}")))
    info = info_of(ds)
    sim = b.load(ds, loaded)
    frame = b.piston_frame(sim, scene, u_p, info)
    h = history_of(ds).arrays()
    n = h["t"].size
    a, *_ = line_fit(h["t"][n // 2 :], h["front"][n // 2 :])
    if not np.isfinite(a):
        a, *_ = line_fit(h["t"], h["front"])
    D_guess = float(a - frame.u_ahead)
    if not (np.isfinite(D_guess) and D_guess > u_p):
        return failure(out, "no_front_speed", f"the loading stage gives no front speed ({n} "
                       f"samples, D guess {D_guess:.4g} at u_p = {u_p:g})", attrs)  # fmt: skip
    step0 = sim.steps
    w = scene["window"]
    try:
        start = b.open_window(sim, ds, scene, u_p, float(h["front"][-1]), D_guess,
                              Pole.from_dataset(ds), info)  # fmt: skip
        win = start.window
        if w["start_offset"]:
            # a deliberately wrong frame (stability maps): the front runs at ~start_offset D
            win.galilean_shift(w["start_offset"] * D_guess)
    except HugomapFailure as exc:
        return failure(out, exc.status, exc.diagnostic, attrs)
    cost = clock.cost(win.n_particles * max(win.steps - step0, 0))
    return b.save(win, out, None, {
        **attrs, **start.attrs, "status": "ok", "D_guess": D_guess,
        "start_offset": w["start_offset"], "omega_signal": json.dumps(start.signal.to_json()),
        "pole": json.dumps(start.pole.as_dict()), "cost": json.dumps(cost),
        INFO_ATTR: json.dumps(info),
    })  # fmt: skip
