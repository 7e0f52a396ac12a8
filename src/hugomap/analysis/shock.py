"""Shock-front tracking, shocked-state averaging and the measurement of a Hugoniot point.

One analysis for every backend and scheme: the front is tracked on the per-bin flow velocity,
the states behind and ahead of it are slabs of whole bins read by the backend's ``Profile``
(neutral fields ρ, u, P = P_xx, P_yy, P_zz, E, T in the backend's units), and the point is
measured from the samples of a run (a piston's drive, a window's steady average) by
``measure_point``. Velocities are in the simulation frame; ``u_ahead`` (the upstream material's
velocity) and ``u_behind`` (the shocked material's, set by the piston or the window's outflow)
are known exactly, so D = (front speed) − u_ahead and u_p = u_behind − u_ahead.

The jump conditions and their residuals are ``analysis.jump``'s. A steady shocked slab is
also at rest relative to the boundary behind it (the piston, the window's outflow):
``measure_point`` checks that as a fourth closure, ``residual_flow``.
"""

from __future__ import annotations

import numpy as np

from ..keys import MIN_SLAB_BINS
from ..states import Pole, Profile, SlabState
from .causes import (
    CLOSE_SIGMAS,
    ahead_off_pole,
    ahead_seen,
    closes,
    elastic_front,
    named_causes,
    residual_text,
    shear_stress,
)
from .jump import jump_residual_errors, jump_residuals, rayleigh_jump
from .stats import (
    CorrelatedSlope,
    block_average,
    block_covariance,
    robust_slope,
    slope_scatter,
)

# A profile whose bin-to-bin scatter of f (3 MAD of its first differences / √2) is below this
# is smooth: measured, CSPH copper (solid and porous) ≤ 0.004, LJ MD ≥ 0.022 (the cold FCC
# crystal at u_p = 3; the liquid 0.10-0.74).
SMOOTH_NOISE = 0.01


def _roughness(f: np.ndarray) -> float:
    """3 median absolute deviations of the first differences of ``f``, over √2: the
    bin-to-bin noise, blind to a smooth trend (a broad front, a precursor's ramp)."""
    d = np.diff(f)
    return 3.0 * float(np.median(np.abs(d - np.median(d)))) / np.sqrt(2.0) if d.size else 0.0


def front_position(
    ux: np.ndarray,
    count: np.ndarray,
    x_edges: np.ndarray,
    x_lo: float,
    x_hi: float,
    u_behind: float,
    u_ahead: float,
) -> float:
    """Front position from one velocity profile, between the flow velocities ``u_behind``
    (shocked) and ``u_ahead`` (upstream) that the frame imposes.

    Bins with centres inside (x_lo, x_hi) and at least 2 particles are scored
    f = clip((u − u_ahead)/(u_behind − u_ahead), 0, 1) and split where the fewest are
    misclassified, Σ_left (1 − f) + Σ_right f (a change-point with the known levels). Then:
    - a smooth profile (bin-to-bin scatter of f below ``SMOOTH_NOISE``, ``_roughness``:
      CSPH, an exact model) gives its half-amplitude point,
      f = ½ interpolated linearly between the two bins at the split. It moves at D for any
      steady shape, however broad (the noisy rule's ±3-bin window clipped a broad weak
      front and drifted: copper at 100 m/s D 0.85 % low), and a partial precursor ahead (an
      elastic one, a porous skeleton's) does not move it;
    - a noisy profile (MD: thermal noise of ~0.2 in f per bin) is fitted with a step: the
      split that best separates two constant levels (largest k (n − k)/n · Δū²) is the rough
      front, refined to sub-bin accuracy by integrating the normalised velocity,
      x_f = x_start + Σ w · clip((u − u_a)/(u_s − u_a), 0, 1), over ±3 bins, with u_s, u_a
      the two fitted levels (one interpolated crossing would carry one bin's noise).
    Returns NaN if fewer than 4 bins qualify, or if the levels behind and ahead of the split
    are off the expected ones by more than half their difference (a split of noise, e.g.
    before a weak shock has formed: the first sample of a u_p = 0.5 piston run put a
    "front" at 63 σ and ended its loading)."""
    centres = 0.5 * (x_edges[:-1] + x_edges[1:])
    sel = np.nonzero((centres > x_lo) & (centres < x_hi) & (count >= 2) & np.isfinite(ux))[0]
    n = sel.size
    if n < 4 or u_behind == u_ahead:
        return float("nan")
    u = ux[sel]
    k = np.arange(1, n)  # left = bins [:k], right = bins [k:]
    f_raw = (u - u_ahead) / (u_behind - u_ahead)
    if _roughness(f_raw) < SMOOTH_NOISE:
        f = np.clip(f_raw, 0.0, 1.0)
        cf = np.cumsum(f)
        kf = int(np.argmin((k - cf[:-1]) + (cf[-1] - cf[:-1])))  # the last bin behind
        if cf[kf] / (kf + 1) < 0.5 or (cf[-1] - cf[kf]) / (n - kf - 1) > 0.5:
            return float("nan")
        f1, f2 = f[kf], f[kf + 1]
        x1, x2 = centres[sel[kf]], centres[sel[kf + 1]]
        if f1 >= 0.5 >= f2 and f1 > f2:
            return float(x1 + (f1 - 0.5) / (f1 - f2) * (x2 - x1))
        return float(x_edges[sel[kf] + 1])
    c = np.cumsum(u)
    left = c[:-1] / k
    right = (c[-1] - c[:-1]) / (n - k)
    score = k * (n - k) / n * (left - right) ** 2
    kb = int(np.argmax(score))
    us, ua = left[kb], right[kb]
    if us == ua:
        return float("nan")
    tol = 0.5 * abs(u_behind - u_ahead)
    if abs(us - u_behind) > tol or abs(ua - u_ahead) > tol:
        return float("nan")
    lo = max(kb + 1 - 3, 0)
    hi = min(kb + 1 + 3, n)
    w = x_edges[sel + 1] - x_edges[sel]
    frac = np.clip((u[lo:hi] - ua) / (us - ua), 0.0, 1.0)
    return float(x_edges[sel[lo]] + np.sum(w[lo:hi] * frac))


