"""Acoustic (linearised) Riemann solution on the line between two CSPH particles.

Parshikov & Medin, JCP 180(1) 2002 (doi:10.1006/jcph.2002.7099), and the seed talk: each pair
ij exchanges momentum and energy through the contact state (U*, σ*) of the discontinuity decay
between the two particles' states, projected on the pair axis e (from i, the "left" state, to
j, the "right" state). Stress σ is the Cauchy stress component on the contact plane, tension
positive [Pa]; velocity u its component along the same direction [m/s]; impedance Z = ρ c
[kg/(m² s)], longitudinal (c_l) for the normal components, shear (c_s) for a tangential one.

The two acoustic waves leaving the contact carry σ − σ_i = Z_i (u − u_i) into i (a wave moving
towards −e) and σ − σ_j = −Z_j (u − u_j) into j, so:

    U* = (Z_i u_i + Z_j u_j + σ_j − σ_i) / (Z_i + Z_j)
    σ* = (Z_j σ_i + Z_i σ_j + Z_i Z_j (u_j − u_i)) / (Z_i + Z_j)

(approaching particles, u_i > u_j, compress the contact: σ* < (Z_jσ_i + Z_iσ_j)/(Z_i+Z_j)).
A rigid wall (piston) moving at u_w on the j side: U* = u_w, σ* = σ_i + Z_i (u_w − u_i);
it is the pair solution with the mirror image of i (u_j = 2u_w − u_i, σ_j = σ_i).
"""

from __future__ import annotations

from ..numba_conf import njit


@njit
def contact(
    u_i: float, s_i: float, z_i: float, u_j: float, s_j: float, z_j: float
) -> tuple[float, float]:
    """(U* [m/s], σ* [Pa]) of the acoustic Riemann problem i | j along e (module docstring).

    Velocities u [m/s], stresses s [Pa] (tension positive), impedances z [kg/(m² s)] ≥ 0.
    ``csph.pair_rates`` calls this twice per pair: longitudinal (u, σ_n, Z_l) and shear
    (w, τ, Z_s). If both impedances are zero (no shear strength), U* = ½(u_i + u_j) and
    σ* = 0: the formula with 1/(Z_i + Z_j) replaced by a finite number, every term of its
    numerator a zero impedance times a finite value (the material carries no such stress;
    σ_i, σ_j are then zero up to round-off). A NaN input still gives a NaN σ*.
    """
    zs = z_i + z_j
    # Branch-free, so the pair loop that inlines it stays one straight block: for zs > 0 the
    # max returns zs and the result is exactly the formula's.
    inv = 1.0 / max(zs, 1e-300)
    u = (z_i * u_i + z_j * u_j + s_j - s_i) * inv if zs > 0.0 else 0.5 * (u_i + u_j)
    s = (z_j * s_i + z_i * s_j + z_i * z_j * (u_j - u_i)) * inv
    return u, s


@njit
def wall_contact(u_i: float, s_i: float, z_i: float, u_w: float) -> tuple[float, float]:
    """(U*, σ*) at a rigid wall moving at u_w on the +e side of i: (u_w, σ_i + Z_i (u_w − u_i))."""
    return u_w, s_i + z_i * (u_w - u_i)
