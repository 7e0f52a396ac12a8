"""Ideal-gas equation of state (used for Sod's shock tube): P = (γ − 1) ρ e, c = √(γ P / ρ).

Units: ρ [kg/m³], e specific internal energy [J/kg], P [Pa], c [m/s]. The params layout is
[γ]. A non-positive pressure (possible only from round-off in a strong rarefaction) gives
c = 0 rather than NaN.
"""

from __future__ import annotations

import math

import numpy as np

from ..numba_conf import njit


@njit
def pressure(rho: float, e: float, params: np.ndarray) -> float:
    """P = (γ − 1) ρ e [Pa]."""
    return (params[0] - 1.0) * rho * e


@njit
def pressure_sound_speed(rho: float, e: float, params: np.ndarray) -> tuple[float, float]:
    """(P [Pa], c = √(γ P/ρ) [m/s])."""
    p = (params[0] - 1.0) * rho * e
    return p, math.sqrt(max(params[0] * p / rho, 0.0))
