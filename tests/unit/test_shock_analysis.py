"""Jump conditions and their error propagation (hugomap.analysis.shock).

Reference: the Rankine–Hugoniot conditions (Zel'dovich & Raizer, ch. I §17) solved exactly for
the state behind a front, so every residual must vanish to rounding (1e-12), whether the state
ahead is the pole at rest or a moving, compressed precursor state.
"""

from __future__ import annotations

import numpy as np
import pytest

from hugomap.analysis.jump import jump_residual_errors, jump_residuals


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


# -- the point measurement: "ok" means the jump conditions close ------------------------------
class _ToyProfile:
    """Bins of width 1 from 0 whose sums are the fields themselves (count, u, ρ, P, E); a
    slab's state is the mean over its bins."""

    x0, bin_width = 0.0, 1.0

    def velocity(self, sums):
        return sums[:, 1], sums[:, 0]

    def state(self, summed, n_bins):
        from hugomap.states import SlabState

        m = summed / n_bins
        return SlabState(rho=m[2], u=m[1], P=m[3], Pyy=m[3], Pzz=m[3], E=m[4])


#: A state ahead as ``measure_point`` reports it, at the pole (ρ0 1, P0 1) at rest, with no
#: error given (so never off the pole): what ``named_causes`` needs to see a state ahead.
AHEAD = {"ahead_rho": 1.0, "ahead_u": 0.0, "ahead_P": 1.0}


def _toy_run(P_bias: float, noise: float, wander: float = 0.0, seed: int = 3, flow: float = 0.0,
             ahead: tuple[float, float, float, float] = (0.0, 1.0, 1.0, 0.0),
             exact_at_slab: bool = False, sway: float = 0.0):  # fmt: skip
    """Samples of a steady front at D into the pole (ρ0 1, P0 1, E0 0) at rest, u_p 1, the
    state behind exact except P × (1 + P_bias), every field with white noise of relative
    size ``noise``; the front position may wander by ``wander`` (one sine over the run); the
    slab behind may flow at ``flow`` relative to the boundary behind it (u = u_p + flow),
    its state exact for u_p (default) or for its own velocity (``exact_at_slab``: the
    window's case, the boundary holds the slab only on average), and may sway along the
    Rayleigh line, u × (1 + ``sway`` sin(2π t/3.3)) with ρ, P, E exact at each instant (an
    acoustic ring moving u and P together); the material ahead is at (u, ρ, P, E) =
    ``ahead`` (default the pole at rest)."""
    from hugomap.states import Pole

    rng = np.random.default_rng(seed)
    D, u_p = 3.0, 1.0
    t = np.linspace(0.0, 20.0, 200)
    xf = 10.0 + D * t + wander * np.sin(2 * np.pi * t / t[-1])
    edges = np.arange(101)
    sums = np.empty((t.size, 100, 5))
    for i, x in enumerate(xf):
        u_i = (u_p + flow) * (1.0 + sway * np.sin(2 * np.pi * t[i] / 3.3))
        rho, P, E = _behind(1.0, 1.0, 0.0, 0.0, D, u_i if exact_at_slab else u_p)
        behind = (edges[1:] <= x)[:, None]
        ahead_state = np.array([30.0, *ahead])
        behind_state = np.array([30.0, u_i, rho, P * (1 + P_bias), E])
        s = np.where(behind, behind_state, ahead_state)
        s[:, 2:] *= 1 + noise * rng.standard_normal((100, 3))
        s[:, 1] += noise * rng.standard_normal(100)
        sums[i] = s
    h = {"t": t, "front": xf, "x_left": np.zeros(t.size), "x_right": np.full(t.size, 100.0),
         "sums": sums}  # fmt: skip
    pole = Pole(rho0=1.0, P0=1.0, E0=0.0, T0=1.0, Pyy0=1.0, rho0_err=0.0, P0_err=0.0,
                E0_err=0.0, T0_err=0.0, Pyy0_err=0.0)  # fmt: skip
    return h, pole


def test_a_point_is_ok_only_if_its_residuals_close_within_tolerance_and_errors():
    """Exact jump states with noise: ok. A 0.6 % momentum bias, inside residual_tol = 1 %
    but 10+ errors wide with little noise: not ok (it is a bias, not noise). The same bias
    (0.4 %) under noise large enough to hide it: ok (its error covers it)."""
    from hugomap.analysis.shock import measure_point

    for bias, noise, status in ((0.0, 0.002, "ok"), (0.006, 0.0005, "not_converged"),
                                (0.004, 0.1, "ok")):  # fmt: skip
        h, pole = _toy_run(bias, noise)
        r = measure_point(h, _ToyProfile(), pole, 1.0, 0.0, gap=3.0, avg_length=20.0,
                          residual_tol=0.01)  # fmt: skip
        assert r["status"] == status, (bias, noise, r["diagnostic"])
        if status != "ok":
            assert "3 of its error" in r["diagnostic"]


