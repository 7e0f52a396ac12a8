"""Strength models for CSPH, one model per module, chosen by name.

``Strength(name, params, source)``: "none" (hydrodynamic, ``none``) or "von_mises"
(elastic–perfectly-plastic, ``von_mises``). params = [G (Pa), Y (Pa)] for both. The solver
kernels take ``kind`` (STRENGTH_KINDS) and ``params``.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from . import none, von_mises

STRENGTH_KINDS = {"none": 0, "von_mises": 1}


@dataclass(frozen=True)
class Strength:
    """A strength model: ``name`` (a key of STRENGTH_KINDS), ``params`` [G, Y] in Pa,
    ``source`` (the literature the numbers come from)."""

    name: str
    params: np.ndarray = field(default_factory=lambda: none.PARAMS.copy(), repr=False)
    source: str = ""

    def __post_init__(self) -> None:
        if self.name not in STRENGTH_KINDS:
            raise ValueError(
                f"unknown strength model {self.name!r}; known: {sorted(STRENGTH_KINDS)}"
            )
        p = np.asarray(self.params, dtype=np.float64)
        if p.shape != (2,):
            raise ValueError(f"strength params must be [G, Y] in Pa, got shape {p.shape}")
        if self.name == "none":
            p = none.PARAMS.copy()
        else:
            G, Y = p
            if not (G > 0.0 and Y > 0.0):
                raise ValueError(f"von_mises needs G > 0 and Y > 0 (Pa), got G={G}, Y={Y}")
            if Y >= G:
                raise ValueError(
                    f"yield stress Y={Y:.4g} Pa is not below the shear modulus G={G:.4g} Pa: "
                    "the yield strain Y/(3G) would exceed 1/3 (not a metal; check units)"
                )
        object.__setattr__(self, "params", p)

    @property
    def kind(self) -> int:
        return STRENGTH_KINDS[self.name]

    @property
    def G(self) -> float:
        return float(self.params[0])

    @property
    def Y(self) -> float:
        return float(self.params[1])


def hydrodynamic() -> Strength:
    """No strength."""
    return Strength("none")


def copper() -> Strength:
    """Copper, von Mises with Steinberg–Guinan G0, Y0 (see ``von_mises``)."""
    return Strength("von_mises", von_mises.COPPER.copy(), von_mises.COPPER_SOURCE)
