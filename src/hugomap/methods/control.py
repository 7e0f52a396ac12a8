"""The moving window's control, written once for every solver: the ω signal, AMW and MW's
control loop, and the fixed runs of the dichotomy (the steady average that follows them:
``methods.steady``).

The solver is any object with the window protocol (``methods.protocol.WindowSolver``:
``particles.window.ParticleWindow`` over numba MD or LAMMPS, ``sph.window.SPHWindow``, …).

Front signal (SEED-en.md, reading notes). With the window [x_lo, x_hi] of length L holding
upstream material (density ρ0, stress P0) ahead of the front x_f and shocked material (ρ1, P1)
behind it,
    N  = A [ρ1 (x_f − x_lo) + ρ0 (x_hi − x_f)],   Σσ = A [P1 (x_f − x_lo) + P0 (x_hi − x_f)],
so ω = (q − q_up)/(q_sh − q_up) = (x_f − x_lo)/L for q = N or Σσ (q_up, q_sh: the window full
of upstream or of shocked material), and L dω/dt is the front velocity in the window frame.

AMW (adaptive moving window): over each averaging window k, a least-squares fit
ω(t) = a_k t + b_k with standard error s_k; the Galilean shift Δu_k = −β L a_k (the source's
correction); steady when |a_k| ≤ z s_k for M consecutive windows. The amplitude u_p =
u_out − u_in is held, the front speed D is found.
MW: the inflow (so D) is held and u_out is steered, u_out ← u_out − g_v L a_k
− g_x L (ω̄_k − ω*) (a proportional-integral controller on the front position), so the
amplitude settles to the u_p whose D matches the window.
"""

from __future__ import annotations

import logging
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from ..analysis.shock import bin_edges, slab_state, track_front
from ..analysis.stats import CorrelatedSlope

log = logging.getLogger("hugomap")


@dataclass
class OmegaSignal:
    """ω from the atom count (``kind`` = "N") or the longitudinal stress sum ("stress");
    ``q_up``/``q_sh``: the value for a window full of upstream / shocked material. The stress
    signal reads the window's profile through the backend's ``profile`` reader (bins of
    ``bin_width``)."""

    kind: str
    q_up: float
    q_sh: float
    bin_width: float
    profile: object | None = field(default=None, repr=False, compare=False)

    def __post_init__(self) -> None:
        if self.kind not in ("N", "stress"):
            raise ValueError(f"omega kind {self.kind!r}: allowed 'N' or 'stress'")
        if not abs(self.q_sh - self.q_up) > 0:
            raise ValueError("omega normalisation: shocked and upstream values are equal")

    @classmethod
    def from_states(
        cls, kind: str, length: float, area: float, up: dict, sh: dict, bin_width: float
    ) -> OmegaSignal:
        """Normalise from the upstream and shocked states ({'n', 'Pxx'} per unit volume)."""
        key = "n" if kind == "N" else "Pxx"
        return cls(kind, up[key] * area * length, sh[key] * area * length, bin_width)

    def raw(self, solver) -> float:
        if self.kind == "N":
            return float(solver.count_in_window())
        if self.profile is None:
            raise ValueError("the stress omega signal needs the backend's profile reader")
        sums = self.profile.sums(solver)
        w = self.bin_width
        edges = bin_edges(self.profile, sums.shape[0])
        inside = (edges[:-1] >= solver.geom.x_lo - 1e-9) & (edges[1:] <= solver.geom.x_hi + 1e-9)
        P = [self.profile.state(sums[i], 1)["P"] for i in np.nonzero(inside)[0]]
        return float(np.nansum(P) * solver.area * w)

    def to_json(self) -> dict:
        return {"kind": self.kind, "q_up": self.q_up, "q_sh": self.q_sh,
                "bin_width": self.bin_width}  # fmt: skip

    def __call__(self, solver) -> float:
        """ω = (x_f − x_lo)/L estimated from the signal (dimensionless)."""
        return (self.raw(solver) - self.q_up) / (self.q_sh - self.q_up)

    @classmethod
    def from_settled(
        cls, win, profile, kind: str, gap: float, front_fraction: float, q_up: float,
        q_of: Callable[[object], float],
    ) -> OmegaSignal:  # fmt: skip
        """Normalised on a settled window: q_sh from the shocked slab between the outflow
        edge and the front, ``gap``/2 clear of both (the front tracked on the window's
        profile; where none is found, at ``front_fraction`` of L), read by ``q_of`` from the
        slab's state (per unit volume: a number density for "N", P_xx for "stress");
        ``q_up`` per unit volume of the upstream material. Both times the window's volume
        A L; ``gap`` in the window's length unit."""
        g = win.geom
        sums = profile.sums(win)
        x_f = track_front(profile, sums, g.x_lo, g.x_hi, win.u_out, win.u_in)
        if not np.isfinite(x_f):
            x_f = g.x_lo + front_fraction * g.length
        edges = bin_edges(profile, sums.shape[0])
        shocked = slab_state(profile, sums, edges, g.x_lo + 0.5 * gap, x_f - 0.5 * gap)
        return cls(kind, q_up * win.area * g.length, q_of(shocked) * win.area * g.length,
                   profile.bin_width, profile)  # fmt: skip


