"""CSPH kernels: per-particle state, wall ghosts, pair sums, time step, update (SI units).

Equations: Parshikov & Medin, J. Comput. Phys. 180(1), 2002 (doi:10.1006/jcph.2002.7099), as
written in the source talk (Murzov et al., VANT 2025), in 2D plane strain (1D: uniaxial strain,
y terms vanish). Stress σ = −P I + S (tension positive), S deviatoric; ∇_i W_ij = −W'_ij e_ij
with e_ij = (r_j − r_i)/r_ij the unit vector from i to j and W' = dW/dr (r_ij, h_ij) ≤ 0
(``kernel.dwdr``), h_ij = θ (l_i + l_j) (``kernel.pair_h``). Per pair, the acoustic Riemann
solution (``riemann.contact``) along e (normal: longitudinal impedance ρ c_l and
σ_n = e·σ·e; tangential t = (−e_y, e_x): shear impedance ρ c_s and τ = t·σ·e) gives the
contact velocity U* = u* e + w* t and traction σ*·e = σ_n* e + τ* t. Then

    dv_i/dt     = −2 Σ_j m_j/(ρ_i ρ_j) (σ*_ij · e_ij) W'_ij                       [m/s²]
    dE_i/dt     = −2 Σ_j m_j/(ρ_i ρ_j) (σ*_ij · e_ij) · U*_ij W'_ij               [W/kg]
    L_i^{ab}    = −2 Σ_j (m_j/ρ_j) (U*_ij − v_i)^a e_ij^b W'_ij  (velocity gradient ∂v^a/∂x^b) [1/s]
    μ̇_i        = tr L_i = −2 Σ_j (m_j/ρ_j)(u*_ij − v_i·e_ij) W'_ij                 [1/s]
    dS_i/dt     = 2 G (D_i − tr D_i/3 I),  D = sym L  (plus the rotation by Ω, below)
    ω_i         = ½ (L^{yx} − L^{xy})  (rotation rate about z)                      [1/s]

These are the seed's equations with its sign conventions made explicit: its ε̇ = μ̇ = ∇·v
(ρ(t+Δt) = ρ exp(−μ̇Δt)); its σ* is the compression-positive contact stress and its e_ij points
from j to i (so both flip sign here and the products agree); its u*^k in dS/dt is the relative
contact velocity (U*_ij − U_i)^k, and its [U_i, e_ij] in ω likewise uses U_i − U*_ij (with the
absolute U_i a rigid translation would rotate the stress at a free surface).

Gradient correction (an addition to the seed, on by default; ``correct=False`` gives the
seed's sums unchanged): with M_i^{ab} = −Σ_j (m_j/ρ_j) r_ij e^a e^b W'_ij and B_i = M_i⁻¹
(Bonet & Lok, CMAME 180, 97 (1999)), L_i is multiplied by B_i (exact for a linear velocity
field, free surfaces included), and in the momentum and energy sums the gradient −W' e becomes
g_ij = −W' B̄_ij e, B̄_ij = ½(B_i + B_j), contracted with the contact stress tensor
σ*_ij = σ_n* e⊗e + τ*(e⊗t + t⊗e) + ½(σ_tt,i + σ_tt,j) t⊗t (the Riemann traction on the pair
plane; the tangential-normal part σ_tt, which no pair Riemann problem gives, averaged). g_ij is
antisymmetric in ij, so momentum and total energy stay conserved to round-off. Why: the
discrete kernel sum Σ_j (m_j/ρ_j) r |W'| is 0.980 of 1 for θ = 0.6 in 1D (0.964 on a 2D
square lattice), so without B the stress carried across a plane is 0.98 σ and the continuity
density under-tracks the real compression: the copper shock speed comes out 1.8–1.9 % low
for u_p = 100–2000 m/s (−0.9 % to +0.03 % with it; tests/physics/test_sph_piston.py).

Density. The seed integrates the continuity equation, ρ(t+Δt) = ρ exp(−μ̇Δt) (``continuity``).
Its μ̇ is exact for a linear velocity field, but through a shock a few particles wide the
weights of its pair sum change while the pair distances change unevenly, and what a particle
takes through the front stays with it: behind a 1D copper shock the continuity density is
0.19, 0.83, 2.7 % below the particle spacing's m/Δx at u_p = 1000, 2000, 4000 m/s (the same
at half the spacing). Momentum and total energy are conserved pairwise (E_kin + E_int equals
the piston's work to round-off, e = u_p²/2 behind the front), so the EOS is evaluated at the
wrong density and the shock speed comes out low: −0.39, −0.89, −1.7 %. The ``kernel_ratio``
density removes that memory: each step multiplies ρ by the change of the kernel sum
n̂_i = Σ_j W(r_ij, h_ij) (j = i included; a number density: with the masses m_j in it, a
heavy neighbour across a contact discontinuity would count in a light particle's density)
over the step,

    ρ_i(t+Δt) = ρ_i(t) n̂_i(x(t+Δt), l*) / n̂_i(x(t), l(t)),   l* = (m/ρ*)^(1/dim),
    ρ* = ρ exp(−μ̇Δt) (the continuity prediction, for the smoothing lengths at t+Δt; then
    refined: n̂(t+Δt) again with l from the ratio's own ρ, ``simulation.KERNEL_RATIO_PASSES``),

so that over a run ρ_i/ρ_i(0) = n̂_i(t)/n̂_i(0) to O(Δt) per step: a function of where the
particles are, not of how they got there. On a uniform line of spacing Δx (h ∝ l) n̂ is
1/Δx times a constant, so behind the front ρ = m/Δx whatever the front did; the initial
normalisation (free surfaces, the kernel's lattice sum) cancels in the ratio. It needs the
neighbourhood to keep its particles, so it is the 1D default (particles keep their order);
in 2D a pore that closes would bring new neighbours into n̂ and the ratio would read them as
compression, so 2D keeps the continuity equation (``simulation.density_mode``).
"""

