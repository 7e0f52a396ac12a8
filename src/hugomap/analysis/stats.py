"""Statistics of correlated time series: block averages and weighted line fits."""

from __future__ import annotations

import functools

import numpy as np

from .linear_hugoniot import shock_velocity


def block_average(series: np.ndarray, n_blocks: int = 8) -> tuple[float, float]:
    """Mean and standard error of a correlated series by block averaging.

    The series is cut into ``n_blocks`` equal consecutive blocks (a remainder at the start is
    dropped, so the latest data are kept); the standard error is the standard deviation of
    the block means over √(n_blocks) (Flyvbjerg & Petersen, J. Chem. Phys. 91, 461 (1989)).
    Blocks must be longer than the correlation time for the error to be honest. Returns
    (nan, nan) for an empty series and (mean, nan) when fewer than 2 blocks can be formed.
    """
    y = np.asarray(series, dtype=float)
    y = y[np.isfinite(y)]
    if y.size == 0:
        return float("nan"), float("nan")
    if min(n_blocks, y.size) < 2:
        return float(y.mean()), float("nan")
    blocks = _block_means(y, n_blocks)
    return float(y.mean()), float(blocks.std(ddof=1) / np.sqrt(blocks.size))


def _block_means(y: np.ndarray, n_blocks: int) -> np.ndarray:
    """Means of min(n_blocks, y.size) equal consecutive blocks of y (a remainder at the
    start dropped, so the latest samples are kept)."""
    nb = min(n_blocks, y.size)
    m = y.size // nb
    return y[y.size - nb * m :].reshape(nb, m).mean(axis=1)


def block_covariance(x: np.ndarray, y: np.ndarray, n_blocks: int = 8) -> float:
    """Covariance of the means of two correlated series sampled together, by block
    averaging: cov(x̄, ȳ) = Σ (x̄_b − ⟨x̄_b⟩)(ȳ_b − ⟨ȳ_b⟩) / ((n_blocks − 1) n_blocks) over
    the blocks' means, the samples where both are finite cut as in ``block_average`` (so
    that cov(x, x) is the square of its standard error). NaN with fewer than 2 blocks."""
    x, y = np.asarray(x, dtype=float), np.asarray(y, dtype=float)
    ok = np.isfinite(x) & np.isfinite(y)
    x, y = x[ok], y[ok]
    if min(n_blocks, x.size) < 2:
        return float("nan")
    bx, by = _block_means(x, n_blocks), _block_means(y, n_blocks)
    nb = bx.size
    return float(np.sum((bx - bx.mean()) * (by - by.mean())) / ((nb - 1) * nb))


