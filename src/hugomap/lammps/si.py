"""What crosses the seam from a units-metal LAMMPS run, in SI: ``SIView`` (a simulation,
``methods.protocol.ShockSolver``) and ``WindowSIView`` (a window, ``WindowSolver``). The
simulation or window underneath keeps LAMMPS's units (Å, ps) and its raw profile sums (read
by ``backend.MetalProfile``, which converts them). Each conversion is one factor of
``units.UnitSystem``: time and dt [s] = [ps]·time_s; velocities, u_in, u_out [m/s] =
[Å/ps]·velocity_m_s; positions, x_lo, x_hi, length [m] = [Å]·length_m; area [m²] =
[Å²]·length_m²; a bin width [m] → [Å] for ``profile_sums``.
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .simulation import LammpsSimulation


class SIView:
    """A units-metal ``LammpsSimulation`` seen in SI by the shock methods
    (``methods.protocol.ShockSolver``): time [s], wall positions [m], velocities [m/s]; the
    simulation underneath (``sim``) keeps LAMMPS's units (Å, ps) and its raw profile sums
    (read by ``backend.MetalProfile``, which converts them). Each conversion is one factor
    of ``units.UnitSystem``: t = t_ps · time_s, x = x_Å · length_m, u = u_Å/ps ·
    velocity_m_s."""

    def __init__(self, sim: LammpsSimulation) -> None:
        self.sim = sim
        self.u = sim.unit_system

    @property
    def time(self) -> float:
        return self.sim.time * self.u.time_s

    @property
    def steps(self) -> int:
        return self.sim.steps

    @property
    def n_particles(self) -> int:
        return self.sim.n_particles

    @property
    def dt(self) -> float:
        return self.sim.dt * self.u.time_s

    def advance(self, n_steps: int) -> None:
        self.sim.advance(n_steps)

    def wall_positions(self) -> tuple[float, float]:
        xl, xr = self.sim.wall_positions()
        return xl * self.u.length_m, xr * self.u.length_m

    def set_walls(self, v_left: float, v_right: float) -> None:
        self.sim.set_walls(v_left / self.u.velocity_m_s, v_right / self.u.velocity_m_s)

    def mean_velocity(self) -> float:
        return self.sim.mean_velocity() * self.u.velocity_m_s

    def galilean_shift(self, du: float) -> None:
        self.sim.galilean_shift(du / self.u.velocity_m_s)

    def profile_sums(self, width: float) -> np.ndarray:
        """The simulation's raw sums (native units) over bins of ``width`` [m]."""
        return self.sim.profile_sums(width / self.u.length_m)

    def save(self, path: str | os.PathLike, extra=None, attrs=None) -> Path:
        return self.sim.save(path, extra=extra, attrs=attrs)


@dataclass(frozen=True)
class SIGeometry:
    """A window's edges in SI: x_lo, x_hi [m]."""

    x_lo: float
    x_hi: float

    @property
    def length(self) -> float:
        return self.x_hi - self.x_lo


class WindowSIView(SIView):
    """A units-metal window (``particles.window.ParticleWindow`` over a ``LammpsSimulation``) as the
    window methods see it, in SI (module docstring); ``sim`` is the window itself. What a
    shock solver shows (clock, walls, shifts, profiles, save) is ``SIView``'s;
    this adds the window's own quantities."""

    def __init__(self, window) -> None:
        self.sim = window
        self.u = window.sim.unit_system

    @property
    def u_in(self) -> float:
        return self.sim.u_in * self.u.velocity_m_s

    @property
    def u_out(self) -> float:
        return self.sim.u_out * self.u.velocity_m_s

    @property
    def geom(self) -> SIGeometry:
        g, m = self.sim.geom, self.u.length_m
        return SIGeometry(g.x_lo * m, g.x_hi * m)

    @property
    def area(self) -> float:
        return self.sim.area * self.u.length_m**2

    def set_outflow(self, u_out: float) -> None:
        self.sim.set_outflow(u_out / self.u.velocity_m_s)

    def count_in_window(self) -> int:
        return self.sim.count_in_window()