from __future__ import annotations

import math

import numpy as np

from ..eos import eos_pc
from ..numba_conf import njit, pjit, prange
from ..strength.von_mises import radial_return
from .kernel import dwdr, pair_h, w
from .neighbors import image_lengths, min_image
from .riemann import contact

# Columns of the packed per-particle array (real particles, then wall ghosts).
PX, PY, PVX, PVY, PM, PRHO, PL, PSXX, PSYY, PSXY, PZL, PZS, PCL, PBXX, PBXY, PBYY = range(16)
NPACK = 16
# Columns of the per-particle rates.
RVX, RVY, RE, RLXX, RLXY, RLYX, RLYY, RMU = range(8)
NRATE = 8
# Status codes of ``update``.
OK, NAN, EOS_RANGE = 0, 1, 2


@pjit
def pack(
    x: np.ndarray,
    v: np.ndarray,
    m: np.ndarray,
    rho: np.ndarray,
    e: np.ndarray,
    S: np.ndarray,
    l: np.ndarray,
    eos_kind: int,
    eos_p: np.ndarray,
    strength_p: np.ndarray,
    pk: np.ndarray,
    pressure: np.ndarray,
) -> None:
    """Rows 0..n−1 of ``pk`` (NPACK columns) and P [Pa]: positions, velocities, m, ρ, l,
    stress σ = −P I + S, impedances Z_l = ρ c_l, Z_s = ρ c_s and c_l, with
    c_l² = c_b² + 4G/(3ρ), c_s² = G/ρ, c_b the EOS bulk sound speed [m/s]."""
    n = x.shape[0]
    dim = x.shape[1]
    G = strength_p[0]
    for i in prange(n):
        r = rho[i]
        p, cb = eos_pc(eos_kind, eos_p, r, e[i])
        cl = math.sqrt(cb * cb + 4.0 * G / (3.0 * r))
        pressure[i] = p
        pk[i, PX] = x[i, 0]
        pk[i, PVX] = v[i, 0]
        if dim == 2:
            pk[i, PY] = x[i, 1]
            pk[i, PVY] = v[i, 1]
        else:
            pk[i, PY] = 0.0
            pk[i, PVY] = 0.0
        pk[i, PM] = m[i]
        pk[i, PRHO] = r
        pk[i, PL] = l[i]
        pk[i, PSXX] = S[i, 0] - p
        pk[i, PSYY] = S[i, 1] - p
        pk[i, PSXY] = S[i, 3]
        pk[i, PZL] = r * cl
        pk[i, PZS] = math.sqrt(G * r)
        pk[i, PCL] = cl