def test_the_piston_slab_keeps_clear_of_the_layers_its_start_heated():
    """The toy column over its whole length (avg_length 1000), with the 20 bins next to the
    piston 4 % of the energy jump too warm (what the LJ piston's start leaves 5-55 sigma
    from it): from 3 bins off the piston the slab's energy residual reads the warm layers
    and the point is not ok; from 22 bins (``left_gap``, the stage's ``shock.piston_gap``)
    the jump closes and the point is ok."""
    from hugomap.analysis.shock import measure_point

    h, pole = _toy_run(0.0, 0.0005)
    jump = _behind(1.0, 1.0, 0.0, 0.0, 3.0, 1.0)[2]
    warm = np.arange(100) < 20
    behind = np.arange(1, 101)[None, :] <= h["front"][:, None]
    h["sums"][..., 4] += 0.04 * jump * (warm[None, :] & behind)
    kw = dict(gap=3.0, avg_length=1000.0, residual_tol=0.01)
    near = measure_point(h, _ToyProfile(), pole, 1.0, 0.0, **kw)
    clear = measure_point(h, _ToyProfile(), pole, 1.0, 0.0, left_gap=22.0, **kw)
    assert near["residual_energy"] > 0.01 and near["status"] == "not_converged"
    assert "energy" in near["diagnostic"], near["diagnostic"]
    assert abs(clear["residual_energy"]) < 0.002 and clear["status"] == "ok", clear["diagnostic"]


def test_a_point_is_not_ok_without_a_measured_state_ahead():
    """The exact jump of the toy run is ok; the same run with the far boundary 8 bins ahead
    of the front (2 gap = 6 leave 2 bins, below MIN_SLAB_BINS) has no state ahead, so what
    the jump starts from was not seen: not ok, and the diagnostic says so."""
    from hugomap.analysis.shock import measure_point

    h, pole = _toy_run(0.0, 0.002)
    r = measure_point(h, _ToyProfile(), pole, 1.0, 0.0, gap=3.0, avg_length=20.0,
                      residual_tol=0.01)  # fmt: skip
    assert r["status"] == "ok", r["diagnostic"]
    h["x_right"] = h["front"] + 8.0
    r = measure_point(h, _ToyProfile(), pole, 1.0, 0.0, gap=3.0, avg_length=20.0,
                      residual_tol=0.01)  # fmt: skip
    assert np.isnan(r["ahead_P"])
    assert r["status"] == "not_converged"
    assert r["diagnostic"].startswith("no state ahead measured"), r["diagnostic"]


def test_a_relaxation_zone_is_cleared_behind_and_the_state_ahead_read_close_to_the_front():
    """The toy run's exact jump with a relaxation zone: the 15 bins behind the front 5 % of
    the energy jump too warm (a crystal's plastic wave still relaxing there). With gap 3 the
    slab reads the zone and the point is not ok; with gap 18 it is cleared, but a window
    with 30 bins ahead of the front then has no slab ahead (2 gap + 3 bins > 30) and is not
    ok either; with ``ahead_gap`` 3 the state ahead is read again and the point is ok."""
    from hugomap.analysis.shock import measure_point

    h, pole = _toy_run(0.0, 0.0005)
    jump = _behind(1.0, 1.0, 0.0, 0.0, 3.0, 1.0)[2]
    x = np.arange(1, 101)[None, :]
    zone = (x <= h["front"][:, None]) & (x > h["front"][:, None] - 15)
    h["sums"][..., 4] += 0.05 * jump * zone
    h["x_right"] = h["front"] + 30.0
    kw = dict(avg_length=20.0, residual_tol=0.01)
    near = measure_point(h, _ToyProfile(), pole, 1.0, 0.0, gap=3.0, **kw)
    assert near["status"] == "not_converged" and near["residual_energy"] > 0.01
    far = measure_point(h, _ToyProfile(), pole, 1.0, 0.0, gap=18.0, **kw)
    assert np.isnan(far["ahead_P"]) and far["status"] == "not_converged"
    both = measure_point(h, _ToyProfile(), pole, 1.0, 0.0, gap=18.0, ahead_gap=3.0, **kw)
    assert both["status"] == "ok", both["diagnostic"]
    assert abs(both["residual_energy"]) < 0.002 and both["ahead_P"] == pytest.approx(1.0, rel=1e-3)


def test_the_relaxation_zone_is_where_P_leaves_the_slabs_band():
    """A mean profile with the front at 100 and P = 10 + 2 e^(−d/10) at a distance d behind
    it (an overshoot of 20 % of the jump 10 − P0, P0 = 0, relaxing over 10 bins to the
    slab's 10): the zone is the d at which |P − 10| falls to 1 % of the jump, 10 ln 20 ≈ 30; with
    the band at 10 % it is 10 ln 2 ≈ 6.9; a flat profile has none; no front: NaN. One-bin
    (1 σ) resolution."""
    from hugomap.analysis.shock import relaxation_length

    x = np.arange(0.5, 150.0)
    d = 100.0 - x
    P = np.where(d > 0, 10.0 + 2.0 * np.exp(-d / 10.0), 0.0)  # overshoot 2 = 20 % of the jump
    assert relaxation_length(x, P, 100.0, 5.0, 10.0, 0.0, 0.01) == pytest.approx(
        10 * np.log(20), abs=1.0
    )
    assert relaxation_length(x, P, 100.0, 5.0, 10.0, 0.0, 0.1) == pytest.approx(
        10 * np.log(2), abs=1.0
    )
    assert relaxation_length(x, np.where(d > 0, 10.0, 0.0), 100.0, 5.0, 10.0, 0.0, 0.01) == 0
    assert np.isnan(relaxation_length(x, P, np.nan, 5.0, 10.0, 0.0, 0.01))


