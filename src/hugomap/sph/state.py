"""The CSPH state: a dataclass of per-particle arrays (SI units).

Dimension ``dim`` = 1 (uniaxial strain) or 2 (plane strain, per metre of depth).
Conventions match ``sph.sample``: in 1D a mass is per unit cross-section [kg/m²], in 2D per
metre of depth [kg/m].
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

#: Components of the deviatoric stress array S (zz is needed in plane and uniaxial strain).
STRESS_COMPONENTS = ("xx", "yy", "zz", "xy")


@dataclass
class SPHState:
    """Complete dynamical state of a CSPH run.

    x (n, dim) positions [m]; v (n, dim) velocities [m/s]; m (n,) masses [kg/m^(3−dim)];
    rho (n,) densities [kg/m³]; e (n,) specific internal energies [J/kg];
    S (n, 4) deviatoric stress, components STRESS_COMPONENTS [Pa] (traceless: xx + yy + zz = 0);
    eps_p (n,) accumulated equivalent plastic strain [-]; l (n,) particle sizes [m], kept equal
    to (m/ρ)^(1/dim) by the solver; time [s].
    """

    x: np.ndarray
    v: np.ndarray
    m: np.ndarray
    rho: np.ndarray
    e: np.ndarray
    S: np.ndarray = field(default=None)  # type: ignore[assignment]
    eps_p: np.ndarray = field(default=None)  # type: ignore[assignment]
    l: np.ndarray = field(default=None)  # type: ignore[assignment]
    time: float = 0.0

    def __post_init__(self) -> None:
        x = np.asarray(self.x, dtype=np.float64)
        if x.ndim == 1:
            x = x[:, None]
        n, dim = x.shape
        if dim not in (1, 2):
            raise ValueError(f"CSPH state needs dim 1 or 2, got positions of shape {x.shape}")
        self.x = np.ascontiguousarray(x)
        v = np.asarray(self.v, dtype=np.float64).reshape(n, dim)
        self.v = np.ascontiguousarray(v)
        self.m = _vec(self.m, n, "m")
        self.rho = _vec(self.rho, n, "rho")
        self.e = _vec(self.e, n, "e")
        self.S = np.zeros((n, 4)) if self.S is None else np.array(self.S, dtype=np.float64)
        if self.S.shape != (n, 4):
            raise ValueError(f"S must have shape ({n}, 4) (xx, yy, zz, xy), got {self.S.shape}")
        self.eps_p = np.zeros(n) if self.eps_p is None else _vec(self.eps_p, n, "eps_p")
        if self.l is None:
            self.l = (self.m / self.rho) ** (1.0 / dim)
        else:
            self.l = _vec(self.l, n, "l")
        if np.any(self.m <= 0) or np.any(self.rho <= 0):
            raise ValueError("masses and densities must be positive")

    @property
    def n(self) -> int:
        return int(self.x.shape[0])

    @property
    def dim(self) -> int:
        return int(self.x.shape[1])

    def copy(self) -> SPHState:
        return SPHState(
            self.x.copy(), self.v.copy(), self.m.copy(), self.rho.copy(), self.e.copy(),
            self.S.copy(), self.eps_p.copy(), self.l.copy(), self.time,
        )  # fmt: skip


def _vec(a, n: int, name: str) -> np.ndarray:
    a = np.asarray(a, dtype=np.float64)
    if a.ndim == 0:
        a = np.full(n, float(a))
    if a.shape != (n,):
        raise ValueError(f"{name} must have shape ({n},), got {a.shape}")
    return np.ascontiguousarray(a.copy())