@njit
def fill_ghosts(pk: np.ndarray, n: int, src: np.ndarray, side: np.ndarray, walls: np.ndarray):
    """Ghost rows n.. of ``pk``: the mirror images of particles ``src`` in the wall ``side``
    (0 left, 1 right) at x_w = walls[2 side] moving at u_w = walls[2 side + 1] [m, m/s].

    Mirror: x → 2x_w − x, v_x → 2u_w − v_x, σ_xy → −σ_xy, the rest copied; the pair of a
    particle and its own image then gives exactly the wall solution U* = u_w,
    σ* = σ_i + Z_i (u_w − u_i) (``riemann.wall_contact``), and the other ghosts complete the
    kernel sums near the wall (a free-slip rigid wall: the piston).
    """
    for g in range(src.shape[0]):
        i = src[g]
        k = n + g
        xw = walls[2 * side[g]]
        uw = walls[2 * side[g] + 1]
        for c in range(NPACK):
            pk[k, c] = pk[i, c]
        pk[k, PX] = 2.0 * xw - pk[i, PX]
        pk[k, PVX] = 2.0 * uw - pk[i, PVX]
        pk[k, PSXY] = -pk[i, PSXY]
        pk[k, PBXY] = -pk[i, PBXY]


# M's eigenvalues are held at or above this before inverting: M ≈ 0.96 I in the bulk of a
# square lattice, while a particle on a one-particle chain between pores has an eigenvalue of
# 0.002 across the chain, and M⁻¹ would multiply its velocity gradient 500-fold (porous copper
# at 100 m/s: five such particles reached ρ 2.2 ρ_s and e −63 MJ/kg, Δt fell 60-fold)
EIG_FLOOR = 0.1


@njit
def floored_inverse(mxx: float, mxy: float, myy: float) -> tuple[float, float, float]:
    """(B_xx, B_xy, B_yy) of B = Q diag(1/max(λ_k, ``EIG_FLOOR``)) Qᵀ for the symmetric 2×2
    M = Q diag(λ_1, λ_2) Qᵀ [-]: M⁻¹ wherever both eigenvalues reach the floor, so a linear
    field stays exact there; the gradient along a direction M barely samples is amplified at
    most 1/``EIG_FLOOR``-fold. B = I when λ_2 (the larger) is itself below the floor."""
    half = 0.5 * (mxx + myy)
    q = math.sqrt(0.25 * (mxx - myy) ** 2 + mxy * mxy)
    l1 = half - q
    l2 = half + q
    if l2 < EIG_FLOOR:
        return 1.0, 0.0, 1.0
    if l1 >= EIG_FLOOR:
        det = mxx * myy - mxy * mxy
        return myy / det, -mxy / det, mxx / det
    # unit eigenvector of λ_1: the larger of two equivalent forms (one vanishes if mxy = 0)
    ax, ay = mxy, l1 - mxx
    bx, by = l1 - myy, mxy
    if ax * ax + ay * ay < bx * bx + by * by:
        ax, ay = bx, by
    # λ_1 < λ_2 here (q > 0), so the larger form is never the zero vector
    norm = math.sqrt(ax * ax + ay * ay)
    ax /= norm
    ay /= norm
    # B = (1/λ_2)(I − a aᵀ) + (1/floor) a aᵀ
    d = 1.0 / EIG_FLOOR - 1.0 / l2
    return 1.0 / l2 + d * ax * ax, d * ax * ay, 1.0 / l2 + d * ay * ay


