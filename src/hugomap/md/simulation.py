"""The LJ molecular-dynamics simulation (``MDSimulation``): time loop, walls, observables and
its checkpoint.

``MDSimulation`` owns its state (an ``md.state.MDState``) and its time loop; the shock methods
drive it through ``advance``, ``set_walls``, ``galilean_shift``, ``profile_sums`` and
``save``/``load``. Its checkpoint is an ``io.checkpoint.MD_CHECKPOINT`` (format version and
checksum). Reduced LJ units throughout (σ, ε, m, τ = σ√(m/ε), k_B = 1).
"""

from __future__ import annotations

import json
import math
import os
from pathlib import Path

import numpy as np
import xarray as xr

from .. import __version__
from ..failures import SolverUnstable
from ..io.atomic import write_netcdf
from ..io.checkpoint import MD_CHECKPOINT, read_checkpoint, seal_checkpoint, verify_checkpoint
from ..numba_conf import num_threads
from ..particles.bins import bin_sums
from ..particles.profiles import SUM_FIELDS
from . import integrate as ig
from .forces import energy_virial_full, energy_virial_half
from .neighbor import cell_of, counting_sort, grid_shape
from .potential import LJParams
from .state import MDState


class MDSimulation:
    """Velocity-Verlet MD of an LJ system in a box with walls in x (or periodic in x).

    Parameters: ``state`` (MDState), ``lj`` (LJParams), ``dt`` [τ], optional thermostat
    temperature ``T_bath`` [ε/k_B] and time constant ``tau_bath`` [τ] (CSVR), ``seed``, and
    ``use_half`` (default True: Newton's third law on a half list, each pair computed once;
    False: the full list, each pair computed from both ends, rows in ``prange``).
    """

    def __init__(
        self,
        state: MDState,
        lj: LJParams,
        dt: float,
        T_bath: float | None = None,
        tau_bath: float = 0.5,
        seed: int = 0,
        use_half: bool = True,
    ):
        if not dt > 0:
            raise ValueError(f"dt = {dt}: must be > 0 tau")
        self.state = state
        self.lj = lj
        self._dt = float(dt)
        state.epoch_time, state.epoch_step = float(state.time), int(state.step)
        self.T_bath = T_bath
        self.tau_bath = float(tau_bath)
        self.seed = int(seed)
        # The half list (built from a half stencil, Newton's third law) does half the pair
        # work and half the list build of the full list (benchmarks/md_lj.py).
        self.use_half = bool(use_half)
        self.list_builds = 0
        self.rowless = 0  # frozen atoms with ids -1 ... -rowless have no force row
        for d in range(3):
            if state.periodic[d] and state.L[d] < 2.0 * lj.rlist:
                raise ValueError(
                    f"box length L[{'xyz'[d]}] = {state.L[d]:.4g} sigma is shorter than "
                    f"2 (rc + skin) = {2 * lj.rlist:.4g} sigma: the minimum image fails"
                )
        self.nc = grid_shape(state.L, lj.rlist)
        self._alloc_lists(self._row_estimate())
        self._build_list(sort=True)
        self._compute_forces()

    # -- neighbour lists -------------------------------------------------------------------
    def _row_estimate(self) -> int:
        """A first row width: the neighbours within rlist at the mean density, with room
        (a half-stencil row holds about half of them: bench/in.lj 38 on average, 63 at most
        of 77)."""
        s = self.state
        est = 4.0 / 3.0 * math.pi * self.lj.rlist**3 * s.n / float(np.prod(s.L))
        if self._direct_half():
            return int(est * 0.9) + 16
        return int(est * 1.5) + 16

    def _direct_half(self) -> bool:
        return self.use_half and bool(ig.half_stencil_ok(self.nc, self.state.periodic))

    def _alloc_lists(self, maxnb: int) -> None:
        """Rows of width ``maxnb`` for the list in use; the full list also when the half
        list is derived from it (a periodic dimension too short for the half stencil). A
        half row derived so can be as long as a full one (the atom sorted first in its
        neighbourhood has every neighbour j > i). Unused lists are 1 × 1 placeholders."""
        n = self.state.n
        self._direct = self._direct_half()
        full = not self._direct
        self.nbr = np.zeros((n if full else 1, maxnb if full else 1), dtype=np.int32)
        self.nnb = np.zeros(n if full else 1, dtype=np.int32)
        self.half = np.zeros((n if self.use_half else 1, maxnb if self.use_half else 1), np.int32)
        self.nhalf = np.zeros(n if self.use_half else 1, dtype=np.int32)
        # Newton's third law on several threads: one force buffer per thread but the first.
        nt = num_threads() if self.use_half else 1
        self.fbuf = np.zeros((nt - 1, n if nt > 1 else 1, 3))
        self._rows = n

    def _build_list(self, sort: bool) -> None:
        """(Re)build the list; ``sort=False`` rebuilds exactly the list made at x_ref."""
        s = self.state
        if self._direct != self._direct_half() or self._rows != s.n:
            self._alloc_lists(max(ig.list_width(self.nbr, self.half), 16))
        if sort:
            s.ref_shift = 0.0
        # The build's cell offsets, kept for the run's pair-by-pair list test.
        self.start = np.zeros(int(np.prod(self.nc)) + 1, dtype=np.int64)
        while True:
            if sort:
                need = ig.rebuild(
                    s.x, s.v, s.f, s.ids, s.x_ref, s.L, s.periodic, self.nc,
                    self.lj.rlist**2, self.nbr, self.nnb, self.use_half, self.half, self.nhalf,
                    self.rowless, self.start,
                )  # fmt: skip
                sort = False
            else:
                self.start[:] = counting_sort(cell_of(s.x_ref, s.L, self.nc), self.start.size - 1)[
                    1
                ]
                need = ig.build_lists(
                    s.x_ref, s.ids, s.L, s.periodic, self.nc, self.start, self.lj.rlist**2,
                    self.nbr, self.nnb, self.use_half, self.half, self.nhalf, self.rowless,
                )  # fmt: skip
            if need <= ig.list_width(self.nbr, self.half):
                self.list_builds += 1
                return
            self._alloc_lists(int(need * 1.3) + 8)

    def _force_args(self) -> tuple:
        s = self.state
        return (
            s.x, s.L, s.periodic, self.nbr, self.nnb, self.use_half, self.half, self.nhalf,
            self.lj.rc**2,
        )  # fmt: skip

    def _compute_forces(self) -> None:
        s = self.state
        ig.compute_forces(*self._force_args(), s.f, self.fbuf, s.ids, self.rowless)

    # -- time loop ---------------------------------------------------------------------------
    @property
    def dt(self) -> float:
        """Time step [τ]."""
        return self._dt

    @dt.setter
    def dt(self, value: float) -> None:
        if not value > 0:
            raise ValueError(f"dt = {value}: must be > 0 tau")
        if float(value) != self._dt:
            # A new epoch: time keeps counting from here in steps of the new dt.
            self.state.epoch_time, self.state.epoch_step = self.state.time, self.state.step
            self._dt = float(value)

    def _sync_time(self) -> None:
        s = self.state
        s.time = s.epoch_time + (s.step - s.epoch_step) * self._dt

    @property
    def time(self) -> float:
        return self.state.time

    @property
    def n_particles(self) -> int:
        return self.state.n

    @property
    def steps(self) -> int:
        """Time steps taken since the run began (the step counter of the state)."""
        return int(self.state.step)

    def _thermo_numbers(self, n: int) -> tuple[np.ndarray, np.ndarray, np.ndarray, int]:
        nf = 3 * self.state.n - (3 if self.state.periodic.all() else 0)
        if self.T_bath is None:
            return np.zeros(3), np.zeros(n), np.zeros(n), nf
        r1 = np.empty(n)
        chi = np.empty(n)
        for k in range(n):
            # One generator per absolute step: the stream does not depend on how the run is
            # split into advance() calls, so a resumed run draws the same numbers.
            g = np.random.default_rng([self.seed, self.state.step + k])
            r1[k] = g.standard_normal()
            chi[k] = g.chisquare(nf - 1)
        return np.array([self.T_bath, self.tau_bath, float(nf)]), r1, chi, nf

    def advance(self, n_steps: int) -> None:
        """Run ``n_steps`` velocity-Verlet steps; raise SolverUnstable if the run breaks."""
        s = self.state
        if self.T_bath is not None and (s.ids < 0).any():
            raise ValueError("the thermostat cannot run with frozen atoms (ids < 0)")
        done_total = 0
        thermo, r1, chi, _ = self._thermo_numbers(n_steps)
        counters = np.zeros(1, dtype=np.int64)
        ref = np.array([s.ref_velocity, s.ref_shift])
        while done_total < n_steps:
            done, code = ig.run_steps(
                n_steps - done_total, s.x, s.v, s.f, s.ids, s.x_ref, s.L, s.periodic, s.walls0,
                s.epoch_time, s.step - s.epoch_step, self.dt, self.lj.rc**2, self.lj.rlist**2, (0.5 * self.lj.skin) ** 2,
                self.nc, self.nbr, self.nnb, self.use_half, self.half, self.nhalf, self.fbuf,
                s.impulse, thermo, r1[done_total:], chi[done_total:], counters, ref, self.rowless,
                self.start,
            )  # fmt: skip
            s.ref_shift = float(ref[1])
            s.step += done
            self._sync_time()
            done_total += done
            if code == ig.OK:
                break
            if code == ig.GROW:
                # The step in progress is half done: grow the list and finish it.
                self._alloc_lists(int(ig.list_width(self.nbr, self.half) * 1.5) + 8)
                self._build_list(sort=False)
                ig.finish_step(
                    s.x, s.v, s.f, s.ids, s.L, s.periodic, self.nbr, self.nnb, self.use_half,
                    self.half, self.nhalf, self.fbuf, self.lj.rc**2, self.dt, thermo,
                    r1[done_total], chi[done_total], self.rowless,
                )  # fmt: skip
                s.step += 1
                self._sync_time()
                done_total += 1
                continue
            raise SolverUnstable(ig.STATUS_NAMES[code], self._diagnose(code))
        self.list_builds += int(counters[0])

    def _diagnose(self, code: int) -> str:
        s = self.state
        vmax = float(np.nanmax(np.abs(s.v))) if np.isfinite(s.v).any() else float("nan")
        msg = f"at step {s.step}, t = {s.time:.4f} tau, max |v| = {vmax:.4g} sigma/tau"
        if code == ig.CFL:
            msg += (
                f"; an atom moved more than skin/2 = {0.5 * self.lj.skin} sigma in one step of "
                f"dt = {self.dt} tau: reduce dt or the shock strength"
            )
        elif code == ig.LOST:
            msg += "; an atom left the box (it crossed a wall in one step)"
        elif code == ig.NAN:
            msg += "; NaN or infinite coordinates"
        return msg

    # -- boundaries --------------------------------------------------------------------------
    def wall_positions(self) -> tuple[float, float]:
        """Current positions of the left and right walls [σ]."""
        w, t = self.state.walls0, self.state.time
        return float(w[0] + w[1] * t), float(w[2] + w[3] * t)

    def set_walls(self, v_left: float, v_right: float) -> None:
        """Set wall velocities [σ/τ], keeping their current positions."""
        xl, xr = self.wall_positions()
        t = self.state.time
        self.state.walls0[:] = [xl - v_left * t, v_left, xr - v_right * t, v_right]

    def place_walls(self, x_left: float, v_left: float, x_right: float, v_right: float) -> None:
        """Put the walls at ``x_left``/``x_right`` [σ] now, moving at ``v_left``/``v_right``
        [σ/τ]."""
        t = self.state.time
        self.state.walls0[:] = [x_left - v_left * t, v_left, x_right - v_right * t, v_right]

    def skip_force_rows(self, n: int) -> None:
        """From now on the frozen atoms with ids −1 … −``n`` (the window's inflow copy) have
        no force row of their own (``integrate.drop_rows``; the half list keeps their pairs
        with the other atoms and leaves out those among them, ``integrate.build_lists``) and
        zero force: the force on a frozen atom is never used, and every pair with a mobile
        atom is still listed, so the mobile atoms move bit for bit as before at a fraction
        of the cost."""
        self.rowless = int(n)
        if self.rowless <= 0:
            return
        s = self.state
        if self.use_half:
            self._build_list(sort=False)  # the list made at x_ref, less the copy's pairs
        else:
            ig.drop_rows(s.ids, self.nnb, self.rowless)
        s.f[(s.ids < 0) & (s.ids >= -self.rowless)] = 0.0

    def replace_atoms(self, x: np.ndarray, v: np.ndarray, ids: np.ndarray) -> None:
        """Replace the atom set (the window's inflow and outflow add and remove atoms).

        The list is rebuilt (sorted) and the forces recomputed at the new positions, so the
        next step is a plain velocity-Verlet step of the new system."""
        s = self.state
        s.x = np.ascontiguousarray(x, dtype=np.float64)
        s.v = np.ascontiguousarray(v, dtype=np.float64)
        s.ids = np.ascontiguousarray(ids, dtype=np.int64)
        s.f = np.zeros_like(s.x)
        s.x_ref = s.x.copy()
        self._build_list(sort=True)
        self._compute_forces()

    def scale_x(self, factor: float) -> None:
        """Stretch the box along x affinely by ``factor`` (dimensionless): x_i → factor·x_i,
        L_x → factor·L_x, the walls at factor times their positions (static walls only);
        velocities are kept. The list is rebuilt (sorted, on the new cell grid) and the
        forces recomputed, so the next step is a plain velocity-Verlet step of the stretched
        system. For a box closed in x by walls (``particles.sizing.size_bulk``)."""
        s = self.state
        if s.periodic[0] or s.walls0[1] != 0.0 or s.walls0[3] != 0.0:
            raise ValueError("scale_x needs a box closed in x by two static walls")
        if not factor > 0:
            raise ValueError(f"factor = {factor}: must be > 0")
        s.x[:, 0] *= factor
        s.L[0] *= factor
        s.walls0[[0, 2]] *= factor
        self.nc = grid_shape(s.L, self.lj.rlist)
        self._build_list(sort=True)
        self._compute_forces()

    def galilean_shift(self, du: float) -> None:
        """Add ``du`` [σ/τ] to every x velocity and to both wall velocities."""
        self.state.v[:, 0] += du
        w = self.state.walls0
        self.set_walls(w[1] + du, w[3] + du)

    # -- observables -------------------------------------------------------------------------
    def per_atom_energy_virial(self) -> tuple[np.ndarray, np.ndarray]:
        """Per-atom potential energy (n,) [ε] and virial (n, 6) [ε] at the current positions."""
        s = self.state
        pe = np.empty(s.n)
        vir = np.empty((s.n, 6))
        if self.use_half:
            energy_virial_half(
                s.x, s.L, s.periodic, self.half, self.nhalf, self.lj.rc**2, self.lj.ushift,
                pe, vir,
            )  # fmt: skip
        else:
            energy_virial_full(
                s.x, s.L, s.periodic, self.nbr, self.nnb, self.lj.rc**2, self.lj.ushift, pe, vir
            )
        return pe, vir

    def mobile(self) -> np.ndarray:
        """Boolean mask of the mobile atoms (frozen boundary atoms have ids < 0)."""
        return self.state.ids >= 0

    def profile_sums(self, width: float) -> np.ndarray:
        """Raw per-bin sums (nbins, len(SUM_FIELDS)) of the mobile atoms over slabs of
        ``width`` [σ] along x (a frozen atom's share of a pair's energy and virial counts for
        the mobile partner's half only)."""
        s = self.state
        nbins = int(math.floor(s.L[0] / width + 1e-9))
        out = np.zeros((nbins, len(SUM_FIELDS)))
        pe, vir = self.per_atom_energy_virial()
        m = self.mobile()
        if m.all():
            bin_sums(s.x, s.v, pe, vir, width, out)
        else:
            bin_sums(s.x[m], s.v[m], pe[m], vir[m], width, out)
        return out

    def energies(self) -> tuple[float, float]:
        """Total kinetic and potential energy of the mobile atoms [ε]."""
        pe, _ = self.per_atom_energy_virial()
        m = self.mobile()
        return 0.5 * float(np.sum(self.state.v[m] ** 2)), float(np.sum(pe[m]))

    def momentum(self) -> np.ndarray:
        """Total momentum (3,) of the mobile atoms [m σ/τ]."""
        return self.state.v[self.mobile()].sum(axis=0)

    def mean_velocity(self) -> float:
        """Mean x velocity of the mobile atoms [σ/τ] (all masses are 1)."""
        return float(self.state.v[self.mobile(), 0].mean())

    # -- checkpoints -------------------------------------------------------------------------
    def to_dataset(self, extra: xr.Dataset | None = None, attrs: dict | None = None) -> xr.Dataset:
        """The complete state as an xarray Dataset (see ``save``), sealed with its format
        version and checksum (``seal_checkpoint``). The arrays are copies: the dataset stays
        the state of this moment while the simulation runs on."""
        s = self.state
        dims = ("atom", "xyz")
        ds = xr.Dataset(
            {
                "x": (dims, s.x.copy(), {"units": "sigma", "long_name": "position"}),
                "v": (dims, s.v.copy(), {"units": "sigma tau^-1", "long_name": "velocity"}),
                "f": (dims, s.f.copy(), {"units": "epsilon sigma^-1", "long_name": "force"}),
                "x_ref": (dims, s.x_ref.copy(), {"units": "sigma", "long_name": "positions at last list build"}),
                "ids": (("atom",), s.ids.copy(), {"units": "1", "long_name": "atom label"}),
                "L": (("xyz",), s.L.copy(), {"units": "sigma", "long_name": "box lengths"}),
                "periodic": (("xyz",), s.periodic.astype(np.int8), {"units": "1", "long_name": "periodic flags"}),
                "walls0": (("wall_param",), s.walls0.copy(), {"units": "sigma, sigma tau^-1", "long_name": "[x_L0, v_L, x_R0, v_R]"}),
                "impulse": (("wall",), s.impulse.copy(), {"units": "m sigma tau^-1", "long_name": "x momentum given by left/right wall"}),
            },
            coords={"xyz": ["x", "y", "z"]},
        )  # fmt: skip
        if extra is not None:
            ds = ds.merge(extra)
        ds.attrs.update(
            format=MD_CHECKPOINT.format,
            time=float(s.time),
            step=int(s.step),
            epoch_time=float(s.epoch_time),
            epoch_step=int(s.epoch_step),
            ref_velocity=float(s.ref_velocity),
            ref_shift=float(s.ref_shift),
            dt=self.dt,
            lj=json.dumps({"rc": self.lj.rc, "shift": self.lj.shift, "skin": self.lj.skin}),
            thermostat=json.dumps(
                None if self.T_bath is None else {"T": self.T_bath, "tau": self.tau_bath}
            ),
            seed=self.seed,
            numba_threads=num_threads(),
            hugomap_version=__version__,
        )
        ds.attrs.update(attrs or {})
        return seal_checkpoint(ds)

    def save(
        self, path: str | os.PathLike, extra: xr.Dataset | None = None, attrs: dict | None = None
    ) -> Path:
        """Save the complete state (and ``extra`` variables) to netCDF, atomically, with its
        format version and checksum."""
        return write_netcdf(self.to_dataset(extra, attrs), path)

    @classmethod
    def from_dataset(cls, ds: xr.Dataset, source: str | os.PathLike | None = None) -> MDSimulation:
        """Rebuild a simulation that continues bit-for-bit from a saved state.

        The dataset is verified first (``verify_checkpoint``: format version and checksum); a
        foreign, outdated or altered one raises ``CheckpointError`` naming ``source`` (default:
        the file ``ds`` was opened from). The neighbour list is rebuilt from x_ref (where it
        was built) without re-sorting, and the saved forces are kept, so the next step is the
        one the original run would take.
        """
        verify_checkpoint(ds, source)
        state = MDState(
            x=ds["x"].values.copy(), v=ds["v"].values.copy(), L=ds["L"].values.copy(),
            periodic=ds["periodic"].values.astype(bool), walls0=ds["walls0"].values.copy(),
            f=ds["f"].values.copy(), ids=ds["ids"].values.astype(np.int64),
            x_ref=ds["x_ref"].values.copy(), time=float(ds.attrs["time"]),
            step=int(ds.attrs["step"]), impulse=ds["impulse"].values.copy(),
            epoch_time=float(ds.attrs.get("epoch_time", ds.attrs["time"])),
            epoch_step=int(ds.attrs.get("epoch_step", ds.attrs["step"])),
            ref_velocity=float(ds.attrs.get("ref_velocity", 0.0)),
            ref_shift=float(ds.attrs.get("ref_shift", 0.0)),
        )  # fmt: skip
        lj = LJParams(**json.loads(ds.attrs["lj"]))
        th = json.loads(ds.attrs["thermostat"])
        sim = cls.__new__(cls)
        sim.state = state
        sim.lj = lj
        sim._dt = float(ds.attrs["dt"])
        sim.T_bath = None if th is None else th["T"]
        sim.tau_bath = 0.5 if th is None else th["tau"]
        sim.seed = int(ds.attrs["seed"])
        sim.use_half = True  # the default of __init__
        sim.list_builds = 0
        sim.rowless = 0  # a window sets its own (``MDWindow``)
        sim.nc = grid_shape(state.L, lj.rlist)
        sim._alloc_lists(sim._row_estimate())
        sim._build_list(sort=False)
        return sim

    @classmethod
    def load(cls, path: str | os.PathLike) -> MDSimulation:
        """Load a checkpoint written by ``save`` (refused with ``CheckpointError`` if it is
        unreadable, foreign, outdated or altered)."""
        return cls.from_dataset(read_checkpoint(path, verify=False), path)
