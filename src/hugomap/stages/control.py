"""Stage ``amw``/``mw``: a control scheme until the front is steady, then the steady
average (``methods.steady.steady_state``)."""

from __future__ import annotations

import logging
import os
from pathlib import Path

from ..failures import HugomapFailure
from ..methods.control import amw, mw, recentre
from ..methods.steady import steady_state
from ..methods.target import ErrorTarget
from ..registry import backend as backend_of
from .files import Clock, info_of, write_extras
from .window_files import failed_point, open_window, prior_cost, window_point

log = logging.getLogger("hugomap")


def control_point(
    window0: str | os.PathLike, scene: dict, u_p: float, out: str | os.PathLike, scheme: str
) -> Path:
    """An AMW point (``methods.control.amw``: the amplitude u_p = u_out − u_in held, the frame
    shifted by −β L a_k) or an MW point (``methods.control.mw``: the inflow, so D = −u_in,
    held and u_out steered) until steady, then the steady average. MW's amplitude settles to
    the u_p whose shock runs at the held D: its point is (D, u_p_set)."""
    b = backend_of(scene)
    clock = Clock()
    if scheme not in ("amw", "mw"):
        return failed_point(out, b, scheme, scene, u_p, clock, "bad_config",
                            f"scheme {scheme} is not a control scheme (amw, mw)")  # fmt: skip
    try:
        win, sig, pole, ds, profile = open_window(b, window0, scene)
    except HugomapFailure as exc:
        return failed_point(out, b, scheme, scene, u_p, clock, exc.status, exc.diagnostic)
    clock.add(prior_cost(ds))
    cp = b.control_params(scene, u_p, win)
    sh = scene["shock"]
    step0 = win.steps
    common = dict(window_time=cp.window_time, calm_windows=cp.calm_windows,
                  max_windows=cp.max_windows, every=cp.every, z=cp.z, max_drift=cp.max_drift)  # fmt: skip
    values: dict = {}
    hist = h = None
    try:
        if scheme == "amw":
            res, hist = amw(win, sig, beta=cp.beta, **common)
        else:
            res, hist = mw(win, sig, gain_rate=cp.gain_rate, gain_position=cp.gain_position,
                           target=cp.target, **common)  # fmt: skip
        if res.converged and scheme == "amw" and cp.recentre:
            recentre(win, sig, cp.target, hist.omega[-1], cp.window_time, cp.every)
        if res.converged:
            values, h = steady_state(win, profile, pole, sig, cp.average_time, cp.every,
                                     cp.gap, cp.avg_length, sh["residual_tol"],
                                     cp.outflow_gap, cp.max_average_time,
                                     ahead_gap=cp.ahead_gap, target=ErrorTarget.of_scene(scene),
                                     cpu=lambda: clock.cost()["cpu_s"],
                                     time_unit=b.units.axes["time"])  # fmt: skip
            status, diagnostic = str(values.pop("status")), str(values.pop("diagnostic"))
            log.info("%s: D = %.6g +- %.2g, u_p = %.6g, P = %.6g, %s", scheme, values["D"],
                     values["D_err"], values["u_p_set"], values["P"], status)  # fmt: skip
        else:
            status, diagnostic = res.status, res.diagnostic
    except HugomapFailure as exc:
        status, diagnostic = exc.status, exc.diagnostic
    cost = clock.cost(win.n_particles * (win.steps - step0))
    write_extras(b.window_extras, win, Path(out), scene, u_p, scheme, info_of(ds))
    return window_point(out, b, scheme, scene, u_p, pole, win, values, cost, status, diagnostic,
                        h, profile, hist)  # fmt: skip
