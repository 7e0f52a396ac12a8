"""A moving observation window around a 1D CSPH simulation (``SPHWindow``): the window
protocol (``methods.protocol.WindowSolver``, which the particle window
``particles.window.ParticleWindow`` implements too) in SI units, so that ``hugomap.methods``
runs on SPH unchanged. Its checkpoint is the simulation's (``sph.checkpoint``) plus the
window state.
"""

from __future__ import annotations

import json
import math
import os
from dataclasses import asdict, dataclass
from pathlib import Path

import numpy as np
import xarray as xr

from ..failures import SPHUnstable
from ..io.atomic import write_netcdf
from ..io.checkpoint import (
    CSPH_WINDOW_2D_CHECKPOINT,
    CSPH_WINDOW_CHECKPOINT,
    checkpoint_source,
    read_checkpoint,
    verify_checkpoint,
)
from . import checkpoint as ckpt
from .simulation import CSPHSimulation, _threads_for
from .state import SPHState

#: The per-particle arrays of an ``SPHState`` that the boundaries cut and extend.
STATE_ARRAYS = ("x", "v", "m", "rho", "e", "S", "eps_p", "l")


def _fresh_arrays(x, v, m, rho, e, l) -> dict[str, np.ndarray]:
    """Fresh, unstressed material (S = 0, no plastic strain) as ``STATE_ARRAYS``."""
    n = m.size
    return {"x": x, "v": v, "m": m, "rho": rho, "e": e, "S": np.zeros((n, 4)),
            "eps_p": np.zeros(n), "l": l}  # fmt: skip


