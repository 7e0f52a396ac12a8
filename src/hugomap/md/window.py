"""The moving observation window for LJ molecular dynamics.

Frame: the window's. Fresh material enters at the upstream edge ``x_hi`` moving at
``u_in`` < 0; shocked material leaves at the downstream edge ``x_lo`` moving at ``u_out``.
With the lab frame's upstream material at rest and the window moving at W (SEED-en.md, reading
notes): u_in = −W, u_out = u_p − W, so u_p = u_out − u_in, and a front at rest in the window
has D = −u_in. Reduced LJ units (σ, τ, ε; m = 1).

Inflow (no gap or overlap at the seam). Fresh material comes from a reservoir: a small fully
periodic box (length L_r ≥ 2 (rc + skin), the domain's transverse size) of the scene's initial
state, run in lockstep (same Δt, NVE, in its own rest frame). The reservoir's periodic images
are laid on a conveyor beyond ``x_hi``: image k of reservoir atom j sits at
x_hi + ξ_j + k L_r − c(t), with ξ_j its unwrapped coordinate and c = ∫ −u_in dt. The next image
of each atom is a frozen "ghost" in the domain (it exerts forces on the mobile atoms and
drifts at its reservoir velocity + u_in between updates); once it has crossed ``x_hi`` it
becomes a mobile atom with the reservoir's position and velocity + u_in. The mobile atom just
inside the seam is therefore the previous image of the ghost's periodic neighbour, evolved
for at most ~ (rc + skin)/|u_in| since it entered: the seam is the reservoir's own periodic
boundary, not a cut.

Outflow (holds the shocked state). The material behind ``x_lo`` is a rigid piston made of the
shocked material itself: the atoms within ``ghost_width`` (≥ rc) behind the face are frozen
and move at ``u_out``, so the mobile atoms see a snapshot of their own state on the far side
rather than a wall, and the boundary is a velocity condition at the flow speed (the piston of
the piston method, in the window frame). When the face has moved ``cut_every`` behind
``x_lo``, the layer is cut again: frozen atoms farther than ``ghost_width`` behind ``x_lo``
are removed, the mobile atoms behind ``x_lo`` are frozen (their thermal velocities dropped),
and the face returns to ``x_lo``. A reflecting wall behind the frozen layer, moving with it,
catches any atom that would slip through.

Frozen atoms carry negative ids (inflow ghosts −1 − j, outflow ghosts ≤ −1 − N_res) and are
skipped by the kicks, the walls and every observable (``md.integrate``, ``MDSimulation``).
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
from .potential import LJParams
from .sample import fcc_state
from .simulation import MDSimulation, MDState, SolverUnstable

WINDOW_FORMAT = "hugomap-md-window/1"
MARGIN = 2.0  # σ of empty box beyond the frozen layers


class WindowError(RuntimeError):
    """The window cannot be set up or cannot go on: ``status`` says which way."""

    def __init__(self, status: str, diagnostic: str):
        super().__init__(f"{status}: {diagnostic}")
        self.status = status
        self.diagnostic = diagnostic


@dataclass
class WindowGeometry:
    """x_lo, x_hi [σ]: window edges in the box; ghost_width [σ]: frozen outflow layer;
    cut_every [σ]: face travel between outflow cuts; sync_steps: steps between boundary
    updates; res_length [σ]: reservoir length (a whole number of lattice cells)."""

    x_lo: float
    x_hi: float
    ghost_width: float
    cut_every: float
    sync_steps: int
    res_length: float

    @property
    def length(self) -> float:
        return self.x_hi - self.x_lo


def make_reservoir(
    cells_yz: tuple[int, int], rho0: float, T0: float, lj: LJParams, dt: float, seed: int,
    equilibrate_time: float, tau_bath: float = 0.5,
) -> MDSimulation:  # fmt: skip
    """A fully periodic FCC box at (ρ0, T0), thermostatted (CSVR) for ``equilibrate_time``
    [τ], then left to run NVE; x is as many cells as make L_r ≥ 2 (rc + skin) + 1 σ."""
    a = (4.0 / rho0) ** (1.0 / 3.0)
    nx = max(2, math.ceil((2.0 * lj.rlist + 1.0) / a))
    state = fcc_state((nx, *cells_yz), rho0, T0, seed, periodic_x=True)
    res = MDSimulation(state, lj, dt, T_bath=T0, tau_bath=tau_bath, seed=seed)
    res.advance(max(1, int(round(equilibrate_time / dt))))
    res.T_bath = None
    res.galilean_shift(-res.mean_velocity())  # the reservoir's rest frame
    return res


def _phase(x: np.ndarray, period: float) -> float:
    """Phase [0, period) of a set of coordinates against a lattice of planes of that period."""
    z = np.exp(2j * np.pi * x / period).mean()
    return float((np.angle(z) / (2 * np.pi)) % 1.0 * period)


class MDWindow:
    """A moving window around an ``MDSimulation`` (module docstring).

    Implements the shock-solver protocol of ``window.protocol`` in the window frame:
    ``advance``, ``galilean_shift``, ``set_outflow``, ``omega`` and checkpoints.
    """

    def __init__(
        self,
        sim: MDSimulation,
        res: MDSimulation,
        geom: WindowGeometry,
        u_in: float,
        u_out: float,
        conveyor: float,
        res_unwrapped: np.ndarray,
        res_prev: np.ndarray,
        next_image: np.ndarray,
        x_face: float,
        next_id: int,
    ):
        self.sim = sim
        self.res = res
        self.geom = geom
        self.u_in = float(u_in)
        self.u_out = float(u_out)
        self.conveyor = float(conveyor)
        self.res_unwrapped = res_unwrapped  # (N_res,) by reservoir id
        self.res_prev = res_prev  # (N_res,) wrapped x at the last update, by id
        self.next_image = next_image  # (N_res,) int, by id
        self.x_face = float(x_face)
        self.next_id = int(next_id)
        self.area = float(sim.state.L[1] * sim.state.L[2])
        self.n_res = int(res.state.n)

    # -- set-up ------------------------------------------------------------------------------
    @classmethod
    def from_piston(
        cls,
        sim: MDSimulation,
        res: MDSimulation,
        x_front: float,
        u_p: float,
        D_guess: float,
        length: float,
        front_fraction: float,
        ghost_width: float,
        cut_every: float,
        sync_steps: int,
        wall_layer: float = 4.0,
        crystal: bool = False,
        lattice: float | None = None,
    ) -> MDWindow:
        """Cut a window out of a piston run (piston frame: piston at rest at the left wall,
        upstream material at −u_p) with the front at ``front_fraction`` of ``length`` from
        the outflow edge, and move to the frame in which a front of speed ``D_guess`` is at
        rest: every velocity gets u_p − D_guess, so u_in = −D_guess, u_out = u_p − D_guess.

        For a crystal (``crystal``), the seam is placed so that the reservoir's lattice planes
        continue the sample's (period a/2 along each axis, ``lattice`` = a)."""
        s = sim.state
        xl, xr = sim.wall_positions()
        lo_s = x_front - front_fraction * length
        hi_s = x_front + (1.0 - front_fraction) * length
        if lo_s - ghost_width < xl + wall_layer or hi_s > xr - wall_layer:
            raise WindowError(
                "sample_too_short",
                f"a window of {length:.1f} sigma around the front at {x_front:.1f} needs "
                f"[{lo_s - ghost_width:.1f}, {hi_s:.1f}] inside [{xl + wall_layer:.1f}, "
                f"{xr - wall_layer:.1f}]: shorten the window or lengthen the sample",
            )
        mobile = s.ids >= 0
        x, v = s.x[mobile].copy(), s.v[mobile].copy()
        r = res.state
        rx = r.x.copy()
        Lr = float(r.L[0])
        if crystal:
            if lattice is None:
                raise ValueError("crystal windows need the lattice constant")
            half = 0.5 * lattice
            up = (x[:, 0] > hi_s - 4 * lattice) & (x[:, 0] < hi_s)
            for d in (1, 2):  # transverse registry: shift the reservoir onto the sample
                shift = _phase(x[up, d], half) - _phase(rx[:, d], half)
                rx[:, d] = (rx[:, d] + shift) % r.L[d]
            # Reservoir planes at a/4 + m a/2; the seam x_hi goes a/4 past a sample plane, so
            # the first ghost plane, at x_hi + a/4, continues the sample's lattice.
            rx[:, 0] = (rx[:, 0] + 0.25 * lattice - _phase(rx[:, 0], half)) % Lr
            target = (_phase(x[up, 0], half) + 0.25 * lattice) % half
            hi_s = hi_s - ((hi_s - target) % half)
            r.x[:] = rx  # the reservoir itself moves in y, z (a rigid periodic shift)
            r.x_ref[:] = rx
            res._build_list(sort=False)
        x_lo = ghost_width + cut_every + MARGIN
        shift = x_lo - (hi_s - length)
        x[:, 0] += shift
        x_hi = hi_s + shift
        keep = (x[:, 0] >= x_lo - ghost_width) & (x[:, 0] < x_hi)
        x, v = x[keep], v[keep]
        ids = np.arange(x.shape[0], dtype=np.int64)
        du = u_p - D_guess
        v[:, 0] += du
        u_in, u_out = -u_p + du, du
        frozen = x[:, 0] < x_lo
        n_res = r.n
        ids[frozen] = -1 - n_res - ids[frozen]
        v[frozen] = [u_out, 0.0, 0.0]
        Lx = x_hi + Lr + 2.0 * MARGIN
        L = np.array([Lx, s.L[1], s.L[2]])
        geom = WindowGeometry(x_lo, x_hi, ghost_width, cut_every, sync_steps, Lr)
        wall_x = x_lo - ghost_width - 0.5 * MARGIN
        state = MDState(
            x=x, v=v, L=L, periodic=np.array([False, True, True]),
            walls0=np.array([wall_x, u_out, Lx, 0.0]), ids=ids,
        )  # fmt: skip
        # The window keeps the piston run's clock (and its dt).
        state.time, state.step = s.time, s.step
        dom = MDSimulation(state, sim.lj, sim.dt)
        dom.place_walls(wall_x, u_out, Lx, 0.0)
        order = np.argsort(r.ids)
        xr_by_id = r.x[order, 0].copy()
        win = cls(
            dom, res, geom, u_in, u_out, conveyor=0.0, res_unwrapped=xr_by_id.copy(),
            res_prev=xr_by_id.copy(), next_image=np.zeros(n_res, dtype=np.int64),
            x_face=x_lo, next_id=int(x.shape[0]),
        )  # fmt: skip
        win._update_boundaries(first=True)
        return win

    # -- the time loop -------------------------------------------------------------------------
    @property
    def time(self) -> float:
        return self.sim.time

    @property
    def dt(self) -> float:
        return self.sim.dt

    @property
    def n_particles(self) -> int:
        return int(np.count_nonzero(self.sim.state.ids >= 0))

    def advance(self, n_steps: int) -> None:
        """Advance ``n_steps`` (rounded up to whole boundary updates of ``sync_steps``)."""
        k = self.geom.sync_steps
        for _ in range(max(1, math.ceil(n_steps / k))):
            self.sim.advance(k)
            self.res.advance(k)
            self.conveyor += -self.u_in * k * self.sim.dt
            self.x_face += self.u_out * k * self.sim.dt
            self._update_boundaries()

    def _update_boundaries(self, first: bool = False) -> None:
        """Refresh the inflow ghosts from the reservoir, admit the atoms that crossed the
        seam, and cut the outflow layer when its face has moved ``cut_every``."""
        g, s, r = self.geom, self.sim.state, self.res.state
        if not self.u_in < 0:
            raise WindowError("no_inflow", f"u_in = {self.u_in:.4g} sigma/tau must be < 0")
        if self.x_face > g.x_lo + g.cut_every:
            raise WindowError(
                "outflow_reversed",
                f"the outflow face moved {self.x_face - g.x_lo:.2f} sigma into the window "
                f"(u_out = {self.u_out:.4g} sigma/tau > 0 for too long)",
            )
        Lr = g.res_length
        order = np.argsort(r.ids)
        rx, rv = r.x[order], r.v[order]
        d = rx[:, 0] - self.res_prev
        d -= Lr * np.rint(d / Lr)
        self.res_unwrapped += d
        self.res_prev = rx[:, 0].copy()
        keep = ~((s.ids < 0) & (s.ids >= -self.n_res))  # drop the old inflow ghosts
        x, v, ids = s.x[keep], s.v[keep], s.ids[keep]
        new_x, new_v, new_ids = [], [], []
        # Admit every image that has crossed the seam (normally one or none per atom).
        while True:
            X = g.x_hi + self.res_unwrapped + self.next_image * Lr - self.conveyor
            enter = X < g.x_hi
            if first or not enter.any():
                break
            j = np.nonzero(enter)[0]
            pos = np.column_stack([X[j], rx[j, 1], rx[j, 2]])
            vel = rv[j].copy()
            vel[:, 0] += self.u_in
            new_x.append(pos)
            new_v.append(vel)
            new_ids.append(self.next_id + np.arange(j.size, dtype=np.int64))
            self.next_id += int(j.size)
            self.next_image[j] += 1
        # The next image of every reservoir atom within one reservoir length is a ghost.
        X = g.x_hi + self.res_unwrapped + self.next_image * Lr - self.conveyor
        j = np.nonzero(X < g.x_hi + Lr + 0.5 * MARGIN)[0]
        gv = rv[j].copy()
        gv[:, 0] += self.u_in
        new_x.append(np.column_stack([X[j], rx[j, 1], rx[j, 2]]))
        new_v.append(gv)
        new_ids.append(-1 - j.astype(np.int64))
        x = np.concatenate([x, *new_x])
        v = np.concatenate([v, *new_v])
        ids = np.concatenate([ids, *new_ids])
        if self.x_face < g.x_lo - g.cut_every:
            behind = x[:, 0] < g.x_lo
            gone = x[:, 0] < g.x_lo - g.ghost_width
            freeze = behind & ~gone & (ids >= 0)
            ids[freeze] = -1 - self.n_res - ids[freeze]
            v[behind] = [self.u_out, 0.0, 0.0]
            x, v, ids = x[~gone], v[~gone], ids[~gone]
            self.x_face = g.x_lo
            wall_x = g.x_lo - g.ghost_width - 0.5 * MARGIN
            self.sim.place_walls(wall_x, self.u_out, float(s.L[0]), 0.0)
        if first:
            x, v, ids = self._remove_seam_overlaps(x, v, ids)
        bad = (x[:, 0] < 0) | (x[:, 0] > s.L[0])
        if bad.any():
            raise SolverUnstable(
                "atom_lost", f"{int(bad.sum())} atoms outside the window box at t = {s.time:.3f}"
            )
        self.sim.replace_atoms(x, v, ids)

    def _remove_seam_overlaps(
        self, x: np.ndarray, v: np.ndarray, ids: np.ndarray, r_min: float = 0.8
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """At set-up only: drop mobile atoms closer than ``r_min`` σ to an inflow ghost (the
        first seam joins the piston sample to the reservoir; later seams are periodic)."""
        g, L = self.geom, self.sim.state.L
        near = np.nonzero((ids >= 0) & (x[:, 0] > g.x_hi - r_min))[0]
        ghosts = np.nonzero((ids < 0) & (ids >= -self.n_res) & (x[:, 0] < g.x_hi + r_min))[0]
        drop = np.zeros(x.shape[0], dtype=bool)
        for i in near:
            dd = x[ghosts] - x[i]
            for dim in (1, 2):
                dd[:, dim] -= L[dim] * np.rint(dd[:, dim] / L[dim])
            if ghosts.size and np.min(np.einsum("ij,ij->i", dd, dd)) < r_min**2:
                drop[i] = True
        return x[~drop], v[~drop], ids[~drop]

    # -- controls ------------------------------------------------------------------------------
    def galilean_shift(self, du: float) -> None:
        """Add ``du`` to every x velocity in the domain (mobile and frozen), to u_in, u_out and
        both walls; the reservoir stays in its own rest frame."""
        self.sim.galilean_shift(du)
        self.u_in += du
        self.u_out += du

    def set_outflow(self, u_out: float) -> None:
        """Set the outflow velocity [σ/τ]: the frozen layer and the wall behind it."""
        s = self.sim.state
        outflow = s.ids < -self.n_res
        s.v[outflow, 0] = u_out
        s.v[outflow, 1:] = 0.0
        xl, xr = self.sim.wall_positions()
        self.sim.place_walls(xl, u_out, xr, self.sim.state.walls0[3])
        self.u_out = float(u_out)

    def wall_positions(self) -> tuple[float, float]:
        return self.geom.x_lo, self.geom.x_hi

    def profile_sums(self, width: float) -> np.ndarray:
        return self.sim.profile_sums(width)

    def mean_velocity(self) -> float:
        return self.sim.mean_velocity()

    def count_in_window(self) -> int:
        """Mobile atoms with x_lo ≤ x < x_hi."""
        s = self.sim.state
        xs = s.x[:, 0]
        return int(np.count_nonzero((s.ids >= 0) & (xs >= self.geom.x_lo) & (xs < self.geom.x_hi)))

    # -- checkpoints ---------------------------------------------------------------------------
    def to_dataset(self, extra: xr.Dataset | None = None, attrs: dict | None = None) -> xr.Dataset:
        """The complete window state: the domain, the reservoir (``res_*``), the conveyor."""
        ds = self.sim.to_dataset(extra, attrs)
        rd = self.res.to_dataset()
        rd = rd.rename({k: "res_" + k for k in rd.data_vars}).rename(
            {"atom": "res_atom", "wall_param": "res_wall_param", "wall": "res_wall"}
        )
        ds = ds.merge(rd.drop_vars("xyz"))
        ds["res_unwrapped"] = (("res_atom",), self.res_unwrapped, {"units": "sigma"})
        ds["res_prev"] = (("res_atom",), self.res_prev, {"units": "sigma"})
        ds["res_next_image"] = (("res_atom",), self.next_image, {"units": "1"})
        ds.attrs.update(
            window_format=WINDOW_FORMAT,
            window_geometry=json.dumps(asdict(self.geom)),
            window_state=json.dumps(
                {
                    "u_in": self.u_in,
                    "u_out": self.u_out,
                    "conveyor": self.conveyor,
                    "x_face": self.x_face,
                    "next_id": self.next_id,
                }
            ),  # fmt: skip
            reservoir_attrs=json.dumps({k: rd.attrs[k] for k in rd.attrs}),
        )
        return ds

    def save(
        self, path: str | os.PathLike, extra: xr.Dataset | None = None, attrs: dict | None = None
    ) -> Path:
        """Save the window atomically (bit-exact on resume, at the same thread count)."""
        return write_netcdf(self.to_dataset(extra, attrs), path)

    @classmethod
    def from_dataset(cls, ds: xr.Dataset) -> MDWindow:
        """Rebuild a window saved by ``save``."""
        if ds.attrs.get("window_format") != WINDOW_FORMAT:
            raise ValueError(f"not an MD window checkpoint ({ds.attrs.get('window_format')!r})")
        sim = MDSimulation.from_dataset(ds)
        names = ("x", "v", "f", "x_ref", "ids", "L", "periodic", "walls0", "impulse")
        rd = xr.Dataset({k: ds["res_" + k] for k in names}).rename({"res_" + k: k for k in names})
        rd = rd.rename({"res_atom": "atom", "res_wall_param": "wall_param", "res_wall": "wall"})
        rd.attrs.update(json.loads(ds.attrs["reservoir_attrs"]))
        res = MDSimulation.from_dataset(rd)
        geom = WindowGeometry(**json.loads(ds.attrs["window_geometry"]))
        st = json.loads(ds.attrs["window_state"])
        return cls(
            sim, res, geom, st["u_in"], st["u_out"], st["conveyor"],
            ds["res_unwrapped"].values.copy(), ds["res_prev"].values.copy(),
            ds["res_next_image"].values.astype(np.int64), st["x_face"], st["next_id"],
        )  # fmt: skip