@pjit
def correction(
    pk: np.ndarray,
    n: int,
    dim: int,
    nbr: np.ndarray,
    nnb: np.ndarray,
    theta: float,
    periodic: np.ndarray,
    length: np.ndarray,
    correct: bool,
) -> None:
    """B_i = M_i⁻¹ into pk[:n, PBXX:PBYY+1], M_i^{ab} = −Σ_j (m_j/ρ_j) r_ij e^a e^b W'_ij
    (module docstring), with M's eigenvalues raised to ``EIG_FLOOR`` first (``floored_inverse``);
    B = I where the correction is off or M has almost no weight at all (1D: M < ``EIG_FLOOR``;
    2D: its larger eigenvalue below it, a particle with almost no neighbours)."""
    Lx, Ly, iLx, iLy = image_lengths(periodic, length)
    for i in prange(n):
        bxx = 1.0
        bxy = 0.0
        byy = 1.0
        if correct:
            xi = pk[i, PX]
            yi = pk[i, PY]
            li = pk[i, PL]
            mxx = 0.0
            mxy = 0.0
            myy = 0.0
            for k in range(nnb[i]):
                j = nbr[i, k]
                dx = pk[j, PX] - xi
                dy = pk[j, PY] - yi
                dx = min_image(dx, Lx, iLx)
                dy = min_image(dy, Ly, iLy)
                r2 = dx * dx + dy * dy
                r = math.sqrt(r2)
                wp = dwdr(r, pair_h(li, pk[j, PL], theta), dim)
                gm = -pk[j, PM] / pk[j, PRHO] * wp / r
                mxx += gm * dx * dx
                mxy += gm * dx * dy
                myy += gm * dy * dy
            if dim == 1:
                if mxx > EIG_FLOOR:
                    bxx = 1.0 / mxx
            else:
                bxx, bxy, byy = floored_inverse(mxx, mxy, myy)
        pk[i, PBXX] = bxx
        pk[i, PBXY] = bxy
        pk[i, PBYY] = byy


@pjit
def pair_rates(
    pk: np.ndarray,
    n: int,
    dim: int,
    nbr: np.ndarray,
    nnb: np.ndarray,
    theta: float,
    periodic: np.ndarray,
    length: np.ndarray,
    dev_mean: bool,
    out: np.ndarray,
) -> None:
    """Per-particle rates (NRATE columns: dv_x/dt, dv_y/dt, dE/dt, L_xx, L_xy, L_yx, L_yy, μ̇)
    from the pair sums of the module docstring, one row per thread-iteration (deterministic).

    μ̇ = tr(L B) always uses the contact velocity U*. ``dev_mean``: the L columns (which
    drive dS/dt and ω) use the mean velocity ½(v_i + v_j) instead of U* (module docstring)."""
    Lx, Ly, iLx, iLy = image_lengths(periodic, length)
    for i in prange(n):
        xi = pk[i, PX]
        yi = pk[i, PY]
        vxi = pk[i, PVX]
        vyi = pk[i, PVY]
        rhoi = pk[i, PRHO]
        li = pk[i, PL]
        sxxi = pk[i, PSXX]
        syyi = pk[i, PSYY]
        sxyi = pk[i, PSXY]
        zli = pk[i, PZL]
        zsi = pk[i, PZS]
        bxxi = pk[i, PBXX]
        bxyi = pk[i, PBXY]
        byyi = pk[i, PBYY]
        ax = 0.0
        ay = 0.0
        de = 0.0
        lxx = 0.0
        lxy = 0.0
        lyx = 0.0
        lyy = 0.0
        mu = 0.0
        for k in range(nnb[i]):
            j = nbr[i, k]
            dx = pk[j, PX] - xi
            dy = pk[j, PY] - yi
            dx = min_image(dx, Lx, iLx)
            dy = min_image(dy, Ly, iLy)
            r = math.sqrt(dx * dx + dy * dy)
            ir = 1.0 / r
            ex = dx * ir
            ey = dy * ir
            wp = dwdr(r, pair_h(li, pk[j, PL], theta), dim)
            vxj = pk[j, PVX]
            vyj = pk[j, PVY]
            sxxj = pk[j, PSXX]
            syyj = pk[j, PSYY]
            sxyj = pk[j, PSXY]
            # normal (e) and tangential (t = (−e_y, e_x)) components
            ui = vxi * ex + vyi * ey
            uj = vxj * ex + vyj * ey
            wi = vyi * ex - vxi * ey
            wj = vyj * ex - vxj * ey
            txi = sxxi * ex + sxyi * ey
            tyi = sxyi * ex + syyi * ey
            txj = sxxj * ex + sxyj * ey
            tyj = sxyj * ex + syyj * ey
            sni = txi * ex + tyi * ey
            snj = txj * ex + tyj * ey
            tti = tyi * ex - txi * ey
            ttj = tyj * ex - txj * ey
            # contact states: longitudinal (u*, σ_n*) and shear (w*, τ*) Riemann problems
            ustar, sstar = contact(ui, sni, zli, uj, snj, pk[j, PZL])
            wstar, tstar = contact(wi, tti, zsi, wj, ttj, pk[j, PZS])
            mj = pk[j, PM]
            vj = mj / pk[j, PRHO]
            # corrected pair gradient g = −W' B̄ e, B̄ = ½(B_i + B_j) (antisymmetric in ij)
            bxx = 0.5 * (bxxi + pk[j, PBXX])
            bxy = 0.5 * (bxyi + pk[j, PBXY])
            byy = 0.5 * (byyi + pk[j, PBYY])
            gx = -wp * (bxx * ex + bxy * ey)
            gy = -wp * (bxy * ex + byy * ey)
            ge = gx * ex + gy * ey
            gt = gy * ex - gx * ey
            # contact stress tensor in (e, t): [[σ_n*, τ*], [τ*, ½(σ_tt,i + σ_tt,j)]]
            stt = 0.5 * (sxxi * ey * ey - 2.0 * sxyi * ex * ey + syyi * ex * ex)
            stt += 0.5 * (sxxj * ey * ey - 2.0 * sxyj * ex * ey + syyj * ex * ex)
            fe = sstar * ge + tstar * gt
            ft = tstar * ge + stt * gt
            f = 2.0 * mj / (rhoi * pk[j, PRHO])
            ax += f * (fe * ex - ft * ey)
            ay += f * (fe * ey + ft * ex)
            de += f * (ustar * fe + wstar * ft)
            # velocity gradient, uncorrected here (B_i applied once per row below)
            usx = ustar * ex - wstar * ey
            usy = ustar * ey + wstar * ex
            g = -2.0 * vj * wp
            rx = usx - vxi
            ry = usy - vyi
            mu += g * (rx * (bxxi * ex + bxyi * ey) + ry * (bxyi * ex + byyi * ey))
            if dev_mean:
                rx = 0.5 * (vxj - vxi)
                ry = 0.5 * (vyj - vyi)
            lxx += g * rx * ex
            lxy += g * rx * ey
            lyx += g * ry * ex
            lyy += g * ry * ey
        # L ← L B_i
        t_xx = lxx * bxxi + lxy * bxyi
        t_xy = lxx * bxyi + lxy * byyi
        t_yx = lyx * bxxi + lyy * bxyi
        t_yy = lyx * bxyi + lyy * byyi
        lxx = t_xx
        lxy = t_xy
        lyx = t_yx
        lyy = t_yy
        out[i, RVX] = ax
        out[i, RVY] = ay
        out[i, RE] = de
        out[i, RLXX] = lxx
        out[i, RLXY] = lxy
        out[i, RLYX] = lyx
        out[i, RLYY] = lyy
        out[i, RMU] = mu


