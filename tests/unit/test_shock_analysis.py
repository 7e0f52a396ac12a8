"""Jump conditions and their error propagation (hugomap.analysis.shock).

Reference: the Rankine–Hugoniot conditions (Zel'dovich & Raizer, ch. I §17) solved exactly for
the state behind a front, so every residual must vanish to rounding (1e-12), whether the state
ahead is the pole at rest or a moving, compressed precursor state.
"""

from __future__ import annotations

import numpy as np
import pytest

from hugomap.analysis.shock import jump_residual_errors, jump_residuals


def _behind(rho1, P1, E1, u1, D, u):
    """The exact state behind a front at D, from the state ahead (mass, momentum, energy)."""
    rho = rho1 * (D - u1) / (D - u)
    P = P1 + rho1 * (D - u1) * (u - u1)
    E = E1 + 0.5 * (P + P1) * (1 / rho1 - 1 / rho)
    return rho, P, E


@pytest.mark.parametrize(
    "ahead",
    [(0.8, 5.9, -0.9, 0.0), (1.2, 14.0, -3.1, 0.4)],
    ids=["pole", "precursor"],
)
def test_exact_states_have_zero_residuals(ahead):
    rho1, P1, E1, u1 = ahead
    D, u = 10.7, 2.0
    rho, P, E = _behind(rho1, P1, E1, u1, D, u)
    res = jump_residuals(rho1, P1, E1, D, u, rho, P, E, u1=u1)
    assert all(abs(v) < 1e-12 for v in res.values()), res


def test_a_wrong_pressure_shows_in_the_momentum_residual_only():
    rho, P, E = _behind(0.8, 5.9, -0.9, 0.0, 10.7, 2.0)
    res = jump_residuals(0.8, 5.9, -0.9, 10.7, 2.0, rho, P * 1.05, E)
    assert abs(res["mass"]) < 1e-12
    assert res["momentum"] == pytest.approx(0.05 * P / (P - 5.9), rel=1e-9)


def test_error_propagation_matches_the_analytic_derivative():
    """momentum = (P − P1)/(ρ1 (D − u1)(u − u1)) − 1 is linear in P: σ_r = σ_P / (ρ1 D u)."""
    vals = dict(rho1=0.8, P1=5.9, E1=-0.9, D=10.7, u=2.0, u1=0.0)
    vals.update(zip(("rho", "P", "E"), _behind(0.8, 5.9, -0.9, 0.0, 10.7, 2.0), strict=True))
    err = jump_residual_errors(vals, {"P": 0.1})
    assert err["momentum"] == pytest.approx(0.1 / (0.8 * 10.7 * 2.0), rel=1e-6)
    assert err["mass"] == 0.0
    # Independent errors add in quadrature.
    both = jump_residual_errors(vals, {"P": 0.1, "D": 0.05})
    d_only = jump_residual_errors(vals, {"D": 0.05})
    assert both["momentum"] == pytest.approx(np.hypot(err["momentum"], d_only["momentum"]))


def test_robust_slope_ignores_tracker_jumps():
    """Theil–Sen: 10 % of the samples thrown 5 length units off (a tracker that sometimes
    jumps to the foot of a broad front) move the least-squares slope by several %, the
    median slope by well under 1 % (the noise alone moves either by ~0.3 %)."""
    from hugomap.analysis.stats import line_fit, robust_slope

    rng = np.random.default_rng(3)
    t = np.linspace(0.0, 10.0, 200)
    y = 7.4 * t + rng.normal(0.0, 0.5, t.size)
    jumps = rng.choice(t.size, 20, replace=False)
    y[jumps] += 5.0 * np.sign(t[jumps] - 5.0)  # late samples jump ahead, early ones behind
    assert abs(line_fit(t, y)[0] / 7.4 - 1) > 0.02
    assert abs(robust_slope(t, y) / 7.4 - 1) < 0.01
