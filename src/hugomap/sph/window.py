"""A moving observation window around a 1D CSPH simulation (``SPHWindow``): the window
protocol of ``md.window.MDWindow`` in SI units, so that ``window.methods`` runs on SPH
unchanged. Its checkpoint is the simulation's (``sph.checkpoint``) plus the window state.
"""

from __future__ import annotations

import json
import math
import os
from dataclasses import asdict, dataclass
from pathlib import Path

import numpy as np
import xarray as xr

from ..io.atomic import write_netcdf
from ..md.simulation import CheckpointError
from . import checkpoint as ckpt
from .simulation import CSPHSimulation, SPHUnstable
from .state import SPHState

# /2: the simulation inside is an ``sph.checkpoint`` (format hugomap-sph-checkpoint/1)
WINDOW_FORMAT = "hugomap-sph-window/2"


@dataclass
class SPHWindowGeometry:
    """x_lo, x_hi [m]: window edges; cut_every [m]: how far the outflow face (the wall) may
    recede behind x_lo before the particles behind x_lo are removed; sync_steps: steps between
    boundary updates; dx0 [m]: spacing of the fresh inflow material; n_inflow: frozen inflow
    particles kept beyond x_hi (≥ the kernel support in particles)."""

    x_lo: float
    x_hi: float
    cut_every: float
    sync_steps: int
    dx0: float
    n_inflow: int

    @property
    def length(self) -> float:
        return self.x_hi - self.x_lo


