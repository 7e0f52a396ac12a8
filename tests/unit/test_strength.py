"""von Mises elastic–perfectly-plastic strength: radial return and the HEL formula.

The return is exact arithmetic on four numbers, so the checks are at round-off (1e-12):
the returned stress lies on the yield surface σ_eq = Y, a second return changes nothing
(idempotent), a stress inside is untouched, the deviator stays traceless, and Δε_p equals
(σ_eq − Y)/(3G) (the plastic part of the trial strain in equivalent-strain measure).
HEL: Y (1 − ν)/(1 − 2ν) must equal Y (K + 4G/3)/(2G) (linear elasticity identity).
"""

from __future__ import annotations

import numpy as np
import pytest

from hugomap.strength import Strength, copper, hydrodynamic
from hugomap.strength.von_mises import equivalent_stress, hel, radial_return

G, Y = 47.7e9, 0.12e9


def _dev(rng):
    a = rng.normal(size=3) * 1e8
    a -= a.mean()
    return a[0], a[1], a[2], rng.normal() * 1e8


def test_return_lands_on_surface_and_is_idempotent():
    rng = np.random.default_rng(1)
    for _ in range(50):
        s = _dev(rng)
        seq = equivalent_stress(*s)
        r = radial_return(*s, G, Y)
        if seq > Y:
            assert abs(equivalent_stress(*r[:4]) / Y - 1.0) < 1e-12
            assert abs(r[4] - (seq - Y) / (3 * G)) < 1e-12 * r[4] + 1e-300
            r2 = radial_return(*r[:4], G, Y)
            assert np.allclose(r2[:4], r[:4], rtol=1e-15, atol=0.0)
            assert r2[4] <= 1e-12 * Y / (3 * G)  # round-off can leave σ_eq = Y(1 + ε)
        else:
            assert r[:4] == s and r[4] == 0.0
        assert abs(r[0] + r[1] + r[2]) < 1e-6  # traceless (Pa, against 1e8 Pa components)


def test_uniaxial_strain_yield():
    # uniaxial strain: S_yy = S_zz = −S_xx/2, σ_eq = 1.5 |S_xx|; yield at |S_xx| = 2Y/3
    sxx = -0.1e9
    r = radial_return(sxx, -sxx / 2, -sxx / 2, 0.0, G, Y)
    assert abs(r[0] + 2 * Y / 3) < 1e-6


def test_hel_identity():
    K = 8930.0 * 3940.0**2
    assert abs(hel(G, Y, K) / (Y * (K + 4 * G / 3) / (2 * G)) - 1.0) < 1e-14
    assert abs(hel(G, Y, K) / 0.2544e9 - 1.0) < 1e-3


def test_models_and_validation():
    cu = copper()
    assert cu.kind == 1 and cu.G == 47.7e9 and cu.Y == 0.12e9 and "Steinberg" in cu.source
    assert hydrodynamic().kind == 0 and hydrodynamic().G == 0.0
    with pytest.raises(ValueError, match="not below the shear modulus"):
        Strength("von_mises", [1e9, 2e9])
    with pytest.raises(ValueError, match="G > 0"):
        Strength("von_mises", [0.0, 1e8])
    with pytest.raises(ValueError, match="unknown strength"):
        Strength("johnson_cook", [1e9, 1e8])