def test_front_speed_error_covers_a_slow_wander():
    """A front that wanders by A = 0.5 (one sine over the run, T = 20: an acoustic wave
    ringing longer than the average) moves a least-squares D by 6A/(πT) = 0.048 (the
    Theil–Sen slope by about as much); the AR(1)-corrected error of the whole span is far
    smaller, the error from the slope's scatter over four spans covers it."""
    from hugomap.analysis.shock import measure_point
    from hugomap.analysis.stats import CorrelatedSlope

    h, pole = _toy_run(0.0, 0.002, wander=0.5)
    r = measure_point(h, _ToyProfile(), pole, 1.0, 0.0, gap=3.0, avg_length=20.0,
                      residual_tol=0.01)  # fmt: skip
    dev = abs(r["D"] - 3.0)
    assert dev > 0.02
    assert CorrelatedSlope().fit(h["t"], h["front"])[1] < 0.5 * dev
    assert r["D_err"] >= dev


def test_a_slab_that_still_flows_is_not_ok_and_the_point_says_why():
    """The state behind exact, but the slab moves at 0.98 u_p relative to the piston (as the
    default 80-cell LJ piston's did at u_p = 1, its slab in the weak front's relaxation
    tail): the three jump residuals close, the flow residual (−2 %, 40 errors) does not, and
    the diagnostic names the cause. A flow below RESIDUAL_FLOOR (5e-5) closes."""
    from hugomap.analysis.shock import measure_point

    h, pole = _toy_run(0.0, 0.0005, flow=-0.02)
    r = measure_point(h, _ToyProfile(), pole, 1.0, 0.0, gap=3.0, avg_length=20.0,
                      residual_tol=0.01)  # fmt: skip
    assert r["residual_flow"] == pytest.approx(-0.02, abs=1e-3)
    assert all(abs(r[f"residual_{k}"]) < 1e-3 for k in ("mass", "momentum", "energy"))
    assert r["status"] == "not_converged"
    assert r["diagnostic"].startswith("slab not at rest")
    h, pole = _toy_run(0.0, 0.0005, flow=-5e-5)
    r = measure_point(h, _ToyProfile(), pole, 1.0, 0.0, gap=3.0, avg_length=20.0,
                      residual_tol=0.01)  # fmt: skip
    assert r["status"] == "ok", r["diagnostic"]


def test_a_window_takes_the_jump_at_its_slab_and_the_flow_is_a_diagnostic():
    """A window's outflow holds the shocked material only on average: a slab moving at
    0.98 of the boundary's u_p, its state exact for its own velocity, closes its jumps at
    that velocity (``u_p_from = "slab"``: ok, ``u_p_jump`` 0.98, the −2 % flow reported but
    not a closure) and fails at the boundary's (momentum +2 %, the slab named not at
    rest)."""
    from hugomap.analysis.shock import measure_point

    h, pole = _toy_run(0.0, 0.0005, flow=-0.02, exact_at_slab=True)
    kw = dict(gap=3.0, avg_length=20.0, residual_tol=0.01)
    r = measure_point(h, _ToyProfile(), pole, 1.0, 0.0, **kw, u_p_from="slab")
    assert r["status"] == "ok", r["diagnostic"]
    assert r["u_p_jump"] == pytest.approx(0.98, abs=1e-3)
    assert r["u_p_jump_err"] == pytest.approx(r["u_p_measured_err"])
    assert r["residual_flow"] == pytest.approx(-0.02, abs=1e-3)
    assert abs(r["residual_momentum"]) < 1e-3 and r["P_flow_err"] == 0.0
    assert r["P_rh"] == pytest.approx(1.0 + 3.0 * 0.98, rel=1e-3)
    b = measure_point(h, _ToyProfile(), pole, 1.0, 0.0, **kw)
    assert b["status"] == "not_converged" and b["u_p_jump"] == 1.0
    assert b["residual_momentum"] == pytest.approx(-0.02, abs=2e-3)
    assert b["diagnostic"].startswith("slab not at rest")
    with pytest.raises(ValueError, match="u_p_from"):
        measure_point(h, _ToyProfile(), pole, 1.0, 0.0, **kw, u_p_from="outflow")


def test_a_slab_swaying_along_its_rayleigh_line_has_correlated_u_and_P_errors():
    """The slab's state slides along the Rayleigh line (u ± 1 %, P = P0 + ρ0 D u at each
    instant, a ring of period 3.3 over a 20-τ run): its u and P errors are correlated
    (u_p_P_corr > 0.95) and the momentum residual at the slab's u, exact on average, gets
    an error a fraction of the one that treats them as independent; that error still
    covers the residual."""
    from hugomap.analysis.jump import jump_residual_errors
    from hugomap.analysis.shock import measure_point

    h, pole = _toy_run(0.0, 0.0002, sway=0.01, exact_at_slab=True)
    r = measure_point(h, _ToyProfile(), pole, 1.0, 0.0, gap=3.0, avg_length=20.0,
                      residual_tol=0.01, u_p_from="slab")  # fmt: skip
    assert r["u_p_P_corr"] > 0.95
    vals = dict(rho1=1.0, P1=1.0, E1=0.0, u1=0.0, D=r["D"], u=r["u_p_jump"], rho=r["rho"],
                P=r["P"], E=r["E"])  # fmt: skip
    errs = {"D": r["D_err"], "u": r["u_p_jump_err"], "rho": r["rho_err"], "P": r["P_err"],
            "E": r["E_err"]}  # fmt: skip
    independent = jump_residual_errors(vals, errs)["momentum"]
    assert r["residual_momentum_err"] < 0.5 * independent
    assert abs(r["residual_momentum"]) <= 3.0 * r["residual_momentum_err"] + 1e-4


