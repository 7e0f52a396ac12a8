"""The linear Us–up Hugoniot: the states behind a steady shock in a material whose shock
velocity is linear in the particle velocity.

Source: the Rankine–Hugoniot jump conditions across a steady plane shock moving at D into
material at rest in the state (ρ0, P0, E0), V0 = 1/ρ0 (Zel'dovich & Raizer, Physics of
Shock Waves and High-Temperature Hydrodynamic Phenomena, ch. I §17):

    mass        ρ0 D = ρ (D − u_p)
    momentum    P − P0 = ρ0 D u_p
    energy      E − E0 = ½ (P + P0)(V0 − V)

closed by the linear relation D = c0 + s u_p (the usual fit of shock data on solids, as in
the LASL Shock Hugoniot Data compilation). By particle velocity (``jump_state``):

    D = c0 + s u_p,   ρ = ρ0 D/(D − u_p),   V = (1 − u_p/D)/ρ0,
    P = P0 + ρ0 D u_p,   E = E0 + ½ u_p² + P0 (V0 − V),   V0 − V = u_p/(ρ0 D),

the energy written with (P − P0)(V0 − V) = u_p² (so with P0 = 0 it is ½ u_p² exactly). By
compression η = 1 − V/V0 = u_p/D (``compression_state``: u_p = η D and D = c0 + s η D give
D = c0/(1 − s η)):

    P = P0 + ρ0 c0² η/(1 − s η)²,   E = E0 + (P + P0) η/(2 ρ0),

finite for s η < 1. Units: any consistent set, e.g. SI (u_p, D, c0 [m/s], s [-],
ρ [kg/m³], V [m³/kg], P [Pa], E [J/kg]) or reduced LJ units; E is specific (per mass).

Every function is plain arithmetic on its arguments: it takes floats or numpy arrays
(broadcast together), and a numba kernel compiles the same function with
``numba_conf.njit`` (``eos.mie_gruneisen``); this module imports nothing (no numba, no
numpy), so light modules (scene checks, the test models) use it too.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, TypeVar

if TYPE_CHECKING:
    import numpy as np

#: a float or a numpy array (the functions broadcast)
F = TypeVar("F", float, "np.ndarray")


def shock_velocity(u_p: F, c0: float, s: float) -> F:
    """D = c0 + s u_p [velocity]: the linear Us–up relation (module docstring)."""
    return c0 + s * u_p


def jump_state(
    u_p: F, rho0: float, c0: float, s: float, P0: float = 0.0, E0: float = 0.0
) -> tuple[F, F, F, F, F]:
    """(D, ρ, V, P, E) behind a steady shock of particle velocity ``u_p`` (with D > u_p)
    into material at rest at (ρ0, P0, E0): D = c0 + s u_p, ρ = ρ0 D/(D − u_p),
    V = (1 − u_p/D)/ρ0, P = P0 + ρ0 D u_p, E = E0 + ½ u_p² + P0 u_p/(ρ0 D) (the
    Rankine–Hugoniot jump conditions with the linear Us–up relation; module docstring).
    Units: consistent (SI: m/s, kg/m³, m³/kg, Pa, J/kg)."""
    D = c0 + s * u_p
    rho = rho0 * D / (D - u_p)
    V = (1.0 - u_p / D) / rho0
    P = P0 + rho0 * D * u_p
    E = E0 + 0.5 * u_p * u_p + P0 * (u_p / (rho0 * D))
    return D, rho, V, P, E


def compression_state(
    eta: F, rho0: float, c0: float, s: float, P0: float = 0.0, E0: float = 0.0
) -> tuple[F, F]:
    """(P, E) on the linear Us–up Hugoniot at compression η = 1 − V/V0 = u_p/D (s η < 1):
    P = P0 + ρ0 c0² η/(1 − s η)², E = E0 + (P + P0) η/(2 ρ0) (the energy jump
    condition ½ (P + P0)(V0 − V) with V0 − V = η/ρ0; module docstring). Units: consistent
    (SI: Pa, J/kg from kg/m³, m/s)."""
    d = 1.0 - s * eta
    P = P0 + rho0 * c0 * c0 * eta / (d * d)
    return P, E0 + (P + P0) * eta / (2.0 * rho0)


__all__ = ["compression_state", "jump_state", "shock_velocity"]