@dataclass
class ControlHistory:
    """Per averaging window k: end time [τ], slope a_k [1/τ] and its error, mean ω, u_in,
    u_out [σ/τ or the solver's units], the applied Δu, and the raw ω samples (t, ω)."""

    t: list = field(default_factory=list)
    a: list = field(default_factory=list)
    a_err: list = field(default_factory=list)
    omega: list = field(default_factory=list)
    u_in: list = field(default_factory=list)
    u_out: list = field(default_factory=list)
    du: list = field(default_factory=list)
    samples_t: list = field(default_factory=list)
    samples_omega: list = field(default_factory=list)

    def arrays(self) -> dict[str, np.ndarray]:
        return {k: np.asarray(v, dtype=float) for k, v in self.__dict__.items()}


@dataclass
class ControlResult:
    converged: bool
    status: str
    diagnostic: str
    windows: int


def sample_omega(solver, signal: OmegaSignal, duration: float, every: int) -> tuple:
    """Run ``duration`` sampling ω every ``every`` steps; return (t, ω) arrays."""
    n = max(3, int(round(duration / (every * solver.dt))))
    t, w = np.empty(n), np.empty(n)
    for i in range(n):
        solver.advance(every)
        t[i], w[i] = solver.time, signal(solver)
    return t, w


def _record(h: ControlHistory, solver, t, w, a, se, du) -> None:
    log.info(
        "progress: window %d, t = %.3f, omega %.3f, a = %.3g +- %.2g, u_in %.4f, u_out %.4f",
        len(h.t) + 1, float(t[-1]), float(np.mean(w)), a, se, solver.u_in, solver.u_out,
    )  # fmt: skip
    h.t.append(float(t[-1]))
    h.a.append(a)
    h.a_err.append(se)
    h.omega.append(float(np.mean(w)))
    h.u_in.append(solver.u_in)
    h.u_out.append(solver.u_out)
    h.du.append(du)
    h.samples_t.extend(map(float, t))
    h.samples_omega.extend(map(float, w))


def _check_inside(w: np.ndarray, margin: float) -> str | None:
    if not np.all(np.isfinite(w)):
        return "omega is not finite"
    if w.min() < margin or w.max() > 1.0 - margin:
        return f"the front left the window (omega in [{w.min():.3f}, {w.max():.3f}])"
    return None


def _diverging(
    h: ControlHistory, z: float, floor: float = 0.0, noise: float = 0.0
) -> tuple[str, str] | None:
    """Failure read from the slopes a_k that are significant (|a_k| > z s_k, s_k at least
    ``noise``: the slopes' own scatter as measured so far, which the first windows, recorded
    before it could be measured, are judged against too).

    A correction of gain g multiplies the front speed by (1 − g) per window (AMW: g = β),
    so over-correction shows as slopes of alternating sign:
    - diverged: the last 3 alternate and each is at least 1.3 times the one before (g > 2);
    - oscillating: the signs have changed at least 3 times (4 lobes) and the last lobe's
      peak |a| is at least 0.7 of the peak one period (two lobes) earlier: an oscillation
      that does not decay (AMW's β = 2; an MW whose gains and response delay ring).
    AMW with β ∈ (1, 2) overshoots but decays (|1 − β| < 1) and is not flagged."""
    a, se = np.asarray(h.a), np.maximum(np.asarray(h.a_err), noise)
    significant = (np.abs(a) > z * se) & (np.abs(a) > floor)
    sig = a[significant]
    if a.size >= 3 and significant[-3:].all():
        x = a[-3:]
        if np.all(x[1:] * x[:-1] < 0) and np.all(np.abs(x[1:]) >= 1.3 * np.abs(x[:-1])):
            return "diverged", (
                f"a_k alternates in sign and grows ({', '.join(f'{v:.3g}' for v in x)}): "
                "correction gain too large"
            )
    lobes: list[float] = []  # peak |a| of each run of significant slopes of one sign
    last = 0.0
    for v in sig:
        if v * last > 0:
            lobes[-1] = max(lobes[-1], abs(v))
        else:
            lobes.append(abs(v))
        last = v
    if len(lobes) >= 4 and lobes[-1] >= 0.7 * lobes[-3]:
        return "oscillating", (
            f"the front speed oscillates without decaying ({len(lobes) - 1} sign changes of "
            f"a_k; peaks {', '.join(f'{v:.3g}' for v in lobes[-4:])}): the correction gain is "
            "too large, or the front speed wanders on time scales longer than window_time"
        )
    return None