def test_correlated_errors_propagate_as_a_monte_carlo_says():
    """Reference: 40 000 draws of the slab's (u, P) from a bivariate normal (σ_u 1 %, σ_P
    0.5 %, correlation ±0.8) through ``jump_residuals``; the first-order error with the
    covariance matches the draws' sd of the momentum residual within 3 % (the sd of a sd
    over 40 000 draws is 0.35 %; the rest is the residual's curvature in u)."""
    vals = dict(rho1=0.8, P1=5.9, E1=-0.9, D=10.7, u=2.0, u1=0.0)
    vals.update(zip(("rho", "P", "E"), _behind(0.8, 5.9, -0.9, 0.0, 10.7, 2.0), strict=True))
    su, sP = 0.02, 0.005 * vals["P"]
    rng = np.random.default_rng(7)
    for corr in (0.8, -0.8):
        cov = np.array([[su**2, corr * su * sP], [corr * su * sP, sP**2]])
        du, dP = rng.multivariate_normal([0.0, 0.0], cov, 40_000).T
        r = [jump_residuals(**{**vals, "u": vals["u"] + a, "P": vals["P"] + b})["momentum"]
             for a, b in zip(du, dP, strict=True)]  # fmt: skip
        got = jump_residual_errors(vals, {"u": su, "P": sP}, cov={("u", "P"): cov[0, 1]})
        assert got["momentum"] == pytest.approx(np.std(r), rel=0.03)
    # no covariance: the independent sum, as before
    plain = jump_residual_errors(vals, {"u": su, "P": sP})
    assert plain == jump_residual_errors(vals, {"u": su, "P": sP}, cov={("u", "P"): 0.0})


def test_block_covariance_is_the_covariance_of_the_means():
    """cov(x, x) is the square of ``block_average``'s error; y = −2x + noise gives a
    covariance −2 of it; over 2000 pairs of AR(1) series (correlation 0.7 between them)
    the block covariance's mean is the true covariance of the two means within 10 %
    (reference: the covariance of the means over the 2000 pairs)."""
    from hugomap.analysis.stats import block_average, block_covariance

    rng = np.random.default_rng(5)
    x = rng.standard_normal(400)
    assert block_covariance(x, x) == pytest.approx(block_average(x)[1] ** 2, rel=1e-12)
    y = -2.0 * x
    assert block_covariance(x, y) == pytest.approx(-2.0 * block_average(x)[1] ** 2, rel=1e-12)
    assert np.isnan(block_covariance(x[:1], x[:1]))
    n, reps, phi = 400, 2000, 0.5
    z1 = rng.standard_normal((reps, n))
    z2 = 0.7 * z1 + np.sqrt(1 - 0.49) * rng.standard_normal((reps, n))
    a, b = np.empty_like(z1), np.empty_like(z2)
    a[:, 0], b[:, 0] = z1[:, 0], z2[:, 0]
    for i in range(1, n):
        a[:, i] = phi * a[:, i - 1] + z1[:, i]
        b[:, i] = phi * b[:, i - 1] + z2[:, i]
    true = np.cov(a.mean(axis=1), b.mean(axis=1))[0, 1]
    est = np.mean([block_covariance(a[k], b[k]) for k in range(reps)])
    assert est == pytest.approx(true, rel=0.10)


def test_P_error_takes_only_the_flow_beyond_its_noise():
    """A slab flowing 2 % of u_p (40 of its errors) carries momentum ρ0 D δu = 0.06 that P's
    error must hold; a slab at rest adds nothing beyond its noise (its velocity noise is
    the acoustic motion whose pressure swings P's block error already holds), so there
    P_flow_err = ρ0 D √max(0, δu² − σ²) is zero where |δu| ≤ σ."""
    from hugomap.analysis.shock import beyond_noise, measure_point

    assert beyond_noise(0.3, 0.4) == 0.0 and beyond_noise(-0.5, 0.3) == pytest.approx(0.4)
    h, pole = _toy_run(0.0, 0.0005, flow=-0.02)
    r = measure_point(h, _ToyProfile(), pole, 1.0, 0.0, gap=3.0, avg_length=20.0,
                      residual_tol=0.01)  # fmt: skip
    assert r["P_flow_err"] == pytest.approx(3.0 * 0.02, rel=0.02)
    assert r["P_err"] >= r["P_flow_err"]
    seen_zero = False
    for seed in range(6):
        h, pole = _toy_run(0.0, 0.002, seed=seed)
        r = measure_point(h, _ToyProfile(), pole, 1.0, 0.0, gap=3.0, avg_length=20.0,
                          residual_tol=0.01)  # fmt: skip
        du, s = r["u_p_measured"] - 1.0, r["u_p_measured_err"]
        assert r["P_flow_err"] == pytest.approx(r["D"] * beyond_noise(du, s), abs=1e-12)
        seen_zero |= abs(du) <= s and r["P_flow_err"] == 0.0
    assert seen_zero