@pjit
def time_step(pk: np.ndarray, rates: np.ndarray, n: int, cfl: float, k_comp: float) -> float:
    """Δt = C min_i l_i / √(c_l,i² + (k μ̇_i l_i)²) [s], the seed's formula with
    k = max{sign(−ε̇), 16}. As printed k is 16 whatever the sign of ε̇ (sign is ±1 or 0), and
    the square drops the sign of ε̇: the solver passes k (16 by default; 0 turns it off)."""
    dt = np.inf
    for i in prange(n):
        mu = rates[i, RMU]
        l = pk[i, PL]
        cl = pk[i, PCL]
        kl = k_comp * mu * l
        dt = min(dt, l / math.sqrt(cl * cl + kl * kl))
    return cfl * dt


@pjit
def update(
    x: np.ndarray,
    v: np.ndarray,
    m: np.ndarray,
    rho: np.ndarray,
    e: np.ndarray,
    S: np.ndarray,
    eps_p: np.ndarray,
    l: np.ndarray,
    rates: np.ndarray,
    dt: float,
    strength_kind: int,
    strength_p: np.ndarray,
    periodic: np.ndarray,
    lo: np.ndarray,
    length: np.ndarray,
    rho_max: float,
) -> int:
    """One step of the seed's scheme for every particle; returns the number of bad particles
    (non-finite state or ρ ≥ rho_max) — the caller raises.

        v(t+Δt) = v + dv/dt Δt
        e(t+Δt) = e + dE/dt Δt − ½(|v(t+Δt)|² − |v(t)|²)     (E total → e internal)
        ρ(t+Δt) = ρ exp(−μ̇ Δt)
        S(t+Δt) = Ω (S + dS/dt Δt) Ωᵀ, then the von Mises radial return (Δε_p accumulated)
        x(t+Δt) = x + v(t+Δt) Δt,   l = (m/ρ)^(1/dim)

    Ω is the rotation by ω Δt about z, written exactly (cos, sin): the seed's
    Ω = δ + ε ω Δt is its first-order form, and the exact one keeps J2 (so the yield test)
    unchanged by the rotation.
    """
    n = x.shape[0]
    dim = x.shape[1]
    G = strength_p[0]
    Y = strength_p[1]
    bad = 0
    for i in prange(n):
        vx0 = v[i, 0]
        vx1 = vx0 + rates[i, RVX] * dt
        k0 = vx0 * vx0
        k1 = vx1 * vx1
        v[i, 0] = vx1
        x[i, 0] += vx1 * dt
        if dim == 2:
            vy0 = v[i, 1]
            vy1 = vy0 + rates[i, RVY] * dt
            k0 += vy0 * vy0
            k1 += vy1 * vy1
            v[i, 1] = vy1
            x[i, 1] += vy1 * dt
        e[i] += rates[i, RE] * dt - 0.5 * (k1 - k0)
        lxx = rates[i, RLXX]
        lyy = rates[i, RLYY]
        rho[i] *= math.exp(-rates[i, RMU] * dt)
        l[i] = (m[i] / rho[i]) ** (1.0 / dim)
        if strength_kind == 1:
            tr3 = (lxx + lyy) / 3.0
            txx = S[i, 0] + 2.0 * G * (lxx - tr3) * dt
            tyy = S[i, 1] + 2.0 * G * (lyy - tr3) * dt
            tzz = S[i, 2] - 2.0 * G * tr3 * dt
            txy = S[i, 3] + G * (rates[i, RLXY] + rates[i, RLYX]) * dt
            a = 0.5 * (rates[i, RLYX] - rates[i, RLXY]) * dt
            c = math.cos(a)
            s = math.sin(a)
            sxx = c * c * txx - 2.0 * c * s * txy + s * s * tyy
            syy = s * s * txx + 2.0 * c * s * txy + c * c * tyy
            sxy = c * s * (txx - tyy) + (c * c - s * s) * txy
            sxx, syy, szz, sxy, dep = radial_return(sxx, syy, tzz, sxy, G, Y)
            S[i, 0] = sxx
            S[i, 1] = syy
            S[i, 2] = szz
            S[i, 3] = sxy
            eps_p[i] += dep
        for d in range(dim):
            if periodic[d]:
                x[i, d] = lo[d] + (x[i, d] - lo[d]) % length[d]
        ok = (
            math.isfinite(x[i, 0])
            and math.isfinite(v[i, 0])
            and math.isfinite(e[i])
            and math.isfinite(rho[i])
            and math.isfinite(S[i, 0] + S[i, 1] + S[i, 3])
            and rho[i] < rho_max
        )
        bad += 0 if ok else 1
    return bad


