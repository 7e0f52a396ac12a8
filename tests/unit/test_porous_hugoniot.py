"""Porous and solid Hugoniots from the copper Mie–Grüneisen EOS (hugomap.analysis.porous).

References: the linear Us–up fit D = c0 + s·u_p itself (α = 1), the Rankine–Hugoniot jump
conditions, the Mie–Grüneisen surface P = P_H + (Γ0/V0)(E − E_H) (an independent formula from
the one the module solves), a value worked out by hand at V/V0 = 0.95, and the snowplow limit.

Tolerances: states solved from u_p come from a bisection on the compression η = 1 − V/V0 that
stops when the bracket is one ulp of η wide; D, P, E are then a handful of float64 operations
on η, so they agree with closed forms to a few ulp: RTOL = 1e-14 (≈ 45 ulp). Checks that form
V00 − V or V0 − V from the returned V lose log10(V0/(V00 − V)) digits to cancellation, at most a
factor 1/η ≈ 400 at u_p = 10 m/s and α = 1 (η = 0.0025), i.e. ≈ 4e-14: RTOL_DV = 1e-13.
The hand value is exact rational arithmetic rounded once; rtol 1e-13.
"""

from __future__ import annotations

import numpy as np
import pytest

from hugomap.analysis.porous import (
    COPPER,
    MGSolid,
    partial_compaction_from_up,
    pore_collapse_distention,
    porous_hugoniot_from_up,
    porous_hugoniot_from_volume,
    porous_hugoniot_pressure,
    snowplow_hugoniot,
    solid_hugoniot_from_up,
    solid_hugoniot_pressure,
)

UP = np.array([10.0, 50.0, 100.0, 200.0, 500.0, 1000.0, 2000.0, 4000.0])  # [m/s]
RTOL = 1e-14
RTOL_DV = 1e-13  # checks that subtract volumes (see the module doc)


def test_alpha_one_reproduces_the_linear_us_up_hugoniot():
    st = porous_hugoniot_from_up(UP, 1.0)
    np.testing.assert_allclose(st.D, COPPER.c0 + COPPER.s * UP, rtol=RTOL, atol=0)
    ref = solid_hugoniot_from_up(UP)
    for name in ("P", "V", "rho", "E"):
        np.testing.assert_allclose(getattr(st, name), getattr(ref, name), rtol=RTOL, atol=0)
    # And from the volume side, without any root solve.
    V = COPPER.V0 * np.linspace(0.72, 0.999, 30)
    sv = porous_hugoniot_from_volume(V, 1.0)
    np.testing.assert_allclose(sv.D, COPPER.c0 + COPPER.s * sv.u_p, rtol=RTOL, atol=0)
    np.testing.assert_array_equal(porous_hugoniot_pressure(V, 1.0), solid_hugoniot_pressure(V))


@pytest.mark.parametrize("alpha", [1.0, 1.1, 1.35, 1.8])
def test_jump_conditions_and_eos_surface_hold(alpha):
    st = porous_hugoniot_from_up(UP, alpha)
    V00, rho00 = alpha * COPPER.V0, COPPER.rho0 / alpha
    assert st.rho00 == pytest.approx(rho00, rel=1e-15)
    # Mass: ρ00 D = ρ (D − u_p); momentum: P = ρ00 D u_p; energy: E = ½ P (V00 − V) = ½ u_p².
    np.testing.assert_allclose(rho00 * st.D, st.rho * (st.D - st.u_p), rtol=RTOL)
    np.testing.assert_allclose(st.P, rho00 * st.D * st.u_p, rtol=RTOL)
    np.testing.assert_allclose(st.E, 0.5 * st.P * (V00 - st.V), rtol=RTOL_DV)
    np.testing.assert_allclose(st.E, 0.5 * UP**2, rtol=RTOL)
    # The state lies on the solid's Mie–Grüneisen surface: P = P_H(V) + (Γ0/V0)(E − E_H(V)),
    # written here in the compression η = 1 − V/V0 the state carries (V itself has only the
    # digits of V0 − V: at u_p = 10 m/s, α = 1.8, η ≈ 3e-6 and V-based P_H keeps ~11 digits).
    np.testing.assert_allclose(st.V, COPPER.V0 * (1.0 - st.eta), rtol=RTOL)
    c, eta = COPPER, st.eta
    PH = c.rho0 * c.c0**2 * eta / (1.0 - c.s * eta) ** 2
    EH = 0.5 * PH * c.V0 * eta
    np.testing.assert_allclose(st.P, PH + c.gamma0 / c.V0 * (st.E - EH), rtol=RTOL)