def test_P_error_takes_half_the_momentum_gap_beyond_its_noise():
    """The slab's P 0.6 % above the Rayleigh line P0 + ρ0 D u_p = 4 with little noise: the
    two measures of the jump's pressure part by 0.024, 10+ of their errors, so P's error
    gains half of it (0.012), whatever its block error says. Exact jumps under noise: a gap
    within its noise adds nothing (P_closure_err = ½ √max(0, gap² − σ²), as D's front-model
    term)."""
    from hugomap.analysis.shock import beyond_noise, measure_point

    h, pole = _toy_run(0.006, 0.0005)
    r = measure_point(h, _ToyProfile(), pole, 1.0, 0.0, gap=3.0, avg_length=20.0,
                      residual_tol=0.01)  # fmt: skip
    assert r["P_closure_err"] == pytest.approx(0.5 * 0.006 * 4.0, rel=0.1)
    assert r["P_err"] >= r["P_closure_err"] > 10 * r["P_flow_err"]
    seen_zero = False
    for seed in range(6):
        h, pole = _toy_run(0.0, 0.002, seed=seed)
        r = measure_point(h, _ToyProfile(), pole, 1.0, 0.0, gap=3.0, avg_length=20.0,
                          residual_tol=0.01)  # fmt: skip
        scale = r["D"] * r["u_p_jump"]  # ρ0 (D − 0)(u − 0): P − P_rh per unit residual
        gap, noise = r["residual_momentum"] * scale, r["residual_momentum_err"] * scale
        assert r["P_closure_err"] == pytest.approx(0.5 * beyond_noise(gap, noise), abs=1e-12)
        seen_zero |= abs(gap) <= noise and r["P_closure_err"] == 0.0
    assert seen_zero


def test_pores_left_open_in_a_steady_slab_are_not_a_cause():
    """A steady, uniform porous slab at distention 1.05 is a Hugoniot state of the porous
    body (Herrmann's P–α form): no cause is named for it; pores still closing show as a
    slab not uniform (its near and far halves' ρ apart beyond noise)."""
    from hugomap.analysis.causes import named_causes
    from hugomap.states import Pole

    base = {"residual_flow": 0.0, "residual_flow_err": 0.001, "rho": 9000.0, "P": 1e9,
            "E": 5e3, **AHEAD}  # fmt: skip
    pole = Pole(rho0=6600.0, T0=300.0, P0=0.0, E0=0.0)
    assert named_causes({**base, "alpha": 1.05, "alpha_err": 0.002}, 0.01, None, pole) == []
    closing = named_causes({**base, "alpha": 1.05, "alpha_err": 0.002}, 0.01,
                           {"rho": (60.0, 0.0)}, pole)  # fmt: skip
    assert len(closing) == 1 and closing[0].startswith("slab not uniform")


def test_a_slab_not_uniform_or_not_steady_beyond_tolerance_is_named():
    """Near/far-half and late/early differences beyond noise (``spread``) above
    residual_tol of the jump are named, the worst field with it; below it nothing is."""
    from hugomap.analysis.causes import named_causes
    from hugomap.states import Pole

    pole = Pole(rho0=1.0, P0=1.0, E0=0.0, T0=1.0, Pyy0=1.0, rho0_err=0.0, P0_err=0.0,
                E0_err=0.0, T0_err=0.0, Pyy0_err=0.0)  # fmt: skip
    v = {"rho": 1.5, "P": 4.0, "E": 0.5, "residual_flow": 0.0, "residual_flow_err": 0.01, **AHEAD}
    # jumps: rho 0.5, P 3, E 0.5; E's halves differ by 0.02 = 4 % of its jump
    causes = named_causes(v, 0.01, {"rho": (0.001, 0.0), "P": (0.0, 0.0), "E": (0.02, 0.0)}, pole)
    assert len(causes) == 1 and causes[0].startswith("slab not uniform")
    assert "4.00% of the jump in E" in causes[0]
    causes = named_causes(v, 0.01, {"rho": (0.0, 0.01), "P": (0.0, 0.0), "E": (0.0, 0.0)}, pole)
    assert len(causes) == 1 and causes[0].startswith("slab not steady")
    assert named_causes(v, 0.01, {"rho": (0.004, 0.004), "P": (0.02, 0.0)}, pole) == []


def test_a_window_slab_lagging_its_boundary_is_named_not_closed():
    """In a window (the flow a diagnostic, ``flow_closes`` False) a slab moving 1.96 ± 0.12 %
    of u_p slower than the outflow boundary (AMW on porous copper at 300 m/s) is named as a
    shocked region that is not uniform; 0.8 % (below residual_tol) or 1.96 ± 0.8 % (within 3
    errors) is not. Where the flow is a closure (the piston) it is named as a slab not at
    rest instead."""
    from hugomap.analysis.causes import named_causes

    v = {"residual_flow": -0.0196, "residual_flow_err": 0.0012, "u_p": 294.1,
         "u_p_measured": 294.1, "u_p_measured_err": 0.4, **AHEAD}  # fmt: skip
    causes = named_causes(v, 0.01, flow_closes=False)
    assert len(causes) == 1 and causes[0].startswith("shocked region not uniform")
    assert "-1.96% ± 0.12%" in causes[0]
    assert named_causes({**v, "residual_flow": -0.008}, 0.01, flow_closes=False) == []
    assert named_causes({**v, "residual_flow_err": 0.008}, 0.01, flow_closes=False) == []
    assert named_causes(v, 0.01)[0].startswith("slab not at rest")


