"""The two-wave Hugoniot of an elastic–perfectly-plastic solid (hugomap.analysis.elastic_plastic).

References: without strength the plastic wave is the hydrodynamic shock, D = c0 + s u_p exactly
(the Mie–Grüneisen EOS is referenced to that Hugoniot), to the bisection's 1e-10 relative
precision; with strength the returned state must satisfy the three jump conditions across the
plastic wave from the HEL state, and σ_x = P(ρ, e) + 2Y/3 behind it (to rounding).
"""

from __future__ import annotations

import pytest

from hugomap.analysis.elastic_plastic import two_wave_state
from hugomap.eos import copper
from hugomap.eos.mie_gruneisen import pressure
from hugomap.strength import copper as copper_strength
from hugomap.strength import hydrodynamic


@pytest.mark.parametrize("up", [50.0, 500.0, 2000.0])
def test_without_strength_it_is_the_linear_hugoniot(up):
    w = two_wave_state(up, copper(), hydrodynamic())
    assert w["D_plastic"] == pytest.approx(3940.0 + 1.49 * up, rel=1e-9)
    assert w["sigma_HEL"] == 0.0 and w["u_HEL"] == 0.0


@pytest.mark.parametrize("up", [100.0, 1000.0])
def test_plastic_wave_satisfies_the_jump_conditions(up):
    eos, st = copper(), copper_strength()
    w = two_wave_state(up, eos, st)
    rho0 = eos.params[0]
    rho_h = rho0 * w["c_L"] / (w["c_L"] - w["u_HEL"])
    d, uh, sh = w["D_plastic"], w["u_HEL"], w["sigma_HEL"]
    assert rho_h * (d - uh) == pytest.approx(w["rho"] * (d - up), rel=1e-12)  # mass
    assert w["sigma_x"] - sh == pytest.approx(rho_h * (d - uh) * (up - uh), rel=1e-12)
    e_h = 0.5 * uh * uh
    de = 0.5 * (sh + w["sigma_x"]) * (1 / rho_h - 1 / w["rho"])
    assert w["e"] - e_h == pytest.approx(de, rel=1e-12)  # energy
    # on the yield surface: the EOS pressure plus 2Y/3 (bisection precision 1e-10 in D)
    p = pressure(w["rho"], w["e"], eos.params)
    assert w["sigma_x"] == pytest.approx(p + 2.0 * st.Y / 3.0, rel=1e-6)


def test_offset_from_the_hydrodynamic_line_is_small_positive_and_falls_with_u_p():
    offsets = [
        two_wave_state(up, copper(), copper_strength())["D_plastic"] / (3940.0 + 1.49 * up) - 1
        for up in (100.0, 500.0, 2000.0)
    ]
    assert 0.0 < offsets[2] < offsets[1] < offsets[0] < 0.005


def test_below_the_hel_there_is_no_plastic_wave():
    with pytest.raises(ValueError, match="u_HEL"):
        two_wave_state(3.0, copper(), copper_strength())