def slab_state(
    profile: Profile, sums: np.ndarray, edges: np.ndarray, x_lo: float, x_hi: float
) -> SlabState | None:
    """Neutral state of the bins lying wholly inside [x_lo, x_hi] (their sums added up
    first, then read by ``profile.state``); None if no bin is inside."""
    inside = (edges[:-1] >= x_lo) & (edges[1:] <= x_hi)
    nb = int(inside.sum())
    if nb == 0:
        return None
    return profile.state(sums[inside].sum(axis=0), nb)


def slab_halves(
    profile: Profile, sums: np.ndarray, edges: np.ndarray, x_lo: float, x_hi: float
) -> tuple[SlabState, SlabState] | None:
    """The states of the two halves (the far one first, then the near one: lower x, higher
    x) of the whole bins inside [x_lo, x_hi]; None with fewer than 2 bins."""
    idx = np.nonzero((edges[:-1] >= x_lo) & (edges[1:] <= x_hi))[0]
    if idx.size < 2:
        return None
    h = idx.size // 2
    return (profile.state(sums[idx[:h]].sum(axis=0), h),
            profile.state(sums[idx[h:]].sum(axis=0), idx.size - h))  # fmt: skip


def beyond_noise(d: float, noise: float) -> float:
    """The part of a difference d that its noise cannot explain: √max(0, d² − noise²)
    (same units as d). Zero for a difference within its noise."""
    if not (np.isfinite(d) and np.isfinite(noise)):
        return 0.0
    return float(np.sqrt(max(d * d - noise * noise, 0.0)))


def excess_spread(a: np.ndarray, b: np.ndarray, n_blocks: int = 8) -> float:
    """Half the mean difference of two paired series beyond its noise, with its sign:
    ½ sign(Δ) √max(0, Δ² − σ_Δ²), Δ the mean of b − a and σ_Δ its block-average error
    (``stats.block_average``). Zero for two halves that agree within their noise; half
    their difference for a deterministic solver's non-uniform slab or a drifting one. The
    sign lets two fields' spreads be correlated (the slab's u and P drift together)."""
    d = np.asarray(b, dtype=float) - np.asarray(a, dtype=float)
    m, e = block_average(d, n_blocks)
    excess = beyond_noise(m, e if np.isfinite(e) else 0.0)
    return float(np.sign(m)) * 0.5 * excess if excess > 0 else 0.0


def bin_edges(profile: Profile, nbins: int) -> np.ndarray:
    """Bin edges x0 + k·width, k = 0..nbins."""
    return profile.x0 + np.arange(nbins + 1) * profile.bin_width


def track_front(
    profile: Profile, sums: np.ndarray, x_lo: float, x_hi: float, u_behind: float,
    u_ahead: float,
) -> float:  # fmt: skip
    """The front in one profile sample (``front_position`` on the bins' flow velocity)."""
    u, count = profile.velocity(sums)
    return front_position(u, count, bin_edges(profile, sums.shape[0]), x_lo, x_hi,
                          u_behind, u_ahead)  # fmt: skip


