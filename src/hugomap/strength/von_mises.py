"""Elastic–perfectly-plastic von Mises strength: radial return of the deviatoric stress.

Deviatoric stress S (traceless, symmetric; plane strain and uniaxial strain need the components
xx, yy, zz, xy) [Pa]. Second invariant J2 = ½ S:S = ½(S_xx² + S_yy² + S_zz²) + S_xy², von Mises
equivalent stress σ_eq = √(3 J2). Yield condition σ_eq ≤ Y (i.e. J2 ≤ Y²/3).

Radial return (Wilkins 1964; e.g. Simo & Hughes, Computational Inelasticity, 1998, §3.3): a
trial stress outside the surface is scaled back onto it, S ← S·Y/σ_eq, and the equivalent
plastic strain grows by Δε_p = (σ_eq − Y)/(3 G) (the plastic part of the trial deviatoric
strain, in the equivalent-strain measure ε_p = ∫ √(2/3 ε̇_p:ε̇_p) dt).

Copper (``COPPER``): shear modulus G = 47.7 GPa and yield stress Y = 0.12 GPa, the
Steinberg–Guinan G0 and Y0 of OFHC copper (D. J. Steinberg, S. G. Cochran, M. W. Guinan,
J. Appl. Phys. 51, 1498 (1980), Table I), taken constant (no pressure, temperature or
work hardening: perfectly plastic).
"""

from __future__ import annotations

import math

import numpy as np

from ..numba_conf import njit

#: params layout: [G (Pa), Y (Pa)]
COPPER = np.array([47.7e9, 0.12e9])
COPPER_SOURCE = (
    "Steinberg, Cochran & Guinan, J. Appl. Phys. 51, 1498 (1980): G0=47.7 GPa, Y0=0.12 GPa"
)


@njit
def equivalent_stress(sxx: float, syy: float, szz: float, sxy: float) -> float:
    """σ_eq = √(3 J2) [Pa], J2 = ½(S_xx² + S_yy² + S_zz²) + S_xy²."""
    j2 = 0.5 * (sxx * sxx + syy * syy + szz * szz) + sxy * sxy
    return math.sqrt(3.0 * j2)


@njit
def radial_return(
    sxx: float, syy: float, szz: float, sxy: float, G: float, Y: float
) -> tuple[float, float, float, float, float]:
    """Return (S_xx, S_yy, S_zz, S_xy) on or inside the yield surface and Δε_p ≥ 0.

    S ← S·min(1, Y/σ_eq); Δε_p = max(σ_eq − Y, 0)/(3G). Idempotent: a stress on the surface
    is returned unchanged with Δε_p = 0.
    """
    seq = equivalent_stress(sxx, syy, szz, sxy)
    if seq > Y:
        f = Y / seq
        return sxx * f, syy * f, szz * f, sxy * f, (seq - Y) / (3.0 * G)
    return sxx, syy, szz, sxy, 0.0


def hel(G: float, Y: float, K: float) -> float:
    """Hugoniot elastic limit σ_HEL = Y (1 − ν)/(1 − 2ν) = Y (K + 4G/3)/(2G) [Pa] (uniaxial
    strain, von Mises), with Poisson ratio ν = (3K − 2G)/(2(3K + G)); K bulk modulus [Pa]."""
    nu = (3.0 * K - 2.0 * G) / (2.0 * (3.0 * K + G))
    return Y * (1.0 - nu) / (1.0 - 2.0 * nu)