def test_porous_hugoniot_lies_above_the_solid_one_and_is_monotonic():
    V = COPPER.V0 * np.linspace(0.70, 0.999, 200)
    P_s = solid_hugoniot_pressure(V)
    prev = P_s
    for alpha in (1.05, 1.2, 1.35, 1.6):
        P_p = porous_hugoniot_pressure(V, alpha)
        # Γ0 > 0: the pore-closing work is heat, whose pressure adds to the solid's.
        assert np.all(P_p > prev) and np.all(P_s > 0)
        assert np.all(np.diff(P_p) < 0)  # P falls as V grows
        prev = P_p
    # Γ0 = 0: no thermal pressure, the porous curve is the solid one.
    cold = MGSolid(COPPER.rho0, COPPER.c0, COPPER.s, 0.0)
    np.testing.assert_array_equal(porous_hugoniot_pressure(V, 1.35, cold), P_s)
    st = porous_hugoniot_from_up(UP, 1.35)
    assert np.all(np.diff(st.D) > 0) and np.all(np.diff(st.P) > 0) and np.all(np.diff(st.V) < 0)
    assert np.all(st.V < COPPER.V0)


def test_hand_computed_point():
    # V/V0 = 0.95, α = 1.35, copper: η = 0.05,
    # P_H = 8930·3940²·0.05/(1 − 1.49·0.05)² = 6 931 337 400/0.85655025 = 8.092096639981133e9 Pa,
    # bracket ratio with Γ0 = 2: [1 − (1 − 0.95)]/[1 − (1.35 − 0.95)] = 0.95/0.6,
    # P = 1.2812486346636795e10 Pa (exact fractions, rounded to float64).
    V = 0.95 * COPPER.V0
    assert solid_hugoniot_pressure(V) == pytest.approx(8.092096639981133e9, rel=1e-13)
    P = porous_hugoniot_pressure(V, 1.35)
    assert P == pytest.approx(1.2812486346636795e10, rel=1e-13)
    # u_p = √(P·0.4·V0) = 757.5668703944 m/s, D = 1.35 V0 √(P/(0.4 V0)) = 2556.788187581 m/s.
    st = porous_hugoniot_from_volume(V, 1.35)
    assert float(st.u_p) == pytest.approx(757.566870394442, rel=1e-13)
    assert float(st.D) == pytest.approx(2556.7881875812423, rel=1e-13)
    back = porous_hugoniot_from_up(757.566870394442, 1.35)
    assert float(back.V) == pytest.approx(V, rel=1e-13)


def test_weak_shock_tends_to_the_snowplow_limit():
    alpha = 1.35
    sp = snowplow_hugoniot(UP, alpha, COPPER.rho0)
    # The snowplow state itself satisfies the jump conditions with V = V0.
    np.testing.assert_allclose(sp.P, sp.rho00 * sp.D * sp.u_p, rtol=RTOL)
    np.testing.assert_allclose(sp.D, UP * alpha / (alpha - 1), rtol=RTOL)
    np.testing.assert_allclose(sp.P, COPPER.rho0 / alpha * UP**2 * alpha / (alpha - 1), rtol=RTOL)
    st = porous_hugoniot_from_up(UP, alpha)
    rel = np.abs(st.D / sp.D - 1)
    # The full-compaction model approaches the snowplow limit as u_p → 0 (the solid's own
    # compression is O(P/K)) and is always slower (V < V0 ⇒ D = u_p V00/(V00 − V) smaller).
    assert rel[0] < 1e-3 and np.all(np.diff(rel) > 0) and np.all(st.D < sp.D)