def flat_omega_error(signal: OmegaSignal, t: np.ndarray, w: np.ndarray, se: float) -> float:
    """The slope error of an ω that never changed over ``t`` (the front moved less than one
    particle's worth, L/|q_sh − q_up|): that quantum's, std quantum/√6 over the span (two
    ends uniform within it), instead of the fit's 0; ``se`` otherwise. A flat ω carries no
    information that the front is still, only that it moved less than the quantum."""
    if signal.kind == "N" and np.size(w) and np.ptp(w) == 0:
        quantum = 1.0 / abs(signal.q_sh - signal.q_up)  # in ω
        return float(quantum / (np.sqrt(6.0) * max(float(t[-1] - t[0]), 1e-300)))
    return float(se)


def steered_out_scatter(
    a: list[float], du: list[float], length: float, response: float | None = 1.0
) -> float:
    """Standard error of one window's slope from the slopes' own scatter, the steering
    undone: NaN before 2 differences exist (3 with a fitted response).

    A step Δu_j of the steering changes dω/dt by r Δu_j/L, so the slope window k would
    have had with no steering is ã_k = a_k − r Σ_{j<k} Δu_j/L, and its successive
    differences d_k = a_{k+1} − a_k − r Δu_k/L hold only the noise of two windows (and any
    real change of the front speed): the error of one slope is √(⟨d²⟩/2) (von Neumann's
    mean square successive difference). It sees what a fit inside one window cannot: ω
    wandering on time scales of the window or longer. On the LJ liquid at u_p = 1
    (u_p/c0 = 0.14; 6-τ windows) the AR(1) error of a slope was 0.05 σ/τ in L a_k, while a
    window held fixed for 36 τ gave 6-τ slopes scattering by 0.16-0.19 σ/τ, and this rule
    read 0.16 from the windows of a steered run.

    ``response`` r: AMW's Galilean shift moves every velocity, so r = 1 exactly. MW steers
    u_out alone, and ω answers through the waves the step sends into the window, so r is
    not known in advance: with ``response`` None it is the least-squares slope of d on
    Δu/L over the run's own windows (one degree of freedom taken from the scatter). Eight
    MW runs at u_p = 1 gave r = 2.65 ± 0.22 pooled (1.5-3.6 each, correlation 0.88) and,
    with it undone, a slope scatter of 1.4·10⁻³ τ⁻¹ against fit errors of 0.5-0.7·10⁻³.
    Window 0, which still carries the start's transient, is left out. ``a`` holds windows
    0..k, ``du`` the steps applied after windows 0..k−1; slopes in 1/time, steps in
    velocity, ``length`` L.
    """
    a_, du_ = np.asarray(a, dtype=float), np.asarray(du, dtype=float)
    if a_.size < (4 if response is not None else 5) or du_.size < a_.size - 1:
        return float("nan")
    x, y = _steering_pairs(a_, du_, length)
    fitted = response is None
    if fitted:
        r = _response_fit(x, y)
        response = r if np.isfinite(r) else 0.0  # no step taken: the slopes' own scatter
    d = y - response * x
    return float(np.sqrt(np.sum(d * d) / (2.0 * (d.size - int(fitted)))))


def _steering_pairs(a: np.ndarray, du: np.ndarray, length: float) -> tuple:
    """(Δu_k/L, a_{k+1} − a_k) for k = 1..: the steps and the slope changes they caused
    (window 0, which still carries the start's transient, left out)."""
    return du[1 : a.size - 1] / length, a[2:] - a[1:-1]


def steering_response(a, du, length: float) -> float:
    """The response r of the slope to a step of the steering, a_{k+1} − a_k ≈ r Δu_k/L:
    the least-squares slope through the origin of the pairs ``_steering_pairs`` (windows
    0..k in ``a``, the steps after windows 0..k−1 in ``du``); NaN before four pairs, or
    with no step taken. Slopes in 1/time, steps in velocity, ``length`` L."""
    a_, du_ = np.asarray(a, dtype=float), np.asarray(du, dtype=float)
    if a_.size < 5 or du_.size < a_.size - 1:
        return float("nan")
    return _response_fit(*_steering_pairs(a_, du_, length))


