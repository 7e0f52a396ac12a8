"""Equations of state for CSPH, one model per module, chosen by name.

Each model module exposes ``pressure_sound_speed(rho, e, params) -> (P, c)`` (numba, SI units)
with its own float ``params`` layout. ``EOS`` binds a name to its params; the solver kernels
dispatch on ``EOS.kind`` (an int, so numba can take it) through ``eos_pc``.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..numba_conf import njit
from . import ideal_gas, mie_gruneisen

EOS_KINDS = {"mie_gruneisen": 0, "ideal_gas": 1}


@dataclass(frozen=True)
class EOS:
    """An equation of state: ``name`` (a key of EOS_KINDS), ``params`` (the model's float
    layout, see its module), ``source`` (where the numbers come from)."""

    name: str
    params: np.ndarray = field(repr=False)
    source: str = ""

    def __post_init__(self) -> None:
        if self.name not in EOS_KINDS:
            raise ValueError(f"unknown EOS {self.name!r}; known: {sorted(EOS_KINDS)}")
        object.__setattr__(self, "params", np.asarray(self.params, dtype=np.float64))

    @property
    def kind(self) -> int:
        return EOS_KINDS[self.name]

    def pressure_sound_speed(self, rho: float, e: float) -> tuple[float, float]:
        """(P [Pa], bulk sound speed [m/s]) at ρ [kg/m³], e [J/kg]."""
        return eos_pc(self.kind, self.params, float(rho), float(e))


def copper() -> EOS:
    """Copper, Mie–Grüneisen on the linear Hugoniot (LASL data; see ``mie_gruneisen``)."""
    return EOS("mie_gruneisen", mie_gruneisen.COPPER.copy(), mie_gruneisen.COPPER_SOURCE)


def ideal(gamma: float) -> EOS:
    """Ideal gas P = (γ − 1) ρ e."""
    if not gamma > 1.0:
        raise ValueError(f"ideal gas needs gamma > 1, got {gamma}")
    return EOS("ideal_gas", np.array([gamma]), "ideal gas")


@njit
def eos_pc(kind: int, params: np.ndarray, rho: float, e: float) -> tuple[float, float]:
    """(P [Pa], c [m/s]) of model ``kind`` (EOS_KINDS) at ρ [kg/m³], e [J/kg]."""
    if kind == 0:
        return mie_gruneisen.pressure_sound_speed(rho, e, params)
    return ideal_gas.pressure_sound_speed(rho, e, params)