class SPHWindow:
    """A moving observation window around a 1D ``CSPHSimulation`` (the protocol of
    ``md.window.MDWindow``, SI units, per unit cross-section: ``area`` = 1 m²).

    Frame: the window's. Inflow: beyond x_hi, ``n_inflow`` frozen particles of fresh material
    at the initial state (ρ0, e0, S = 0, spacing dx0) move rigidly at u_in < 0; one that
    crosses x_hi is released (integrated from then on) and new ones are laid behind the last.
    Outflow: the left wall of the simulation is a rigid piston moving at u_out (its mirror
    ghosts hold the shocked state: it is the piston of the piston method, in the window
    frame); when it has receded ``cut_every`` behind x_lo, the particles behind x_lo are
    removed and the wall is put back halfway between the last removed and the first kept
    particle (as far from it as the piston face from the first particle at the start).
    With the lab frame's upstream at rest: u_in = −W, u_out = u_p − W, u_p = u_out − u_in.
    """

    def __init__(
        self,
        sim: CSPHSimulation,
        geom: SPHWindowGeometry,
        u_in: float,
        u_out: float,
        rho0: float,
        e0: float,
        m0: float,
    ):
        if sim.state.dim != 1:
            raise ValueError("SPHWindow runs 1D simulations only")
        self.sim = sim
        self.geom = geom
        self.u_in = float(u_in)
        self.u_out = float(u_out)
        self.rho0 = float(rho0)
        self.e0 = float(e0)
        self.m0 = float(m0)
        self.area = 1.0
        self.n_updates = 0  # boundary updates that added or removed particles (this process)

    @classmethod
    def from_piston(
        cls,
        sim: CSPHSimulation,
        x_front: float,
        u_p: float,
        D_guess: float,
        length: float,
        front_fraction: float = 0.5,
        cut_every: float | None = None,
        sync_steps: int = 10,
        n_inflow: int = 8,
        rho0: float | None = None,
        e0: float = 0.0,
    ) -> SPHWindow:
        """Cut a window out of a 1D piston run (lab frame: piston at the left wall moving at
        u_p, upstream at rest, initial density ``rho0``, default the EOS's ρ0) with the front
        at ``front_fraction`` of ``length`` from x_lo, in the frame moving at ``D_guess``."""
        st = sim.state
        if st.dim != 1:
            raise ValueError("SPHWindow.from_piston needs a 1D piston run")
        if rho0 is None:
            rho0 = float(sim.eos.params[0]) if sim.eos.name == "mie_gruneisen" else None
            if rho0 is None:
                raise ValueError("give rho0 for this EOS")
        order = np.argsort(st.x[:, 0], kind="stable")
        xs = st.x[order, 0]
        lo = x_front - front_fraction * length
        hi = x_front + (1.0 - front_fraction) * length
        k0 = int(np.searchsorted(xs, lo))
        m0 = float(np.median(st.m))
        dx0 = m0 / rho0
        if k0 < 2 or int(np.searchsorted(xs, hi)) + n_inflow > xs.size:
            raise ValueError(
                f"a window [{lo:.4g}, {hi:.4g}] m with {n_inflow} inflow particles does not fit "
                f"in the sample [{xs[0]:.4g}, {xs[-1]:.4g}] m: shorten it or lengthen the sample"
            )
        wall = 0.5 * (xs[k0 - 1] + xs[k0])
        keep = order[k0:]
        kx = st.x[keep, 0]
        inflow = kx >= hi
        n_keep = int(np.count_nonzero(~inflow)) + n_inflow
        keep = keep[:n_keep]
        frozen = np.zeros(n_keep, dtype=bool)
        frozen[n_keep - n_inflow :] = True
        du = -D_guess
        new = SPHState(
            x=st.x[keep] - lo, v=st.v[keep] + du, m=st.m[keep], rho=st.rho[keep],
            e=st.e[keep], S=st.S[keep], eps_p=st.eps_p[keep], l=st.l[keep], time=st.time,
        )  # fmt: skip
        u_in, u_out = du, u_p + du
        new.v[frozen, 0] = u_in
        w = CSPHSimulation(
            new, sim.eos, sim.strength, theta=sim.theta, cfl=sim.cfl, k_comp=sim.k_comp,
            walls=(wall - lo, u_out, None, 0.0), grad_correction=sim.grad_correction,
            dev_mean=sim.dev_mean, skin=sim.skin, dt_floor=sim.dt_floor, escape_distance=sim.escape,
        )  # fmt: skip
        w.dt = sim.dt  # the last step's Δt until the window takes its own (methods read it)
        w.frozen = frozen
        w.frozen_velocity = u_in
        w.frozen_state = (float(rho0), float(e0), float(dx0))
        cut = float(cut_every) if cut_every is not None else 10.0 * dx0
        geom = SPHWindowGeometry(0.0, hi - lo, cut, int(sync_steps), float(dx0), int(n_inflow))
        return cls(w, geom, u_in, u_out, rho0, e0, m0)

    # -- protocol ----------------------------------------------------------------------------
    @property
    def time(self) -> float:
        return self.sim.time

    @property
    def dt(self) -> float:
        return self.sim.dt

    @property
    def n_particles(self) -> int:
        f = self.sim.frozen
        return int(self.sim.state.n - (0 if f is None else np.count_nonzero(f)))

    def advance(self, n_steps: int) -> None:
        """Advance ``n_steps`` (rounded up to whole boundary updates of ``sync_steps``)."""
        k = self.geom.sync_steps
        for _ in range(max(1, math.ceil(n_steps / k))):
            self.sim.advance(k)
            self._update_boundaries()

    def _update_boundaries(self) -> None:
        g = self.geom
        sim = self.sim
        st = sim.state
        if not self.u_in < 0:
            raise SPHUnstable("no_inflow", f"u_in = {self.u_in:.4g} m/s must be < 0")
        if sim.walls[0] > g.x_lo + g.cut_every:
            raise SPHUnstable(
                "outflow_reversed",
                f"the outflow face moved {sim.walls[0] - g.x_lo:.3g} m into the window "
                f"(u_out = {self.u_out:.4g} m/s > 0 for too long)",
            )
        frozen = sim.frozen.copy()
        xs = st.x[:, 0]
        frozen &= xs >= g.x_hi  # release what crossed x_hi
        n_frozen = int(np.count_nonzero(frozen))
        add = g.n_inflow - n_frozen if n_frozen < g.n_inflow // 2 + 1 else 0
        cut = sim.walls[0] < g.x_lo - g.cut_every
        if not (add or cut):
            sim.frozen = frozen
            return
        keep = np.ones(st.n, dtype=bool)
        wall = float(sim.walls[0])
        if cut:
            behind = (xs < g.x_lo) & ~frozen
            keep = ~behind
            if behind.any() and keep.any():
                wall = 0.5 * (float(xs[behind].max()) + float(xs[keep].min()))
        arrays = {k: getattr(st, k)[keep] for k in ("x", "v", "m", "rho", "e", "S", "eps_p", "l")}
        frozen = frozen[keep]
        if add:
            last = float(xs[sim.frozen].max()) if sim.frozen.any() else float(xs.max())
            xn = last + g.dx0 * np.arange(1, add + 1)
            arrays["x"] = np.concatenate([arrays["x"], xn[:, None]])
            arrays["v"] = np.concatenate([arrays["v"], np.full((add, 1), self.u_in)])
            arrays["m"] = np.concatenate([arrays["m"], np.full(add, self.m0)])
            arrays["rho"] = np.concatenate([arrays["rho"], np.full(add, self.rho0)])
            arrays["e"] = np.concatenate([arrays["e"], np.full(add, self.e0)])
            arrays["S"] = np.concatenate([arrays["S"], np.zeros((add, 4))])
            arrays["eps_p"] = np.concatenate([arrays["eps_p"], np.zeros(add)])
            arrays["l"] = np.concatenate([arrays["l"], np.full(add, g.dx0)])
            frozen = np.concatenate([frozen, np.ones(add, dtype=bool)])
        sim.walls[0] = wall
        sim.replace_particles(SPHState(**arrays, time=st.time), frozen)
        self.n_updates += 1

    def galilean_shift(self, du: float) -> None:
        """Add ``du`` [m/s] to every velocity (mobile and frozen), u_in, u_out and the wall."""
        self.sim.state.v[:, 0] += du
        self.sim.walls[1] += du
        self.sim.frozen_velocity += du
        self.u_in += du
        self.u_out += du

    def set_outflow(self, u_out: float) -> None:
        """Set the outflow velocity [m/s]: the wall (piston) behind x_lo."""
        self.sim.walls[1] = u_out
        self.u_out = float(u_out)

    def wall_positions(self) -> tuple[float, float]:
        return self.geom.x_lo, self.geom.x_hi

    def count_in_window(self) -> int:
        """Mobile particles with x_lo ≤ x < x_hi."""
        xs = self.sim.state.x[:, 0]
        inside = (xs >= self.geom.x_lo) & (xs < self.geom.x_hi) & ~self.sim.frozen
        return int(np.count_nonzero(inside))

    def mean_velocity(self) -> float:
        st = self.sim.state
        mob = ~self.sim.frozen
        return float(np.sum(st.m[mob] * st.v[mob, 0]) / np.sum(st.m[mob]))

    def profile_sums(self, width: float) -> np.ndarray:
        """``csph.PROFILE_FIELDS`` sums in bins of ``width`` [m] from x_lo across the window."""
        nb = int(math.ceil(self.geom.length / width - 1e-9))
        return self.sim.profile_sums(width, x0=self.geom.x_lo, nbins=nb)

    # -- checkpoints -------------------------------------------------------------------------
    def to_dataset(self, attrs: dict | None = None) -> xr.Dataset:
        """Everything the continuation needs: the simulation's checkpoint
        (``sph.checkpoint.to_dataset``: state, frozen mask, walls, neighbour list, clock,
        solver, SHA-256) with the window's geometry and boundary state as attributes."""
        window = {"u_in": self.u_in, "u_out": self.u_out, "rho0": self.rho0, "e0": self.e0,
                  "m0": self.m0}  # fmt: skip
        return ckpt.to_dataset(
            self.sim,
            attrs={**(attrs or {}), "window_format": WINDOW_FORMAT,
                   "geometry": json.dumps(asdict(self.geom)), "window": json.dumps(window)},
        )  # fmt: skip

    def save(self, path: str | os.PathLike, attrs: dict | None = None) -> Path:
        """Save atomically; ``load`` continues bit for bit (same thread count)."""
        return write_netcdf(self.to_dataset(attrs), path)

    @classmethod
    def from_dataset(cls, ds: xr.Dataset, source: str | os.PathLike | None = None) -> SPHWindow:
        """Rebuild a window saved by ``save``; a foreign or altered file raises
        ``CheckpointError`` naming ``source``."""
        where = str(source if source is not None else ds.encoding.get("source", "(in memory)"))
        if ds.attrs.get("window_format") != WINDOW_FORMAT:
            raise CheckpointError(
                where, f"not an SPH window (format {ds.attrs.get('window_format')!r})"
            )
        sim = ckpt.from_dataset(ds, where)
        geom = SPHWindowGeometry(**json.loads(ds.attrs["geometry"]))
        w = json.loads(ds.attrs["window"])
        return cls(sim, geom, w["u_in"], w["u_out"], w["rho0"], w["e0"], w["m0"])

    @classmethod
    def load(cls, path: str | os.PathLike) -> SPHWindow:
        with xr.open_dataset(path, engine="netcdf4") as ds:
            ds.load()
        return cls.from_dataset(ds, path)