def test_a_disturbed_state_ahead_is_named_unless_two_wave():
    """Material ahead moving at 0.064 ± 0.008 with P 0.40 ± 0.02 above P0 (AMW at u_p = 3 on
    the default liquid): 1.4 % of a 29.75 jump in P, 2.1 % of u_p, beyond 3 errors: named.
    Within its errors, below residual_tol of the jump, or flagged two_wave: not."""
    from hugomap.analysis.causes import named_causes
    from hugomap.states import Pole

    pole = Pole(rho0=0.8, P0=6.0, E0=-0.9, T0=2.0, Pyy0=6.0, rho0_err=0.0, P0_err=0.0,
                E0_err=0.0, T0_err=0.0, Pyy0_err=0.0)  # fmt: skip
    v = {"P": 35.75, "rho": 1.047, "u_p": 3.0, "residual_flow": 0.0, "residual_flow_err": 0.01,
         "ahead_P": 6.40, "ahead_P_err": 0.02, "ahead_u": 0.064, "ahead_u_err": 0.008,
         "ahead_rho": 0.8005, "ahead_rho_err": 0.002, "two_wave": 0.0}  # fmt: skip
    causes = named_causes(v, 0.01, pole=pole)
    assert len(causes) == 1 and causes[0].startswith("state ahead off the pole: its u")
    assert named_causes({**v, "two_wave": 1.0}, 0.01, pole=pole) == []
    quiet = {**v, "ahead_P_err": 0.2, "ahead_u_err": 0.03}
    assert named_causes(quiet, 0.01, pole=pole) == []
    assert named_causes(v, 0.03, pole=pole) == []


def test_two_waves_need_a_precursor_compressed_in_the_sense_of_the_main_jump():
    """The state ahead off the pole in P by 10 % of the main jump (P − P0 = 3 here), far beyond
    its noise, the state behind the exact jump from the pole: compressed (P +0.3, ρ +0.3 %,
    moving +0.01), it is a precursor and the jump is taken from it (``two_wave``; the
    residuals then show the mismatch); rarefied by as much (as a disturbed inflow can leave
    it: the MD window's material ahead once came out 0.5 % rarefied, P 4 % of the jump
    low), it is not: the jump is taken from the pole (residuals ~0 here) and the state ahead
    is named as off the pole."""
    from hugomap.analysis.causes import named_causes
    from hugomap.analysis.shock import measure_point

    for sign, two_wave in ((+1, 1.0), (-1, 0.0)):
        d = sign * 0.3
        h, pole = _toy_run(0.0, 0.0005, ahead=(0.01 * sign, 1.0 + 0.01 * d, 1.0 + d, 0.0))
        r = measure_point(h, _ToyProfile(), pole, 1.0, 0.0, gap=3.0, avg_length=20.0,
                          residual_tol=0.01)  # fmt: skip
        assert r["two_wave"] == two_wave, (sign, r["ahead_P"])
        off = abs(r["residual_momentum"]) > 0.05  # the jump from the precursor, not the pole
        assert off == bool(two_wave), r["residual_momentum"]
        causes = " ".join(named_causes({**r, "u_p": 1.0}, 0.01, pole=pole))
        assert ("state ahead off the pole" in causes) == (not two_wave), causes


def test_two_waves_are_measured_as_two_waves():
    """An elastic precursor at D_el = 5 (u 0.2) and a plastic wave at D = 3 (u_p = 1) from
    its state, both starting at x = 10 (the toy's exact jump states, 0.2 % noise): the
    precursor's plateau between the two fronts is shorter than the slab ahead
    (``avg_length`` 20) for the whole run, so read up to the far boundary the state ahead
    would mix plateau and pole. ``measure_point`` flags two waves, tracks the precursor's
    front (``precursor_D`` within 1 % of 5, the tracker's sub-bin accuracy over a 40-bin
    run, and within 3 of its stated errors), reads the state ahead on the plateau only (its u within 2 % of 0.2, P within
    1 % of the precursor's) and closes the plastic jump from it: ok."""
    from hugomap.analysis.shock import measure_point
    from hugomap.states import Pole

    rng = np.random.default_rng(5)
    D_el, u_el, D, u_p = 5.0, 0.2, 3.0, 1.0
    pre = _behind(1.0, 1.0, 0.0, 0.0, D_el, u_el)
    pla = _behind(*pre, u_el, D, u_p)
    t = np.linspace(0.5, 8.0, 200)
    xf, xp = 10.0 + D * t, 10.0 + D_el * t
    x = np.arange(1, 101)[None, :]
    region = (x > xf[:, None]).astype(int) + (x > xp[:, None]).astype(int)  # 0, 1, 2
    levels = np.array([[30.0, u_p, *pla], [30.0, u_el, *pre], [30.0, 0.0, 1.0, 1.0, 0.0]])
    sums = levels[region].copy()
    sums[..., 2:] *= 1 + 0.002 * rng.standard_normal(sums[..., 2:].shape)
    sums[..., 1] += 0.002 * rng.standard_normal(sums[..., 1].shape)
    h = {"t": t, "front": xf, "x_left": np.zeros(t.size), "x_right": np.full(t.size, 100.0),
         "sums": sums}  # fmt: skip
    pole = Pole(rho0=1.0, P0=1.0, E0=0.0, T0=1.0, Pyy0=1.0, rho0_err=0.0, P0_err=0.0,
                E0_err=0.0, T0_err=0.0, Pyy0_err=0.0)  # fmt: skip
    r = measure_point(h, _ToyProfile(), pole, u_p, 0.0, gap=3.0, avg_length=20.0,
                      residual_tol=0.01)  # fmt: skip
    assert r["two_wave"] == 1.0
    assert r["precursor_D"] == pytest.approx(D_el, rel=0.01), r["precursor_D"]
    # its stated error holds (the exact 5 within 3 errors) and resolves it (under 2 %)
    err = r["precursor_D_err"]
    assert abs(r["precursor_D"] - D_el) <= 3 * err and err < 0.02 * D_el, err
    assert r["ahead_u"] == pytest.approx(u_el, rel=0.02)
    assert r["ahead_P"] == pytest.approx(pre[1], rel=0.01)
    assert r["status"] == "ok", r["diagnostic"]
    assert abs(r["residual_momentum"]) < 0.01 and abs(r["residual_energy"]) < 0.01