def _response_fit(x: np.ndarray, y: np.ndarray) -> float:
    """Least-squares slope through the origin of y on x; NaN where every x is 0."""
    sxx = float(np.sum(x * x))
    return float(np.sum(x * y)) / sxx if sxx > 0 else float("nan")


def _control(
    solver,
    signal: OmegaSignal,
    correction: Callable[[float, np.ndarray], float],
    apply: Callable[[float], None],
    window_time: float,
    calm_windows: int,
    max_windows: int,
    every: int,
    z: float,
    edge_margin: float,
    history: ControlHistory | None,
    on_window: Callable[[], None] | None,
    max_drift: float | None = None,
    response: float | None = 1.0,
) -> tuple[ControlResult, ControlHistory]:
    """The loop AMW and MW share: per averaging window, fit ω = a t + b (slope error
    corrected for correlated samples, ``stats.CorrelatedSlope``, and at least the slopes'
    own scatter with the steering undone, ``steered_out_scatter`` with the steering's
    ``response``: 1 for AMW's Galilean shifts, None (fitted) for MW's outflow), stop if
    the front left the window or the slopes diverge or oscillate (judged against that
    scatter too), count the windows with |a| ≤ z s_a, else ``apply(correction(a, ω))``.

    ``max_drift`` [velocity]: the front-speed resolution z s_a L a calm window must reach.
    A window whose slope is 'zero' only because its error is huge proves nothing; when
    ``calm_windows`` windows in a row are calm by the slope test but coarser than
    ``max_drift``, the run stops as ``too_noisy`` (a longer averaging window is needed).
    Conversely a front speed L|a| below ``0.1 max_drift`` counts as calm even when s_a is
    smaller still: long windows resolve a slow wander of the front (0.05 σ/τ at u_p = 3 in
    6-τ windows) that moves it a fraction of a σ over the average and does not bias D,
    which is measured over the average itself."""
    h = history or ControlHistory()
    L = solver.geom.length
    floor = 0.0 if max_drift is None else 0.1 * max_drift / L  # on a [1/time]
    calm = coarse = 0
    slopes = CorrelatedSlope()
    for k in range(max_windows):
        t, w = sample_omega(solver, signal, window_time, every)
        a, se, _ = slopes.fit(t, w)
        se = flat_omega_error(signal, t, w, se)
        scatter = steered_out_scatter([*h.a, a], h.du, L, response)
        scatter = scatter if np.isfinite(scatter) else 0.0
        se = max(se, scatter)
        bad = _check_inside(w, edge_margin)
        if bad:
            _record(h, solver, t, w, a, se, 0.0)
            return ControlResult(False, "front_left_window", bad, k + 1), h
        still = abs(a) <= max(z * se, floor)
        fine = max_drift is None or z * se * L <= max_drift
        calm = calm + 1 if still and fine else 0
        coarse = coarse + 1 if still and not fine else 0
        du = correction(a, w)
        _record(h, solver, t, w, a, se, du)
        if calm >= calm_windows:
            return ControlResult(True, "ok", "", k + 1), h
        if coarse >= calm_windows:
            return ControlResult(
                False, "too_noisy",
                f"the front-speed resolution z s_k L = {z * se * L:.3g} exceeds the allowed "
                f"drift speed {max_drift:.3g} in {coarse} windows: lengthen window_time",
                k + 1,
            ), h  # fmt: skip
        failed = _diverging(h, z, floor, scatter)
        if failed:
            return ControlResult(False, failed[0], failed[1], k + 1), h
        apply(du)
        if on_window is not None:
            on_window()
    return (
        ControlResult(
            False, "never_steady",
            f"|a_k| > {z} s_k within the last {calm_windows} of {max_windows} windows "
            f"(last a = {h.a[-1]:.3g} +- {h.a_err[-1]:.2g} 1/time)",
            max_windows,
        ),
        h,
    )  # fmt: skip


def amw(
    solver,
    signal: OmegaSignal,
    beta: float,
    window_time: float,
    calm_windows: int,
    max_windows: int,
    every: int,
    z: float = 2.0,
    edge_margin: float = 0.05,
    history: ControlHistory | None = None,
    on_window: Callable[[], None] | None = None,
    max_drift: float | None = None,
) -> tuple[ControlResult, ControlHistory]:
    """AMW (module docstring): shift the frame by −β L a_k after each averaging window."""
    L = solver.geom.length
    return _control(
        solver, signal, lambda a, w: -beta * L * a, solver.galilean_shift, window_time,
        calm_windows, max_windows, every, z, edge_margin, history, on_window, max_drift,
        response=1.0,
    )  # fmt: skip