def track_precursor(
    h: dict[str, np.ndarray], profile: Profile, ahead_gap: float, u_ahead: float,
    u_plateau: float,
) -> np.ndarray:  # fmt: skip
    """Per sample, the front of an elastic precursor running ahead of the tracked front
    (``h``'s ``front``, ``x_right``, ``sums`` as in ``measure_point``): ``front_position``
    between the precursor's plateau flow ``u_plateau`` (behind it) and the upstream flow
    ``u_ahead``, over the bins from ``ahead_gap`` ahead of the main front to the far
    boundary. NaN in a sample where none is found or where it lies within ``ahead_gap`` of
    that boundary (it has reached the far end, or left a window through its inflow)."""
    xf = np.asarray(h["front"], dtype=float)
    xr = np.asarray(h["x_right"], dtype=float)
    sums = np.asarray(h["sums"], dtype=float)
    edges = bin_edges(profile, sums.shape[1])
    out = np.full(xf.size, np.nan)
    for i in range(xf.size):
        if not np.isfinite(xf[i]):
            continue
        u, count = profile.velocity(sums[i])
        x = front_position(u, count, edges, xf[i] + ahead_gap, xr[i], u_plateau, u_ahead)
        if np.isfinite(x) and x < xr[i] - ahead_gap:
            out[i] = x
    return out