def test_bad_arguments_are_refused():
    with pytest.raises(ValueError, match="alpha"):
        porous_hugoniot_from_up(100.0, 0.9)
    with pytest.raises(ValueError, match="u_p"):
        porous_hugoniot_from_up(0.0, 1.35)
    with pytest.raises(ValueError, match="alpha = 2.5 must be < 1 \\+ 2/Γ0"):
        porous_hugoniot_from_up(100.0, 2.5)
    with pytest.raises(ValueError, match="V must lie in"):
        porous_hugoniot_pressure(0.3 * COPPER.V0, 1.35)
    with pytest.raises(ValueError, match="compressive"):
        porous_hugoniot_from_volume(1.1 * COPPER.V0, 1.35)
    with pytest.raises(ValueError, match="gamma0"):
        MGSolid(8930.0, 3940.0, 1.49, -1.0)


# The partial-compaction state: solved for η to one ulp as the full-compaction one is, so
# it meets the closed forms to the same few ulp (RTOL); volume differences lose the same
# digits as above (RTOL_DV).
def test_partial_compaction_at_full_compaction_is_mcqueen():
    for alpha0 in (1.1, 1.35):
        a = porous_hugoniot_from_up(UP, alpha0)
        b = partial_compaction_from_up(UP, alpha0, 1.0)
        for name in ("D", "P", "V", "E", "eta"):
            np.testing.assert_allclose(getattr(b, name), getattr(a, name), rtol=RTOL_DV)


@pytest.mark.parametrize(("alpha", "tau"), [(1.02, 0.0), (1.05, 7.0e7), (1.2, 0.0)])
def test_partial_compaction_closes_the_jump_on_the_herrmann_surface(alpha, tau):
    up = UP[UP >= 100.0]
    st = partial_compaction_from_up(up, 1.35, alpha, deviator=tau)
    V00, rho00 = 1.35 * COPPER.V0, COPPER.rho0 / 1.35
    np.testing.assert_allclose(rho00 * st.D, st.rho * (st.D - st.u_p), rtol=RTOL_DV)
    np.testing.assert_allclose(st.E, 0.5 * st.P * (V00 - st.V), rtol=RTOL_DV)
    # The matrix on the solid's Mie–Grüneisen surface at V_s = V/α, its mean stress over α,
    # plus the slab's deviator (Herrmann's P–α form).
    c, eta = COPPER, st.eta
    np.testing.assert_allclose(st.V, alpha * c.V0 * (1.0 - eta), rtol=RTOL)
    PH = c.rho0 * c.c0**2 * eta / (1.0 - c.s * eta) ** 2
    Ps = PH + c.gamma0 / c.V0 * (st.E - 0.5 * PH * c.V0 * eta)
    np.testing.assert_allclose(st.P, Ps / alpha + tau, rtol=RTOL_DV)
    # Pores left open make the shocked state less dense, so the front is faster at equal u_p.
    assert np.all(st.D > porous_hugoniot_from_up(up, 1.35).D)


def test_pore_collapse_distention_hand_values():
    # Carroll & Holt: P = k ln(α/(α − 1)) with k = Y/√3 (2D) or (2/3) Y (3D); at P = k ln 2
    # the pores hold α = 2, whatever Y.
    Y = 1.2e8
    assert pore_collapse_distention(Y / np.sqrt(3.0) * np.log(2.0), Y, 2) == pytest.approx(2.0)
    assert pore_collapse_distention(2.0 / 3.0 * Y * np.log(2.0), Y, 3) == pytest.approx(2.0)
    with pytest.raises(ValueError):
        pore_collapse_distention(-1.0, Y, 2)
    with pytest.raises(ValueError, match="below the initial distention"):
        partial_compaction_from_up(100.0, 1.35, 1.4)
    with pytest.raises(ValueError, match="too weak"):
        partial_compaction_from_up(10.0, 1.35, 1.05, deviator=8.0e7)