def test_a_weak_precursor_is_read_as_a_first_wave():
    """A precursor at D_el = 5 carrying u 0.012 (P 2 % of the main jump, under
    ``TWO_WAVE_FRACTION``) fills everything ahead of a plastic wave at D = 3, u_p = 1 taken
    exactly from it (as in a window the precursor has left through its inflow). Read from the
    pole the state ahead is 1.2 % of u_p off it, so the point could not be ok; it is denser
    and moving in the sense of u_p beyond its noise (``weak_precursor``), so the jump is taken
    from it and closes. The same u and P ahead at the pole's density (no compression: a
    disturbed inflow) stay off the pole, not ok."""
    from hugomap.analysis.shock import TWO_WAVE_FRACTION, measure_point
    from hugomap.states import Pole

    rng = np.random.default_rng(7)
    u_el, D, u_p = 0.012, 3.0, 1.0
    pre = _behind(1.0, 1.0, 0.0, 0.0, 5.0, u_el)
    pla = _behind(*pre, u_el, D, u_p)
    t = np.linspace(0.5, 20.0, 200)
    xf = 10.0 + D * t
    x = np.arange(1, 101)[None, :]
    pole = Pole(rho0=1.0, P0=1.0, E0=0.0, T0=1.0, Pyy0=1.0, rho0_err=0.0, P0_err=0.0,
                E0_err=0.0, T0_err=0.0, Pyy0_err=0.0)  # fmt: skip
    for rho_ahead, status in ((pre[0], "ok"), (1.0, "not_converged")):
        levels = np.array([[30.0, u_p, *pla], [30.0, u_el, rho_ahead, pre[1], pre[2]]])
        sums = levels[(x > xf[:, None]).astype(int)].copy()
        sums[..., 2:] *= 1 + 0.0005 * rng.standard_normal(sums[..., 2:].shape)
        sums[..., 1] += 0.0005 * rng.standard_normal(sums[..., 1].shape)
        h = {"t": t, "front": xf, "x_left": np.zeros(t.size), "x_right": np.full(t.size, 100.0),
             "sums": sums}  # fmt: skip
        r = measure_point(h, _ToyProfile(), pole, u_p, 0.0, gap=3.0, avg_length=20.0,
                          residual_tol=0.01)  # fmt: skip
        assert r["ahead_P"] - 1.0 < TWO_WAVE_FRACTION * (r["P"] - 1.0)
        assert r["status"] == status, r["diagnostic"]
        assert r["two_wave"] == float(status == "ok")
        assert ("state ahead off the pole" in r["diagnostic"]) == (status != "ok")
        assert r["ahead_u"] == pytest.approx(u_el, rel=0.05)  # the precursor's plateau


def test_a_point_whose_state_ahead_is_off_the_pole_is_not_ok():
    """The state behind the exact jump from the pole (its residuals from the pole ~0), the
    material ahead moving at δu: at δu = 0.02 (2 % of u_p = 1, far beyond its noise) the
    jump from what is actually ahead is 2 % off in momentum, so the point is not ok and says
    why (``ahead_off_pole``); at δu = 0.005 (0.5 %, inside residual_tol = 1 %) it is ok."""
    from hugomap.analysis.shock import measure_point

    for du, status in ((0.02, "not_converged"), (0.005, "ok")):
        h, pole = _toy_run(0.0, 0.0005, ahead=(du, 1.0, 1.0, 0.0))
        r = measure_point(h, _ToyProfile(), pole, 1.0, 0.0, gap=3.0, avg_length=20.0,
                          residual_tol=0.01)  # fmt: skip
        assert abs(r["residual_momentum"]) < 0.002, r["residual_momentum"]
        assert r["status"] == status, (du, r["status"], r["diagnostic"])
        assert r["ahead_off_pole"] == float(status != "ok")
        assert ("state ahead off the pole" in r["diagnostic"]) == (status != "ok")


def test_material_ahead_that_arrives_warm_is_off_the_pole():
    """The state behind the exact jump from the pole, the material ahead at rest at ρ0, P0
    but warmer: E − E0 = 0.02 (2.4 % of the jump E − E0 = 0.83, far beyond its noise) moves
    the energy residual taken from it by that much, so the point is not ok, its residuals
    from the pole closed (a window's live inflow at weak shocks: +0.066 ε, 10 % of the jump,
    on the default liquid's AMW at u_p = 0.5); at 0.004 (0.5 %) it is ok."""
    from hugomap.analysis.shock import measure_point

    for dE, status in ((0.02, "not_converged"), (0.004, "ok")):
        h, pole = _toy_run(0.0, 0.0005, ahead=(0.0, 1.0, 1.0, dE))
        r = measure_point(h, _ToyProfile(), pole, 1.0, 0.0, gap=3.0, avg_length=20.0,
                          residual_tol=0.01)  # fmt: skip
        assert abs(r["residual_energy"]) < 0.002, r["residual_energy"]
        assert r["status"] == status, (dE, r["status"], r["diagnostic"])
        assert ("state ahead off the pole: its E differs" in r["diagnostic"]) == (status != "ok")


