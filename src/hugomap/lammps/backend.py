"""The LAMMPS backend: ``hugomap.backend.Backend`` with the LAMMPS library doing the MD
(``solver: lammps``; ``lammps.simulation.LammpsSimulation``).

Two unit systems (``model.units``), one backend object each (``LammpsBackend.for_scene``,
which the registry asks for a scene's backend, since the datasets' units follow the
scene):
- units lj (σ, ε, m = 1, τ = σ√(m/ε), k_B = 1): ``LammpsBackend``, datasets in reduced
  units (``io.dataset.lj_units``), the equilibrium-MD reference of an lj/cut model;
- units metal (Å, ps, eV, g/mol, K; e.g. copper with ``pair_style eam/alloy``):
  ``MetalBackend``, datasets in SI (``io.dataset.si_units``: m, s, kg m⁻³, Pa, J kg⁻¹, K;
  ``unit_system`` names LAMMPS units metal). The simulation keeps LAMMPS's units; the
  shock methods see it through ``si.SIView`` (time [s], positions [m], velocities
  [m/s]) and read its raw sums through ``MetalProfile`` (ρ [kg/m³], u [m/s], P [Pa], E
  [J/kg], T [K]), so D, u_p and the jump residuals are measured in one coherent system.
  Scene keys keep LAMMPS's units (lengths Å, times ps, T0 K, mass g/mol, ``sample.rho0``
  Å⁻³ or ``sample.lattice_constant`` Å), except the piston velocities ``shock.u_p`` [m/s]
  (the datasets' coordinate) and the reference's c0 [m/s]. Conversions: ``units``.
  Reference: a linear Us–u_p fit (``reference.model: linear_us_up``, e.g. LASL's for
  copper), tabulated as the CSPH backend tabulates its EOS's (``linear_reference``).

The sample is
the MD backend's: an FCC lattice (``particles.fcc.fcc_positions``, Maxwell velocities at T0)
between a reflecting wall at x = 0 and a one-sided harmonic wall at L_x, y and z periodic,
equilibrated with a CSVR thermostat (LAMMPS ``fix temp/csvr``) while ``particles.sizing.size_bulk``
sizes a fluid's box so its bulk is at ρ0 and ends at the canonical mean energy of T0; then
an NVE run measures the pole away from the walls (block averages, ``analysis.stats``).
The piston runs in the MD backend's frame (drift removed, every atom at −u_p, the piston
wall at rest, the far wall moving at −u_p with the upstream material), so u_p is exact and
the shared analysis (``methods.piston``, ``analysis.shock.measure_point``) measures the point
from the profile sums (``particles.profiles.SUM_FIELDS``, read by
``particles.profiles.ParticleProfile``, the MD backend's reader too).

The moving-window schemes (AMW, MW, the dichotomy) run the particle window the MD backend
runs, ``particles.window.ParticleWindow``, over LAMMPS simulations
(``lammps.window.LammpsKit``: frozen atoms
as LAMMPS type 2 under ``fix nve/noforce``, the outflow face a rigidly moving harmonic
wall, the inflow a reservoir made by LAMMPS with the scene's model); units metal's window is
seen in SI through ``si.WindowSIView``, and ``control_params`` gives the stages
the measured slabs' lengths in the frame's units (m). Its checkpoint is
``hugomap-lammps-window/1``. The absorbing outflow is refused at validation (the wall's
impulse is not measured).

The shock-frame schemes msst and nphug (LAMMPS ``fix msst``, ``fix nphug`` on a periodic box
at the sample's pole, no loading, no window): ``shock_frame_point``, ``lammps.shockframe``.

Not yet: trajectories (``extras`` writes the last frame only), a LAMMPS reference (an
lj/cut scene's reference is the MD backend's equilibrium MD of the same potential, asked of
the registry's ``solver: md`` backend: this package imports no ``hugomap.md``).
"""

from __future__ import annotations

import dataclasses
import json
import logging
import math
import os
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
import xarray as xr

from ..analysis.linear_hugoniot import jump_state
from ..backend import lengthened
from ..io.dataset import UnitTable, lj_units, si_units
from ..particles.fcc import lattice_constant
from ..particles.pole import measure_pole, reference_pole
from ..particles.profiles import ParticleProfile
from ..registry import backend as backend_of
from ..states import ControlParams, PistonFrame, Pole, Resources, SlabState, WindowStart
from .lattice import STATUS as POLE_OFF_PRESSURE
from .lattice import bin_width, lattice_density
from .scene_config import pair_style_name
from .units import METAL, UnitSystem, number_density_factor, si_pole, unit_system

if TYPE_CHECKING:
    from ..backend import ShockFrameResult

log = logging.getLogger("hugomap")
#: Kept clear of a wall when measuring the pole [σ | Å]: lj the MD backend's 4 σ; metal
#: 8 Å, beyond the walls' disturbed planes (an EAM cutoff, 5.5 Å for Cu_mishin1, and more).
WALL_LAYER = {"lj": 4.0, "metal": 8.0}
#: Longitudinal sound speed of a crystal [σ/τ | Å/ps] where the scene gives none (lj: an
#: FCC LJ solid near its triple point; metal: copper [100]), for a crystal's Langevin phase.
CRYSTAL_SOUND = {"lj": 8.0, "metal": 44.0}

# Cost model, measured on the 2-core development machine (one rank, one OpenMP thread):
# LJ rc 2.5 at rho 0.8 ran 1.5e-6 s per atom-step under load (``run`` of 1920 atoms);
# x2 for the per-sample gathering in Python and a loaded machine.
BASE_MB = 1024  # Python + xarray + liblammps
BYTES_PER_ATOM = 2048  # LAMMPS arrays, ghosts and neighbour lists, x4 margin
S_PER_ATOM_STEP = 3.0e-6
# the fastest a LAMMPS atom-step runs on one core (lj/cut at 2.5 sigma ~2e-7 s here, EAM
# copper ~2e-6; machines of this kind differ by 2x): a lower bound, for refusing a budget
FASTEST_S_PER_ATOM_STEP = 1.0e-7