def precursor_plateau(
    h: dict[str, np.ndarray], profile: Profile, ahead_gap: float, u_ahead: float,
    u_p: float,
) -> float:  # fmt: skip
    """The flow velocity of a precursor's plateau, or NaN where the material ahead of the
    tracked front shows none: in each sample, the bins from ``ahead_gap`` ahead of the front
    to the far boundary split into two constant levels where they separate best (largest
    k (n − k)/n · Δū²); a sample shows a precursor when its far level is the upstream flow
    ``u_ahead`` (within a quarter of the step) and its near level leads it, in the sense of
    the jump ``u_p`` (= u_behind − u_ahead), by more than ``TWO_WAVE_FRACTION`` of u_p. The
    plateau is the median near level over the samples that show one, if at least half do.
    (The slab ahead's mean cannot give it: while the precursor is young its plateau is
    shorter than the slab, which then averages plateau and pole.)"""
    xf = np.asarray(h["front"], dtype=float)
    xr = np.asarray(h["x_right"], dtype=float)
    sums = np.asarray(h["sums"], dtype=float)
    edges = bin_edges(profile, sums.shape[1])
    centres = 0.5 * (edges[:-1] + edges[1:])
    levels = []
    for i in range(xf.size):
        if not np.isfinite(xf[i]):
            continue
        u, count = profile.velocity(sums[i])
        sel = (centres > xf[i] + ahead_gap) & (centres < xr[i]) & (count >= 2) & np.isfinite(u)
        v = (u[sel] - u_ahead) * np.sign(u_p)
        n = v.size
        if n < 2 * MIN_SLAB_BINS:
            continue
        k = np.arange(MIN_SLAB_BINS, n - MIN_SLAB_BINS + 1)
        c = np.concatenate([[0.0], np.cumsum(v)])
        near, far = c[k] / k, (c[n] - c[k]) / (n - k)
        j = int(np.argmax(k * (n - k) / n * (near - far) ** 2))
        step = near[j] - far[j]
        if step > TWO_WAVE_FRACTION * abs(u_p) and abs(far[j]) < 0.25 * step:
            levels.append(near[j])
    if len(levels) < max(1, np.isfinite(xf).sum() // 2):
        return float("nan")
    return float(u_ahead + np.sign(u_p) * np.median(levels))


def relaxation_length(
    x: np.ndarray,
    P: np.ndarray,
    x_front: float,
    x_min: float,
    P_slab: float,
    P0: float,
    tol: float,
) -> float:
    """The relaxation zone behind a held front, from its mean profile P_xx(x) (bin centres
    ``x``, the front at ``x_front``; lengths in the profile's unit): the distance from the
    front to the farthest bin behind it, down to ``x_min`` (a window: the slab's far end),
    whose P
    differs from the slab's ``P_slab`` by more than ``tol`` of the jump P_slab − P0. Behind
    it the state is the slab's within the tolerance; a slab that starts nearer the front
    than this reads the zone. 0 if every bin is within; NaN without a front."""
    if not np.isfinite(x_front):
        return float("nan")
    x, P = np.asarray(x, dtype=float), np.asarray(P, dtype=float)
    behind = (x < x_front) & (x > x_min) & np.isfinite(P)
    off = behind & (np.abs(P - P_slab) > tol * abs(P_slab - P0))
    return float(x_front - x[off].min()) if off.any() else 0.0


# Rules of the point measurement, the same for every backend and scheme.
N_BLOCKS = 8  # block averages over the samples (stats.block_average)
TWO_WAVE_SIGMAS = 5.0  # a precursor's P_xx jump must exceed this many standard errors…
TWO_WAVE_FRACTION = 0.03  # …and this fraction of the main jump P − P0 (or be a weak_precursor)


def weak_precursor(values: dict, residual_tol: float, pole: Pole) -> bool:
    """Whether a state ahead below ``TWO_WAVE_FRACTION`` of the jump is still a first wave:
    it is off the pole by enough to move the residuals past ``residual_tol``
    (``ahead_off_pole``), and it is a compression wave's state: denser than the pole and
    moving in the sense of u_p, each by more than ``CLOSE_SIGMAS`` errors. A precursor does
    both (the momentum and mass jumps of any wave running ahead into the pole); material the
    inflow or the far end warmed raises P at the pole's density and at rest, and stays off
    the pole (porous copper at 500 m/s: ρ +0.40 %, u +2.8 ± 0.5 m/s, P 0.9 % of the jump, an
    elastic wave ahead of the compaction; the reading from the pole left momentum at
    +0.98 ± 0.43 %). The two-wave end state differs from the one-wave Hugoniot's by the
    difference of the precursor's fractions of the P and V jumps (the energy jumps summed,
    ½ΔPΔV(ε_P − ε_V)), well under ``residual_tol`` for a precursor this weak."""
    u_p = values.get("u_p", np.nan)
    sense = np.sign(u_p) if np.isfinite(u_p) and u_p != 0 else 0.0
    d_rho = (values.get("ahead_rho", np.nan) - pole.rho0) * np.sign(values["rho"] - pole.rho0)
    du = values.get("ahead_u", np.nan) * sense
    return bool(
        ahead_off_pole(values, residual_tol, pole) is not None
        and d_rho > CLOSE_SIGMAS * values.get("ahead_rho_err", np.inf)
        and du > CLOSE_SIGMAS * values.get("ahead_u_err", np.inf)
    )


def _slabs(
    h: dict[str, np.ndarray], profile: Profile, gap: float, avg_length: float,
    left_gap: float | None, ahead_gap: float | None = None,
) -> tuple[list[SlabState | None], list[SlabState | None], dict[str, list]]:  # fmt: skip
    """Per sample, the slab state behind and ahead of the front and their (far, near) half
    slabs (``measure_point`` gives the slabs' bounds); None where a slab is too narrow."""
    xf = np.asarray(h["front"], dtype=float)
    xl = np.asarray(h["x_left"], dtype=float)
    xr = np.asarray(h["x_right"], dtype=float)
    sums = np.asarray(h["sums"], dtype=float)
    edges = bin_edges(profile, sums.shape[1] if sums.ndim == 3 else 0)
    min_len = MIN_SLAB_BINS * profile.bin_width - 1e-9 * profile.bin_width
    lg = gap if left_gap is None else left_gap
    ag = gap if ahead_gap is None else ahead_gap
    behind: list[SlabState | None] = []
    ahead: list[SlabState | None] = []
    halves: dict[str, list] = {"behind": [], "ahead": []}  # (far, near) half-slab states
    for i in range(xf.size):
        st = sa = hb = ha = None
        if np.isfinite(xf[i]):
            lo, hi = max(xl[i] + lg, xf[i] - gap - avg_length), xf[i] - gap
            if hi - lo >= min_len:
                st = slab_state(profile, sums[i], edges, lo, hi)
                hb = slab_halves(profile, sums[i], edges, lo, hi)
            a_lo, a_hi = xf[i] + ag, min(xr[i] - ag, xf[i] + ag + avg_length)
            if a_hi - a_lo >= min_len:
                sa = slab_state(profile, sums[i], edges, a_lo, a_hi)
                ha = slab_halves(profile, sums[i], edges, a_lo, a_hi)
        behind.append(st)
        ahead.append(sa)
        halves["behind"].append(hb)
        halves["ahead"].append(ha)
    return behind, ahead, halves


def _field(states: list[SlabState | None], k: str) -> np.ndarray:
    """Field k of per-sample slab states, NaN where a sample has no slab."""
    return np.array([np.nan if s is None else s[k] for s in states], dtype=float)


def slab_series(
    h: dict[str, np.ndarray], profile: Profile, keys: tuple[str, ...], gap: float,
    avg_length: float, left_gap: float | None = None,
) -> dict[str, np.ndarray]:  # fmt: skip
    """Fields ``keys`` of the slab behind the front in each sample (the slab of
    ``measure_point``; NaN where it is too narrow), in the solver's units: the series whose
    block averages are the point's values, kept in a point file so that their error rule
    can be checked against replicas without re-running them. One pass over the samples."""
    behind, _, _ = _slabs(h, profile, gap, avg_length, left_gap)
    return {k: _field(behind, k) for k in keys}


def measure_point(
    h: dict[str, np.ndarray],
    profile: Profile,
    pole: Pole,
    u_behind: float,
    u_ahead: float,
    gap: float,
    avg_length: float,
    residual_tol: float,
    left_gap: float | None = None,
    front_speed: tuple[float, float] | None = None,
    n_blocks: int = N_BLOCKS,
    track: tuple[np.ndarray, np.ndarray] | None = None,
    u_p_from: str = "boundary",
    ahead_gap: float | None = None,
    _precursor: tuple[float, float] | None = None,
) -> dict[str, float | str | bool]:
    """One Hugoniot point from the samples of a run (module docstring).

    ``h``: per sample t, front (tracked, NaN where none), x_left, x_right (the boundaries
    behind and ahead) and the raw profile sums (nsamples, nbins, nfields) read by ``profile``.
    For each sample the slab behind the front is [max(x_left + left_gap, x_f − gap −
    avg_length), x_f − gap] (``left_gap`` defaults to ``gap``: the most recently shocked
    material, clear of the piston or the outflow edge) and the slab ahead [x_f + g_a,
    min(x_right − g_a, x_f + g_a + avg_length)], g_a = ``ahead_gap`` (default ``gap``: a
    relaxation zone lies behind a front, not ahead of it); a slab narrower than
    ``MIN_SLAB_BINS`` bins is skipped in that sample. Then
      D = D_w − u_ahead, D_w the front speed: the Theil–Sen slope of x_f(t) over ``track``
        (times, fronts; default the samples': a piston passes its whole steady run, loading
        included, since the front wanders by a few tenths of σ over several τ in a small
        MD cross-section and a longer base averages that out), robust to a tracker that now
        and then jumps; its standard error the larger of the least-squares slope's corrected
        for correlated samples (``stats.CorrelatedSlope``) and the slope's scatter over four
        spans (``stats.slope_scatter``: the wander); a window passes its L dω/dt as
        ``front_speed`` (speed, error), and the tracked D is kept as ``D_front``; where the
        two differ by more than their noise, half the excess is added to D's error (the
        front model's);
      u_p = u_behind − u_ahead (set by the piston or the outflow), and the shocked slab's
        velocity relative to the upstream material as ``u_p_measured``. The slab's own flow
        in the frame that should hold it at rest, δu = u_p_measured − u_p, is acoustic motion
        the average did not resolve (the long waves of a finite cross-section ring between
        piston and front for several τ): σ_flow = √(δu² + σ²(u_p_measured)) is the
        uncertainty of the jump the slab really saw, so it is u_p's error in the jump
        residuals; P's error gains, in quadrature, ρ0 D √max(0, δu² − σ²(u_p_measured))
        (``P_flow_err``): the momentum of the flow beyond its noise, since the noise part is
        acoustic motion whose pressure swings P's block error already holds (replica study
        of the default liquid, 8 seeds: with ρ0 D σ_flow the pooled reduced χ² of P was 0.40,
        its errors 1.6 times the seeds' scatter; with this rule 0.79 over every scheme).
        The slab's P and the Rayleigh line's P1 + ρ1 (D − u1)(u − u1) are two measures of
        the jump's pressure; where they part by more than the noise of the momentum
        residual, P's error gains half the excess in quadrature (``P_closure_err``), as D's
        gains half its front models' disagreement: a ring of the slab slower than the
        blocks escapes P's block error but not the closure (docs/window-methods.md).
        With ``u_p_from = "slab"`` (the window methods) the jump is taken at the slab's own
        velocity instead, ``u_p_jump`` = u_p_measured ± its error, P's error is its own and
        the flow a diagnostic, not a closure: a window's outflow boundary holds the shocked
        material only on average, the region between the slab and the outflow lags it, and
        the front sees the slab (replica study, 39 window points: the median |momentum
        residual| 0.89 % at the boundary's u_p, 0.28 % at the slab's; the slab's P on the
        equilibrium Hugoniot within 0.1 % sd over seeds, 0.4-1 % at the boundary's u_p).
        The slab's u and P errors are correlated (``u_p_P_corr``: the block covariance of
        their means plus the products of their signed spreads, ``excess_spread``; median
        0.9 on the replica points) and propagate into the residuals so
        (``jump_residual_errors``); ``u_p_jump`` is the piston's velocity (error 0)
        otherwise;
      every field of the slabs: block averages over the samples (``N_BLOCKS`` blocks) with
        standard errors, widened in quadrature by what is not noise: half the difference of
        the slab's near and far halves (a slab that is not uniform: a relaxation zone, the
        tail of a broad front) and of the first and second halves of the samples (a drift),
        each only where it exceeds its own noise (``excess_spread``; a deterministic solver
        has no noise, and its slab's gradient is then its error); the slab ahead as
        ``ahead_*`` (its u relative to the upstream).
    Two waves: when the state ahead carries a P_xx jump from P0 larger than
    ``TWO_WAVE_SIGMAS`` of its error and ``TWO_WAVE_FRACTION`` of P − P0, in the sense of
    P − P0 (an elastic precursor compresses), ``two_wave`` = 1 and the jump conditions are
    taken from that state instead of the pole; the precursor's own front is then tracked
    ahead of the main one (``track_precursor``), its speed stored as ``precursor_D`` (±
    ``precursor_D_err``, the same slope rules as D; NaN with one wave, or where fewer than
    half the samples see the precursor: it has left the measured region, as it leaves a
    window through its inflow), and the point measured again with the slab ahead ending
    ``ahead_gap`` short of the precursor's front, so that the state ahead is the
    precursor's plateau, not a mixture with the pole's material. Residuals (``jump_residuals``) with
    first-order propagated errors (``jump_residual_errors``), and a fourth, the slab's flow:
    ``residual_flow`` = (u_p_measured − u_p)/u_p ± σ(u_p_measured)/u_p (a steady shocked
    state is at rest relative to the boundary that holds it). Status: ``ok`` when D, u_p, ρ, P, E are finite,
    at least max(2 n_blocks, half the samples) have a slab behind the front and all four
    close: |r| ≤ ``residual_tol`` and |r| ≤ ``CLOSE_SIGMAS`` of its error (a residual of
    0.8 % with an error of 0.1 % is a bias, not noise) or ≤ ``RESIDUAL_FLOOR``, the state
    ahead was measured (``ahead_seen``), and it is at the pole the jump is taken from
    (``ahead_off_pole``: off by more than
    ``CLOSE_SIGMAS`` errors and ``residual_tol`` of the jump, it moves the residuals taken
    from the state ahead as measured past the tolerance; flag ``ahead_off_pole``);
    ``not_converged`` when one does not (the flow only with ``u_p_from = "boundary"``);
    else ``too_few_samples``. ``diagnostic`` says why
    a point is not ok, with the physical causes measured on it (``named_causes``).
    """
    if u_p_from not in ("boundary", "slab"):
        raise ValueError(f"u_p_from must be 'boundary' or 'slab', not {u_p_from!r}")
    t = np.asarray(h["t"], dtype=float)
    xf = np.asarray(h["front"], dtype=float)
    n = t.size
    behind, ahead, halves = _slabs(h, profile, gap, avg_length, left_gap, ahead_gap)
    # no slab in any sample: the fields every point has, NaN (status too_few_samples)
    keys = next((list(s) for s in behind + ahead if s is not None),
                ["rho", "u", "P", "E", "Pyy", "Pzz", "T"])  # fmt: skip

    spread: dict[str, tuple[float, float]] = {}  # behind: (near − far, late − early) beyond noise

    def mean_err(side: str, k: str) -> tuple[float, float]:
        """Block average of field k of one slab, its error widened by the slab's
        non-uniformity (near half against far half) and drift (second half of the samples
        against the first), each where it exceeds the noise (``excess_spread``)."""
        states = behind if side == "behind" else ahead
        y = _field(states, k)
        m, e = block_average(y, n_blocks)
        pairs = [(np.nan, np.nan) if h is None else (h[0][k], h[1][k]) for h in halves[side]]
        far, near = (
            (np.array(c, dtype=float) for c in zip(*pairs, strict=True)) if pairs else (y, y)
        )
        ok = np.isfinite(far) & np.isfinite(near)
        space = excess_spread(far[ok], near[ok], n_blocks) if ok.sum() >= 2 * n_blocks else 0.0
        yf = y[np.isfinite(y)]
        h = yf.size // 2
        time_ = excess_spread(yf[:h], yf[yf.size - h :], n_blocks) if h >= n_blocks else 0.0
        e = e if np.isfinite(e) else np.nan
        if side == "behind":
            spread[k] = (2.0 * space, 2.0 * time_)
        return m, float(np.sqrt(e * e + space * space + time_ * time_))

    def covariance(k1: str, k2: str) -> float:
        """Covariance of the slab behind's means of fields k1, k2 (as ``mean_err`` widens
        their errors): the block covariance, plus the products of their signed spreads
        (half the near-far and late-early differences beyond noise, each one shift that
        moves both fields together)."""
        c = block_covariance(_field(behind, k1), _field(behind, k2), n_blocks)
        c = c if np.isfinite(c) else 0.0
        return float(c + 0.25 * sum(a * b for a, b in zip(spread[k1], spread[k2], strict=True)))

    out: dict[str, float | str | bool] = {}
    tt, tx = (
        (t, xf) if track is None else (np.asarray(track[0], float), np.asarray(track[1], float))
    )
    D_w = robust_slope(tt, tx)
    _, D_w_err, _ = CorrelatedSlope().fit(tt, tx)
    wander = slope_scatter(tt, tx)
    if np.isfinite(wander):
        D_w_err = max(float(D_w_err), wander)
    if front_speed is not None:
        out["D_front"], out["D_front_err"] = D_w - u_ahead, float(D_w_err)
        D_w, D_w_err = front_speed
        # the two front speeds (the tracked front, the window's mass balance) disagreeing
        # beyond their noise is the front model's error
        gap_D = D_w - (out["D_front"] + u_ahead)
        noise = np.hypot(out["D_front_err"], D_w_err)
        D_w_err = float(np.hypot(D_w_err, 0.5 * beyond_noise(gap_D, noise)))
    D, D_err = float(D_w - u_ahead), float(D_w_err)
    u_p = float(u_behind - u_ahead)
    out["D"], out["D_err"] = D, D_err
    out["u_p"], out["u_p_err"] = u_p, 0.0
    u_s, u_s_err = mean_err("behind", "u")
    out["u_p_measured"], out["u_p_measured_err"] = u_s - u_ahead, u_s_err
    for k in keys:
        if k == "u":
            continue
        out[k], out[k + "_err"] = mean_err("behind", k)
    for k in keys:
        if k in ("T", "Pyy", "Pzz"):
            continue
        out["ahead_" + k], out["ahead_" + k + "_err"] = mean_err("ahead", k)
    out["ahead_u"] = out["ahead_u"] - u_ahead  # in the frame of the pole material
    rho, P, E = out["rho"], out["P"], out["E"]
    P0, P0_err = pole.P0, pole.P0_err
    at_slab = u_p_from == "slab"
    du = out["u_p_measured"] - u_p
    flow = float(np.hypot(du, u_s_err)) if np.isfinite(du) and np.isfinite(u_s_err) else 0.0
    out["u_p_flow_err"] = flow
    # the slab's u and P move together (acoustic motion, a drift along the Hugoniot)
    cov_uP = covariance("u", "P")
    P_stat = float(out["P_err"])  # without the flow: in the residuals it enters through u
    norm = u_s_err * P_stat  # 0 for an exact model: no correlation to speak of
    corr = cov_uP / norm if np.isfinite(norm) and norm > 0 else np.nan
    out["u_p_P_corr"] = float(np.clip(corr, -1.0, 1.0)) if np.isfinite(corr) else np.nan
    if at_slab:
        # the jump the front sees: the slab's own velocity, its error correlated with P's
        u_jump, u_jump_err, P_flow = float(out["u_p_measured"]), float(u_s_err), 0.0
        cov = {("u", "P"): out["u_p_P_corr"] * norm} if np.isfinite(corr) else {}
    else:
        # P's error gains only the flow beyond its noise: the slab's velocity noise is
        # acoustic motion whose pressure swings (δP = Z δu) P's own block error holds
        u_jump, u_jump_err, cov = u_p, 0.0, {}
        P_flow = pole.rho0 * abs(D) * beyond_noise(du, u_s_err) if np.isfinite(D) else 0.0
    out["u_p_jump"], out["u_p_jump_err"] = u_jump, u_jump_err
    out["P_flow_err"] = float(P_flow)
    out["P_err"] = float(np.hypot(P_stat, P_flow))
    out["V"] = 1.0 / rho
    out["V_err"] = out["rho_err"] / rho**2
    out["P_rh"] = P0 + rayleigh_jump(pole.rho0, D, u_jump)
    out["P_rh_err"] = float(pole.rho0 * np.hypot(abs(u_jump) * D_err, abs(D) * u_jump_err) + P0_err)
    out["E_minus_E0"] = E - pole.E0
    out["E_minus_E0_err"] = float(np.hypot(out["E_err"], pole.E0_err))
    out["shear_stress"], out["shear_stress_err"] = shear_stress({**out, "P_err": P_stat})
    out["elastic_front"] = float(elastic_front(out, pole))
    dP_ahead = out["ahead_P"] - P0
    dP_ahead_err = float(np.hypot(out["ahead_P_err"], P0_err))
    # a precursor compresses in the main jump's sense; material ahead rarefied (a disturbed
    # inflow) is off the pole, not a first wave, and is named as such (``named_causes``)
    lead = dP_ahead * np.sign(P - P0)  # the state ahead's jump, positive if it compresses
    two_wave = bool(
        np.isfinite(lead)
        and lead > TWO_WAVE_SIGMAS * dP_ahead_err
        and (
            lead > TWO_WAVE_FRACTION * abs(P - P0)
            or weak_precursor({**out, "u_p": u_jump}, residual_tol, pole)
        )
    )
    out["two_wave"] = float(two_wave)
    out["precursor_D"], out["precursor_D_err"] = _precursor or (np.nan, np.nan)
    # a precursor young enough that the slab ahead also reads the pole's material beyond it
    # is off the pole but not uniform: look for its plateau whenever it leads by enough
    if _precursor is None and np.isfinite(lead) and lead > TWO_WAVE_FRACTION * abs(P - P0):
        ag = gap if ahead_gap is None else ahead_gap
        plateau = precursor_plateau(h, profile, ag, u_ahead, u_p)
        xp = (track_precursor(h, profile, ag, u_ahead, plateau) if np.isfinite(plateau)
              else np.full(n, np.nan))  # fmt: skip
        seen = np.isfinite(xp)
        if seen.sum() >= max(2 * n_blocks, n // 2):
            Dp = robust_slope(t[seen], xp[seen]) - u_ahead
            _, Dp_err, _ = CorrelatedSlope().fit(t[seen], xp[seen])
            wander_p = slope_scatter(t[seen], xp[seen])
            Dp_err = max(float(Dp_err), wander_p) if np.isfinite(wander_p) else float(Dp_err)
            # the state ahead read on the precursor's plateau only (none in a sample where
            # the precursor was not seen: its slab ahead could hold the pole's material)
            h2 = {**h, "x_right": np.where(seen, np.fmin(h["x_right"], xp), h["front"])}
            return measure_point(
                h2, profile, pole, u_behind, u_ahead, gap, avg_length, residual_tol,
                left_gap=left_gap, front_speed=front_speed, n_blocks=n_blocks, track=track,
                u_p_from=u_p_from, ahead_gap=ahead_gap, _precursor=(float(Dp), Dp_err),
            )  # fmt: skip
    vals = {"D": D, "u": u_jump, "rho": rho, "P": P, "E": E}
    errs = {"D": D_err, "u": u_jump_err if at_slab else flow, "rho": out["rho_err"], "P": P_stat,
            "E": out["E_err"]}  # fmt: skip
    if two_wave:
        vals.update(rho1=out["ahead_rho"], P1=out["ahead_P"], E1=out["ahead_E"],
                    u1=out["ahead_u"])  # fmt: skip
        for k, a in (("rho1", "rho"), ("P1", "P"), ("E1", "E"), ("u1", "u")):
            errs[k] = out[f"ahead_{a}_err"]
    else:
        vals.update(rho1=pole.rho0, P1=P0, E1=pole.E0, u1=0.0)
        errs.update(rho1=pole.rho0_err, P1=P0_err, E1=pole.E0_err)
    res = jump_residuals(**vals)
    out.update({f"residual_{k}": v for k, v in res.items()})
    res_err = jump_residual_errors(vals, errs, cov=cov)
    out.update({f"residual_{k}_err": v for k, v in res_err.items()})
    # The slab's P and the Rayleigh line's P1 + ρ1 (D − u1)(u − u1) measure the same jump's
    # pressure: where they part by more than their noise, one is off, and P's error takes
    # half the excess (as D's takes half the front models' disagreement)
    rayleigh = rayleigh_jump(vals["rho1"], D, u_jump, vals["u1"])
    P_closure = 0.5 * beyond_noise(res["momentum"] * rayleigh, res_err["momentum"] * abs(rayleigh))
    out["P_closure_err"] = float(P_closure)
    out["P_err"] = float(np.hypot(out["P_err"], P_closure))
    n_ok = int(np.isfinite(_field(behind, "rho")).sum())
    out["n_samples"] = n_ok
    finite = all(np.isfinite(v) for v in (D, u_jump, rho, P, E))
    enough = n_ok >= max(2 * n_blocks, n // 2)
    # the fourth closure: the shocked slab at rest relative to the boundary behind it; a
    # diagnostic only where the jump is taken at the slab's own velocity
    out["residual_flow"] = float(du / u_p) if u_p != 0 and np.isfinite(du) else np.nan
    out["residual_flow_err"] = float(u_s_err / abs(u_p)) if u_p != 0 else np.nan
    if not at_slab:
        res["flow"], res_err["flow"] = out["residual_flow"], out["residual_flow_err"]
    all_close = all(closes(v, res_err[k], residual_tol) for k, v in res.items())
    # ok is a jump from what is actually ahead too: a state ahead measurably off the pole
    # moves the residuals taken from it beyond the tolerance (``ahead_off_pole``)
    off = ahead_off_pole({**out, "u_p": u_jump}, residual_tol, pole)
    out["ahead_off_pole"] = float(off is not None)
    # ...and from a state ahead that was seen at all: without it a precursor or a disturbed
    # inflow goes unnoticed (porous copper in a window with no room ahead: momentum +22 %)
    seen = ahead_seen(out)
    converged = bool(finite and enough and all_close and off is None and seen)
    out["converged"] = converged
    if not (finite and enough):
        out["status"] = "too_few_samples"
        out["diagnostic"] = (
            f"{n_ok} of {n} samples have a slab of at least {MIN_SLAB_BINS} bins behind the "
            f"front (median front {np.nanmedian(xf) if np.isfinite(xf).any() else np.nan:.4g},"
            f" boundaries {np.median(h['x_left']):.4g} .. {np.median(h['x_right']):.4g}); needs "
            f"{max(2 * n_blocks, n // 2)}"
        )
    else:
        out["status"] = "ok" if converged else "not_converged"
        # the measured causes first: a status table shows the diagnostic's start
        causes = named_causes({**out, "u_p": u_jump}, residual_tol, spread, pole,
                              flow_closes=not at_slab)  # fmt: skip
        out["diagnostic"] = (
            ""
            if converged
            else "".join(f"{c}; " for c in causes)
            + f"{residual_text(out, tuple(res))}; ok needs each within shock.residual_tol = "
            f"{residual_tol:.3g} and {CLOSE_SIGMAS:g} of its error"
        )
    return out