def finite_pairs(t: np.ndarray, y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(t, y) as float arrays, keeping the samples where both are finite."""
    t = np.asarray(t, dtype=float)
    y = np.asarray(y, dtype=float)
    ok = np.isfinite(t) & np.isfinite(y)
    return t[ok], y[ok]


def line_fit(t: np.ndarray, y: np.ndarray) -> tuple[float, float, float, float]:
    """Least-squares y = a t + b: returns (a, b, se_a, se_b) with ordinary standard errors
    from the residual variance (a lower bound when residuals are correlated)."""
    t, y = finite_pairs(t, y)
    n = t.size
    if n < 3:
        return float("nan"), float("nan"), float("nan"), float("nan")
    tm = t.mean()
    sxx = np.sum((t - tm) ** 2)
    a = float(np.sum((t - tm) * (y - y.mean())) / sxx)
    b = float(y.mean() - a * tm)
    s2 = float(np.sum((y - a * t - b) ** 2) / (n - 2))
    return a, b, float(np.sqrt(s2 / sxx)), float(np.sqrt(s2 * (1.0 / n + tm**2 / sxx)))


@functools.lru_cache(maxsize=32)
def _detrended_rho_table(n: int) -> tuple[np.ndarray, np.ndarray]:
    """E[ρ̂1] of the residuals of a straight-line fit to n samples of an AR(1) series of
    lag-1 correlation ρ, pooled over many series (Monte Carlo, fixed seed): the detrending
    biases ρ̂1 low, strongly so for short series (n = 16, ρ = 0.78 gives ρ̂1 ≈ 0.34)."""
    rng = np.random.default_rng(12345)
    rhos = np.linspace(0.0, 0.95, 20)
    reps = 600
    t = np.arange(n, dtype=float)
    X = np.stack([np.ones(n), t], axis=1)
    proj = np.eye(n) - X @ np.linalg.pinv(X)  # residual maker of the line fit
    out = np.empty(rhos.size)
    z = rng.standard_normal((reps, n))
    for j, r in enumerate(rhos):
        e = np.empty_like(z)
        e[:, 0] = z[:, 0]
        for i in range(1, n):
            e[:, i] = r * e[:, i - 1] + np.sqrt(1 - r * r) * z[:, i]
        res = e @ proj.T
        out[j] = np.sum(res[:, 1:] * res[:, :-1]) / np.sum(res * res)
    return rhos, np.maximum.accumulate(out)


class CorrelatedSlope:
    """Least-squares slopes of successive windows of one noisy signal, with standard errors
    corrected for serially correlated samples (AR(1)).

    The ordinary slope error (``line_fit``) assumes independent residuals; ω(t) sampled
    every few steps is not (density waves cross the window over several samples), and the
    ordinary error was 3-4 times too small (the a_k of consecutive AMW windows scattered by
    4 s_k). For an AR(1) process of lag-1 correlation ρ the effective sample size is
    n (1 − ρ)/(1 + ρ), so the error is inflated by √((1 + ρ)/(1 − ρ)) (e.g. Wilks,
    Statistical Methods in the Atmospheric Sciences, 3rd ed., §5.2.4). ρ is estimated from
    the residuals of every window fitted so far (pooled), and the detrending bias of that
    estimate is undone with ``_detrended_rho_table``; ρ is capped at 0.95."""

    def __init__(self) -> None:
        self.lag1 = 0.0
        self.sq = 0.0
        self.n = 0

    def rho(self) -> float:
        if self.sq <= 0 or self.n < 4:
            return 0.0
        raw = self.lag1 / self.sq
        rhos, biased = _detrended_rho_table(self.n)
        return float(np.interp(raw, biased, rhos))  # clips to [0, 0.95]

    def fit(self, t: np.ndarray, y: np.ndarray) -> tuple[float, float, float]:
        """Slope a, its corrected standard error and the pooled ρ used: (a, se_a, ρ)."""
        t, y = finite_pairs(t, y)
        a, b, se, _ = line_fit(t, y)
        if not np.isfinite(se):
            return a, se, float("nan")
        r = y - a * t - b
        self.lag1 += float(np.sum(r[1:] * r[:-1]))
        self.sq += float(np.sum(r * r))
        self.n = r.size
        rho = self.rho()
        return a, se * float(np.sqrt((1.0 + rho) / (1.0 - rho))), rho


def slope_scatter(t: np.ndarray, y: np.ndarray, n_sub: int = 4, bounded: bool = False) -> float:
    """Standard error of a slope from its scatter over ``n_sub`` consecutive spans of equal
    length in t: std(a_k)/√n_sub, a_k the least-squares slope of span k (NaN with fewer than
    2 spans of at least 4 samples); std(a_k)/n_sub if ``bounded``.

    It sees what a one-span error cannot: a signal that wanders on a time scale comparable
    to the run (a front that an acoustic wave in a small cross-section pushes back and forth
    for several τ; measured on the LJ liquid, ±0.4 σ over 4-10 τ, when the AR(1) error of
    the whole span was 3-5 times smaller than the scatter over seeds). For a random-walk
    wander (white front-speed noise) the mean slope over the spans is the whole span's, and
    its error is this; for white noise on y it errs high by about n_sub.

    A ``bounded`` signal (a stationary fluctuation about the line whose correlation time is
    comparable to a span) has a slope error that falls as 1/T with the span T, not 1/√T: the
    whole span's is std(a_k)/n_sub. The window's ω is such a signal (the front's position in
    a held frame, plus the window's own number fluctuation): on held frames of the LJ liquid
    at u_p = 1 and 2 (36 τ each, three runs) the sd of its 6-τ and 12-τ slopes fell by 2.0-2.2
    from one to the other, and std(a_k)/n_sub over 4 spans matched it within 0.9-1.4 times,
    where the random-walk rule read 1.8-2.7 times too high."""
    t, y = finite_pairs(t, y)
    if t.size < 8:
        return float("nan")
    cuts = np.linspace(t.min(), t.max(), n_sub + 1)
    a = []
    for k in range(n_sub):
        m = (t >= cuts[k]) & (t <= cuts[k + 1])
        if m.sum() >= 4:
            a.append(line_fit(t[m], y[m])[0])
    if len(a) < 2:
        return float("nan")
    # a random walk's span slopes average to the whole one's; a bounded wiggle's shrink as 1/T
    return float(np.std(a, ddof=1) / (len(a) if bounded else np.sqrt(len(a))))


def robust_slope(t: np.ndarray, y: np.ndarray, min_separation: float = 0.25) -> float:
    """Theil–Sen slope: the median of (y_j − y_i)/(t_j − t_i) over the pairs at least
    ``min_separation`` of the time span apart (Sen, J. Am. Stat. Assoc. 63, 1379 (1968)).

    A front tracker that now and then jumps by a few σ (a weak, broad front; the foot or the
    top of a two-wave profile) shifts a least-squares slope by a few %; the median ignores
    such samples. NaN samples are dropped; NaN if fewer than 3 remain."""
    t, y = finite_pairs(t, y)
    if t.size < 3:
        return float("nan")
    i, j = np.triu_indices(t.size, k=1)
    dt = t[j] - t[i]
    far = dt >= min_separation * (t.max() - t.min())
    if not far.any():
        return float("nan")
    return float(np.median((y[j] - y[i])[far] / dt[far]))


def linear_hugoniot_fit(
    u_p: np.ndarray, D: np.ndarray, D_err: np.ndarray | None = None
) -> dict[str, float]:
    """Weighted least-squares fit of the linear Us–up Hugoniot D = c0 + s·u_p.

    Weights 1/D_err² (equal weights without errors or where an error is missing or zero).
    The parameter covariance is (XᵀWX)⁻¹, scaled by the reduced χ² when it exceeds 1 (points
    scattered more than their stated errors: the errors are then taken as relative only).
    Returns c0, c0_err, s, s_err (units of D and of D/u_p), their correlation ``rho_cs``,
    ``chi2_red`` and the number of points ``n``; NaN for fewer than two distinct u_p."""
    u = np.asarray(u_p, dtype=float)
    d = np.asarray(D, dtype=float)
    e = np.full_like(d, np.nan) if D_err is None else np.asarray(D_err, dtype=float)
    ok = np.isfinite(u) & np.isfinite(d)
    u, d, e = u[ok], d[ok], e[ok]
    nan = float("nan")
    out = {"c0": nan, "c0_err": nan, "s": nan, "s_err": nan, "rho_cs": nan,
           "chi2_red": nan, "n": int(u.size)}  # fmt: skip
    if u.size < 2 or np.ptp(u) == 0:
        return out
    have = np.isfinite(e) & (e > 0)
    w = np.where(have, 1.0 / np.where(have, e, 1.0) ** 2, 0.0)
    if not have.all():  # a point without an error: equal weights for all
        w = np.ones_like(u)
    X = np.column_stack([np.ones_like(u), u])
    A = X.T @ (w[:, None] * X)
    cov = np.linalg.inv(A)
    c0, s = cov @ (X.T @ (w * d))
    r = d - shock_velocity(u, c0, s)
    dof = u.size - 2
    chi2 = float(np.sum(w * r * r) / dof) if dof > 0 else nan
    if not have.all():  # unweighted: the scatter is the only error estimate
        cov = cov * (chi2 if dof > 0 else nan)
    elif dof > 0 and chi2 > 1.0:
        cov = cov * chi2
    out.update(c0=float(c0), s=float(s), c0_err=float(np.sqrt(cov[0, 0])),
               s_err=float(np.sqrt(cov[1, 1])), chi2_red=chi2,
               rho_cs=float(cov[0, 1] / np.sqrt(cov[0, 0] * cov[1, 1])))  # fmt: skip
    return out
