"""Initial samples: FCC lattices and Maxwell velocities (reduced LJ units).

FCC with lattice constant a = (4/ρ)^(1/3) [σ] for number density ρ [σ⁻³]: four atoms per
cubic cell at (0,0,0), (½,½,0), (½,0,½), (0,½,½)·a, the whole lattice offset by a/4 so that no
atom sits on a wall or on a periodic boundary.
"""

from __future__ import annotations

import numpy as np

from .state import MDState

_BASIS = np.array([[0.0, 0.0, 0.0], [0.5, 0.5, 0.0], [0.5, 0.0, 0.5], [0.0, 0.5, 0.5]])


def fcc_positions(cells: tuple[int, int, int], rho: float) -> tuple[np.ndarray, np.ndarray]:
    """Positions (4·nx·ny·nz, 3) [σ] of an FCC lattice at density ``rho`` and the box (3,)."""
    a = (4.0 / rho) ** (1.0 / 3.0)
    nx, ny, nz = cells
    grid = np.stack(np.meshgrid(np.arange(nx), np.arange(ny), np.arange(nz), indexing="ij"), -1)
    pos = (grid.reshape(-1, 1, 3) + _BASIS[None, :, :]).reshape(-1, 3) + 0.25
    # x fastest in memory is not required: the simulation sorts atoms by cell.
    return pos * a, a * np.array([nx, ny, nz], dtype=float)


def maxwell_velocities(n: int, T: float, seed: int) -> np.ndarray:
    """Velocities (n, 3) [σ/τ] drawn at temperature T [ε/k_B], zero mean, rescaled to T exactly."""
    rng = np.random.default_rng(seed)
    v = rng.standard_normal((n, 3)) * np.sqrt(T)
    v -= v.mean(axis=0)
    if T > 0:
        v *= np.sqrt(T * 3 * (n - 1) / np.sum(v * v))
    return v


def fcc_state(
    cells: tuple[int, int, int], rho: float, T: float, seed: int, periodic_x: bool
) -> MDState:
    """An FCC sample at (ρ, T). With ``periodic_x`` False the box is closed in x by two static
    walls at x = 0 and x = L_x; y and z are always periodic."""
    x, L = fcc_positions(cells, rho)
    v = maxwell_velocities(x.shape[0], T, seed)
    return MDState(
        x=x,
        v=v,
        L=L,
        periodic=np.array([periodic_x, True, True]),
        walls0=np.array([0.0, 0.0, L[0], 0.0]),
    )