def recentre(
    solver, signal: OmegaSignal, target: float, omega: float, duration: float, every: int
) -> float:
    """Bring the front from ω = ``omega`` back to ω* = ``target`` by a Galilean excursion:
    shift every velocity by Δu = L (ω* − ω)/T, run T = ``duration``, shift back by −Δu.
    The front then moves by Δu T = (ω* − ω) L relative to the window while the material's
    state, a function of relative velocities only, is unchanged; AMW's shifts are the same
    transformation (the seed's Galilean shifts). T is lengthened so that |Δu| stays within
    half |u_in| (the inflow stays an inflow). A front within 0.02 of ω* is left. Returns
    Δu [velocity] (0 when left)."""
    L = solver.geom.length
    d = (target - omega) * L
    if abs(target - omega) < 0.02 or not np.isfinite(d):
        return 0.0
    T = max(duration, abs(d) / (0.5 * abs(solver.u_in)))
    du = d / T
    solver.galilean_shift(du)
    _, w = sample_omega(solver, signal, T, every)
    solver.galilean_shift(-du)
    log.info("recentre: omega %.3f -> %.3f (target %.3f) by a %.4g excursion over %.4g",
             omega, float(w[-1]), target, du, T)  # fmt: skip
    return du


def mw(
    solver,
    signal: OmegaSignal,
    gain_rate: float,
    gain_position: float,
    target: float,
    window_time: float,
    calm_windows: int,
    max_windows: int,
    every: int,
    z: float = 2.0,
    edge_margin: float = 0.05,
    history: ControlHistory | None = None,
    on_window: Callable[[], None] | None = None,
    max_drift: float | None = None,
) -> tuple[ControlResult, ControlHistory]:
    """MW (module docstring): the inflow is held and u_out is steered by
    Δu = −(g_rate L a_k + g_pos L (ω̄_k − target)) / max(r, 1).

    The gains are for a unit response. A step of u_out moves the next slope by r Δu/L,
    and r is not 1: the front answers through the waves the step sends into the window
    (eight MW runs on the LJ liquid at u_p = 1: r = 1.5-3.6, so the rate gain 0.5 took
    0.75-1.8 of the slope away per window, and the larger steps overshot). Once it can be
    fitted from the run's own windows (``steering_response``, from the fifth), r divides
    both gains; a fitted r below 1 leaves them as set.

    A run that settles with the amplitude u_out − u_in below a quarter of its start ends as
    ``no_shock``: MW holds D, and below the sound speed no shock matches it, so MW lowers the
    amplitude towards nothing (weak shocks whose loading D guess fell below c0)."""
    L = solver.geom.length
    u_p0 = solver.u_out - solver.u_in
    h = history or ControlHistory()

    def correction(a: float, w: np.ndarray) -> float:
        # the gains are for a unit response; the measured one, once fitted, divides them
        r = steering_response([*h.a, a], h.du, L)
        gain = 1.0 / r if np.isfinite(r) and r > 1.0 else 1.0
        return -gain * (gain_rate * L * a + gain_position * L * (float(np.mean(w)) - target))

    result, h = _control(
        solver, signal, correction, lambda du: solver.set_outflow(solver.u_out + du),
        window_time, calm_windows, max_windows, every, z, edge_margin, h, on_window,
        max_drift, response=None,
    )  # fmt: skip
    amplitude = solver.u_out - solver.u_in
    if result.converged and amplitude < 0.25 * u_p0:
        result = ControlResult(
            False, "no_shock",
            f"MW lowered the amplitude u_out - u_in to {amplitude:.3g} (started at "
            f"{u_p0:.3g}): the held D = {-solver.u_in:.4g} has no shock",
            result.windows,
        )  # fmt: skip
    return result, h


def fixed_run(
    solver, signal: OmegaSignal, duration: float, every: int, edge_margin: float = 0.02
) -> dict[str, float | str]:
    """One dichotomy trial: run at the current (u_in, u_out), fit ω(t); return ⟨dω/dt⟩ with
    its standard error, the front speed in the window frame L⟨dω/dt⟩, and a status."""
    t, w = sample_omega(solver, signal, duration, every)
    a, se, _ = CorrelatedSlope().fit(t, w)
    bad = _check_inside(w, edge_margin)
    L = solver.geom.length
    return {
        "u_out": solver.u_out,
        "u_in": solver.u_in,
        "slope": a,
        "slope_err": se,
        "front_velocity": L * a,
        "front_velocity_err": L * se,
        "omega_mean": float(np.mean(w)),
        "status": "front_left_window" if bad else "ok",
        "diagnostic": bad or "",
        "t": t,
        "omega": w,
    }
