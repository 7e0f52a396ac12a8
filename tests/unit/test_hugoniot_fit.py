"""The linear Us–up fit (hugomap.analysis.stats.linear_hugoniot_fit).

References: points exactly on D = c0 + s u_p give c0 and s to rounding; for Gaussian errors
of known σ the weighted least-squares parameters are unbiased with standard errors from
(XᵀWX)⁻¹ (textbook linear regression), checked over 400 synthetic data sets: the pull
(estimate − truth)/error has unit spread (0.85–1.15: the spread of a 400-sample standard
deviation is ±3.5 %, and the χ² scaling adds a little).
"""

from __future__ import annotations

import numpy as np
import pytest

from hugomap.analysis.stats import linear_hugoniot_fit


def test_exact_line():
    u = np.array([0.5, 1.0, 1.5, 2.0, 3.0])
    f = linear_hugoniot_fit(u, 7.24 + 1.6 * u, np.full(5, 0.05))
    assert f["c0"] == pytest.approx(7.24, abs=1e-12) and f["s"] == pytest.approx(1.6, abs=1e-12)
    assert f["n"] == 5 and f["c0_err"] > 0 and f["s_err"] > 0 and f["rho_cs"] < 0


def test_errors_are_honest():
    rng = np.random.default_rng(4)
    u = np.array([0.5, 1.0, 1.5, 2.0, 2.5, 3.0])
    sig = 0.02 * (7.0 + 1.6 * u)
    pulls = []
    for _ in range(400):
        d = 7.0 + 1.6 * u + rng.normal(0.0, sig)
        f = linear_hugoniot_fit(u, d, sig)
        pulls.append(((f["c0"] - 7.0) / f["c0_err"], (f["s"] - 1.6) / f["s_err"]))
    p = np.array(pulls)
    assert np.all(np.abs(p.mean(axis=0)) < 0.15), p.mean(axis=0)
    assert np.all((p.std(axis=0) > 0.85) & (p.std(axis=0) < 1.15)), p.std(axis=0)


def test_missing_points_and_errors():
    u = np.array([1.0, 2.0, np.nan, 3.0])
    d = np.array([9.0, 11.0, 5.0, 13.0])
    f = linear_hugoniot_fit(u, d, np.array([0.1, np.nan, 0.1, 0.1]))  # one error missing
    assert f["n"] == 3 and f["s"] == pytest.approx(2.0) and f["c0"] == pytest.approx(7.0)
    one = linear_hugoniot_fit(np.array([1.0, 1.0]), np.array([9.0, 9.1]))
    assert np.isnan(one["c0"]) and np.isnan(one["s"])