def test_a_run_without_any_slab_is_too_few_samples_not_an_error():
    """A front always nearer the boundaries than gap + the least slab (a window too short for
    its ``shock.gap``): no sample has a slab on either side, and the point is
    ``too_few_samples`` with NaN fields, not a KeyError from a field no slab supplied."""
    from hugomap.analysis.shock import measure_point

    h, pole = _toy_run(0.0, 0.002)
    r = measure_point(h, _ToyProfile(), pole, 1.0, 0.0, gap=60.0, avg_length=20.0,
                      residual_tol=0.01)  # fmt: skip
    assert r["status"] == "too_few_samples", r["diagnostic"]
    assert np.isnan(r["P"]) and np.isnan(r["Pyy"]) and np.isnan(r["shear_stress"])


def _slope_scatter_ratios(kind: str, n_runs: int = 400) -> tuple[float, float]:
    """RMS of slope_scatter (bounded, random-walk rule) over the true sd of the whole
    span's least-squares slope, for ``n_runs`` independent signals of 400 samples over
    T = 20: an Ornstein–Uhlenbeck wiggle (sd 1, correlation time 4 ≈ one of the four spans)
    or a random walk (unit diffusion)."""
    from hugomap.analysis.stats import line_fit, slope_scatter

    rng = np.random.default_rng(7)
    t = np.linspace(0.0, 20.0, 400)
    dt = t[1] - t[0]
    f = np.exp(-dt / 4.0)
    y = np.empty((n_runs, t.size))
    y[:, 0] = rng.standard_normal(n_runs)
    for i in range(1, t.size):
        step = rng.standard_normal(n_runs)
        y[:, i] = (
            f * y[:, i - 1] + np.sqrt(1 - f * f) * step
            if kind == "ou"
            else y[:, i - 1] + np.sqrt(dt) * step
        )
    sd = np.std([line_fit(t, yk)[0] for yk in y])
    rms = [
        np.sqrt(np.mean([slope_scatter(t, yk, bounded=b) ** 2 for yk in y])) / sd
        for b in (True, False)
    ]
    return rms[0], rms[1]


def test_slope_scatter_suits_each_kind_of_wander():
    """Reference: the sd of the slope over 400 independent runs. A bounded wiggle's span
    slopes shrink as 1/T, so std/n_sub is its error and the random-walk rule std/√n_sub
    reads about 2× high; a random walk's span slopes average to the whole one's, so
    std/√n_sub is its error and std/n_sub reads 2× low. The ±30 % band holds the estimator's
    own spread over 400 runs (a few %) and the OU rule's bias at this correlation time
    (measured 0.92)."""
    bounded, walk = _slope_scatter_ratios("ou")
    assert 0.7 < bounded < 1.3
    assert walk > 1.6
    bounded, walk = _slope_scatter_ratios("walk")
    assert 0.7 < walk < 1.3
    assert bounded < 0.6


def test_slab_series_is_the_series_the_point_averages():
    """``slab_series`` gives, per sample, the slab behind that ``measure_point`` averages: its
    mean u (relative to the upstream at rest here) is ``u_p_measured`` and its mean P is P,
    to rounding; a window point keeps these series for error studies against replicas."""
    from hugomap.analysis.shock import measure_point, slab_series

    h, pole = _toy_run(0.0, 0.002, flow=-0.01)
    r = measure_point(h, _ToyProfile(), pole, 1.0, 0.0, gap=3.0, avg_length=20.0,
                      residual_tol=0.01)  # fmt: skip
    u, P = slab_series(h, _ToyProfile(), ("u", "P"), gap=3.0, avg_length=20.0).values()
    assert u.shape == P.shape == np.asarray(h["t"]).shape
    assert np.isfinite(u).sum() == r["n_samples"]
    assert np.nanmean(u) == pytest.approx(r["u_p_measured"], rel=1e-12)
    assert np.nanmean(P) == pytest.approx(r["P"], rel=1e-12)
    assert np.nanstd(u) > 0  # the samples, not a constant


def test_a_front_that_has_not_yielded_is_named_elastic():
    """EAM copper along [100] at 500 m/s (the piston's slab: P_xx 21.6 GPa above P0, 2.23 GPa
    of shear, 10 % of the jump, errors 0.33 GPa in P_xx and 0.08 in P_yy, P_zz): flagged
    ``elastic_front`` and named; at 1500 m/s the window's 0.68 ± 0.20 GPa of shear on an
    80-GPa jump (0.85 %) is not, nor is 10 % of the jump within three of its errors."""
    from hugomap.analysis.causes import elastic_front, named_causes, shear_stress
    from hugomap.states import Pole

    pole = Pole(rho0=8810.8, P0=0.02e9, E0=0.0)
    P = 21.655e9
    Pyy = Pzz = P - 2 * 2.23e9
    v = {"P": P, "P_err": 0.334e9, "Pyy": Pyy, "Pyy_err": 0.084e9, "Pzz": Pzz,
         "Pzz_err": 0.084e9, **AHEAD}  # fmt: skip
    v["shear_stress"], v["shear_stress_err"] = shear_stress(v)
    assert v["shear_stress"] == pytest.approx(2.23e9)
    assert v["shear_stress_err"] == pytest.approx(0.5 * np.sqrt(0.334**2 + 0.5 * 0.084**2) * 1e9)
    assert elastic_front(v, pole)
    causes = named_causes({**v, "rho": 9000.0, "E": 1e4}, 0.01, None, pole)
    assert any(c.startswith("front not yielded") and "10.3%" in c for c in causes), causes
    window = {**v, "P": 80.66e9, "shear_stress": 0.678e9, "shear_stress_err": 0.20e9}
    assert not elastic_front(window, pole)
    noisy = {**v, "shear_stress_err": 1.0e9}
    assert not elastic_front(noisy, pole)
