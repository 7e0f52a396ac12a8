"""Hugoniots of a solid and of its porous form, from the solid's Mie–Grüneisen EOS (SI units).

Solid: Mie–Grüneisen EOS referenced to the linear Us–up Hugoniot D = c0 + s·u_p with
Γ/V = Γ0/V0 constant (V = 1/ρ specific volume [m³/kg], V0 = 1/ρ0):

    P(V, E) = P_H(V) + (Γ/V)·(E − E_H(V)),
    P_H(V) = ρ0 c0² η / (1 − s η)²,   η = 1 − V/V0,   E_H(V) = ½ P_H(V) (V0 − V),

(the Hugoniot from the jump conditions with u_p = η D, ``linear_hugoniot``; E measured from
the ambient state at V0, P = 0). Copper: ρ0 = 8930 kg/m³, c0 = 3940 m/s, s = 1.49, Γ0 = 2.0 (LASL Shock Hugoniot
Data, S. P. Marsh ed., University of California Press, 1980; the values of the project's issue).

Porous sample: initial specific volume V00 = α·V0 (distention α = ρ0/ρ00 ≥ 1), at P ≈ 0 and
the ambient energy of the solid. Assume the shock compacts it fully to a state (P, V, E) on the
*same* Mie–Grüneisen surface. The energy jump condition E = ½ P (V00 − V) gives, with the EOS,

    P(V) = P_H(V)·[1 − (Γ/2V)(V0 − V)] / [1 − (Γ/2V)(V00 − V)]

(R. G. McQueen, S. P. Marsh, J. W. Taylor, J. N. Fritz, W. J. Carter, "The equation of state of
solids from shock wave studies", in R. Kinslow (ed.), High-Velocity Impact Phenomena, Academic
Press, 1970, ch. VII; Zel'dovich & Raizer, Physics of Shock Waves, ch. XI), and the mass and
momentum jump conditions give

    u_p = √(P (V00 − V)),   D = V00 √(P / (V00 − V)),   ρ = 1/V.

With Γ/V = Γ0/V0 the bracket ratio is [1 − ½Γ0(1 − v)] / [1 − ½Γ0(α − v)], v = V/V0. For α = 1
it is 1 and the solid Hugoniot is recovered. For α > 1 and Γ0 > 0 it exceeds 1 wherever
V < V0, i.e. the porous Hugoniot lies above the solid one at equal V: the extra PdV work of
closing the pores is heat, and heat raises the pressure by Γ/V times it. The formula holds while
the denominator is positive, V > V0·(α − 2/Γ0); P → ∞ as V approaches that volume, the
limiting compression of the porous Hugoniot. For α ≥ 1 + 2/Γ0 (α ≥ 2 for copper) that limit is
at or above V0: the shocked porous material stays less dense than the solid at ambient (the
"anomalous" Hugoniot of very porous materials); ``porous_hugoniot_from_up`` refuses that case.

Weak shocks: as u_p → 0 the solution tends to V → V0 ("snowplow" or full-compaction limit with a
cold, incompressible solid): from the jump conditions with V = V0,

    P = u_p² / (V00 − V0) = ρ00 u_p² · α/(α − 1),   D = u_p V00/(V00 − V0) = u_p α/(α − 1).

Validity: full compaction, no strength, equilibrium (no rate effects), and the solid's
Mie–Grüneisen surface with constant Γ/V extrapolated to the heated states. At weak shocks
(e.g. u_p = 100 m/s, P ≈ 0.3 GPa in copper with α = 1.35) the pores are *not* closed completely
and the matrix's strength carries a large part of the load: measured porous-copper Hugoniots
show an elastic precursor and a distention that falls only gradually with pressure. R. R. Boade,
"Principal Hugoniot, second-shock Hugoniot, and release behavior of pressed copper powder"
(abstract; journal details not checked here), for ρ00 ≈ 6.4 g/cm³: a ≈ 1.4 kbar precursor at
≈ 1.9 mm/μs, then α2 = 1 + (α1 − 1)·exp[−â (P2 − P1)] with â = 0.254 kbar⁻¹ up to ≈ 35 kbar,
so at ≈ 2.5 kbar (u_p ≈ 100 m/s here), taking α1 ≈ the initial distention, about three
quarters of the excess volume α − 1 is still open. There this model is an estimate: at a given
u_p it gives the fully compacted (smallest V, densest) state, while a real, partly compacted
and strong sample has a larger V and, at the same u_p, a faster front (D = u_p V00/(V00 − V)).
Compare simulations with it as the hydrodynamic full-compaction reference, not as an exact
target.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .linear_hugoniot import compression_state, jump_state


@dataclass(frozen=True)
class MGSolid:
    """Mie–Grüneisen solid with a linear Us–up reference Hugoniot and Γ/V = Γ0/V0 (SI).

    rho0 [kg/m³], c0 [m/s], s [-], gamma0 [-]."""

    rho0: float
    c0: float
    s: float
    gamma0: float

    def __post_init__(self) -> None:
        for name in ("rho0", "c0", "s"):
            v = getattr(self, name)
            if not (math.isfinite(v) and v > 0):
                raise ValueError(f"MGSolid.{name} = {v!r} must be a finite number > 0")
        if not (math.isfinite(self.gamma0) and self.gamma0 >= 0):
            raise ValueError(f"MGSolid.gamma0 = {self.gamma0!r} must be a finite number ≥ 0")

    @property
    def V0(self) -> float:
        """Specific volume of the solid at ambient [m³/kg]."""
        return 1.0 / self.rho0


COPPER = MGSolid(rho0=8930.0, c0=3940.0, s=1.49, gamma0=2.0)
"""Copper, LASL Shock Hugoniot Data (1980) linear fit (the Cu table entry)."""


@dataclass(frozen=True)
class HugoniotState:
    """Shocked states (arrays broadcast together), upstream at rest at V00 = α V0, P = 0.

    u_p [m/s], D [m/s], P [Pa], V [m³/kg], rho [kg/m³], E [J/kg] (specific internal energy
    jump E − E00 = ½ P (V00 − V)), alpha (initial distention), rho00 [kg/m³], eta: the solid's
    compression 1 − V/V0 [-] (full precision even for weak shocks)."""

    u_p: np.ndarray
    D: np.ndarray
    P: np.ndarray
    V: np.ndarray
    rho: np.ndarray
    E: np.ndarray
    alpha: float
    rho00: float
    eta: np.ndarray


def _check_alpha(alpha: float) -> float:
    alpha = float(alpha)
    if not (math.isfinite(alpha) and alpha >= 1.0):
        raise ValueError(f"alpha = {alpha!r} must be a finite distention ≥ 1 (ρ0/ρ00)")
    return alpha


def solid_hugoniot_pressure(V: np.ndarray | float, solid: MGSolid = COPPER) -> np.ndarray:
    """P_H(V) = ρ0 c0² η/(1 − s η)², η = 1 − V/V0 [Pa], for V [m³/kg] with s·η < 1.

    For V > V0 (η < 0) this is the usual analytic continuation used as the MG reference curve.
    """
    V = np.asarray(V, dtype=np.float64)
    eta = 1.0 - V / solid.V0
    if np.any(solid.s * eta >= 1.0):
        raise ValueError(
            f"V must exceed V0·(1 − 1/s) = {solid.V0 * (1 - 1 / solid.s):.6g} m³/kg, where the "
            "linear Us–up Hugoniot's pressure diverges"
        )
    return compression_state(eta, solid.rho0, solid.c0, solid.s)[0]


def _eta_max(alpha: float, solid: MGSolid) -> float:
    """Largest compression η = 1 − V/V0 of the porous Hugoniot branch (P → +∞ there)."""
    eta = 1.0 / solid.s
    if solid.gamma0 > 0:
        eta = min(eta, 1.0 - alpha + 2.0 / solid.gamma0)
    return eta


def _pressure_eta(eta: np.ndarray, alpha: float, solid: MGSolid) -> np.ndarray:
    """P(η) [Pa] of the porous Hugoniot, η = 1 − V/V0. In terms of η the bracket reads
    [1 − ½Γ0 η]/[1 − ½Γ0 (α − 1 + η)], since Γ/V = Γ0/V0, V0 − V = V0 η and V00 − V = V0(α − 1 + η).
    Working in η keeps full relative precision for weak shocks, where V is within 1e-5 of V0
    and P = ρ0c0²η would lose most of its digits if η were formed as 1 − V/V0 from a root in V."""
    half_g = 0.5 * solid.gamma0
    P_H = compression_state(eta, solid.rho0, solid.c0, solid.s)[0]
    return P_H * ((1.0 - half_g * eta) / (1.0 - half_g * (alpha - 1.0 + eta)))  # α = 1: P_H·1


def _state(eta: np.ndarray, alpha: float, solid: MGSolid, u_p: np.ndarray | None) -> HugoniotState:
    P = _pressure_eta(eta, alpha, solid)
    dV = solid.V0 * (alpha - 1.0 + eta)  # V00 − V, no cancellation
    return HugoniotState(
        u_p=np.sqrt(P * dV) if u_p is None else u_p,
        D=alpha * solid.V0 * np.sqrt(P / dV),
        P=P,
        V=solid.V0 * (1.0 - eta),
        rho=solid.rho0 / (1.0 - eta),
        E=0.5 * P * dV,
        alpha=alpha,
        rho00=solid.rho0 / alpha,
        eta=eta,
    )


def porous_hugoniot_pressure(
    V: np.ndarray | float, alpha: float, solid: MGSolid = COPPER
) -> np.ndarray:
    """Full-compaction porous Hugoniot P(V) [Pa] (McQueen et al. 1970, see the module doc):

        P = P_H(V)·[1 − (Γ/2V)(V0 − V)] / [1 − (Γ/2V)(V00 − V)],  Γ/V = Γ0/V0, V00 = α V0.

    V [m³/kg] must lie in (V_min, V00] with V_min = V0·(1 − η_max),
    η_max = min(1/s, 1 − α + 2/Γ0).
    """
    alpha = _check_alpha(alpha)
    V = np.asarray(V, dtype=np.float64)
    v_min = solid.V0 * (1.0 - _eta_max(alpha, solid))
    if np.any(V <= v_min) or np.any(V > alpha * solid.V0):
        raise ValueError(
            f"V must lie in ({v_min:.6g}, {alpha * solid.V0:.6g}] m³/kg for alpha = {alpha:g} "
            "(above it the sample would be expanded; below it P diverges)"
        )
    return _pressure_eta(1.0 - V / solid.V0, alpha, solid)


def porous_hugoniot_from_volume(
    V: np.ndarray | float, alpha: float, solid: MGSolid = COPPER
) -> HugoniotState:
    """The porous Hugoniot state at specific volume V [m³/kg] (V < V0 ≤ V00 = α V0): P from
    ``porous_hugoniot_pressure``, u_p = √(P(V00 − V)), D = V00 √(P/(V00 − V)),
    E = ½ P (V00 − V). Only the compressive branch P > 0 (V < V0) is a shock."""
    alpha = _check_alpha(alpha)
    V = np.asarray(V, dtype=np.float64)
    P = porous_hugoniot_pressure(V, alpha, solid)
    if np.any(P <= 0):
        raise ValueError(f"V must be below V0 = {solid.V0:.6g} m³/kg for a compressive shock")
    return _state(1.0 - V / solid.V0, alpha, solid, None)


def _solve_eta(f, eta_max: float, shape: tuple, what: str) -> np.ndarray:
    """The root in (0, η_max) of f(η), vectorised over ``shape``, for f(0) < 0 and f → +∞ as
    η → η_max (a pressure diverging there): the upper end approached geometrically until
    f > 0, then bisection until the bracket is one ulp of η wide; ``what``: the ValueError's
    text if no upper end is found."""
    lo = np.zeros(shape)
    hi = np.zeros(shape)
    need = np.ones(shape, dtype=bool)
    gap = eta_max
    while need.any():
        gap *= 0.5
        if eta_max - gap == eta_max:
            raise ValueError(what)
        hi = np.where(need, eta_max - gap, hi)
        need = f(hi) <= 0
    for _ in range(2200):  # ≤ ~1100 halvings reach one ulp even for denormal-scale roots
        mid = 0.5 * (lo + hi)
        if np.all((mid == lo) | (mid == hi)):
            break  # the bracket is one ulp wide
        pos = f(mid) > 0
        hi = np.where(pos, mid, hi)
        lo = np.where(pos, lo, mid)
    return 0.5 * (lo + hi)


def porous_hugoniot_from_up(
    u_p: np.ndarray | float, alpha: float, solid: MGSolid = COPPER
) -> HugoniotState:
    """The porous Hugoniot state at particle velocity u_p [m/s] > 0.

    Solves f(η) = P(η)·V0(α − 1 + η) − u_p² = 0 for the compression η = 1 − V/V0 in
    (0, η_max) by bisection on a bracket where f changes sign: f(0) = −u_p² < 0 (P = 0 at V0),
    f → +∞ as η → η_max (P → ∞). Bisection (vectorised over u_p) runs until the bracket is one
    ulp of η wide; the state is then evaluated at that η (u_p is returned as given; the root's
    residual is below 1e-15 relative).
    """
    alpha = _check_alpha(alpha)
    u = np.asarray(u_p, dtype=np.float64)
    if np.any(~np.isfinite(u)) or np.any(u <= 0):
        raise ValueError("u_p must be finite and > 0 (m/s)")
    eta_max = _eta_max(alpha, solid)
    if eta_max <= 0:
        raise ValueError(
            f"alpha = {alpha:g} must be < 1 + 2/Γ0 = {1 + 2 / solid.gamma0:g}: beyond it the "
            "full-compaction Hugoniot never reaches the solid's density (anomalous branch)"
        )

    def f(eta: np.ndarray) -> np.ndarray:
        return _pressure_eta(eta, alpha, solid) * solid.V0 * (alpha - 1.0 + eta) - u * u

    shape = np.broadcast(u).shape
    eta = _solve_eta(f, eta_max, shape, f"no porous Hugoniot state found for u_p = {u_p!r} m/s")
    return _state(eta, alpha, solid, u * np.ones(shape))


def solid_hugoniot_from_up(u_p: np.ndarray | float, solid: MGSolid = COPPER) -> HugoniotState:
    """Closed-form solid Hugoniot at u_p [m/s]: D = c0 + s u_p, P = ρ0 D u_p,
    V = V0 (1 − u_p/D), E = ½ u_p² (``linear_hugoniot.jump_state``, pole at rest, P = 0)."""
    u = np.asarray(u_p, dtype=np.float64)
    D, rho, V, P, E = jump_state(u, solid.rho0, solid.c0, solid.s)
    return HugoniotState(
        u_p=u,
        D=D,
        P=P,
        V=V,
        rho=rho,
        E=E,
        alpha=1.0,
        rho00=solid.rho0,
        eta=u / D,
    )


def snowplow_hugoniot(u_p: np.ndarray | float, alpha: float, rho_solid: float) -> HugoniotState:
    """Full compaction to the solid's ambient volume V = V0 (cold, rigid matrix), α > 1:

        P = u_p²/(V00 − V0) = ρ00 u_p² α/(α − 1),  D = u_p α/(α − 1),  E = ½ u_p²,

    from the jump conditions u_p = √(P (V00 − V)), D = V00 √(P/(V00 − V)) with V = V0. The
    weak-shock limit of ``porous_hugoniot_from_up``. u_p [m/s], rho_solid [kg/m³]."""
    alpha = _check_alpha(alpha)
    if alpha == 1.0:
        raise ValueError("alpha = 1: the snowplow limit needs pores (alpha > 1)")
    u = np.asarray(u_p, dtype=np.float64)
    V0 = 1.0 / rho_solid
    V00 = alpha * V0
    P = u * u / (V00 - V0)
    return HugoniotState(
        u_p=u,
        D=u * alpha / (alpha - 1.0),
        P=P,
        V=np.full(u.shape, V0),
        rho=np.full(u.shape, rho_solid),
        E=0.5 * P * (V00 - V0),
        alpha=alpha,
        rho00=rho_solid / alpha,
        eta=np.zeros(u.shape),
    )


def partial_compaction_from_up(
    u_p: np.ndarray | float,
    alpha0: float,
    alpha: float,
    solid: MGSolid = COPPER,
    deviator: float = 0.0,
) -> HugoniotState:
    """The porous Hugoniot state at particle velocity u_p [m/s] whose slab keeps distention
    ``alpha`` (1 ≤ alpha < alpha0): pores partly open behind the front, the matrix on the
    solid's Mie–Grüneisen surface (Herrmann's P–α form, W. Herrmann, J. Appl. Phys. 40,
    2490, 1969: the mean stress of a porous body is the matrix's over α, a pore carrying none).

    With the matrix at compression η = 1 − V_s/V0 and V = α V_s, the jump conditions from
    the pole at rest (V00 = α0 V0, P0 = 0) give E = ½ u_p² and

        (P_s(η, E)/α + τ) · (V00 − V) = u_p²,   V00 − V = V0 (α0 − α + α η),
        P_s = P_H(η) + (Γ0/V0)(E − ½ P_H V0 η)    (the module doc's EOS),

    τ = ``deviator`` [Pa] the slab's mean deviatoric part of P_xx = −σ_xx (0 without
    strength; a yielding matrix in uniaxial strain carries at most (2/3) Y/α). Solved for η
    as ``porous_hugoniot_from_up`` is (``_solve_eta``); then D = u_p V00/(V00 − V),
    P = ρ00 D u_p, E = ½ u_p². At alpha = 1 and τ = 0 it is ``porous_hugoniot_from_up``
    (McQueen's full compaction). The state's ``eta`` is the matrix's compression. u_p must
    be strong enough that the pores' closing alone takes more than u_p² of work per unit
    (V00 − V): else ValueError."""
    alpha0, alpha = _check_alpha(alpha0), _check_alpha(alpha)
    if alpha >= alpha0:
        raise ValueError(f"alpha = {alpha:g} must be below the initial distention {alpha0:g}")
    u = np.asarray(u_p, dtype=np.float64)
    if np.any(~np.isfinite(u)) or np.any(u <= 0):
        raise ValueError("u_p must be finite and > 0 (m/s)")
    V0, g = solid.V0, solid.gamma0 / solid.V0
    E = 0.5 * u * u

    def f(eta: np.ndarray) -> np.ndarray:
        P_H, E_H = compression_state(eta, solid.rho0, solid.c0, solid.s)
        Ps = P_H + g * (E - E_H)
        return (Ps / alpha + deviator) * V0 * (alpha0 - alpha + alpha * eta) - u * u

    shape = np.broadcast(u).shape
    if np.any(f(np.zeros(shape)) >= 0):
        raise ValueError(
            f"u_p = {u_p!r} m/s: too weak for a compaction wave to alpha = {alpha:g} with a "
            f"deviator of {deviator:.3g} Pa (the matrix would stay uncompressed)"
        )
    # P_H diverges as η → 1/s
    eta = _solve_eta(f, 1.0 / solid.s, shape, f"no partial-compaction state for u_p = {u_p!r}")
    dV = V0 * (alpha0 - alpha + alpha * eta)
    V = alpha * V0 * (1.0 - eta)
    D = u * alpha0 * V0 / dV
    rho00 = solid.rho0 / alpha0
    return HugoniotState(u_p=u * np.ones(shape), D=D, P=rho00 * D * u, V=V, rho=1.0 / V, E=E,
                         alpha=alpha0, rho00=rho00, eta=eta)  # fmt: skip


def pore_collapse_distention(P: float, yield_stress: float, dim: int = 2) -> float:
    """The distention α that a perfectly plastic matrix (yield stress Y [Pa]) holds at mean
    pressure P [Pa] when its pores collapse quasi-statically (M. M. Carroll and A. C. Holt,
    J. Appl. Phys. 43, 1626, 1972):

        spherical pores (3D):           P = (2/3) Y ln(α/(α − 1)),
        cylindrical pores, plane strain: P = (Y/√3) ln(α/(α − 1))   (2D),

    so α = 1/(1 − exp(−P/k)), k = (2/3) Y or Y/√3. A static estimate: in a shock the pores'
    inertia and the matrix's heating close them further, so it bounds α from above."""
    if not (P > 0 and yield_stress > 0) or dim not in (2, 3):
        raise ValueError("P and yield_stress must be > 0 Pa and dim 2 or 3")
    k = (2.0 / 3.0) * yield_stress if dim == 3 else yield_stress / math.sqrt(3.0)
    return 1.0 / (1.0 - math.exp(-P / k))
