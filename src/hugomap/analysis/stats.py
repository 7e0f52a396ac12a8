"""Statistics of correlated time series: block averages and weighted line fits."""

from __future__ import annotations

import numpy as np


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
    nb = min(n_blocks, y.size)
    if nb < 2:
        return float(y.mean()), float("nan")
    m = y.size // nb
    blocks = y[y.size - nb * m :].reshape(nb, m).mean(axis=1)
    return float(y.mean()), float(blocks.std(ddof=1) / np.sqrt(nb))


def line_fit(t: np.ndarray, y: np.ndarray) -> tuple[float, float, float, float]:
    """Least-squares y = a t + b: returns (a, b, se_a, se_b) with ordinary standard errors
    from the residual variance (a lower bound when residuals are correlated)."""
    t = np.asarray(t, dtype=float)
    y = np.asarray(y, dtype=float)
    ok = np.isfinite(t) & np.isfinite(y)
    t, y = t[ok], y[ok]
    n = t.size
    if n < 3:
        return float("nan"), float("nan"), float("nan"), float("nan")
    tm = t.mean()
    sxx = np.sum((t - tm) ** 2)
    a = float(np.sum((t - tm) * (y - y.mean())) / sxx)
    b = float(y.mean() - a * tm)
    s2 = float(np.sum((y - a * t - b) ** 2) / (n - 2))
    return a, b, float(np.sqrt(s2 / sxx)), float(np.sqrt(s2 * (1.0 / n + tm**2 / sxx)))


def robust_slope(t: np.ndarray, y: np.ndarray, min_separation: float = 0.25) -> float:
    """Theil–Sen slope: the median of (y_j − y_i)/(t_j − t_i) over the pairs at least
    ``min_separation`` of the time span apart (Sen, J. Am. Stat. Assoc. 63, 1379 (1968)).

    A front tracker that now and then jumps by a few σ (a weak, broad front; the foot or the
    top of a two-wave profile) shifts a least-squares slope by a few %; the median ignores
    such samples. NaN samples are dropped; NaN if fewer than 3 remain."""
    t = np.asarray(t, dtype=float)
    y = np.asarray(y, dtype=float)
    ok = np.isfinite(t) & np.isfinite(y)
    t, y = t[ok], y[ok]
    if t.size < 3:
        return float("nan")
    i, j = np.triu_indices(t.size, k=1)
    dt = t[j] - t[i]
    far = dt >= min_separation * (t.max() - t.min())
    if not far.any():
        return float("nan")
    return float(np.median((y[j] - y[i])[far] / dt[far]))