@pjit
def density_sum(
    pk: np.ndarray,
    n: int,
    dim: int,
    nbr: np.ndarray,
    nnb: np.ndarray,
    theta: float,
    periodic: np.ndarray,
    length: np.ndarray,
    out: np.ndarray,
) -> None:
    """Kernel sums n̂_i = W(0, 2θ l_i) + Σ_j W(r_ij, θ(l_i + l_j)) [1/m^dim] into ``out``
    (rows 0..n−1; j over the list, wall ghosts included) from the positions and sizes l in
    ``pk`` (module docstring, Density)."""
    Lx, Ly, iLx, iLy = image_lengths(periodic, length)
    for i in prange(n):
        xi = pk[i, PX]
        yi = pk[i, PY]
        li = pk[i, PL]
        s = w(0.0, pair_h(li, li, theta), dim)
        for k in range(nnb[i]):
            j = nbr[i, k]
            dx = pk[j, PX] - xi
            dy = pk[j, PY] - yi
            dx = min_image(dx, Lx, iLx)
            dy = min_image(dy, Ly, iLy)
            r = math.sqrt(dx * dx + dy * dy)
            s += w(r, pair_h(li, pk[j, PL], theta), dim)
        out[i] = s


@njit
def move_packed(
    pk: np.ndarray,
    x: np.ndarray,
    l: np.ndarray,
    src: np.ndarray,
    side: np.ndarray,
    walls: np.ndarray,
) -> None:
    """Positions x [m] and sizes l [m] into rows 0..n−1 of ``pk`` and into its ghost rows (the
    mirrors of ``fill_ghosts`` in the walls at ``walls``), the other columns left as they are:
    what ``density_sum`` reads, without the EOS calls of ``pack``."""
    n = x.shape[0]
    for i in range(n):
        pk[i, PX] = x[i, 0]
        pk[i, PY] = x[i, 1] if x.shape[1] == 2 else 0.0
        pk[i, PL] = l[i]
    for g in range(src.shape[0]):
        i = src[g]
        pk[n + g, PX] = 2.0 * walls[2 * side[g]] - pk[i, PX]
        pk[n + g, PY] = pk[i, PY]
        pk[n + g, PL] = l[i]


