"""The Lennard-Jones 12-6 pair potential, truncated (and optionally shifted) at ``rc``.

    U(r) = 4 ε [(σ/r)^12 − (σ/r)^6] − U_c,   r < rc;   U(r) = 0,   r ≥ rc,
    U_c  = 4 ε [(σ/rc)^12 − (σ/rc)^6] if shifted, else 0.

All quantities are in Lennard-Jones reduced units (σ = ε = m = 1, τ = σ√(m/ε)). The shift
makes U continuous at rc (forces are unchanged), so NVE energy is conserved; without it the
total energy jumps by U(rc) whenever a pair crosses the cutoff (see ../shared/FACTS.md).
The potential (rc and the shift) defines the Hugoniot: every dataset records both.
"""

from __future__ import annotations

from dataclasses import dataclass

from ..numba_conf import njit


@dataclass(frozen=True)
class LJParams:
    """Reduced-unit LJ parameters: cutoff ``rc`` [σ], ``shift`` (U(rc) subtracted), ``skin`` [σ]."""

    rc: float = 2.5
    shift: bool = True
    skin: float = 0.3

    def __post_init__(self) -> None:
        if not (0.5 < self.rc <= 10.0):
            raise ValueError(f"potential.rc = {self.rc}: allowed range (0.5, 10] sigma")
        if not (0.0 < self.skin <= 2.0):
            raise ValueError(f"md.skin = {self.skin}: allowed range (0, 2] sigma")

    @property
    def ushift(self) -> float:
        """U_c [ε]: the value subtracted so that U(rc) = 0 when shifted."""
        return lj_energy_unshifted(self.rc * self.rc) if self.shift else 0.0

    @property
    def rlist(self) -> float:
        """Verlet-list radius rc + skin [σ]."""
        return self.rc + self.skin


@njit
def lj_energy_unshifted(r2: float) -> float:
    """U(r) = 4(r^-12 − r^-6) [ε] for squared distance ``r2`` [σ²] (no cutoff)."""
    inv6 = 1.0 / (r2 * r2 * r2)
    return 4.0 * inv6 * (inv6 - 1.0)


@njit
def lj_pair(r2: float, rc2: float, ushift: float) -> tuple[float, float]:
    """Energy U(r) [ε] and F(r)/r = −(dU/dr)/r [ε σ⁻²] of one pair, zero beyond ``rc``.

        U   = 4 r⁻⁶ (r⁻⁶ − 1) − U_c,
        F/r = 48 r⁻¹⁴ − 24 r⁻⁸ = 24 r⁻² r⁻⁶ (2 r⁻⁶ − 1)      (r < rc; both 0 for r ≥ rc),

    with ``r2`` = r² [σ²], ``rc2`` = rc² [σ²] and ``ushift`` = U_c [ε] (module docstring).
    Multiply F/r by the separation vector r_i − r_j to get the force on i.

    This is the one definition of the pair terms: the kernels of ``forces`` call it in their
    pair loops (numba inlines it there; a caller that needs only F/r loses nothing, the unused
    energy is removed as dead code).
    """
    # Branch-free: the cutoff is a select, not a branch, so that the kernels' pair loops stay
    # vectorisable once this is inlined; beyond rc the terms are computed and discarded.
    inv2 = 1.0 / r2
    inv6 = inv2 * inv2 * inv2
    inside = r2 < rc2
    u = 4.0 * inv6 * (inv6 - 1.0) - ushift if inside else 0.0
    fr = 24.0 * inv2 * inv6 * (2.0 * inv6 - 1.0) if inside else 0.0
    return u, fr
