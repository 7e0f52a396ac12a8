"""The steady-state measurement of a window point, the same for every backend and scheme.

Once a scheme holds the front still (AMW, MW) or the dichotomy has found the frame, the window
runs for ``duration`` in that frame (the frame held) and every ``every`` steps records ω, the
profile sums and the tracked front. The point is then measured by
``analysis.shock.measure_point`` with the window's edges as the boundaries, the upstream
velocity u_in known exactly, the jump taken at the velocity of the shocked slab itself
(``u_p_jump``: the outflow u_out holds the material behind the slab only on average; u_out −
u_in is kept as ``u_p_set``), and the front speed taken from L dω/dt over the whole average: the window's
mass balance, which stays sharp for a broad weak front where the change-point tracker wanders
(on the LJ liquid at u_p = 0.5 the tracker gave D 4 % low while ω was flat); the tracker's D
is kept as ``D_front``.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from ..analysis.shock import (
    bin_edges,
    measure_point,
    relaxation_length,
    slab_series,
    track_front,
)
from ..analysis.stats import CorrelatedSlope, slope_scatter
from ..states import Pole, Profile
from .control import OmegaSignal, flat_omega_error
from .protocol import WindowSolver
from .target import AVERAGE_FACTOR, ErrorTarget, error_exponent, judge


def unresolved(values: dict, residual_tol: float) -> bool:
    """Whether a point's average is too short to judge it: one of its jump residuals' errors
    (mass, momentum, energy) exceeds ``residual_tol``, so a residual of the tolerance could
    not be told from zero. It reads the errors only, never the residuals, so averaging on
    while it holds cannot pick out the points that happen to close."""
    errs = [values.get(f"residual_{k}_err", np.nan) for k in ("mass", "momentum", "energy")]
    return any(bool(e > residual_tol) for e in errs)


def steady_state(
    win: WindowSolver,
    profile: Profile,
    pole: Pole,
    signal: OmegaSignal,
    duration: float,
    every: int,
    gap: float,
    avg_length: float,
    residual_tol: float,
    left_gap: float | None = None,
    max_duration: float | None = None,
    ahead_gap: float | None = None,
    target: ErrorTarget | None = None,
    cpu: Callable[[], float] | None = None,
    time_unit: str = "",
) -> tuple[dict, dict[str, np.ndarray]]:
    """Average the steady wave for ``duration`` (module docstring); returns the point's
    values and the samples (t, front, x_left, x_right, sums, stage, omega, and the slab
    behind's u relative to the upstream and P_xx: u_slab, P_slab), and per chunk of the
    average its length, stated relative errors and the point's CPU so far (chunk_T,
    chunk_D_rel_err, chunk_P_rel_err, chunk_cpu_s: NaN without ``cpu``). The slabs are
    ``analysis.shock.measure_point``'s (``gap``, ``avg_length``, ``left_gap`` from the
    outflow edge, ``ahead_gap`` ahead of the front).

    With ``max_duration`` > ``duration`` the average goes on, ``duration`` at a time and
    measured again over every sample, while the point is ``unresolved`` (a residual's error
    above ``residual_tol``), up to ``max_duration``; ``average_time`` says how long it
    ran. The slab behind a weak front keeps its noise for long (the LJ liquid at u_p = 1:
    integrated correlation time 2.4-9.7 τ, so 20 τ hold one to four independent samples
    and its energy residual's error is 0.7-6.5 %; 100 τ: D within 0.16 % sd of the
    reference over eight seeds).

    With an error ``target`` (``methods.target``) it also goes on while D's or P's
    relative error misses it, up to ``max_duration`` (with none: ``AVERAGE_FACTOR``
    ``duration``) and while the next chunk fits the budget ``target.cpu_s`` (``cpu()``: the
    point's CPU seconds so far, its loading counted; the next chunk's cost taken as the
    last one's); the point is then judged (``methods.target.judge``: ``target_not_reached``
    with the time its own error law says it needs, in ``time_unit``).

    A particle count that never changed over the average (the front moved less than one
    particle's worth, L/|q_sh − q_up|) gets that quantum's uncertainty instead of the fit's
    0: two ends uniform within it, std quantum/√6 over the average. The slope's error is
    the larger of the AR(1)-corrected one and its scatter over four spans, with ω a bounded
    signal (``stats.slope_scatter``)."""
    g = win.geom
    step = max(win.dt, 1e-300) * every
    n = max(16, int(round(duration / step)))
    longest = max_duration or 0.0
    if target is not None and longest <= duration:
        longest = AVERAGE_FACTOR * duration
    n_max = max(n, int(round(longest / step)))
    t: list[float] = []
    front: list[float] = []
    sums_all: list[np.ndarray] = []
    omega: list[float] = []
    law: dict[str, list[float]] = {"T": [], "D": [], "P": [], "cpu": []}
    budget_spent = False
    while True:
        c0 = cpu() if cpu is not None else 0.0
        for _ in range(min(n, n_max - len(t))):  # n_max ≥ n: the first chunk is whole
            win.advance(every)
            omega.append(signal(win))
            sums = profile.sums(win)
            t.append(win.time)
            front.append(track_front(profile, sums, g.x_lo, g.x_hi, win.u_out, win.u_in))
            sums_all.append(sums)
        r, h = _measure(win, profile, pole, signal, t, front, sums_all, omega, gap, avg_length,
                        residual_tol, left_gap, ahead_gap)  # fmt: skip
        rel = ErrorTarget.relative_errors(r, pole.P0)
        spent = cpu() if cpu is not None else np.nan
        for k, v in (("T", len(t) * step), ("D", rel["D"]), ("P", rel["P"]), ("cpu", spent)):
            law[k].append(v)
        missed = target is not None and bool(target.missed(r, pole.P0))
        if len(t) >= n_max or not (unresolved(r, residual_tol) or missed):
            break
        if target is not None and target.cpu_s is not None and cpu is not None:
            if spent + (spent - c0) > target.cpu_s:  # the next chunk would overrun it
                budget_spent = True
                break
    r["average_time"] = float(len(t) * step)
    for k, name in (("T", "T"), ("D", "D_rel_err"), ("P", "P_rel_err"), ("cpu", "cpu_s")):
        h["chunk_" + name] = np.asarray(law[k], dtype=float)
    _relaxation_zone(r, h, profile, pole, g.x_lo, gap, avg_length, residual_tol, left_gap)
    laws = {q: error_exponent(law["T"], law[q]) for q in ("D", "P")}
    r["status"], r["diagnostic"] = judge(
        target, r, str(r["status"]), str(r["diagnostic"]), r["average_time"], P0=pole.P0,
        exponents=laws, what="average", unit=f" {time_unit}" if time_unit else "",
    )  # fmt: skip
    if budget_spent and r["status"] != "ok":
        r["diagnostic"] += f" (the budget target.cpu_s = {target.cpu_s:g} s is spent)"
    return r, h


def _relaxation_zone(
    r: dict, h: dict[str, np.ndarray], profile: Profile, pole: Pole, x_lo: float, gap: float,
    avg_length: float, residual_tol: float, left_gap: float | None,
) -> None:  # fmt: skip
    """Store the relaxation zone behind the held front (``relaxation_length``, from the mean
    profile of the whole average) in the point ``r``, and name it first in the diagnostic of
    a point that is not ok when it is longer than ``gap``: a slab nearer the front than the
    zone's end reads a state still changing (a crystal's plastic wave)."""
    mean = mean_profile(h, profile)
    lg = gap if left_gap is None else left_gap
    xf = float(np.nanmedian(h["front"])) if np.isfinite(h["front"]).any() else np.nan
    # down to the slab's far end: what lies behind the slab (the outflow's wake) is not read
    zone = relaxation_length(mean["x"], mean["P"], xf, max(x_lo + lg, xf - gap - avg_length),
                             float(r["P"]), pole.P0, residual_tol)  # fmt: skip
    r["relaxation_length"] = zone
    if r["status"] != "ok" and np.isfinite(zone) and zone > gap:
        r["diagnostic"] = (
            f"relaxation zone longer than shock.gap: P_xx reaches the slab's within "
            f"residual_tol of the jump only {zone:.4g} behind the front, the slab starts "
            f"{gap:.4g} behind it: raise shock.gap past the zone and window.length to hold "
            f"it; " + str(r["diagnostic"])
        )


def _measure(
    win: WindowSolver, profile: Profile, pole: Pole, signal: OmegaSignal, t: list, front: list,
    sums_all: list, omega: list, gap: float, avg_length: float, residual_tol: float,
    left_gap: float | None, ahead_gap: float | None = None,
) -> tuple[dict, dict[str, np.ndarray]]:  # fmt: skip
    """The point from the samples so far (``steady_state``)."""
    g = win.geom
    n = len(t)
    t_a, om = np.asarray(t), np.asarray(omega)
    a, se, _ = CorrelatedSlope().fit(t_a, om)
    # ω wiggles with the front about its drift, bounded in a held frame (stats.slope_scatter)
    wander = slope_scatter(t_a, om, bounded=True)
    if np.isfinite(wander):
        se = max(float(se), wander)
    se = flat_omega_error(signal, t_a, om, se)
    h = {
        "t": t_a, "front": np.asarray(front), "stage": np.ones(n, dtype=np.int8),
        "x_left": np.full(n, g.x_lo), "x_right": np.full(n, g.x_hi),
        "sums": np.asarray(sums_all), "omega": om,
    }  # fmt: skip
    L = g.length
    r = measure_point(
        h, profile, pole, u_behind=win.u_out, u_ahead=win.u_in, gap=gap,
        avg_length=avg_length, residual_tol=residual_tol, left_gap=left_gap,
        front_speed=(L * a, L * se), u_p_from="slab", ahead_gap=ahead_gap,
    )  # fmt: skip
    r["omega_drift"], r["omega_drift_err"] = L * a, L * se
    # the slab's velocity (relative to the upstream) and P_xx per sample: their block
    # errors, checked against replicas, need the series, not only the mean
    slab = slab_series(h, profile, ("u", "P"), gap, avg_length, left_gap)
    h["u_slab"], h["P_slab"] = slab["u"] - win.u_in, slab["P"]
    r["u_p_set"] = r.pop("u_p")
    r.pop("u_p_err")
    return r, h


def mean_profile(h: dict[str, np.ndarray], profile: Profile) -> dict[str, np.ndarray]:
    """The mean steady profile along the window, bin by bin (window frame): x (bin centre)
    and every neutral field of ``profile.state`` (ρ, u, P, …)."""
    mean = np.asarray(h["sums"]).mean(axis=0)
    edges = bin_edges(profile, mean.shape[0])
    states = [profile.state(mean[i], 1) for i in range(mean.shape[0])]
    out = {"x": 0.5 * (edges[:-1] + edges[1:])}
    for k in states[0] if states else ():
        out[k] = np.array([s[k] for s in states], dtype=float)
    return out
