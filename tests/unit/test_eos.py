"""Equations of state: Mie–Grüneisen (copper, LASL linear Hugoniot) and ideal gas.

References: on the reference Hugoniot the EOS must give the Rankine–Hugoniot pressure
P = ρ0 Us up with Us = c0 + s up, ρ = ρ0 Us/(Us − up), e = ½ up² (exact by construction, so
the tolerance is round-off, 1e-12). Sound speed: c² = (∂P/∂ρ)_s, checked by a centred finite
difference along the isentrope de = P dρ/ρ² (error O(δ²); δ = 1e-5 ρ gives ~1e-9 relative,
the tolerance 1e-6 leaves room for the round-off of the difference, ~1e-16/1e-5·|P/c²ρ|).
"""

from __future__ import annotations

import numpy as np
import pytest

from hugomap.eos import EOS, copper, eos_pc, ideal
from hugomap.eos.mie_gruneisen import hugoniot_state


@pytest.mark.parametrize("up", [50.0, 500.0, 1000.0, 2000.0, 3000.0])
def test_pressure_on_linear_hugoniot(up):
    eos = copper()
    h = hugoniot_state(up, eos.params)
    rho0, c0, s = eos.params[:3]
    us = c0 + s * up
    rho = rho0 * us / (us - up)
    p, _ = eos.pressure_sound_speed(rho, 0.5 * up * up)
    assert abs(p / (rho0 * us * up) - 1.0) < 1e-12
    assert abs(h["rho"] / rho - 1.0) < 1e-15 and abs(h["P"] / p - 1.0) < 1e-12


def test_reference_state_and_sound_speed():
    eos = copper()
    p, c = eos.pressure_sound_speed(8930.0, 0.0)
    assert p == 0.0 and abs(c / 3940.0 - 1.0) < 1e-14


def _isentropic_c2(eos: EOS, rho: float, e: float, rel: float = 1e-5) -> float:
    d = rel * rho
    p0, _ = eos.pressure_sound_speed(rho, e)

    # second-order isentrope step: de = P dρ/ρ² with P at the midpoint (Heun)
    def step(sign):
        p1, _ = eos.pressure_sound_speed(rho + sign * d, e + sign * p0 * d / rho**2)
        pm = 0.5 * (p0 + p1)
        rm = rho + 0.5 * sign * d
        return eos.pressure_sound_speed(rho + sign * d, e + sign * pm * d / rm**2)[0]

    return (step(1) - step(-1)) / (2 * d)


@pytest.mark.parametrize(
    "rho,e",
    [
        (8940.0, 0.0),
        (10000.0, 1.3e5),
        (12500.0, 2.0e6),
        (8800.0, 1.0e4),
        (8500.0, 0.0),
    ],  # not at ρ0 itself: the two branches meet there with a kink in d²P/dρ²
)
def test_mie_gruneisen_sound_speed_fd(rho, e):
    eos = copper()
    _, c = eos.pressure_sound_speed(rho, e)
    assert abs(_isentropic_c2(eos, rho, e) / c**2 - 1.0) < 1e-6


def test_tension_branch_is_linear_and_continuous():
    eos = copper()
    rho0, c0 = eos.params[:2]
    for eta in (-1e-3, -0.02):
        rho = rho0 / (1.0 - eta)
        # on the reference curve's energy, P = ρ0 c0² η exactly
        e_ref = rho0 * c0**2 * eta * eta / (2.0 * rho0)
        p, c = eos.pressure_sound_speed(rho, e_ref)
        assert abs(p / (rho0 * c0**2 * eta) - 1.0) < 1e-12
        assert c > 0.0
    eps = 1e-9
    assert abs(eos.pressure_sound_speed(rho0 / (1 + eps), 0.0)[1] - c0) < 1e-3


def test_ideal_gas():
    eos = ideal(1.4)
    p, c = eos.pressure_sound_speed(1.0, 2.5)
    assert abs(p - 1.0) < 1e-15 and abs(c * c - 1.4) < 1e-14
    assert abs(_isentropic_c2(eos, 1.0, 2.5) / c**2 - 1.0) < 1e-6
    assert eos_pc(1, np.array([1.4]), 1.0, 0.0) == (0.0, 0.0)


def test_bad_eos_refused():
    with pytest.raises(ValueError, match="unknown EOS"):
        EOS("tillotson", np.zeros(3))
    with pytest.raises(ValueError, match="gamma"):
        ideal(1.0)
