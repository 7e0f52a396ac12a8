"""A synthetic shock front in a moving window: the window protocol with a known answer.

The material has the linear Hugoniot D = c0 + s u_p (lab frame, upstream at rest). In the
window frame the upstream flows in at u_in and the shocked material leaves at u_out, so the
amplitude is u_p = u_out − u_in and the front moves at
    dx_f/dt = u_in + c0 + s u_p_eff,
where u_p_eff is the amplitude the front feels: a change of u_out reaches the front only
after ``delay`` (the acoustic transit from the outflow boundary), while a Galilean shift
moves every velocity at once and changes nothing but the frame. The window [0, L] holds
upstream (number density ρ0) ahead of the front and shocked material (ρ1) behind it, so
    N = A [ρ1 x_f + ρ0 (L − x_f)] + noise,
with noise an Ornstein–Uhlenbeck process of standard deviation ``noise`` (in units of ω,
i.e. of N/(A L (ρ1 − ρ0))) and correlation time ``tau_c``. The front itself may wander:
``wander`` adds to dx_f/dt an Ornstein–Uhlenbeck velocity of that standard deviation and
correlation time ``wander_tau`` (an MD front pushed back and forth by acoustic waves), so
its position drifts like a random walk on times longer than ``wander_tau``. With the
normalisation of ``methods.OmegaSignal`` (q_up = ρ0 A L, q_sh = ρ1 A L) ω = x_f/L + noise
exactly.

Exact answers: AMW (u_p held) must end in the frame u_in = −(c0 + s u_p); MW and the
dichotomy (u_in held) at u_out = u_in + (−u_in − c0)/s. Units are arbitrary but consistent.
No physics is solved: this exercises the methods' control loops, not a solver.
"""

from __future__ import annotations

import copy
from dataclasses import dataclass

import numpy as np

from ..analysis.linear_hugoniot import shock_velocity


@dataclass
class SyntheticGeometry:
    x_lo: float
    x_hi: float

    @property
    def length(self) -> float:
        return self.x_hi - self.x_lo


class SyntheticFront:
    """The window protocol (``time``, ``dt``, ``u_in``, ``u_out``, ``geom``, ``area``,
    ``advance``, ``galilean_shift``, ``set_outflow``, ``count_in_window``) for the front
    model of the module docstring."""

    def __init__(
        self,
        c0: float,
        s: float,
        u_in: float,
        u_out: float,
        length: float = 50.0,
        front: float = 0.6,
        rho0: float = 1.0,
        rho1: float = 1.5,
        dt: float = 0.005,
        noise: float = 0.0,
        tau_c: float = 0.0,
        delay: float = 0.0,
        seed: int = 1,
        wander: float = 0.0,
        wander_tau: float = 1.0,
    ):
        self.c0, self.s = float(c0), float(s)
        self.u_in, self.u_out = float(u_in), float(u_out)
        self.geom = SyntheticGeometry(0.0, float(length))
        self.area = 1.0
        self.x_f = float(front) * length
        self.rho0, self.rho1 = float(rho0), float(rho1)
        self.dt = float(dt)
        self.noise, self.tau_c, self.delay = float(noise), float(tau_c), float(delay)
        self.rng = np.random.default_rng(seed)
        self.e = self.noise * self.rng.standard_normal() if self.noise > 0 else 0.0
        self.wander, self.wander_tau = float(wander), float(wander_tau)
        self.v = self.wander * self.rng.standard_normal() if self.wander > 0 else 0.0
        self.step = 0
        self._amplitudes: list[tuple[float, float]] = [(-np.inf, self.u_out - self.u_in)]

    @property
    def time(self) -> float:
        return self.step * self.dt

    @property
    def n_particles(self) -> int:
        return int(round(self.count_in_window()))

    def _u_p_eff(self, t: float) -> float:
        u = self._amplitudes[0][1]
        for since, amp in self._amplitudes:
            if since + self.delay <= t:
                u = amp
        return u

    def front_velocity(self) -> float:
        """dx_f/dt in the window frame now (module docstring)."""
        return self.u_in + shock_velocity(self._u_p_eff(self.time), self.c0, self.s)

    def advance(self, n_steps: int) -> None:
        for _ in range(n_steps):
            self.x_f += (self.front_velocity() + self.v) * self.dt
            self.step += 1
        if self.wander > 0:
            self.v = self._ou(self.v, self.wander, self.wander_tau, n_steps * self.dt)
        if self.noise > 0:
            self.e = self._ou(self.e, self.noise, self.tau_c, n_steps * self.dt)

    def _ou(self, x: float, sd: float, tau: float, span: float) -> float:
        """Exact Ornstein–Uhlenbeck update of x (standard deviation sd, correlation time
        tau) over a time span; white noise when tau = 0."""
        f = np.exp(-span / tau) if tau > 0 else 0.0
        return f * x + sd * np.sqrt(1 - f * f) * self.rng.standard_normal()

    def galilean_shift(self, du: float) -> None:
        self.u_in += du
        self.u_out += du

    def set_outflow(self, u_out: float) -> None:
        self.u_out = float(u_out)
        self._amplitudes.append((self.time, self.u_out - self.u_in))

    def count_in_window(self) -> float:
        L = self.geom.length
        x = self.x_f + self.e * L
        return self.area * (self.rho1 * x + self.rho0 * (L - x))

    def omega_normalisation(self) -> tuple[float, float]:
        """(q_up, q_sh) for ``methods.OmegaSignal(kind='N', ...)``."""
        L = self.geom.length
        return self.rho0 * self.area * L, self.rho1 * self.area * L

    def copy(self) -> SyntheticFront:
        """An independent copy (a 'checkpoint' for dichotomy trials)."""
        return copy.deepcopy(self)
