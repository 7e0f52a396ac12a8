"""The seam between shock methods and solvers.

Methods (piston now; MW, AMW and the dichotomy next) talk to a solver only through this
protocol, so they run unchanged on MD and, later, on SPH. Lengths, times and velocities are in
the solver's own units (reduced LJ units for MD, SI for SPH).
"""

from __future__ import annotations

import os
from typing import Protocol

import numpy as np


class ShockSolver(Protocol):
    """What a shock method needs from a solver."""

    @property
    def time(self) -> float:
        """Current simulated time."""

    @property
    def n_particles(self) -> int:
        """Particles in the domain."""

    def advance(self, n_steps: int) -> None:
        """Run ``n_steps`` of the solver's own time loop (raises SolverUnstable)."""

    def wall_positions(self) -> tuple[float, float]:
        """Positions of the left (upstream boundary / piston) and right boundaries."""

    def set_walls(self, v_left: float, v_right: float) -> None:
        """Velocities of the left and right boundaries in the simulation frame."""

    def mean_velocity(self) -> float:
        """Mass-weighted mean x velocity of the material in the domain."""

    def galilean_shift(self, du: float) -> None:
        """Add ``du`` to every x velocity and to both boundary velocities."""

    def profile_sums(self, width: float) -> np.ndarray:
        """Raw per-bin sums along x (nbins, len(SUM_FIELDS)) in slabs of ``width``."""

    def save(self, path: str | os.PathLike, extra=None, attrs=None) -> object:
        """The complete state, bit-exact on resume."""
