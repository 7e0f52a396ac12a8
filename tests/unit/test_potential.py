"""The LJ pair function ``lj_pair``: shift, minimum, force = −dU/dr, cutoff.

Reference: the textbook LJ forms in ``_reference`` (φ, φ', φ'', φ''' written out term by term).
"""

from __future__ import annotations

import numpy as np
import pytest

from hugomap.md.potential import LJParams, lj_energy_unshifted, lj_pair

from ._reference import EPS, d3phi, dphi, phi

RC = 2.5


def _pair(r: float, lj: LJParams) -> tuple[float, float]:
    return lj_pair(r * r, lj.rc * lj.rc, lj.ushift)


def _eval_err(r: float, lj: LJParams) -> float:
    # Absolute round-off of one evaluation of U: a few ulp of each of the terms 4 r⁻¹²,
    # 4 r⁻⁶ and U_c that are added (r² and r⁻⁶ carry ~3 ulp each, so 10 ulp is generous).
    return 10.0 * EPS * (4.0 * r**-12 + 4.0 * r**-6 + abs(lj.ushift))


def test_ushift_is_u_at_rc_and_zero_when_unshifted():
    # U_c = 4 (rc⁻¹² − rc⁻⁶) (textbook form, a different evaluation order): a few ulp of U_c.
    assert LJParams(rc=RC).ushift == pytest.approx(phi(RC), rel=8 * EPS, abs=0)
    assert LJParams(rc=RC, shift=False).ushift == 0.0


@pytest.mark.parametrize("rc", [1.5, 2.5, 3.0])
def test_shifted_energy_vanishes_at_rc(rc):
    lj = LJParams(rc=rc, shift=True)
    rc2 = rc * rc
    # Exactly at and beyond rc the pair is cut: U = 0 exactly.
    assert lj_pair(rc2, rc2, lj.ushift) == (0.0, 0.0)
    # Just inside (one ulp below rc²) U(r) − U(rc) = U'(rc)(r − rc) ≈ 1e-16 · |U'(rc)|: what
    # is left is the round-off of subtracting U_c from U(r) ≈ U_c, _eval_err.
    u_in, _ = lj_pair(np.nextafter(rc2, 0.0), rc2, lj.ushift)
    assert abs(u_in) <= _eval_err(rc, lj)
    # The shift matters: without it U jumps by U_LJ(rc) ≠ 0 at the cutoff (rel. 10 ulp).
    u_in_unshifted, _ = lj_pair(np.nextafter(rc2, 0.0), rc2, 0.0)
    assert u_in_unshifted == pytest.approx(phi(rc), rel=10 * EPS)
    assert abs(phi(rc)) > 1e3 * _eval_err(rc, lj)


@pytest.mark.parametrize("shift", [True, False])
def test_minimum_at_two_to_the_sixth(shift):
    lj = LJParams(rc=RC, shift=shift)
    r2 = 2.0 ** (1.0 / 3.0)  # r = 2^(1/6): U_LJ = −1, dU/dr = 0
    u, f_over_r = lj_pair(r2, RC * RC, lj.ushift)
    # U is stationary at the minimum, so the ~1 ulp error of r² enters only at second order;
    # the rest is the round-off of 4 r⁻⁶ (r⁻⁶ − 1) − U_c, a few ulp of 1.
    assert abs(u - (-1.0 - lj.ushift)) <= 8 * EPS
    # F/r = 24 r⁻⁸ (2 r⁻⁶ − 1): the bracket is 2 × (1/2 + a few ulp) − 1 = O(ulp), times 24 r⁻⁸.
    assert abs(f_over_r) <= 24.0 * 2 ** (-4.0 / 3.0) * 8 * EPS
    if shift:  # −1 + |U_c|: the shift raises the well depth by U(rc) = −0.0163
        assert u == pytest.approx(-1.0 + 0.016316891136, abs=1e-12)


@pytest.mark.parametrize("r", [0.9, 0.95, 1.0, 1.05, 2.0 ** (1 / 6), 1.3, 1.7, 2.2, 2.45])
@pytest.mark.parametrize("shift", [True, False])
def test_force_is_minus_du_dr(r, shift):
    """F(r) = (F/r)·r equals −dU/dr by a central finite difference of lj_pair's energy."""
    lj = LJParams(rc=RC, shift=shift)
    h = 1e-4
    u_plus, _ = _pair(r + h, lj)
    u_minus, _ = _pair(r - h, lj)
    fd = -(u_plus - u_minus) / (2 * h)
    _, f_over_r = _pair(r, lj)
    # Central difference: truncation h²/6 · max |U'''| on [r − h, r + h] (|U'''| is decreasing
    # for r < 1.12 and small beyond, so take the larger end-point value, ×1.01 for the interior)
    # plus the evaluation round-off of the two energies divided by 2h; a few ulp for F itself.
    trunc = h * h / 6.0 * 1.01 * max(abs(d3phi(r - h)), abs(d3phi(r + h)))
    round_off = (_eval_err(r - h, lj) + _eval_err(r + h, lj)) / (2 * h)
    tol = trunc + round_off + 8 * EPS * abs(dphi(r))
    assert abs(f_over_r * r - fd) <= tol
    # The test has teeth: the tolerance is far below |F| (except at the minimum where F = 0).
    assert tol < 1e-5 * max(abs(dphi(r)), 1.0)
    # And F agrees with the textbook −φ'(r) to a few ulp of its two terms.
    assert f_over_r * r == pytest.approx(-dphi(r), abs=16 * EPS * (48 * r**-13 + 24 * r**-7))


@pytest.mark.parametrize("shift", [True, False])
@pytest.mark.parametrize("r", [RC, RC * (1 + 1e-15), RC + 0.1, 3.0, 10.0])
def test_zero_beyond_rc(r, shift):
    lj = LJParams(rc=RC, shift=shift)
    r2 = max(r * r, RC * RC)
    assert lj_pair(r2, RC * RC, lj.ushift) == (0.0, 0.0)


def test_energy_unshifted_textbook():
    r = np.array([0.8, 1.0, 1.5, 2.5, 4.0])
    got = np.array([lj_energy_unshifted(x * x) for x in r])
    # Same function, different evaluation order: a few ulp of the two terms 4 r⁻¹², 4 r⁻⁶.
    np.testing.assert_allclose(got, phi(r), rtol=0, atol=1e-14 * np.max(4 * r**-12))
    assert lj_energy_unshifted(1.0) == 0.0


@pytest.mark.parametrize(("rc", "skin"), [(0.5, 0.3), (10.5, 0.3), (2.5, 0.0), (2.5, 2.5)])
def test_params_validated(rc, skin):
    with pytest.raises(ValueError):
        LJParams(rc=rc, skin=skin)


def test_rlist():
    assert LJParams(rc=2.5, skin=0.3).rlist == pytest.approx(2.8, abs=4 * EPS)