@njit
def kernel_ratio(rho_old: float, rhat_old: float, rhat_new: float) -> float:
    """ρ(t+Δt) = ρ(t) n̂(t+Δt)/n̂(t) [kg/m³] (module docstring, Density)."""
    return rho_old * rhat_new / rhat_old


@pjit
def rescale_density(
    rho: np.ndarray,
    l: np.ndarray,
    m: np.ndarray,
    rho_old: np.ndarray,
    rhat_old: np.ndarray,
    rhat_new: np.ndarray,
    mobile: np.ndarray,
    dim: int,
    rho_max: float,
) -> int:
    """The ``kernel_ratio`` density [kg/m³] of every mobile particle into ``rho`` and its size
    l = (m/ρ)^(1/dim) [m] into ``l``; returns the number of particles whose new ρ is not
    finite or reaches rho_max."""
    bad = 0
    for i in prange(rho.shape[0]):
        if mobile[i]:
            r = kernel_ratio(rho_old[i], rhat_old[i], rhat_new[i])
            rho[i] = r
            l[i] = (m[i] / r) ** (1.0 / dim)
            bad += 0 if (math.isfinite(r) and r < rho_max) else 1
    return bad


@njit
def max_displacement(
    x: np.ndarray, x_ref: np.ndarray, periodic: np.ndarray, length: np.ndarray
) -> float:
    """Largest |x − x_ref| [m] (minimum image along periodic dimensions)."""
    dmax2 = 0.0
    for i in range(x.shape[0]):
        s = 0.0
        for d in range(x.shape[1]):
            dd = x[i, d] - x_ref[i, d]
            if periodic[d]:
                dd -= length[d] * np.rint(dd / length[d])
            s += dd * dd
        dmax2 = max(dmax2, s)
    return math.sqrt(dmax2)


@njit
def profile_sums(
    x: np.ndarray,
    v: np.ndarray,
    m: np.ndarray,
    rho: np.ndarray,
    e: np.ndarray,
    S: np.ndarray,
    pressure: np.ndarray,
    eps_p: np.ndarray,
    x0: float,
    width: float,
    out: np.ndarray,
) -> None:
    """Accumulate (+=) per-bin sums along x (bins of ``width`` [m] from x0) of
    PROFILE_FIELDS: count, Σm, ΣV (V = m/ρ), Σ m v_x, Σ ½ m |v|², Σ m e, Σ V σ_xx, Σ V σ_yy,
    Σ V P, Σ m ε_p. Means: ρ = Σm/ΣV, u = Σmv/Σm, σ_xx = ΣVσ_xx/ΣV, e = Σme/Σm."""
    nb = out.shape[0]
    dim = x.shape[1]
    for i in range(x.shape[0]):
        b = int(np.floor((x[i, 0] - x0) / width))
        if b < 0 or b >= nb:
            continue
        vol = m[i] / rho[i]
        k = v[i, 0] * v[i, 0]
        if dim == 2:
            k += v[i, 1] * v[i, 1]
        out[b, 0] += 1.0
        out[b, 1] += m[i]
        out[b, 2] += vol
        out[b, 3] += m[i] * v[i, 0]
        out[b, 4] += 0.5 * m[i] * k
        out[b, 5] += m[i] * e[i]
        out[b, 6] += vol * (S[i, 0] - pressure[i])
        out[b, 7] += vol * (S[i, 1] - pressure[i])
        out[b, 8] += vol * pressure[i]
        out[b, 9] += m[i] * eps_p[i]


PROFILE_FIELDS = ("count", "mass", "volume", "px", "ke", "ie", "v_sxx", "v_syy", "v_p", "m_eps_p")
