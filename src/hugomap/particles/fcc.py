"""An FCC lattice and Maxwell velocities: the first state of a particle sample, a reservoir
or a periodic box, for both particle backends.

FCC with lattice constant a = (4/ρ)^(1/3) for number density ρ: four atoms per cubic cell
at (0,0,0), (½,½,0), (½,0,½), (0,½,½)·a, the whole lattice offset by a/4 so that no atom
sits on a wall or on a periodic boundary. Units are the caller's: [σ], ρ [σ⁻³] and
velocities [σ/τ] in reduced LJ units (m = k_B = 1); LAMMPS units metal passes ρ [Å⁻³] and
the velocity variance k_B T/(m mvv2e) [Å²/ps²].
"""

from __future__ import annotations

import numpy as np

_BASIS = np.array([[0.0, 0.0, 0.0], [0.5, 0.5, 0.0], [0.5, 0.0, 0.5], [0.0, 0.5, 0.5]])


def lattice_constant(rho: float) -> float:
    """a = (4/ρ)^(1/3): the FCC cell of four atoms at number density ``rho`` [length⁻³]."""
    return (4.0 / float(rho)) ** (1.0 / 3.0)


def fcc_positions(cells: tuple[int, int, int], rho: float) -> tuple[np.ndarray, np.ndarray]:
    """Positions (4·nx·ny·nz, 3) [σ] of an FCC lattice at number density ``rho`` [σ⁻³] and
    the box (3,) [σ] (module docstring)."""
    a = lattice_constant(rho)
    nx, ny, nz = cells
    grid = np.stack(np.meshgrid(np.arange(nx), np.arange(ny), np.arange(nz), indexing="ij"), -1)
    pos = (grid.reshape(-1, 1, 3) + _BASIS[None, :, :]).reshape(-1, 3) + 0.25
    # x fastest in memory is not required: the simulation sorts atoms by cell.
    return pos * a, a * np.array([nx, ny, nz], dtype=float)


def maxwell_velocities(n: int, T: float, seed: int) -> np.ndarray:
    """Velocities (n, 3) [σ/τ] drawn at temperature T [ε/k_B] (the variance k_B T/m per
    component, m = 1), zero mean, rescaled to T exactly: Σ v² = 3 (n − 1) T."""
    rng = np.random.default_rng(seed)
    v = rng.standard_normal((n, 3)) * np.sqrt(T)
    v -= v.mean(axis=0)
    if T > 0:
        v *= np.sqrt(T * 3 * (n - 1) / np.sum(v * v))
    return v