def _area(solver) -> float:
    """Transverse area L_y L_z in the simulation's own units [σ² | Å²]."""
    from .simulation import native

    sim = native(solver)
    return float(sim.L[1] * sim.L[2])


class MetalProfile:
    """Profile reader of a units-metal run, in SI: bins of ``bin_width`` [m] from x = 0
    (``native_width`` [Å] in the simulation) across the transverse ``area`` [Å²], atoms of
    ``mass`` [g/mol]. The raw sums are LAMMPS's (``LammpsSimulation.profile_sums``: count
    c, Σv_a [Å/ps], Σv_a² [Å²/ps²], Σpe [eV], ΣW_aa [eV]); for a slab of volume V = A w n
    [Å³] and m the atom mass (``units.METAL``: u = 1.66053906660e-27 kg per g/mol, mvv2e =
    u (Å/ps)²/eV, k_B [eV/K], 1 eV = 1.602176634e-19 J, 1 Å = 1e-10 m, 1 Å/ps = 100 m/s):

        ū_a  = Σv_a / c                      [Å/ps]  → u = ū_x · 100        [m/s]
        K_aa = m mvv2e (Σv_a² − c ū_a²)       [eV]
        ρ    = c m u_kg / (V · 1e-30)                                     [kg/m³]
        P_aa = (K_aa + ΣW_aa) / V             [eV/Å³] → · 1.602176634e11  [Pa]
        T    = ΣK_aa / (3 (c − 1) k_B)                                    [K]
        E    = (½ ΣK_aa + Σpe) / c            [eV/atom] → · eV/(m u_kg)    [J/kg]

    (``particles.profiles``' formulas, the MD backend's too, with the mass and the unit factors)."""

    x0 = 0.0

    def __init__(self, area: float, bin_width: float, mass: float, units: UnitSystem = METAL):
        self.u = units
        self.area = float(area)
        self.native_width = float(bin_width)
        self.bin_width = self.native_width * units.length_m
        self.mass = float(mass)

    def sums(self, solver) -> np.ndarray:
        from .simulation import native

        return native(solver).profile_sums(self.native_width)

    def velocity(self, sums: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        c = sums[:, 0]
        with np.errstate(invalid="ignore", divide="ignore"):
            return sums[:, 1] / c * self.u.velocity_m_s, c

    def state(self, summed: np.ndarray, n_bins: int) -> SlabState:
        u, s = self.u, np.asarray(summed, dtype=float)
        c = s[0]
        vol = self.area * self.native_width * n_bins  # [Å³]
        with np.errstate(invalid="ignore", divide="ignore"):
            ubar = s[1:4] / c
            kin = self.mass * u.mvv2e * (s[4:7] - c * ubar * ubar)  # [eV]
            P = (kin + s[8:11]) / vol * u.pressure_Pa
            m_kg = self.mass * u.mass_kg
            return SlabState(
                rho=float(c * m_kg / (vol * u.length_m**3)), u=float(ubar[0] * u.velocity_m_s),
                P=float(P[0]), Pyy=float(P[1]), Pzz=float(P[2]),
                E=float((0.5 * kin.sum() + s[7]) / c * u.energy_J / m_kg),
                T=float(kin.sum() / (3.0 * (c - 1.0) * u.k_B)) if c > 1 else float("nan"),
            )  # fmt: skip


def md_view(scene: dict) -> dict:
    """The scene as the MD backend reads it, for the parts that are the same physics
    (an lj/cut model in units lj): ``potential`` = {rc, shift, skin} from ``model``."""
    m = scene["model"]
    if m["units"] != "lj" or pair_style_name(m) != "lj/cut":
        raise NotImplementedError(
            f"model.pair_style = {m['pair_style']!r} in units {m['units']!r}: solver lammps "
            "has a reference Hugoniot for lj/cut in units lj only (the MD backend's "
            "equilibrium MD)"
        )
    rc = float(str(m["pair_style"]).split()[1])
    shift = any(p.split()[:2] == ["shift", "yes"] for p in m.get("pair_modify", []))
    return {**scene, "solver": "md", "potential": {"rc": rc, "shift": shift, "skin": m["skin"]}}


class LammpsBackend:
    """``Backend`` for ``solver: lammps`` scenes (module docstring)."""

    name = "lammps"
    units: UnitTable = lj_units()
    usys: UnitSystem = unit_system({"units": "lj"})

    def for_scene(self, scene: dict) -> LammpsBackend:
        """The backend of a scene's unit system (``hugomap.registry.backend`` asks): this
        one for units lj, ``METAL_BACKEND`` for units metal."""
        units = scene.get("model", {}).get("units", "lj") if isinstance(scene, dict) else "lj"
        return METAL_BACKEND if units == "metal" else BACKEND

    def view(self, sim):
        """The simulation as the shock methods see it (units lj: itself)."""
        return sim

    def window_view(self, win):
        """The window as the window methods see it (units lj: itself)."""
        return win

    def _native_velocity(self, u: float) -> float:
        """A velocity of the frame [σ/τ] in the simulation's units (lj: itself)."""
        return u

    def _native_pole(self, scene: dict, pole: Pole) -> tuple[float, float]:
        """The pole's (number density [σ⁻³], energy per atom [ε]) in the simulation's
        units (lj: as they are)."""
        return float(pole.rho0), float(pole.E0)

    def _pole_from_native(self, scene: dict, pole: dict[str, float]) -> dict[str, float]:
        """A pole measured in the simulation's units, in the frame's (lj: as it is)."""
        return dict(pole)

    def _count_density(self, scene: dict, rho: float) -> float:
        """Atoms per volume of a density of the frame (lj: ρ is the number density)."""
        return rho

    def _length(self, x: float) -> float:
        """A length of the simulation [σ] in the frame's units (lj: itself)."""
        return x

    def _time(self, t: float) -> float:
        """A time of the scene [τ] in the frame's units (lj: itself)."""
        return t

    # -- sample and checkpoints ------------------------------------------------------------
    def prepare(self, scene: dict) -> tuple[Any, Pole, dict[str, Any]]:
        """FCC at (ρ0, T0) between the walls, thermostatted (CSVR) for
        ``sample.equilibrate_time`` while ``particles.sizing.size_bulk`` sizes the box (a fluid:
        L_x stretched so the bulk, ``WALL_LAYER`` from the walls, is at ρ0; a crystal keeps
        its lattice) and ends at the canonical mean energy of T0 (a crystal: first
        ``equilibrate_time`` under a Langevin thermostat, ``run_langevin``, then half
        as long under CSVR); then NVE for
        ``sample.pole_time`` while the pole is measured between ``WALL_LAYER`` and
        L_x − ``WALL_LAYER`` (``particles.pole.measure_pole``): ρ0 [σ⁻³], P0 = P_xx, Pyy0
        [ε σ⁻³], E0 [ε per atom], T0 [ε/k_B], block averages (8 blocks) with standard
        errors. Info: what the sizing measured (``sizing``; its energies in ε | eV per atom,
        ``T_nvt`` in ε/k_B | K).
        Units metal: T0 [K], Maxwell velocities of variance k_B T0/(m mvv2e) [Å²/ps²], the
        pole in SI through ``view`` and ``MetalProfile`` (ρ0 [kg/m³], P0, Pyy0 [Pa], E0
        [J/kg], T0 [K]), the layer 8 Å.

        A crystal with ``sample.lattice_pressure`` is built at the lattice constant of that
        pressure at T0 (``lattice_search.search_lattice``, recorded as ``info["lattice"]``),
        its pole measured in bins of that lattice (``lattice.bin_width``) and checked against
        that pressure (``lattice.pole_pressure_problem``): a pole off it leaves the
        simulation's ``check`` set, and ``save`` writes the sample with status
        ``pole_off_pressure``."""
        from ..particles.fcc import fcc_positions, maxwell_velocities
        from ..particles.sizing import size_bulk
        from .lattice import searched
        from .lattice_search import search_lattice
        from .simulation import LammpsSimulation

        s, us = scene["sample"], self.usys
        info: dict[str, Any] = {}
        if searched(scene):
            info["lattice"] = search_lattice(scene)
        rho_n = lattice_density(scene, info)
        x, L = fcc_positions(tuple(s["cells"]), rho_n)
        # velocity variance k_B T0/(m mvv2e) [velocity²] (lj: T0 itself)
        mkin = float(scene["model"]["mass"]) * us.mvv2e
        v = maxwell_velocities(x.shape[0], us.k_B * s["T0"] / mkin, s["seed"])
        sim = LammpsSimulation(
            x, v, np.arange(x.shape[0]), L, np.array([0.0, 0.0, L[0], 0.0]), scene["model"],
            s["dt"], T_bath=s["T0"], tau_bath=s["thermostat_tau"], seed=s["seed"],
        )  # fmt: skip
        n_eq = int(round(s["equilibrate_time"] / s["dt"]))
        layer = WALL_LAYER[us.name]
        if scene["phase"] == "crystal" and n_eq > 0:
            c = self._crystal_sound(scene)
            damp = float(sim.L[0]) / (2.0 * math.pi * c)  # critical: slowest standing wave
            sim.run_langevin(float(s["T0"]), damp, n_eq)
            info["langevin"] = {"damp": damp, "steps": float(n_eq)}
            n_eq = max(n_eq // 2, 1)  # then CSVR, to end at the canonical energy (size_bulk)
        if n_eq > 0:
            # "T0" is k_B T0 in sim.energies()'s unit (lj: T0). No local thermostat yet: with it
            # this backend's LJ test box gave energy residuals near -3 %, not understood
            info.update(size_bulk(sim, rho_n, us.k_B * s["T0"], n_eq, layer,
                                  resize=scene["phase"] != "crystal", local=False))  # fmt: skip
            info["T_nvt"] = info["T_nvt"] / us.k_B  # [ε/k_B | K]
            log.info("sample sized: %s", json.dumps(info))
        sim.T_bath = None
        view = self.view(sim)
        pole = measure_pole(sim, view, self.profile(view, scene, info),
                            self._length(float(sim.L[0])), self._length(layer), s["pole_time"],
                            s["dt"])  # fmt: skip
        out = {"sizing": {k: v for k, v in info.items() if k != "lattice"}}
        if "lattice" in info:
            out["lattice"] = info["lattice"]
            out["lattice"]["pole_check"] = self._check_sample_pole(
                scene, info, float(sim.L[0]), pole, self._crystal_sound(scene)
            )
            if out["lattice"]["pole_check"]:
                log.error("%s: %s", POLE_OFF_PRESSURE, out["lattice"]["pole_check"])
                sim.check = (POLE_OFF_PRESSURE, out["lattice"]["pole_check"])
        return sim, Pole.from_dict(pole), out

    def _crystal_sound(self, scene: dict) -> float:
        """A crystal's longitudinal sound speed [σ/τ | Å/ps]: the reference's c0
        (``sound_speed``), else the unit system's ``CRYSTAL_SOUND``."""
        c = self.sound_speed(scene)
        return CRYSTAL_SOUND[self.usys.name] if c is None else self._native_velocity(c)

    def _check_sample_pole(
        self, scene: dict, info: dict, L_x: float, pole: dict[str, float], c: float
    ) -> str:
        """``lattice.pole_pressure_problem`` on the prepared sample's pole (the backend's
        units), with what a user can change: the slab's breathing between its free faces
        (``lattice.breathing_period`` of ``L_x`` [σ | Å] at the sound speed ``c`` [σ/τ |
        Å/ps]) against ``sample.pole_time``, the search's run time, the requested pressure
        and its tolerance; '' when the pole is at the pressure."""
        from .lattice import breathing_period, pole_pressure_problem

        s, lat = scene["sample"], info["lattice"]
        problem = pole_pressure_problem(pole["P0"], pole["P0_err"], pole.get("Pyy0"), scene,
                                        "the prepared sample's pole")  # fmt: skip
        if not problem:
            return ""
        t = "tau" if self.usys.name == "lj" else "ps"
        return (
            f"{problem}; the crystal was built at the lattice constant "
            f"{lat['lattice_constant']:.6g} ± {lat['lattice_constant_err']:.2g} "
            f"(the NPT search at {lat['pressure']:g} {lat['pressure_unit']} and T0, which "
            f"measured {lat['pressure_measured']:.3g} ± {lat['pressure_measured_err']:.2g}). "
            "Between the walls its faces along x are free: its P_xx is near 0 unless it "
            "presses on the walls (a lattice under a positive pressure), and its length "
            f"breathes with a period 2 L_x/c of about {breathing_period(L_x, c):.3g} {t}, "
            f"which a pole averages out only over a whole period (sample.pole_time = "
            f"{s['pole_time']:g} {t}). Lengthen sample.pole_time or "
            "sample.lattice_search.run_time, or change sample.lattice_pressure or "
            "sample.pressure_tolerance"
        )

    def save(self, solver, out: str | os.PathLike, extra: xr.Dataset, attrs: dict) -> Path:
        """Save a simulation, a window or their SI views (each saves what it holds). A
        simulation whose preparation failed a check (``LammpsSimulation.check``: a pole off
        its lattice's pressure, ``prepare``) is saved with that status and diagnostic in
        place of the stage's: its state and pole are kept to be looked at, and every stage
        that starts from it ends with that status."""
        from .simulation import native

        check = getattr(native(solver), "check", None)
        if check is not None:
            attrs = {**attrs, "status": check[0], "diagnostic": check[1]}
        return solver.save(out, extra=extra, attrs=attrs)

    def read_checkpoint(self, path: str | os.PathLike) -> xr.Dataset:
        from ..io.checkpoint import read_checkpoint
        from .simulation import LAMMPS_CHECKPOINT

        return read_checkpoint(path, kind=LAMMPS_CHECKPOINT)

    def load(self, ds: xr.Dataset, source: str | os.PathLike | None = None):
        """A new LAMMPS instance from a verified checkpoint (``LammpsSimulation.from_dataset``:
        the same state, not bit-exact on resume)."""
        from .simulation import LammpsSimulation

        return self.view(LammpsSimulation.from_dataset(ds, source))

    def load_window(self, ds: xr.Dataset, source: str | os.PathLike | None = None):
        """A window from a verified ``hugomap-lammps-window/1`` checkpoint (``ParticleWindow``
        over a new LAMMPS instance; ``CheckpointError`` naming ``source`` otherwise), as the
        methods see it (``window_view``)."""
        from ..particles.window import ParticleWindow
        from .window import LammpsKit

        kit = LammpsKit(None, units=str(ds.attrs.get("lammps_units", "lj")))
        return self.window_view(ParticleWindow.from_dataset(ds, source, kit))

    # -- the piston ------------------------------------------------------------------------
    def start_piston(self, solver, scene: dict, u_p: float) -> None:
        """The MD backend's piston frame: the sample's mean x velocity (a thermal drift of
        order √(T/N)) removed, every atom at −u_p; the piston wall (a static ``fix
        wall/reflect``, specular) stays at rest, the far wall moves at −u_p with the
        upstream material. The upstream flow is −u_p exactly and the shocked material
        behind the front is at rest, so the particle-velocity jump is u_p exactly."""
        from .simulation import native

        native(solver).dt = scene["shock"]["dt"]  # [τ | ps]: the scene's native time
        native(solver).T_bath = None
        solver.galilean_shift(-u_p - solver.mean_velocity())  # u_p in the view's units
        solver.set_walls(0.0, -u_p)

    def piston_frame(self, solver, scene: dict, u_p: float, info: dict) -> PistonFrame:
        from .simulation import native

        sh = scene["shock"]
        return PistonFrame(
            u_behind=0.0, u_ahead=-u_p, x_origin=solver.wall_positions()[0],
            load_distance=self._length(sh["load_fraction"] * float(native(solver).L[0])),
            rear_margin=self._length(sh["rear_margin"]), max_time=self._time(sh["max_time"]),
            sample_every=sh["sample_every"], **self._slab_lengths(sh),
        )  # fmt: skip

    def _slab_lengths(self, sh: dict) -> dict[str, float | None]:
        """The measured slabs' ``shock.gap``, ``shock.avg_length`` and ``shock.ahead_gap``
        (None: ``gap``) in the frame's units (``_length``)."""
        ahead = sh.get("ahead_gap")
        return {"gap": self._length(sh["gap"]), "avg_length": self._length(sh["avg_length"]),
                "ahead_gap": None if ahead is None else self._length(ahead)}  # fmt: skip

    def profile(self, solver, scene: dict, info: dict | None = None):
        """The particle backends' reader (``particles.profiles.ParticleProfile``): bins from
        x = 0 across L_y L_z, fields by ``particles.profiles.fields_from_sums`` (units lj,
        m = 1); the bins' width ``lattice.bin_width`` (``shock.bin_width``, scaled with a
        searched lattice)."""
        return ParticleProfile(_area(solver), bin_width(scene, info))

    # -- the window ------------------------------------------------------------------------
    def open_window(
        self, solver, loaded: xr.Dataset, scene: dict, u_p: float, front: float,
        D_guess: float, pole: Pole, info: dict,
    ) -> WindowStart:  # fmt: skip
        """The MD backend's window (``MDBackend.open_window``: the reservoir at the pole,
        its snapshot screened, ``ParticleWindow.from_piston``, the settling, ω) on LAMMPS, the
        reservoir made by LAMMPS with the scene's model (``particles.reservoir.make_reservoir``
        through ``window.LammpsKit``). ``front``,
        ``u_p``, ``D_guess`` arrive in the frame's units (metal: SI) and are converted to
        the simulation's; the returned window, pole and ω are in the frame's. A crystal's
        reservoir and seam are at the sample's lattice (``_lattice_density``); its inflow
        copy ``window.inflow`` (live: ``particles.live_inflow``, the seam's work kept)."""
        from ..methods.control import OmegaSignal
        from ..particles.reservoir import inflow_screen, make_reservoir
        from ..particles.window import ParticleWindow
        from .simulation import native
        from .window import LammpsKit

        sim = native(solver)
        w, sh, s = scene["window"], scene["shock"], scene["sample"]
        fluid = scene["phase"] != "crystal"
        kit = LammpsKit(scene["model"])
        rho_n, e_n = self._native_pole(scene, pole)
        rho_c = rho_n if fluid else self._lattice_density(scene, info, pole)
        res, inflow = make_reservoir(
            kit, (s["cells"][1], s["cells"][2]), rho_c, s["T0"],
            sim.dt, s["seed"] + 7919, w["reservoir_equilibrate_time"], s["thermostat_tau"],
            E0_target=e_n if fluid else None, min_length=w["reservoir_length"],
            screen=(inflow_screen(w, sh["gap"], self._native_velocity(D_guess))
                    if fluid and w["inflow"] == "frozen" else None),
        )  # fmt: skip
        inflow = self._pole_from_native(scene, inflow)
        log.info("inflow pole: %s", json.dumps(inflow))
        to_native = self._length(1.0)
        win = ParticleWindow.from_piston(
            sim, res, front / to_native, self._native_velocity(u_p),
            self._native_velocity(D_guess), w["length"], w["front_fraction"], w["ghost_width"],
            w["cut_every"], w["sync_steps"], crystal=not fluid,
            lattice=lattice_constant(rho_c), kit=kit, segment=w["reservoir_segment"],
            inflow=w["inflow"], seam_work="kept",
        )  # fmt: skip
        res.close()
        wpole = pole if fluid else Pole.from_dict(inflow)
        win.advance(int(round(w["settle_time"] / win.dt)))  # [τ | ps] / [τ | ps]
        view = self.window_view(win)
        if w["omega"] == "N":  # q = atoms in the window: a number density
            up, q_of = self._count_density(scene, wpole.rho0), (
                lambda st: self._count_density(scene, st["rho"]))  # fmt: skip
        else:  # q = Σ P_xx over the window's volume
            up, q_of = wpole.P0, (lambda st: st["P"])
        sig = OmegaSignal.from_settled(view, self.profile(view, scene, info), w["omega"],
                                       self._length(sh["gap"]), w["front_fraction"], up,
                                       q_of)  # fmt: skip
        return WindowStart(view, wpole, sig, {f"inflow_{k}": v for k, v in inflow.items()})

    def control_params(self, scene: dict, u_p: float, window) -> ControlParams:
        """The configured times (``ControlParams.from_window``) in the frame's units."""
        slab = self._slab_lengths(scene["shock"])
        return ControlParams.from_window(self._window_block(scene), window.geom.length,
                                         slab["gap"], slab["avg_length"],
                                         ahead_gap=slab["ahead_gap"])  # fmt: skip

    def _window_block(self, scene: dict) -> dict:
        """The ``window`` block in the frame's units (lj: as it is)."""
        return scene["window"]

    def window_extras(
        self, window, out: Path, scene: dict, u_p: float, scheme: str, info: dict
    ) -> None:
        """A window point's last state as ``<stem>_snapshot.extxyz`` (``extras``; frozen
        atoms have ids < 0)."""
        self._snapshot(window, out, scene, {"run": scheme, "u_p": u_p})

    # -- reference -------------------------------------------------------------------------
    #: The reference is computed at the pole the prepared sample measured (as for MD).
    reference_from_sample = True

    def reference_inputs(self, scene: dict, pole: Pole | None = None) -> dict:
        """What the reference depends on: the model, what makes the sample (``phase``, the
        ``sample`` block, the pole's bins ``shock.bin_width``), the ``reference`` block and,
        once the sample exists, its pole (``reference_pole``)."""
        inputs = {
            "solver": "lammps",
            "model": dict(scene["model"]),
            "phase": scene["phase"],
            "sample": dict(scene["sample"]),
            "pole_bin_width": scene["shock"]["bin_width"],
            "reference": dict(scene["reference"]),
        }
        if pole is not None:
            inputs["pole"] = self.reference_pole(scene, pole)
        return inputs

    def reference_pole(self, scene: dict, pole: Pole) -> dict[str, float]:
        """The MD backend's rule (``particles.pole.reference_pole``): the measured T0 and,
        for a fluid, the measured ρ0 (a crystal: the lattice's; a searched one's from the
        pole, ``_lattice_scene``)."""
        return reference_pole(self._lattice_scene(scene, pole), pole)

    def _lattice_density(self, scene: dict, info: dict | None, pole: Pole | None) -> float:
        """The number density [σ⁻³ | Å⁻³] of the scene's crystal
        (``lattice.lattice_density``: the searched lattice in ``info``, else the pole's ρ0 for
        a searched scene, else the nominal ``sample.rho0``)."""
        rho = None if pole is None else self._native_pole(scene, pole)[0]
        return lattice_density(scene, info, rho)

    def _lattice_scene(self, scene: dict, pole: Pole | None) -> dict:
        """The scene with ``sample.rho0`` its searched crystal's number density (from the
        sample's pole: ``_lattice_density``); any other scene as it is."""
        from .lattice import searched

        if pole is None or not searched(scene):
            return scene
        rho = self._lattice_density(scene, None, pole)
        return {**scene, "sample": {**scene["sample"], "rho0": rho}}

    def reference(self, scene: dict, pole: Pole | None = None) -> xr.Dataset:
        """The equilibrium-MD Hugoniot of the same potential: the reference of the scene's
        ``md_view`` (rc from ``pair_style``, shift from ``pair_modify shift yes``, the skin),
        computed by that scene's backend, the registry's ``solver: md``; its
        ``reference_inputs`` attribute is this backend's. Other models:
        ``NotImplementedError`` (a LAMMPS reference is a later slice). A searched crystal's
        reference is at its lattice (``_lattice_scene``)."""
        twin = md_view(self._lattice_scene(scene, pole))
        ds = backend_of(twin).reference(twin, pole)
        ds.attrs["reference_inputs"] = json.dumps(self.reference_inputs(scene, pole),
                                                  sort_keys=True)  # fmt: skip
        ds.attrs["reference_model"] = "equilibrium MD (hugomap.md.reference) of the lj/cut model"
        return ds

    def extras(self, solver, out: Path, scene: dict, u_p: float, info: dict) -> None:
        """The piston run's last state as ``<stem>_snapshot.extxyz`` beside its point file
        (``io.extxyz``) when ``shock.snapshots`` is set: reduced units as they are (lengths
        σ, velocities σ/τ, masses m = 1, time τ), species ``Ar``, per atom its ``id`` and
        potential energy ``pe`` [ε]; the cell spans the walls and every atom along x, the
        periodic box across. No trajectory yet (``shock.snapshot_every`` is an MD key)."""
        self._snapshot(solver, out, scene, {"run": "piston", "u_p": u_p})

    def _snapshot(self, solver, out: Path, scene: dict, tags: dict) -> None:
        """The last state of a run or window as an extended-XYZ snapshot beside ``out``."""
        if not scene["shock"].get("snapshots", True):
            return
        from ..io.extxyz import format_frame, snapshot_paths, write_extxyz
        from ..particles.snapshot import velocity_frame
        from .simulation import native

        frame = velocity_frame(solver)  # looks through an SI view to the native units
        solver = native(solver)
        x, v, ids = solver.arrays()
        pe = solver.per_atom_energy_virial()[0][np.argsort(solver._ids(), kind="stable")]
        xl, xr = solver.wall_positions()
        lo = min(float(x[:, 0].min()), xl, 0.0)
        hi = max(float(x[:, 0].max()), xr, lo + 1.0)
        text = format_frame(
            x, (hi - lo, solver.L[1], solver.L[2]), velocities=v, fields={"id": ids, "pe": pe},
            origin=(lo, 0.0, 0.0), pbc=(False, True, True), time=float(solver.time),
            frame=frame, **self._snapshot_units(scene),
            info={"scene": scene.get("name", ""), **tags,
                  "step": int(solver.steps), "solver": "lammps",
                  "pair_style": scene["model"]["pair_style"]},
        )  # fmt: skip
        write_extxyz(snapshot_paths(out)[0], text)

    # -- shock-frame schemes (msst, nphug) -------------------------------------------------
    def shock_frame_point(
        self, scene: dict, scheme: str, u_p: float, pole: Pole, info: dict
    ) -> ShockFrameResult:
        """``lammps.shockframe.shock_frame_point``: a periodic box of the scene's model at the
        sample's ``pole`` (a crystal: the box's own pole at the lattice's ρ0,
        ``_lattice_density``, checked against ``sample.lattice_pressure`` when given) held on
        its Hugoniot by ``fix nphug`` or ``fix msst``, iterated until u_p [σ/τ | m/s] is the
        scene's; the start from ``sound_speed`` (lj: none, measured on the box). Values in
        the frame's units (metal: SI)."""
        from ..backend import ShockFrameResult
        from .shockframe import shock_frame_point

        crystal = scene["phase"] == "crystal"
        lattice = self._lattice_density(scene, info, pole) if crystal else None
        values, status, diagnostic, attrs, used = shock_frame_point(
            scene, scheme, u_p, pole, self.sound_speed(scene), lattice
        )
        return ShockFrameResult(values, status, diagnostic, attrs,
                                None if lattice is None else used)  # fmt: skip

    def _snapshot_units(self, scene: dict) -> dict[str, Any]:
        """A snapshot's masses, species and unit labels (units lj: m = 1, ``Ar``)."""
        return {"masses": 1.0, "species": "Ar", "length_unit": "sigma", "time_unit": "tau",
                "units": {"masses": "m", "momenta": "m*sigma/tau", "pe": "epsilon"}}  # fmt: skip

    def longer_sample(self, scene: dict, factor: float) -> dict | None:
        """More lattice cells along x (``backend.lengthened``)."""
        return lengthened(scene, ("sample", "cells", 0), factor)

    # -- cost ------------------------------------------------------------------------------
    def cost(self, scene: dict, stage: str) -> Resources:
        """Memory: LAMMPS's per-atom storage plus the profile history (samples x bins x 11
        float64, held and copied once); CPU: an upper bound of atom-steps at
        ``S_PER_ATOM_STEP`` (prepare: equilibration, pole and a lattice search; load/piston:
        up to ``shock.max_time``; reference: the cost the backend that computes it gives,
        ``reference``'s); ``ranks``: the scene's, the memory that many times (every rank
        holds the gathered per-atom arrays)."""
        s, sh = scene["sample"], scene["shock"]
        if stage == "reference":
            twin = md_view(scene)
            return backend_of(twin).cost(twin, stage)
        n = 4 * s["cells"][0] * s["cells"][1] * s["cells"][2]
        ranks = int(scene["ranks"])
        if stage == "prepare":
            steps = (s["equilibrate_time"] + s["pole_time"]) / s["dt"]
            search = 0.0
            if "lattice_search" in s:  # the lattice's NPT box (lammps.lattice_search)
                q = s["lattice_search"]
                search = 4 * math.prod(q["cells"]) * q["run_time"] / s["dt"]
            mem = int(BASE_MB + n * BYTES_PER_ATOM / 2**20)
            return Resources(ranks * mem, (n * steps + search) * S_PER_ATOM_STEP, ranks)
        length = s["cells"][0] * lattice_constant(s["rho0"])
        hist = sh["max_time"] / sh["dt"] / sh["sample_every"] * (length / sh["bin_width"] + 1) * 88
        mem = int(BASE_MB + (n * BYTES_PER_ATOM + 2 * hist) / 2**20)
        return Resources(ranks * mem, n * sh["max_time"] / sh["dt"] * S_PER_ATOM_STEP, ranks)

    # -- presentation ----------------------------------------------------------------------
    def figure_labels(self, scene: dict) -> dict:
        """Reduced-unit axes (the MD backend's), tag ``LAMMPS``, the model in the title."""
        axes = {"V": ("specific volume V [σ³]", 1.0),
                "P": ("longitudinal stress P_xx [ε σ⁻³]", 1.0),
                "u_p_measured": ("particle velocity u_p [σ/τ]", 1.0),
                "D": ("shock velocity D [σ/τ]", 1.0)}  # fmt: skip
        return {"axes": axes, "tag": "LAMMPS", "reference": "reference (equilibrium MD)",
                "title": f"LAMMPS {scene['model']['pair_style']}"}  # fmt: skip

    def sound_speed(self, scene: dict) -> float | None:
        """No model sound speed: the campaign fits one to the reference Hugoniot."""
        return None

    def window_cpu_s(self, scene: dict) -> float:
        """CPU seconds of one control window at the fastest rate: the window's atoms
        (``scale``) over ``window.window_time``/``shock.dt`` steps [s]."""
        steps = scene["window"]["window_time"] / scene["shock"]["dt"]
        return self.scale(scene)["n_window"] * steps * FASTEST_S_PER_ATOM_STEP

    def scale(self, scene: dict) -> dict[str, float]:
        """As the MD backend's: atoms in a window of ``window.length`` (none here: NaN) at
        ρ0, its length in spacings ρ0^(-1/3)."""
        s = scene["sample"]
        L = float(scene.get("window", {}).get("length", math.nan))
        a = lattice_constant(s["rho0"])
        spacing = float(s["rho0"]) ** (-1.0 / 3.0)
        across = float(s["rho0"]) * s["cells"][1] * s["cells"][2] * a * a * spacing
        return {"n_window": across * L / spacing, "window_spacings": L / spacing,
                "spacing": spacing}  # fmt: skip


def lattice_mass_density(scene: dict) -> float:
    """ρ0 of a units-metal scene's lattice [kg/m³]: n m u_kg/Å³, n = ``sample.rho0`` [Å⁻³]
    (4/a³ for FCC), m = ``model.mass`` [g/mol]."""
    u = METAL
    return (
        float(scene["sample"]["rho0"]) * float(scene["model"]["mass"]) * u.mass_kg / u.length_m**3
    )


def linear_reference(scene: dict, n_points: int = 60) -> xr.Dataset:
    """A linear Us–u_p fit as the reference Hugoniot (SI), dim ``point``: u_p, D, P, V, rho,
    E (the CSPH backend's solid reference, ``sph.backend.CSPHBackend.reference``):

        D = c0 + s u_p,   P = ρ0 D u_p,   V = V0 (1 − u_p/D),   ρ = 1/V,   E − E0 = u_p²/2,

    from the fit's ambient state (P0 = 0), ρ0 the scene's lattice density
    (``lattice_mass_density``); c0 [m/s], s and ``source`` from the ``reference`` block (e.g.
    LASL Shock Hugoniot Data (Marsh 1980) for copper: c0 = 3940 m/s, s = 1.49). An even grid
    to 1.25 max(u_p) and the scene's own u_p."""
    r = scene["reference"]
    c0, s = float(r["c0"]), float(r["s"])
    rho0 = lattice_mass_density(scene)
    grid = np.linspace(0.0, 1.25 * max(scene["shock"]["u_p"]), n_points + 1)[1:]
    up = np.unique(np.concatenate([grid, np.asarray(scene["shock"]["u_p"], float)]))
    D, _, V, P, E = jump_state(up, rho0, c0, s)
    model = f"linear Us-u_p fit D = {c0:g} m/s + {s:g} u_p ({r.get('source', '')})"
    ds = xr.Dataset({
        "u_p": ("point", up, {"units": "m s^-1", "long_name": "particle velocity"}),
        "D": ("point", D, {"units": "m s^-1", "long_name": "shock velocity"}),
        "P": ("point", P, {"units": "Pa", "long_name": "pressure rho0 D u_p"}),
        "V": ("point", V, {"units": "m^3 kg^-1", "long_name": "specific volume"}),
        "rho": ("point", 1.0 / V, {"units": "kg m^-3", "long_name": "density"}),
        "E": ("point", E, {"units": "J kg^-1",
                                     "long_name": "specific internal energy jump"}),
    })  # fmt: skip
    ds.attrs.update(title=f"reference Hugoniot: {model}", reference_model=model,
                    source=str(r.get("source", "")), rho0=rho0, c0=c0, s=s)  # fmt: skip
    return ds


#: The datasets of a units-metal scene: SI, recorded as coming from LAMMPS units metal.
METAL_UNITS = dataclasses.replace(si_units(), system="SI (m, s, kg); LAMMPS units metal")


class MetalBackend(LammpsBackend):
    """``Backend`` for ``solver: lammps`` scenes in units metal (module docstring): the
    LAMMPS run in Å, ps, eV; everything across the seam in SI."""

    units = METAL_UNITS
    usys = METAL
    #: The reference is the scene's Us–u_p fit, not a run at the sample's pole.
    reference_from_sample = False

    def view(self, sim):
        """The simulation in SI (``si.SIView``)."""
        from .si import SIView
        from .simulation import native

        return SIView(native(sim))

    def window_view(self, win):
        """The window in SI (``si.WindowSIView``)."""
        from .si import WindowSIView

        return WindowSIView(win)

    def _native_velocity(self, u: float) -> float:
        return u / METAL.velocity_m_s  # m/s → Å/ps

    def _native_pole(self, scene: dict, pole: Pole) -> tuple[float, float]:
        """ρ0 [kg/m³] → [Å⁻³], E0 [J/kg] → [eV per atom] (``units.si_pole``'s factors)."""
        mass = float(scene["model"]["mass"])
        e = si_pole({"E0": 1.0}, mass)["E0"]
        return float(pole.rho0) / number_density_factor(mass), float(pole.E0) / e

    def _pole_from_native(self, scene: dict, pole: dict[str, float]) -> dict[str, float]:
        return si_pole(pole, float(scene["model"]["mass"]))

    def _count_density(self, scene: dict, rho: float) -> float:
        """Atoms per m³ of ρ [kg/m³]."""
        return rho / (float(scene["model"]["mass"]) * METAL.mass_kg)

    def _window_block(self, scene: dict) -> dict:
        """The window's times [ps] in s, its slab gap [Å] in m (the other keys as they are:
        ``dichotomy.half_width`` and ``tolerance`` are in m/s already)."""
        w = dict(scene["window"])
        for k in ("window_time", "average_time", "max_average_time"):
            if w.get(k):
                w[k] = self._time(w[k])
        d = dict(w["dichotomy"])
        for k in ("trial_time", "final_time"):
            if d.get(k):
                d[k] = self._time(d[k])
        w["dichotomy"] = d
        if w.get("outflow_gap"):
            w["outflow_gap"] = self._length(w["outflow_gap"])
        return w

    def _length(self, x: float) -> float:
        return x * METAL.length_m  # Å → m

    def _time(self, t: float) -> float:
        return t * METAL.time_s  # ps → s

    def profile(self, solver, scene: dict, info: dict | None = None) -> MetalProfile:
        """The SI reader (``MetalProfile``) at ``shock.bin_width`` [Å] (``lattice.bin_width``:
        scaled with a searched lattice)."""
        return MetalProfile(_area(solver), bin_width(scene, info), scene["model"]["mass"])

    def reference_inputs(self, scene: dict, pole: Pole | None = None) -> None:
        """None: the fit is tabulated per scene in milliseconds."""
        return None

    def reference(self, scene: dict, pole: Pole | None = None) -> xr.Dataset:
        """The ``reference`` block's linear Us–u_p fit (``linear_reference``)."""
        return linear_reference(scene)

    def _snapshot_units(self, scene: dict) -> dict[str, Any]:
        """LAMMPS metal as it is: Å, Å/ps, g/mol, eV; species the last ``pair_coeff`` word
        (the element the potential maps the atom type to)."""
        species = str(scene.get("model", {}).get("pair_coeff", ["X"])[0]).split()[-1]
        return {"masses": float(scene.get("model", {}).get("mass", 1.0)), "species": species,
                "length_unit": "Angstrom", "time_unit": "ps",
                "units": {"masses": "g/mol", "momenta": "g/mol*Angstrom/ps", "pe": "eV"}}  # fmt: skip

    def cost(self, scene: dict, stage: str) -> Resources:
        """As units lj's (atom-steps in native units); the reference is a table."""
        if stage == "reference":
            return Resources(BASE_MB, 1.0)
        return super().cost(scene, stage)

    def figure_labels(self, scene: dict) -> dict:
        """SI axes, drawn as V [cm³/g], P [GPa], velocities [m/s] (the CSPH backend's)."""
        axes = {"V": ("specific volume V [cm³/g]", 1e3),
                "P": ("longitudinal stress P_xx [GPa]", 1e-9),
                "u_p_measured": ("particle velocity u_p [m/s]", 1.0),
                "D": ("shock velocity D [m/s]", 1.0)}  # fmt: skip
        return {"axes": axes, "tag": "LAMMPS", "reference": "linear Us-u_p fit",
                "title": f"LAMMPS {scene['model']['pair_style']} (units metal)"}  # fmt: skip

    def sound_speed(self, scene: dict) -> float | None:
        """The reference fit's c0 [m/s]."""
        return float(scene["reference"]["c0"])


BACKEND = LammpsBackend()
METAL_BACKEND = MetalBackend()
