"""The seam between shock methods and solvers.

The methods (the piston driver, AMW, MW, the dichotomy's trials, the steady average) talk to a
solver only through these protocols, so they run unchanged on every backend. Lengths, times
and velocities are in the solver's own units (reduced LJ units for MD, SI for CSPH).
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

    @property
    def steps(self) -> int:
        """Time steps taken since the run began."""

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


class WindowGeometry(Protocol):
    """The observation window [x_lo, x_hi] in the window frame."""

    x_lo: float
    x_hi: float

    @property
    def length(self) -> float:
        """x_hi − x_lo."""


class WindowSolver(ShockSolver, Protocol):
    """What the window methods (``methods.control``, ``methods.steady``) need of a moving
    window: the inflow velocity ``u_in`` at x_hi and the outflow velocity ``u_out`` at x_lo
    (window frame), so that u_p = u_out − u_in; ``geom``; the transverse ``area``; the time
    step ``dt``; the particle count inside the window (the ω signal); and ``set_outflow``
    (MW's handle)."""

    u_in: float
    u_out: float
    geom: WindowGeometry
    area: float

    @property
    def dt(self) -> float:
        """The solver's time step."""

    def count_in_window(self) -> int:
        """Mobile particles between x_lo and x_hi."""

    def set_outflow(self, u_out: float) -> None:
        """Set the outflow velocity (u_p = u_out − u_in changes, the inflow is held)."""
