"""Stages of the dichotomy (``methods.dichotomy``): the loop state, one trial, the point.

Every trial is an independent run from the window checkpoint at one outflow velocity u_out
(a Galilean shift: the amplitude u_p = u_out − u_in held, the frame moves), measuring
⟨dω/dt⟩ (``methods.control.fixed_run``); the loop state is a small JSON file per iteration;
the point is the steady average at the bisection's root.
"""

from __future__ import annotations

import json
import logging
import os
from pathlib import Path

import numpy as np

from ..failures import HugomapFailure
from ..io.atomic import write_json
from ..methods import dichotomy as dich
from ..methods.control import fixed_run
from ..methods.steady import steady_state
from ..methods.target import ErrorTarget
from ..registry import backend as backend_of
from .files import Clock, info_of, open_dataset, write_extras
from .window_files import failed_point, open_window, prior_cost, window_point

log = logging.getLogger("hugomap")


def dichotomy_state(
    window0: str | os.PathLike, scene: dict, k: int, previous: str | None, trials: list[str],
    out: str | os.PathLike,
) -> Path:  # fmt: skip
    """Iteration k of the loop state: k = 0 proposes the bracket u_out0 ± half_width around
    the window checkpoint's u_out; k ≥ 1 folds in the trials run on iteration k − 1's
    proposals (``dichotomy.update``)."""
    p = dich.params_from_config(scene["window"])
    if k == 0:
        ds = open_dataset(window0)
        status = ds.attrs.get("status", "ok")
        if status != "ok":
            s = dich.initial_state(float("nan"), p)
            s.update(done=True, status=status, reason=ds.attrs.get("diagnostic", ""), pending=[])
            return write_json(s, out)
        u_out0 = backend_of(scene).load_window(ds, window0).u_out
        return write_json(dich.initial_state(float(u_out0), p), out)
    prev = json.loads(Path(previous).read_text())
    new = [json.loads(Path(f).read_text()) for f in trials]
    return write_json(dich.update(prev, new, p), out)


def dichotomy_trial(
    window0: str | os.PathLike, scene: dict, state: str, index: int, out: str | os.PathLike
) -> Path:
    """One trial: from the window checkpoint at u_out = state.pending[index], run
    ``trial_time`` and fit ⟨dω/dt⟩. An unstable trial has no slope (``dichotomy.update``
    counts it on the negative side: the window too fast)."""
    b = backend_of(scene)
    clock = Clock()
    u_out = float(json.loads(Path(state).read_text())["pending"][index])
    try:
        win, sig, _, ds, _ = open_window(b, window0, scene)
    except HugomapFailure as exc:
        r = {"u_out": u_out, "slope": float("nan"), "status": exc.status,
             "diagnostic": exc.diagnostic}  # fmt: skip
        return write_json({**r, **clock.cost()}, out)
    cp = b.control_params(scene, float(ds.attrs["u_p"]), win)
    win.galilean_shift(u_out - win.u_out)
    step0 = win.steps
    try:
        r = fixed_run(win, sig, cp.trial_time, cp.every)
    except HugomapFailure as exc:
        r = {"u_out": u_out, "slope": float("nan"), "status": exc.status,
             "diagnostic": exc.diagnostic}  # fmt: skip
        log.error("%s: %s", exc.status, exc.diagnostic)
    r = {k: (v.tolist() if isinstance(v, np.ndarray) else v) for k, v in r.items()}
    log.info("trial u_out = %.6g: front velocity %s, %s", u_out, r.get("front_velocity"),
             r["status"])  # fmt: skip
    return write_json({**r, **clock.cost(win.n_particles * (win.steps - step0))}, out)


def dichotomy_point(
    window0: str | os.PathLike, scene: dict, u_p: float, state: str, trials: list[str],
    out: str | os.PathLike,
) -> Path:  # fmt: skip
    """The dichotomy's point: at the root u_out of the bisection (the window frame shifted
    there, u_p held), the steady average over ``final_time``. The cost adds the loading
    stage's, the window set-up's and every trial's; the trials' (u_out, ⟨dω/dt⟩) are kept as
    ``dichotomy_u_out``, ``dichotomy_slope``."""
    b = backend_of(scene)
    scheme = "dichotomy"
    s = json.loads(Path(state).read_text())
    clock = Clock(*[json.loads(Path(f).read_text()) for f in trials])
    try:
        win, sig, pole, ds, profile = open_window(b, window0, scene)
    except HugomapFailure as exc:
        return failed_point(out, b, scheme, scene, u_p, clock, exc.status, exc.diagnostic)
    clock.add(prior_cost(ds))
    bis = np.array([[t["u_out"], t.get("slope", np.nan)] for t in s["trials"]], dtype=float)
    bis = bis.reshape(-1, 2)
    v, tm = b.units.axes["velocity"], b.units.axes["time"]
    trial_vars = {
        "dichotomy_u_out": ("trial", bis[:, 0], {"units": v, "long_name": "trial u_out"}),
        "dichotomy_slope": ("trial", bis[:, 1], {"units": f"{tm}^-1",
                                                 "long_name": "trial <domega/dt>"}),
    }  # fmt: skip
    if s["status"] != "ok":
        return window_point(out, b, scheme, scene, u_p, pole, None, {}, clock.cost(),
                            s["status"], s["reason"], extra=trial_vars)  # fmt: skip
    cp = b.control_params(scene, u_p, win)
    sh = scene["shock"]
    win.galilean_shift(float(s["u_out"]) - win.u_out)
    step0 = win.steps
    values: dict = {}
    h = None
    try:
        values, h = steady_state(win, profile, pole, sig, cp.final_time, cp.every, cp.gap,
                                 cp.avg_length, sh["residual_tol"], cp.outflow_gap,
                                 cp.max_average_time, ahead_gap=cp.ahead_gap,
                                 target=ErrorTarget.of_scene(scene),
                                 cpu=lambda: clock.cost()["cpu_s"],
                                 time_unit=b.units.axes["time"])  # fmt: skip
        status, diagnostic = str(values.pop("status")), str(values.pop("diagnostic"))
        log.info("dichotomy: D = %.6g +- %.2g, P = %.6g, %s", values["D"], values["D_err"],
                 values["P"], status)  # fmt: skip
    except HugomapFailure as exc:
        status, diagnostic = exc.status, exc.diagnostic
    cost = clock.cost(win.n_particles * (win.steps - step0))
    write_extras(b.window_extras, win, Path(out), scene, u_p, scheme, info_of(ds))
    return window_point(out, b, scheme, scene, u_p, pole, win, values, cost, status, diagnostic,
                        h, profile, extra=trial_vars)  # fmt: skip
