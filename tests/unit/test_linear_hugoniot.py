"""The linear Us–up Hugoniot (hugomap.analysis.linear_hugoniot) against the Rankine–Hugoniot
jump conditions.

References: the three jump conditions across a steady shock into material at rest,
ρ0 D = ρ (D − u_p), P − P0 = ρ0 D u_p, E − E0 = ½ (P + P0)(V0 − V), each evaluated here from
the returned state, and the linear relation D = c0 + s u_p itself (the jump conditions hold
for any D). Poles: copper in SI (LASL fit, P0 = E0 = 0) and a reduced-unit fluid with
P0, E0 ≠ 0, so that the pole's terms count.

Tolerances: each residual is a handful of float64 operations, relative to its largest
term; V0 − V, formed from the returned V, loses log10(1/η) digits to cancellation, η = u_p/D
≥ 0.03 on these grids, so RTOL = 1e-13 (about 450 ulp) covers it with room.
"""

from __future__ import annotations

import numpy as np
import pytest

from hugomap.analysis.linear_hugoniot import compression_state, jump_state, shock_velocity
from hugomap.eos.mie_gruneisen import COPPER, reference_curve

RTOL = 1e-13
#: (rho0, c0, s, P0, E0, u_p grid): copper in SI; an LJ-like fluid in reduced units
POLES = {
    "copper_SI": (8930.0, 3940.0, 1.49, 0.0, 0.0, np.linspace(150.0, 4000.0, 12)),
    "fluid_reduced": (0.8, 6.2, 1.37, 2.3, -3.1, np.linspace(0.25, 6.0, 12)),
}


@pytest.mark.parametrize("pole", sorted(POLES))
def test_jump_conditions_close(pole):
    rho0, c0, s, P0, E0, u = POLES[pole]
    D, rho, V, P, E = jump_state(u, rho0, c0, s, P0, E0)
    V0 = 1.0 / rho0
    mass = (rho0 * D - rho * (D - u)) / (rho0 * D)
    momentum = (P - P0 - rho0 * D * u) / (rho0 * D * u)
    energy = (E - E0 - 0.5 * (P + P0) * (V0 - V)) / np.abs(0.5 * (P + P0) * (V0 - V))
    for name, r in (("mass", mass), ("momentum", momentum), ("energy", energy)):
        assert np.max(np.abs(r)) < RTOL, (name, r)
    np.testing.assert_allclose(V * rho, 1.0, rtol=RTOL)
    np.testing.assert_allclose(D - s * u, c0, rtol=RTOL)
    np.testing.assert_allclose(shock_velocity(u, c0, s), D, rtol=0)


@pytest.mark.parametrize("pole", sorted(POLES))
def test_compression_form_is_the_same_curve(pole):
    """P(η), E(η) at η = u_p/D are the state ``jump_state`` gives at u_p."""
    rho0, c0, s, P0, E0, u = POLES[pole]
    D, _, V, P, E = jump_state(u, rho0, c0, s, P0, E0)
    Pc, Ec = compression_state(u / D, rho0, c0, s, P0, E0)
    np.testing.assert_allclose(Pc, P, rtol=RTOL)
    np.testing.assert_allclose(Ec - E0, E - E0, rtol=RTOL)
    np.testing.assert_allclose(1.0 - V * rho0, u / D, rtol=RTOL)


def test_floats_and_arrays_agree():
    rho0, c0, s, P0, E0, u = POLES["fluid_reduced"]
    arrays = jump_state(u, rho0, c0, s, P0, E0)
    for k, uk in enumerate(u):
        one = jump_state(float(uk), rho0, c0, s, P0, E0)
        assert all(isinstance(v, float) for v in one)
        assert one == tuple(float(a[k]) for a in arrays)


@pytest.mark.parametrize("eta", [1e-4, 0.02, 0.1, 0.25, 0.4])
def test_mie_gruneisen_kernel_uses_the_curve(eta):
    """The EOS's reference curve (a numba kernel) is this module's P(η), E(η)."""
    rho0, c0, s = (float(v) for v in COPPER[:3])
    p, e, _ = reference_curve(eta, rho0, c0, s)
    Pc, Ec = compression_state(eta, rho0, c0, s)
    assert p == pytest.approx(Pc, rel=1e-15) and e == pytest.approx(Ec, rel=1e-15)
