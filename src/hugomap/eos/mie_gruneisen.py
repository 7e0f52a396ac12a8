"""Mie–Grüneisen equation of state referenced to the linear Us–up Hugoniot (SI units).

Reference curve (the principal Hugoniot of a linear Us = c0 + s·up material, pole ρ0, P = 0,
e = 0), with the compression η = 1 − ρ0/ρ (``analysis.linear_hugoniot.compression_state``,
compiled here for the kernels):

    P_H(η) = ρ0 c0² η / (1 − s η)²            [Pa]
    E_H(η) = P_H η / (2 ρ0)                   [J/kg]   (Rankine–Hugoniot energy, ½ P (V0 − V))

Off the reference curve, with the Grüneisen parameter taken as Γ ρ = Γ0 ρ0 (so Γ = Γ0 ρ0/ρ, the
usual assumption of hydrocodes for metals):

    P(ρ, e) = P_H(η) + Γ0 ρ0 (e − E_H(η))

Tension (η < 0): no Hugoniot exists; the reference is the linear continuation
P_ref = ρ0 c0² η (bulk modulus K0 = ρ0 c0²) with E_ref = P_ref η/(2 ρ0), which is continuous
with its first derivative at η = 0.

Bulk sound speed (isentropic): c² = ∂P/∂ρ|_e + (P/ρ²) ∂P/∂e, with ∂P/∂e = Γ0 ρ0 and
∂P/∂ρ|_e = (dP_H/dη − Γ0 ρ0 dE_H/dη) ρ0/ρ², dP_H/dη = ρ0 c0² (1 + s η)/(1 − s η)³,
dE_H/dη = (P_H + η dP_H/dη)/(2 ρ0). On the reference curve at η = 0: c = c0.
c² is floored at (C2_FLOOR·c0)² so that an expanded, hot particle never gets an imaginary
sound speed (the floor is far below any state reached in the tests).

The linear-Hugoniot denominator vanishes at η = 1/s; the formulae are evaluated with η capped
at ETA_MAX_FRACTION/s, and the solver stops a run whose density passes that cap
(``max_density``).

Copper (``COPPER``): ρ0 = 8930 kg/m³, c0 = 3940 m/s, s = 1.49, Γ0 = 2.0 — LASL Shock Hugoniot
Data (S. P. Marsh, ed., University of California Press, 1980), Table entry for Cu.
"""

from __future__ import annotations

import math

import numpy as np

from ..analysis import linear_hugoniot
from ..numba_conf import njit

ETA_MAX_FRACTION = 0.9
C2_FLOOR = 0.01

#: params layout: [rho0 (kg/m³), c0 (m/s), s (-), gamma0 (-)]
COPPER = np.array([8930.0, 3940.0, 1.49, 2.0])
COPPER_SOURCE = "LASL Shock Hugoniot Data (Marsh 1980): rho0=8930, c0=3940 m/s, s=1.49, G0=2.0"

#: ``linear_hugoniot.compression_state`` compiled for the kernels: (P_H, E_H) at η
_hugoniot_at_compression = njit(linear_hugoniot.compression_state)


@njit
def reference_curve(eta: float, rho0: float, c0: float, s: float) -> tuple[float, float, float]:
    """P_ref [Pa], E_ref [J/kg] and dP_ref/dη [Pa] at compression η = 1 − ρ0/ρ (docstring)."""
    k0 = rho0 * c0 * c0
    if eta >= 0.0:
        eta = min(eta, ETA_MAX_FRACTION / s)
        d = 1.0 - s * eta
        p, e = _hugoniot_at_compression(eta, rho0, c0, s)
        return p, e, k0 * (1.0 + s * eta) / (d * d * d)
    p = k0 * eta
    return p, p * eta / (2.0 * rho0), k0


@njit
def pressure(rho: float, e: float, params: np.ndarray) -> float:
    """P(ρ, e) = P_H(η) + Γ0 ρ0 (e − E_H(η)) [Pa]; ρ [kg/m³], e specific internal energy [J/kg]."""
    rho0 = params[0]
    eta = 1.0 - rho0 / rho
    ph, eh, _ = reference_curve(eta, rho0, params[1], params[2])
    return ph + params[3] * rho0 * (e - eh)


@njit
def pressure_sound_speed(rho: float, e: float, params: np.ndarray) -> tuple[float, float]:
    """(P [Pa], bulk sound speed c [m/s]) at density ρ [kg/m³], specific energy e [J/kg].

    c² = ∂P/∂ρ|_e + (P/ρ²) ∂P/∂e (module docstring), floored at (C2_FLOOR c0)².
    """
    rho0 = params[0]
    c0 = params[1]
    g0r0 = params[3] * rho0
    eta = 1.0 - rho0 / rho
    ph, eh, dph = reference_curve(eta, rho0, c0, params[2])
    p = ph + g0r0 * (e - eh)
    deh = (ph + eta * dph) / (2.0 * rho0)
    c2 = (dph - g0r0 * deh) * rho0 / (rho * rho) + p * g0r0 / (rho * rho)
    c2 = max(c2, (C2_FLOOR * c0) ** 2)
    return p, math.sqrt(c2)


def hugoniot_state(up: float, params: np.ndarray) -> dict[str, float]:
    """The shocked state on the linear Hugoniot for particle velocity ``up`` [m/s] (pole at rest,
    P = 0, e = 0): Us = c0 + s up, ρ = ρ0 Us/(Us − up), P = ρ0 Us up, e = ½ up² (SI;
    ``analysis.linear_hugoniot.jump_state``)."""
    rho0, c0, s = float(params[0]), float(params[1]), float(params[2])
    us, rho, _, p, e = linear_hugoniot.jump_state(up, rho0, c0, s)
    return {"Us": us, "rho": rho, "P": p, "e": e}