@dataclass
class SPHWindowGeometry:
    """x_lo, x_hi [m]: window edges; cut_every [m]: how far the outflow face (the wall) may
    recede behind x_lo before the particles wholly behind x_lo are removed; sync_steps: steps between
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
    ``methods.protocol.WindowSolver``, as ``particles.window.ParticleWindow``; SI units, per
    unit cross-section: ``area`` = 1 m²).

    Frame: the window's. Inflow: beyond x_hi, ``n_inflow`` frozen particles of fresh material
    at the initial state (ρ0, e0, S = 0, spacing dx0) move rigidly at u_in < 0; one that
    crosses x_hi is released (integrated from then on) and new ones are laid behind the last.
    Outflow: the left wall of the simulation is a rigid piston moving at u_out (its mirror
    ghosts hold the shocked state: it is the piston of the piston method, in the window
    frame); when it has receded ``cut_every`` behind x_lo, the particles wholly behind x_lo
    (x + l/2 ≤ x_lo) are removed and the wall is put back halfway between the last removed and the first kept
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
            dev_mean=sim.dev_mean, density=sim.density_mode, skin=sim.skin,
            dt_floor=sim.dt_floor, escape_distance=sim.escape,
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
    def steps(self) -> int:
        """Time steps of the simulation inside."""
        return int(self.sim.steps)

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
        """Release the frozen inflow particles that crossed x_hi and lay fresh ones behind
        (``_inflow``, ``_fresh``); cut the outflow when its wall has receded ``cut_every``
        behind x_lo: the mobile particles wholly behind x_lo (x + l/2 ≤ x_lo) are removed and the wall put halfway
        between the last removed and the first kept particle."""
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
        xs = st.x[:, 0]
        frozen, add = self._inflow(xs)
        cut = sim.walls[0] < g.x_lo - g.cut_every
        if not (add or cut):
            sim.frozen = frozen
            return
        keep = np.ones(st.n, dtype=bool)
        wall = float(sim.walls[0])
        if cut:
            # wholly behind x_lo: the count (``count_in_window``) does not change
            behind = (xs + 0.5 * st.l <= g.x_lo) & ~frozen
            keep = ~behind
            self._removed(float(np.sum(st.m[behind])))
            if behind.any() and keep.any():
                wall = 0.5 * (float(xs[behind].max()) + float(xs[keep].min()))
        arrays = {k: getattr(st, k)[keep] for k in STATE_ARRAYS}
        frozen = frozen[keep]
        if add:
            fresh = self._fresh(add, xs)
            arrays = {k: np.concatenate([arrays[k], fresh[k]]) for k in STATE_ARRAYS}
            frozen = np.concatenate([frozen, np.ones(fresh["m"].size, dtype=bool)])
        sim.walls[0] = wall
        sim.replace_particles(SPHState(**arrays, time=st.time), frozen)
        self.n_updates += 1

    def _inflow(self, xs: np.ndarray) -> tuple[np.ndarray, int]:
        """(frozen mask after releasing what crossed x_hi, number of fresh particles to lay):
        the frozen layer is topped up to ``n_inflow`` when fewer than half remain."""
        g = self.geom
        frozen = self.sim.frozen & (xs >= g.x_hi)
        n_frozen = int(np.count_nonzero(frozen))
        return frozen, (g.n_inflow - n_frozen if n_frozen < g.n_inflow // 2 + 1 else 0)

    def _fresh(self, add: int, xs: np.ndarray) -> dict[str, np.ndarray]:
        """``add`` particles of fresh material (ρ0, e0, S = 0, spacing dx0) behind the last
        frozen one, moving at u_in."""
        f = self.sim.frozen
        last = float(xs[f].max()) if f.any() else float(xs.max())
        xn = last + self.geom.dx0 * np.arange(1, add + 1)
        return _fresh_arrays(xn[:, None], np.full((add, 1), self.u_in), np.full(add, self.m0),
                             np.full(add, self.rho0), np.full(add, self.e0),
                             np.full(add, self.geom.dx0))  # fmt: skip

    def _removed(self, mass: float) -> None:
        """Mass [kg/m², or kg/m in 2D] cut out behind x_lo (the 2D window counts it)."""

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

    def count_in_window(self) -> float:
        """The particles inside [x_lo, x_hi], each counted by the fraction of its extent
        [x − l/2, x + l/2] along x that lies inside (l = (m/ρ)^(1/dim) [m], its size):

            N = Σ_i clip((min(x_i + l_i/2, x_hi) − max(x_i − l_i/2, x_lo))/l_i, 0, 1),

        frozen and mobile alike (a frozen inflow particle straddling x_hi is partly inside).
        N·m/(L A) is the window's mean density, so ω = (N − q_up)/(q_sh − q_up) moves
        continuously with the front. A whole-particle count moves in steps of one particle,
        dx ρ0/(ρ − ρ0) of front travel (44 µm at 1000 m/s, 0.4 mm at 100 m/s in copper at
        dx = 10 µm): a control window shorter than a step saw ω flat or one step, and MW
        stopped as calm with the front still drifting at 71 m/s (D 1.3 % off its frame at
        1000 m/s). The outflow cut removes only particles wholly behind x_lo, so a cut does
        not change N."""
        st = self.sim.state
        xs, half = st.x[:, 0], 0.5 * st.l
        g = self.geom
        inside = np.minimum(xs + half, g.x_hi) - np.maximum(xs - half, g.x_lo)
        return float(np.sum(np.clip(inside / st.l, 0.0, 1.0)))

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
            attrs={**(attrs or {}), "window_format": CSPH_WINDOW_CHECKPOINT.format,
                   "geometry": json.dumps(asdict(self.geom)), "window": json.dumps(window)},
        )  # fmt: skip

    def save(self, path: str | os.PathLike, attrs: dict | None = None) -> Path:
        """Save atomically; ``load`` continues bit for bit (same thread count)."""
        return write_netcdf(self.to_dataset(attrs), path)

    @classmethod
    def from_dataset(cls, ds: xr.Dataset, source: str | os.PathLike | None = None) -> SPHWindow:
        """Rebuild a window saved by ``save``; a foreign or altered file raises
        ``CheckpointError`` naming ``source``."""
        where = checkpoint_source(ds, source)
        if cls is SPHWindow and ds.attrs.get("window_format") == CSPH_WINDOW_2D_CHECKPOINT.format:
            return SPHWindow2D.from_dataset(ds, source)
        verify_checkpoint(ds, where, CSPH_WINDOW_CHECKPOINT)
        sim = ckpt.from_dataset(ds, where)
        geom = SPHWindowGeometry(**json.loads(ds.attrs["geometry"]))
        w = json.loads(ds.attrs["window"])
        return cls(sim, geom, w["u_in"], w["u_out"], w["rho0"], w["e0"], w["m0"])

    @classmethod
    def load(cls, path: str | os.PathLike) -> SPHWindow:
        """Load a window written by ``save`` (the 1D class hands a 2D file to ``SPHWindow2D``);
        an unreadable, foreign or altered file raises ``CheckpointError`` naming it."""
        return cls.from_dataset(read_checkpoint(path, verify=False), path)


# == the 2D window (plane strain, periodic in y) ===========================================


@dataclass
class InflowTile:
    """The inflow material of the 2D window: one period of a tile periodic in x and y (a
    ``sph.sample.porous_tile_2d`` or a full lattice), laid copy after copy along x.

    x (n, 2) [m]: sites in [0, n_cols·dx) × [y_lo, y_hi), y in the simulation's periodic box;
    m [kg/m], rho [kg/m³] (every particle at the solid density), l [m] per site; dx [m]: the
    column width (the lattice spacing); n_cols: columns in one period, so the period is
    L_t = n_cols·dx; rho_mean [kg/m³]: the tile's mean density ρ_s N a_p/(L_t W), the
    upstream density the window feeds. Column of a site: ⌊x/dx⌋ (square lattice at (i + ½)dx,
    hexagonal at (i + ¼)dx or (i + ¾)dx: always inside its column)."""

    x: np.ndarray
    m: np.ndarray
    rho: np.ndarray
    l: np.ndarray
    dx: float
    n_cols: int
    rho_mean: float

    @property
    def length(self) -> float:
        return self.n_cols * self.dx

    @classmethod
    def from_sample(cls, sample) -> InflowTile:
        """From a ``sph.sample.Sample`` periodic in x and y (a tile)."""
        # a full lattice is periodic in x by construction; pores must wrap round x too
        periodic = sample.periodic_y and (sample.periodic_x or sample.pore_radii.size == 0)
        if sample.dim != 2 or not periodic:
            raise ValueError("the inflow tile must be a 2D sample periodic in x and y")
        n_cols = int(round((sample.x_hi - sample.x_lo) / sample.dx))
        x = np.array(sample.x, dtype=np.float64)
        x[:, 0] -= sample.x_lo
        return cls(x, np.array(sample.m, dtype=np.float64), np.array(sample.rho, dtype=np.float64),
                   np.array(sample.l, dtype=np.float64), float(sample.dx), n_cols,
                   float(sample.rho_mean))  # fmt: skip

    def columns(self) -> np.ndarray:
        return np.floor(self.x[:, 0] / self.dx).astype(np.int64)

    def chunk(self, col0: int, k: int, x_start: float) -> np.ndarray:
        """Indices and window positions of the sites of columns col0 … col0 + k − 1 (modulo
        n_cols), laid from ``x_start`` [m]: returns (index, x (n, 2))."""
        if not 0 < k <= self.n_cols:
            raise ValueError(f"a chunk of {k} columns out of a tile of {self.n_cols}")
        rel = np.mod(self.columns() - col0, self.n_cols)
        sel = np.nonzero(rel < k)[0]
        sel = sel[np.argsort(rel[sel], kind="stable")]
        pos = self.x[sel].copy()
        # the site's offset inside its column is kept: the seam between copies is the tile's
        # own periodic boundary (no gap, no overlap)
        pos[:, 0] = x_start + rel[sel] * self.dx + (self.x[sel, 0] - self.columns()[sel] * self.dx)
        return sel, pos


class SPHWindow2D(SPHWindow):
    """The moving window around a 2D plane-strain ``CSPHSimulation`` periodic in y (the
    protocol of ``SPHWindow``; ``area`` = the periodic width W [m], per metre of depth).

    Inflow: beyond x_hi, frozen particles of an ``InflowTile`` move rigidly at u_in < 0 (x and
    y both held: only x moves, at u_in); one that crosses x_hi is released. The frozen layer is
    kept between (n_inflow/2 + 1)·dx and n_inflow·dx + dx deep by laying the tile's next
    columns behind it: the tile is periodic in x, so the inflow is the tile repeated without a
    seam whatever the chunk size (the cursor ``tile_col`` remembers where the tile was cut).
    ``x_next`` [m] is where the next column starts, moving with the frozen particles at u_in
    (kept as its value at ``t_ref`` [s]). Outflow: the left wall (a piston at u_out with
    mirror ghosts); when it has receded ``cut_every`` behind x_lo, the mobile particles
    wholly behind x_lo are removed and the wall is put halfway between the last removed and the first
    kept particle along x (as in 1D; in compacted, disordered material that is about x_lo,
    where the kept particles' volume begins on average).
    Upstream state: the tile at rest in the lab frame (mean density ``rho0`` = ρ_s/α_tile,
    unstressed, e0); the frozen particles are held at the solid density, e0, S = 0.
    """

    def __init__(
        self,
        sim: CSPHSimulation,
        geom: SPHWindowGeometry,
        u_in: float,
        u_out: float,
        tile: InflowTile,
        e0: float,
        tile_col: int,
        x_next: float,
        t_ref: float,
    ):
        if sim.state.dim != 2 or not sim.periodic[1]:
            raise ValueError("SPHWindow2D runs 2D simulations periodic in y")
        self.sim = sim
        self.geom = geom
        self.u_in = float(u_in)
        self.u_out = float(u_out)
        self.tile = tile
        self.rho0 = float(tile.rho_mean)
        self.e0 = float(e0)
        self.m0 = float(np.median(tile.m))
        self.area = float(sim.length[1])
        self.depth = self.area  # slab states divide by n_bins·width·W (pores count)
        self.tile_col = int(tile_col)
        self.x_next = float(x_next)
        self.t_ref = float(t_ref)
        self.n_updates = 0
        #: mass released across x_hi and removed behind x_lo since the cut [kg/m]
        self.mass_in = 0.0
        self.mass_out = 0.0

    @classmethod
    def from_piston(  # type: ignore[override]
        cls,
        sim: CSPHSimulation,
        x_front: float,
        u_p: float,
        D_guess: float,
        length: float,
        front_fraction: float,
        tile: InflowTile,
        cut_every: float | None = None,
        sync_steps: int = 10,
        n_inflow: int = 8,
        x_origin: float = 0.0,
        e0: float = 0.0,
    ) -> SPHWindow2D:
        """Cut a window out of a 2D piston run (lab frame, upstream at rest) with the front at
        about ``front_fraction`` of ``length`` from x_lo, in the frame moving at D_guess
        [m/s]. x_hi is put on a lattice line of the sample (x_origin + k·dx, dx = the tile's)
        so that the sample's columns below it and the first tile column above it join without
        a gap; the sample's particles beyond x_hi are dropped and the tile is laid from x_hi
        (column 0 first), frozen. Lengths in m."""
        st = sim.state
        if st.dim != 2:
            raise ValueError("SPHWindow2D.from_piston needs a 2D piston run")
        dx = tile.dx
        hi = x_origin + round((x_front + (1.0 - front_fraction) * length - x_origin) / dx) * dx
        lo = hi - length
        xs = st.x[:, 0]
        if lo <= float(sim.walls[0]) + dx or hi > float(xs.max()):
            raise ValueError(
                f"a window [{lo:.4g}, {hi:.4g}] m does not fit in the sample between the "
                f"piston at {sim.walls[0]:.4g} m and its far end at {xs.max():.4g} m: shorten "
                "it, move window.front_fraction or load further"
            )
        keep = np.nonzero(xs >= lo)[0]
        keep = keep[xs[keep] < hi]
        behind = xs < lo
        wall = 0.5 * (float(xs[behind].max()) + float(xs[keep].min())) if behind.any() else lo
        du = -D_guess
        u_in, u_out = du, u_p + du
        k = n_inflow + 1
        sel, pos = tile.chunk(0, k, hi)
        n_t = sel.size
        arrays = {
            "x": np.concatenate([st.x[keep], pos]) - np.array([lo, 0.0]),
            "v": np.concatenate([st.v[keep] + np.array([du, 0.0]),
                                 np.tile([u_in, 0.0], (n_t, 1))]),
            "m": np.concatenate([st.m[keep], tile.m[sel]]),
            "rho": np.concatenate([st.rho[keep], tile.rho[sel]]),
            "e": np.concatenate([st.e[keep], np.full(n_t, e0)]),
            "S": np.concatenate([st.S[keep], np.zeros((n_t, 4))]),
            "eps_p": np.concatenate([st.eps_p[keep], np.zeros(n_t)]),
            "l": np.concatenate([st.l[keep], tile.l[sel]]),
        }  # fmt: skip
        new = SPHState(**arrays, time=st.time)
        frozen = np.zeros(new.n, dtype=bool)
        frozen[keep.size :] = True
        w = CSPHSimulation(
            new, sim.eos, sim.strength, theta=sim.theta, cfl=sim.cfl, k_comp=sim.k_comp,
            walls=(wall - lo, u_out, None, 0.0), periodic=(False, True),
            lo=(0.0, float(sim.lo[1])), length=(1.0, float(sim.length[1])),
            grad_correction=sim.grad_correction, dev_mean=sim.dev_mean,
            density=sim.density_mode, skin=sim.skin,
            dt_floor=sim.dt_floor, escape_distance=sim.escape,
        )  # fmt: skip
        w.dt = sim.dt
        w.frozen = frozen
        w.frozen_velocity = u_in
        w.frozen_state = (float(np.median(tile.rho)), float(e0), float(np.median(tile.l)))
        cut = float(cut_every) if cut_every is not None else 10.0 * dx
        geom = SPHWindowGeometry(0.0, hi - lo, cut, int(sync_steps), float(dx), int(n_inflow))
        return cls(w, geom, u_in, u_out, tile, e0, k % tile.n_cols, length + k * dx, st.time)

    # -- protocol ----------------------------------------------------------------------------
    def advance(self, n_steps: int) -> None:
        """Advance ``n_steps`` (rounded up to whole boundary updates of ``sync_steps``); the
        frozen particles' y is put back after every step (the solver moves only their x)."""
        k = self.geom.sync_steps
        sim = self.sim
        with _threads_for(sim.state.n):
            for _ in range(max(1, math.ceil(n_steps / k))):
                for _ in range(k):
                    f = sim.frozen
                    y = sim.state.x[f, 1].copy()
                    sim.step()
                    sim.state.x[f, 1] = y
                self._update_boundaries()

    def _sync_inflow(self) -> None:
        """Bring ``x_next`` to the current time (it moves with the frozen particles)."""
        t = self.sim.time
        self.x_next += self.sim.frozen_velocity * (t - self.t_ref)
        self.t_ref = t

    def _inflow(self, xs: np.ndarray) -> tuple[np.ndarray, int]:
        """Release what crossed x_hi (its mass counted in ``mass_in``); lay the tile's next
        columns when the frozen layer is thinner than (n_inflow/2 + 1)·dx."""
        g = self.geom
        self._sync_inflow()
        frozen = self.sim.frozen & (xs >= g.x_hi)
        self.mass_in += float(np.sum(self.sim.state.m[self.sim.frozen & ~frozen]))
        depth = self.x_next - g.x_hi
        add = 0
        if depth < (g.n_inflow // 2 + 1) * g.dx0:
            add = int(min(math.ceil(((g.n_inflow + 1) * g.dx0 - depth) / g.dx0), self.tile.n_cols))
        return frozen, add

    def _fresh(self, add: int, xs: np.ndarray) -> dict[str, np.ndarray]:
        """The tile's next ``add`` columns from ``x_next`` (the cursor moves on)."""
        sel, pos = self.tile.chunk(self.tile_col, add, self.x_next)
        n = sel.size
        self.x_next += add * self.geom.dx0
        self.tile_col = (self.tile_col + add) % self.tile.n_cols
        return _fresh_arrays(pos, np.tile([self.u_in, 0.0], (n, 1)), self.tile.m[sel],
                             self.tile.rho[sel], np.full(n, self.e0), self.tile.l[sel])  # fmt: skip

    def _removed(self, mass: float) -> None:
        self.mass_out += mass

    def galilean_shift(self, du: float) -> None:
        """Add ``du`` [m/s] to every x velocity (mobile and frozen), u_in, u_out and the wall;
        the inflow cursor is brought up to date first (it moves at the old u_in until now)."""
        self._sync_inflow()
        super().galilean_shift(du)

    # -- checkpoints -------------------------------------------------------------------------
    def to_dataset(self, attrs: dict | None = None) -> xr.Dataset:
        """The simulation's checkpoint with the tile (arrays ``tile_*``, checksummed with it)
        and the window's geometry and boundary state (inflow cursor) as attributes."""
        t = self.tile
        window = {"u_in": self.u_in, "u_out": self.u_out, "e0": self.e0,
                  "tile_col": self.tile_col, "x_next": self.x_next, "t_ref": self.t_ref,
                  "mass_in": self.mass_in, "mass_out": self.mass_out,
                  "tile_dx": t.dx, "tile_cols": t.n_cols,
                  "tile_rho_mean": t.rho_mean}  # fmt: skip
        extra = xr.Dataset({
            "tile_x": (("tile", "tile_dim"), t.x), "tile_m": ("tile", t.m),
            "tile_rho": ("tile", t.rho), "tile_l": ("tile", t.l),
        })  # fmt: skip
        return ckpt.to_dataset(
            self.sim, extra=extra,
            attrs={**(attrs or {}), "window_format": CSPH_WINDOW_2D_CHECKPOINT.format,
                   "geometry": json.dumps(asdict(self.geom)), "window": json.dumps(window)},
        )  # fmt: skip

    @classmethod
    def from_dataset(cls, ds: xr.Dataset, source: str | os.PathLike | None = None) -> SPHWindow2D:
        where = checkpoint_source(ds, source)
        verify_checkpoint(ds, where, CSPH_WINDOW_2D_CHECKPOINT)
        sim = ckpt.from_dataset(ds, where)
        geom = SPHWindowGeometry(**json.loads(ds.attrs["geometry"]))
        w = json.loads(ds.attrs["window"])
        tile = InflowTile(
            np.array(ds["tile_x"].values, dtype=np.float64), np.array(ds["tile_m"].values),
            np.array(ds["tile_rho"].values), np.array(ds["tile_l"].values), float(w["tile_dx"]),
            int(w["tile_cols"]), float(w["tile_rho_mean"]),
        )  # fmt: skip
        win = cls(sim, geom, w["u_in"], w["u_out"], tile, w["e0"], w["tile_col"], w["x_next"],
                  w["t_ref"])  # fmt: skip
        win.mass_in, win.mass_out = float(w["mass_in"]), float(w["mass_out"])
        return win


def window_from_dataset(ds: xr.Dataset, source: str | os.PathLike | None = None) -> SPHWindow:
    """The 1D or 2D window saved in ``ds`` (by its ``window_format``; ``SPHWindow.from_dataset``
    dispatches the same way)."""
    return SPHWindow.from_dataset(ds, source)
