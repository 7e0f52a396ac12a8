"""The two-wave Hugoniot of an elastic–perfectly-plastic solid in uniaxial strain (SI units).

A piston at u_p into a von Mises solid (shear modulus G, yield stress Y) drives two waves:

1. an elastic precursor at the longitudinal speed c_L = √((K + 4G/3)/ρ0), K = ρ0 c0², to the
   Hugoniot elastic limit σ_HEL = Y (K + 4G/3)/(2G) (``strength.von_mises.hel``), with
   u_HEL = σ_HEL/(ρ0 c_L), ρ_HEL = ρ0 c_L/(c_L − u_HEL), e_HEL = ½ u_HEL²
   (a shock from rest: e − e0 = ½ u²);
2. a plastic wave from that state to u_p, behind which the deviator sits on the yield surface
   in compression, so the longitudinal stress (compression positive) is
       σ_x = P(ρ, e) + 2Y/3
   (uniaxial strain: s_xx = −2Y/3 at yield, σ_xx = −P + s_xx).

The plastic wave's speed D_p solves the jump conditions across it, from the HEL state:
    ρ_HEL (D_p − u_HEL) = ρ (D_p − u_p),
    σ_x − σ_HEL = ρ_HEL (D_p − u_HEL)(u_p − u_HEL),
    e − e_HEL = ½ (σ_HEL + σ_x)(1/ρ_HEL − 1/ρ),
with P(ρ, e) the Mie–Grüneisen EOS (``eos.mie_gruneisen.pressure``, energy e including the
elastic and plastic work, as in the solver). With Y = 0 the precursor vanishes and
D_p = c0 + s u_p exactly (the EOS is referenced to that Hugoniot). The offset D_p − (c0 + s u_p)
is the plastic wave's departure from the hydrodynamic line: for copper (Steinberg–Guinan
G = 47.7 GPa, Y = 0.12 GPa) +0.23 % at 100 m/s falling to +0.08 % at 2000 m/s. (Zel'dovich &
Raizer, Physics of Shock-Wave and High-Temperature Hydrodynamic Phenomena, ch. XI; Meyers,
Dynamic Behavior of Materials, 1994, ch. 7: elastic–plastic waves in uniaxial strain.)
"""

from __future__ import annotations

import math

from ..eos import EOS
from ..eos.mie_gruneisen import pressure
from ..strength import Strength
from ..strength.von_mises import hel
from .linear_hugoniot import shock_velocity


def two_wave_state(u_p: float, eos: EOS, strength: Strength) -> dict[str, float]:
    """The elastic precursor and the plastic wave for piston velocity ``u_p`` [m/s] (module
    docstring): D_plastic [m/s], sigma_x [Pa], rho [kg/m³], e [J/kg] behind it; c_L [m/s],
    sigma_HEL [Pa], u_HEL [m/s] of the precursor; D_hydro = c0 + s u_p [m/s]. ``u_p`` must
    exceed u_HEL (else the wave is elastic only)."""
    if eos.name != "mie_gruneisen":
        raise ValueError(f"two_wave_state needs the mie_gruneisen EOS, got {eos.name!r}")
    rho0, c0, s = (float(v) for v in eos.params[:3])
    K = rho0 * c0 * c0
    G, Y = strength.G, strength.Y
    if strength.name == "none" or Y == 0.0:
        c_l, s_hel, u_hel = c0, 0.0, 0.0
    else:
        c_l = math.sqrt((K + 4.0 * G / 3.0) / rho0)
        s_hel = hel(G, Y, K)
        u_hel = s_hel / (rho0 * c_l)
    if not u_p > u_hel:
        raise ValueError(f"u_p = {u_p:.4g} m/s is below u_HEL = {u_hel:.4g} m/s: no plastic wave")
    rho_h = rho0 * c_l / (c_l - u_hel)
    e_h = 0.5 * u_hel * u_hel
    y23 = 2.0 * Y / 3.0 if strength.name != "none" else 0.0

    def state(d: float) -> tuple[float, float, float]:
        rho = rho_h * (d - u_hel) / (d - u_p)
        sx = s_hel + rho_h * (d - u_hel) * (u_p - u_hel)
        e = e_h + 0.5 * (s_hel + sx) * (1.0 / rho_h - 1.0 / rho)
        return rho, sx, e

    def f(d: float) -> float:
        rho, sx, e = state(d)
        return pressure(rho, e, eos.params) + y23 - sx

    # f > 0 for a wave too slow (too much compression for its stress), < 0 too fast: bisect
    # between just above u_p and well above the hydrodynamic speed.
    d_hydro = shock_velocity(u_p, c0, s)
    lo, hi = u_p + 1e-6 * (c0 + u_p), 2.0 * d_hydro + c_l
    if not (f(lo) > 0.0 > f(hi)):
        raise ValueError(f"no plastic wave speed found in ({lo:.4g}, {hi:.4g}) m/s")
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        if f(mid) > 0.0:
            lo = mid
        else:
            hi = mid
        if hi - lo < 1e-10 * mid:
            break
    d = 0.5 * (lo + hi)
    rho, sx, e = state(d)
    return {"D_plastic": d, "sigma_x": sx, "rho": rho, "e": e, "c_L": c_l,
            "sigma_HEL": s_hel, "u_HEL": u_hel, "D_hydro": d_hydro}  # fmt: skip
