"""The Lennard-Jones 12-6 pair potential, truncated (and optionally shifted) at ``rc``.

    U(r) = 4 ε [(σ/r)^12 − (σ/r)^6] − U_c,   r < rc;   U(r) = 0,   r ≥ rc,
    U_c  = 4 ε [(σ/rc)^12 − (σ/rc)^6] if shifted, else 0.

All quantities are in Lennard-Jones reduced units (σ = ε = m = 1, τ = σ√(m/ε)). The shift
makes U continuous at rc (forces are unchanged), so NVE energy is conserved; without it the
total energy jumps by U(rc) whenever a pair crosses the cutoff.
The potential (rc and the shift) defines the Hugoniot: every dataset records both.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass

from ..numba_conf import njit


@dataclass(frozen=True)
class LJParams:
    """Reduced-unit LJ parameters: cutoff ``rc`` [σ], ``shift`` (U(rc) subtracted), ``skin`` [σ]."""

    rc: float = 2.5
    shift: bool = True
    skin: float = 0.3

    def __post_init__(self) -> None:
        # The ranges are the config schema's (potential.rc, potential.skin): one statement.
        for key in ("rc", "skin"):
            value = getattr(self, key)
            lo, lo_open, hi, hi_open = _schema_range(key)
            inside = (lo < value if lo_open else lo <= value) and (
                value < hi if hi_open else value <= hi
            )
            if not inside:
                lb, rb = "(" if lo_open else "[", ")" if hi_open else "]"
                raise ValueError(
                    f"potential.{key} = {value}: allowed range {lb}{lo}, {hi}{rb} sigma"
                )

    @property
    def ushift(self) -> float:
        """U_c [ε]: the value subtracted so that U(rc) = 0 when shifted."""
        return lj_energy_unshifted(self.rc * self.rc) if self.shift else 0.0

    @property
    def rlist(self) -> float:
        """Verlet-list radius rc + skin [σ]."""
        return self.rc + self.skin


@functools.cache
def _schema_range(key: str) -> tuple[float, bool, float, bool]:
    """(low, low exclusive, high, high exclusive) of ``potential.<key>`` in the config
    schema (``workflow/schemas/config.schema.json``), the one statement of the range."""
    from ..config import load_schema

    s = load_schema()["$defs"]["md_scene"]["properties"]["potential"]["properties"][key]
    lo_open, hi_open = "exclusiveMinimum" in s, "exclusiveMaximum" in s
    lo = s["exclusiveMinimum"] if lo_open else s["minimum"]
    hi = s["exclusiveMaximum"] if hi_open else s["maximum"]
    return float(lo), lo_open, float(hi), hi_open


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
