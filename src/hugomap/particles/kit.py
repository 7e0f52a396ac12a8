"""What the moving window (``particles.window.ParticleWindow``) and its inflow reservoir
(``particles.reservoir.make_reservoir``) need to know of a particle backend beyond the
simulation's own interface (``ParticleKit``); ``md.kit.MDKit`` is the numba MD's,
``lammps.window.LammpsKit`` LAMMPS's.
"""

from __future__ import annotations

import os
from typing import Any, Protocol

import numpy as np
import xarray as xr

from ..io.checkpoint import CheckpointKind

__all__ = ["ParticleKit", "ParticleSim"]

#: A particle simulation as this package drives it: an ``md.simulation.MDSimulation`` or a
#: ``lammps.simulation.LammpsSimulation`` (what it must offer: ``particles.window``'s
#: module docstring). Each backend's is its own class; nothing checks the type.
ParticleSim = Any


class ParticleKit(Protocol):
    """What ``ParticleWindow`` and ``make_reservoir`` need to know of a particle backend
    beyond the simulation's own interface (module docstring), in the simulation's units:
    ``window_kind`` (its window checkpoint kind), ``units`` (the names of its length and
    velocity units), ``scale`` (the length the set-up's fixed lengths are counted in; σ),
    ``m_kin`` (K = ½ m_kin Σ v²)."""

    window_kind: CheckpointKind
    units: tuple[str, str]
    scale: float
    m_kin: float

    def rc(self, sim) -> float:
        """The cutoff of ``sim``'s model."""

    def rlist(self) -> float:
        """Cutoff plus neighbour skin."""

    def kT(self, T: float) -> float:
        """k_B T in energy units."""

    def reservoir(self, cells: tuple[int, int, int], rho0: float, T0: float, dt: float,
                  seed: int, tau_bath: float):  # fmt: skip
        """A fully periodic FCC box at (ρ0, T0) under a thermostat."""

    def periodic(self, x: np.ndarray, v: np.ndarray, L: np.ndarray, dt: float):
        """A fully periodic NVE box of these atoms."""

    def bulk_fields(self, run, L: np.ndarray) -> tuple[float, float, float]:
        """(P_xx, (P_yy + P_zz)/2, T) of a periodic box."""

    def domain(self, like, x: np.ndarray, v: np.ndarray, ids: np.ndarray, L: np.ndarray,
               walls0: np.ndarray):  # fmt: skip
        """The window's domain (walls along x), with the clock and time step of ``like``."""

    def load(self, ds: xr.Dataset, source: str | os.PathLike | None):
        """The simulation of a verified window checkpoint."""

    def skip_force_rows(self, sim, n: int) -> None:
        """Let ``sim`` skip the force on the frozen atoms with ids −1 … −n (the inflow copy),
        where it can without changing the mobile atoms' motion."""

    def live_reservoir(self, x: np.ndarray, v: np.ndarray, L: np.ndarray, dt: float,
                       seam_work: str):  # fmt: skip
        """The live inflow reservoir (``inflow = "live"``) of these atoms, a periodic box of
        side ``L`` run beside the window; ``WindowError`` ("bad_config") where the backend
        has none."""

    def load_live(self, ds: xr.Dataset, source: str | os.PathLike | None):
        """The live inflow reservoir a window checkpoint holds, or None."""
