"""The MD backend: Lennard-Jones molecular dynamics behind ``hugomap.backend.Backend``.

Reduced LJ units throughout (σ, ε, m = 1, τ = σ√(m/ε), k_B = 1). The sample is an FCC box
closed by two static walls (``md.sample.fcc_state``); the piston runs in the piston's frame
(the sample at −u_p, the piston wall at rest, the far wall moving with the upstream
material); the window is ``md.window.MDWindow`` (the particle window with ``md.kit.MDKit``)
with an equilibrated periodic reservoir (``particles.reservoir``) as its inflow; the
reference Hugoniot is equilibrium NVT MD (``md.reference``), shared between scenes with the
same inputs.
"""

from __future__ import annotations

import json
import logging
import math
import os
from pathlib import Path
from typing import Any

import numpy as np
import xarray as xr

from ..backend import lengthened
from ..io.dataset import lj_units
from ..particles.fcc import lattice_constant
from ..particles.pole import measure_pole, reference_pole
from ..particles.profiles import ParticleProfile
from ..states import ControlParams, PistonFrame, Pole, Resources, WindowStart

log = logging.getLogger("hugomap")
WALL_LAYER = 4.0  # sigma kept clear of a wall when measuring the pole (wall layering)

# Cost model (Snakemake mem_mb, runtime), measured on the 2-core development machine.
BASE_MB = 1024  # Python + numba + xarray/netCDF: about 350 MB resident, measured
# state ~0.2 kB + full Verlet list ~0.8 kB (int32 rows, rho* <= 1.5), x4 margin
BYTES_PER_ATOM = 4096
S_PER_ATOM_STEP = 1.0e-6  # 1-core kernel ~3e-7 s, x3: sampling, I/O
# the fastest the kernel runs an atom-step on one core: ~3e-7 s measured, machines of this
# kind differ by 2x (a lower bound, for refusing a budget no machine could keep)
FASTEST_S_PER_ATOM_STEP = 1.5e-7
REF_POLE_FACTOR, REF_MAX_ITER = 4, 10  # md.reference.reference_hugoniot defaults


def lj(scene: dict):
    """The scene's potential, ``md.potential.LJParams`` (``potential`` block: rc [σ],
    shift, skin [σ])."""
    from .potential import LJParams

    p = scene["potential"]
    return LJParams(rc=p["rc"], shift=p["shift"], skin=p["skin"])


def _area(solver) -> float:
    area = getattr(solver, "area", None)
    if area is not None:
        return float(area)
    L = solver.state.L
    return float(L[1] * L[2])


def _n_atoms(scene: dict) -> int:
    nx, ny, nz = scene["sample"]["cells"]
    return 4 * nx * ny * nz  # FCC


def md_frame(solver, scene: dict, tags: dict) -> str:
    """An extended-XYZ frame of an MD run or window (``io.extxyz.format_frame``), in reduced
    units as they are (lengths σ, velocities σ/τ, masses m = 1, time τ; the comment line
    says so: ``length_unit=sigma time_unit=tau`` and ``units``), species ``Ar``.

    Per atom: ``id`` (hugomap's label), ``frozen`` (ids < 0), and, relative to the atom's
    profile bin (``shock.bin_width`` along x; its mean velocity u_b over the bin's mobile
    atoms, all its atoms if it has none; V_b its volume, N_b its mobile atoms, at least 1):
    ``P_xx`` = N_b/V_b [(v_x − u_b,x)² + W_xx] [ε σ⁻³] (W the atom's virial), whose mean
    over a bin's mobile atoms is the profile's P_xx; ``e`` = ½|v − u_b|² + U [ε] (U its
    potential energy; the bin mean is the profile's e); ``T`` = |v − u_b|²/3 [ε/k_B] (the
    bin mean is N_b/(N_b − 1) times lower than the profile's T). The cell: y, z the periodic
    box, x the walls and every atom."""
    sim = getattr(solver, "sim", solver)  # an MDWindow holds its simulation
    s = sim.state
    pe, vir = sim.per_atom_energy_virial()
    width = float(scene["shock"]["bin_width"])
    mobile = s.ids >= 0
    b = np.floor(s.x[:, 0] / width).astype(np.int64)
    keys, inverse = np.unique(b, return_inverse=True)
    m = len(keys)
    count = np.bincount(inverse, weights=mobile.astype(float), minlength=m)
    every = np.bincount(inverse, minlength=m).astype(float)
    u = np.empty((m, 3))
    for k in range(3):
        vm = np.bincount(inverse, weights=s.v[:, k] * mobile, minlength=m)
        va = np.bincount(inverse, weights=s.v[:, k], minlength=m)
        u[:, k] = np.where(count > 0, vm / np.maximum(count, 1.0), va / every)
    c = s.v - u[inverse]
    density = np.maximum(count, 1.0)[inverse] / (_area(solver) * width)
    fields = {
        "id": s.ids.astype(np.int64),
        "frozen": ~mobile,
        "P_xx": density * (c[:, 0] ** 2 + vir[:, 0]),
        "e": 0.5 * np.sum(c * c, axis=1) + pe,
        "T": np.sum(c * c, axis=1) / 3.0,
    }
    xl, xr = sim.wall_positions()
    xs = s.x[:, 0] if s.n else np.zeros(1)
    x_lo = min(float(xs.min()), xl, xr, 0.0)
    x_hi = max(float(xs.max()), xl, xr, x_lo + width)
    from ..io.extxyz import format_frame
    from ..particles.snapshot import velocity_frame

    return format_frame(
        s.x, np.array([x_hi - x_lo, s.L[1], s.L[2]]), velocities=s.v, masses=1.0,
        frame=velocity_frame(solver),
        fields=fields, species="Ar", origin=(x_lo, 0.0, 0.0), pbc=tuple(bool(p) for p in s.periodic),
        time=float(s.time), length_unit="sigma", time_unit="tau",
        units={"masses": "m", "momenta": "m*sigma/tau", "P_xx": "epsilon/sigma^3",
               "e": "epsilon", "T": "epsilon/k_B"},
        info={"scene": scene.get("name", ""), **tags, "step": int(s.step),
              "potential": "LJ", "rc": float(sim.lj.rc)},
    )  # fmt: skip


def _snapshots(solver, out: Path, scene: dict, tags: dict) -> None:
    """Write the run's trajectory (if one was taken) and its last frame beside ``out``."""
    from ..io.extxyz import snapshot_paths, write_extxyz

    snap, traj = snapshot_paths(out)
    recorder = getattr(solver, "trajectory", None)
    if recorder is not None:
        recorder.save(traj)
    if scene["shock"].get("snapshots", True):
        write_extxyz(snap, md_frame(solver, scene, tags))


class MDBackend:
    """``Backend`` for ``solver: md`` scenes (module docstring)."""

    name = "md"
    units = lj_units()

    # -- sample and checkpoints ------------------------------------------------------------
    def prepare(self, scene: dict) -> tuple[Any, Pole, dict[str, Any]]:
        """FCC at (ρ0, T0) (or the atoms of ``sample.data_file``, a LAMMPS data file) between
        two static walls, thermostatted (CSVR, and slab by slab along x:
        ``particles.sizing.flatten_temperature``) for ``equilibrate_time`` while
        ``particles.sizing.size_bulk`` sizes the box so that the bulk, ``WALL_LAYER`` from the
        walls, is at ρ0 (a fluid: L_x = cells·a less the walls' excess layer, about 0.2 % for the
        default liquid; a crystal keeps its lattice) and ends at the canonical mean energy of
        T0; then run without thermostat for ``pole_time`` while the pole is measured away
        from the walls (``particles.pole.measure_pole``): ρ0, P0 = P_xx, E0, T0, P_yy0 (block
        averages with standard errors).
        The sample info is what ``size_bulk`` did (``length_x`` [σ], ``x_scale``, the bulk
        density and energies it measured), for the record."""
        from ..particles.sizing import size_bulk
        from .sample import initial_state
        from .simulation import MDSimulation

        s = scene["sample"]
        state = initial_state(s)  # FCC, or the scene's LAMMPS data file
        sim = MDSimulation(
            state, lj(scene), s["dt"], T_bath=s["T0"], tau_bath=s["thermostat_tau"],
            seed=s["seed"],
        )  # fmt: skip
        n_eq = int(round(s["equilibrate_time"] / s["dt"]))
        info: dict[str, Any] = {}
        if n_eq > 0:
            info = size_bulk(sim, s["rho0"], s["T0"], n_eq, WALL_LAYER,
                             resize=scene["phase"] != "crystal")  # fmt: skip
            log.info("sample sized: %s", json.dumps(info))
        sim.T_bath = None
        prof = ParticleProfile(_area(sim), scene["shock"]["bin_width"])
        pole = measure_pole(sim, sim, prof, float(sim.state.L[0]), WALL_LAYER, s["pole_time"],
                            s["dt"])  # fmt: skip
        return sim, Pole.from_dict(pole), {"sizing": info}

    def save(self, solver, out: str | os.PathLike, extra: xr.Dataset, attrs: dict) -> Path:
        return solver.save(out, extra=extra, attrs=attrs)

    def read_checkpoint(self, path: str | os.PathLike) -> xr.Dataset:
        from ..io.checkpoint import MD_CHECKPOINT, read_checkpoint

        return read_checkpoint(path, kind=MD_CHECKPOINT)

    def load(self, ds: xr.Dataset, source: str | os.PathLike | None = None):
        from .simulation import MDSimulation

        return MDSimulation.from_dataset(ds, source)

    def load_window(self, ds: xr.Dataset, source: str | os.PathLike | None = None):
        from .window import MDWindow

        return MDWindow.from_dataset(ds, source)

    # -- the piston ------------------------------------------------------------------------
    def start_piston(self, solver, scene: dict, u_p: float) -> None:
        """Piston frame: the sample's own mean x velocity (a thermal drift of order √(T/N)
        left by the walls and thermostat of the preparation) is removed and every atom gets
        −u_p; the piston wall stays at rest, the far wall moves at −u_p. The upstream flow is
        then exactly −u_p and the particle-velocity jump exactly u_p."""
        solver.dt = scene["shock"]["dt"]
        solver.T_bath = None
        solver.galilean_shift(-u_p - solver.mean_velocity())
        solver.set_walls(0.0, -u_p)
        solver.loading = True  # no trajectory (``profile``): the loading stage ends in a checkpoint

    def piston_frame(self, solver, scene: dict, u_p: float, info: dict) -> PistonFrame:
        sh = scene["shock"]
        return PistonFrame(
            u_behind=0.0, u_ahead=-u_p, x_origin=solver.wall_positions()[0],
            load_distance=sh["load_fraction"] * float(solver.state.L[0]),
            rear_margin=sh["rear_margin"], max_time=sh["max_time"],
            sample_every=sh["sample_every"], piston_gap=sh["piston_gap"],
            ahead_gap=sh.get("ahead_gap"),
        )  # fmt: skip

    def profile(self, solver, scene: dict, info: dict | None = None) -> ParticleProfile:
        """The profile reader; with ``shock.snapshot_every`` = N it also takes a trajectory
        frame (``md_frame``) every N samples (``io.extxyz.RecordingProfile``; not while
        loading: ``start_piston`` marks the solver), which ``extras`` and ``window_extras``
        write."""
        prof = ParticleProfile(_area(solver), scene["shock"]["bin_width"])
        every = scene["shock"].get("snapshot_every", 0)
        if not every or getattr(solver, "loading", False):
            return prof
        from ..io.extxyz import RecordingProfile, Trajectory

        solver.trajectory = getattr(solver, "trajectory", None) or Trajectory(every)
        return RecordingProfile(prof, solver.trajectory,
                                lambda s: md_frame(s, scene, {"run": "trajectory"}))  # fmt: skip

    # -- the window ------------------------------------------------------------------------
    def open_window(
        self, solver, loaded: xr.Dataset, scene: dict, u_p: float, front: float,
        D_guess: float, pole: Pole, info: dict,
    ) -> WindowStart:  # fmt: skip
        """``MDWindow.from_piston`` with the front at ``window.front_fraction``, its inflow a
        reservoir snapshot (``particles.reservoir.make_reservoir``), run on beside the window
        (``window.inflow`` = "live", ``md.live_inflow``) or carried frozen. A fluid's inflow is
        made at the piston sample's measured (ρ0, E0), a frozen snapshot screened by the flow
        it feeds in at D_guess (``window.reservoir_screen``, ``inflow_screen``), so both
        schemes share one pole
        (the sample's more precise P0, T0 are kept; the inflow's own measurement, a
        ~1000-atom box over 2 τ, is stored beside them as a check); a crystal's keeps the nominal lattice (the seam needs its registry) and T0,
        and its pole is the inflow's. The window runs ``settle_time`` at the guessed D (the
        set-up transient: new boundaries, the first seam), then ω is normalised by the pole
        (ρ0, P0) and the shocked slab between the outflow edge and the front (``shock.gap``
        clear of both)."""
        from ..methods.control import OmegaSignal
        from ..particles.reservoir import inflow_screen, make_reservoir
        from .kit import MDKit
        from .window import MDWindow

        w, sh, s = scene["window"], scene["shock"], scene["sample"]
        fluid = scene["phase"] != "crystal"
        res, inflow = make_reservoir(
            MDKit(solver.lj), (s["cells"][1], s["cells"][2]), pole.rho0 if fluid else s["rho0"],
            s["T0"], solver.dt, s["seed"] + 7919, w["reservoir_equilibrate_time"],
            s["thermostat_tau"], E0_target=pole.E0 if fluid else None,
            min_length=w["reservoir_length"],
            screen=inflow_screen(w, sh["gap"], D_guess) if fluid and w["inflow"] == "frozen"
            else None,
        )  # fmt: skip
        log.info("inflow pole: %s", json.dumps(inflow))
        win = MDWindow.from_piston(
            solver, res, front, u_p, D_guess, w["length"], w["front_fraction"],
            w["ghost_width"], w["cut_every"], w["sync_steps"],
            crystal=not fluid, lattice=lattice_constant(s["rho0"]),
            segment=w["reservoir_segment"], inflow=w["inflow"], seam_work=w["seam_work"],
        )  # fmt: skip
        wpole = pole if fluid else Pole.from_dict(inflow)
        o = w["outflow"]
        if o["kind"] == "absorbing":
            # Z = ρ0 D and the averages started at the jump condition's P0 + ρ0 D u_p
            win.set_absorbing(wpole.rho0 * D_guess, o["tau_fast"], o["tau_slow"],
                              wpole.P0 + wpole.rho0 * D_guess * u_p)  # fmt: skip
        win.advance(int(round(w["settle_time"] / win.dt)))
        key = "rho" if w["omega"] == "N" else "P"
        sig = OmegaSignal.from_settled(
            win, self.profile(win, scene), w["omega"], sh["gap"], w["front_fraction"],
            wpole.rho0 if key == "rho" else wpole.P0, lambda st: st[key],
        )  # fmt: skip
        return WindowStart(win, wpole, sig, {f"inflow_{k}": v for k, v in inflow.items()})

    def control_params(self, scene: dict, u_p: float, window) -> ControlParams:
        """The configured times (``ControlParams.from_window``)."""
        sh = scene["shock"]
        return ControlParams.from_window(scene["window"], window.geom.length, sh["gap"],
                                         sh["avg_length"], ahead_gap=sh.get("ahead_gap"))  # fmt: skip

    #: The reference is computed at the pole the prepared sample measured (``reference``).
    reference_from_sample = True

    def reference_inputs(self, scene: dict, pole: Pole | None = None) -> dict:
        """What the equilibrium reference depends on (``reference`` reads nothing else):
        the potential block, the pole it is computed at and the ``reference`` block. The
        pole is the sample's measured one (``reference_pole``), so the inputs are what
        makes the sample (``phase``, the whole ``sample`` block, the pole's bins
        ``shock.bin_width``) and, once it is made, that pole (``pole``: ρ0 [σ⁻³], T0
        [ε/k_B]). Scenes that agree on these share one computation; the workflow's key is
        the part without the pole (known before any sample exists, and deciding it: the
        preparation is deterministic), and a scene copies the shared file only when its
        own sample measured the same pole."""
        inputs = {
            "solver": "md",
            "potential": dict(scene["potential"]),
            "phase": scene["phase"],
            "sample": dict(scene["sample"]),
            "pole_bin_width": scene["shock"]["bin_width"],
            "reference": dict(scene["reference"]),
        }
        if pole is not None:
            inputs["pole"] = self.reference_pole(scene, pole)
        return inputs

    def reference_pole(self, scene: dict, pole: Pole) -> dict[str, float]:
        """The (ρ0 [σ⁻³], T0 [ε/k_B]) the reference is computed at, with their standard
        errors (``particles.pole.reference_pole``: the measured T0 and, for a fluid, the
        measured bulk ρ0; a crystal keeps the lattice's)."""
        return reference_pole(scene, pole)

    def reference(self, scene: dict, pole: Pole | None = None) -> xr.Dataset:
        """The equilibrium-MD Hugoniot (``md.reference``) of ``reference_inputs(scene,
        pole)``: at the sample's measured pole (``reference_pole``), or without ``pole`` at
        the requested ``sample.rho0``, ``sample.T0``. The pole it was computed at is stored
        as the variables ``pole_rho0``, ``pole_T0`` (with ``_err``: the sample's standard
        errors) beside the requested ``requested_rho0``, ``requested_T0``."""
        from .reference import reference_hugoniot

        s, r = scene["sample"], scene["reference"]
        at = (
            {"rho0": s["rho0"], "rho0_err": 0.0, "T0": s["T0"], "T0_err": 0.0}
            if pole is None
            else self.reference_pole(scene, pole)
        )
        ds = reference_hugoniot(
            at["rho0"], at["T0"], lj(scene),
            compressions=r["compressions"], cells=(r["cells"],) * 3, dt=r["dt"],
            n_equil=r["equilibrate_steps"], n_prod=r["production_steps"], seed=s["seed"],
        )  # fmt: skip
        u = {"rho0": "sigma^-3", "T0": "epsilon k_B^-1"}
        names = {"rho0": "number density", "T0": "temperature"}
        src = "requested" if pole is None else "the prepared sample's measured"
        for k in ("rho0", "T0"):
            ds[f"pole_{k}"] = ((), at[k], {"units": u[k], "long_name": f"pole {names[k]} the "
                               f"reference is computed at ({src})"})  # fmt: skip
            ds[f"pole_{k}_err"] = ((), at[k + "_err"], {"units": u[k], "long_name":
                                   f"standard error of pole_{k} (the sample's)"})  # fmt: skip
            ds[f"requested_{k}"] = ((), float(s[k]), {"units": u[k], "long_name":
                                    f"requested pole {names[k]} (sample.{k})"})  # fmt: skip
        ds.attrs["pole_source"] = "requested" if pole is None else "sample"
        ds.attrs["reference_inputs"] = json.dumps(
            self.reference_inputs(scene, pole), sort_keys=True
        )
        return ds

    def extras(self, solver, out: Path, scene: dict, u_p: float, info: dict) -> None:
        """A piston run's snapshot ``<stem>_snapshot.extxyz`` (``md_frame``) beside its point
        file when ``shock.snapshots`` is set, and its trajectory ``<stem>_trajectory.extxyz``
        when ``shock.snapshot_every`` is."""
        _snapshots(solver, out, scene, {"run": "piston", "u_p": u_p})

    def window_extras(
        self, window, out: Path, scene: dict, u_p: float, scheme: str, info: dict
    ) -> None:
        """A window run's snapshot and trajectory, as ``extras``."""
        _snapshots(window, out, scene, {"run": scheme, "u_p": u_p})

    # -- cost ------------------------------------------------------------------------------
    def _profile_bytes(self, scene: dict) -> float:
        """Profile history of one shock stage: samples x bins x 11 sums (float64)."""
        s, sh = scene["sample"], scene["shock"]
        length = s["cells"][0] * lattice_constant(s["rho0"])
        n_samples = sh["max_time"] / sh["dt"] / sh["sample_every"]
        return n_samples * (length / sh["bin_width"] + 1) * 11 * 8

    def longer_sample(self, scene: dict, factor: float) -> dict | None:
        """More FCC cells along x (``backend.lengthened``); None for a sample read from
        ``sample.data_file``, whose length is the file's."""
        if scene["sample"].get("data_file"):
            return None
        return lengthened(scene, ("sample", "cells", 0), factor)

    def cost(self, scene: dict, stage: str) -> Resources:
        """Memory: the state and neighbour list per atom, plus the profile history held and
        copied once into the dataset; CPU: an upper bound of atom-steps at the 1-core rate
        (``prepare``: equilibration and pole; ``load``/``piston``: each stops at
        ``shock.max_time``; ``reference``: the pole (REF_POLE_FACTOR x production) then
        REF_MAX_ITER NVT runs per compression; other stages as a piston stage)."""
        s, sh = scene["sample"], scene["shock"]
        if stage == "reference":
            r = scene["reference"]
            n = 4 * r["cells"] ** 3
            run = r["equilibrate_steps"] + r["production_steps"]
            steps = r["equilibrate_steps"] + REF_POLE_FACTOR * r["production_steps"]
            steps += REF_MAX_ITER * len(r["compressions"]) * run
            return Resources(int(BASE_MB + n * BYTES_PER_ATOM / 2**20), n * steps * S_PER_ATOM_STEP)
        n = _n_atoms(scene)
        if stage == "prepare":
            steps = (s["equilibrate_time"] + s["pole_time"]) / s["dt"]
            return Resources(int(BASE_MB + n * BYTES_PER_ATOM / 2**20), n * steps * S_PER_ATOM_STEP)
        extra = self._profile_bytes(scene)
        mem = int(BASE_MB + (n * BYTES_PER_ATOM + 2 * extra) / 2**20)
        return Resources(mem, n * sh["max_time"] / sh["dt"] * S_PER_ATOM_STEP)

    # -- presentation ----------------------------------------------------------------------
    def figure_labels(self, scene: dict) -> dict:
        """Axis labels and scale factors (reduced units), the points' tag, the reference's
        name and the title (the potential's cutoff: the Hugoniot depends on it)."""
        axes = {"V": ("specific volume V [σ³]", 1.0),
                "P": ("longitudinal stress P_xx [ε σ⁻³]", 1.0),
                "u_p_measured": ("particle velocity u_p [σ/τ]", 1.0),
                "D": ("shock velocity D [σ/τ]", 1.0)}  # fmt: skip
        rc = scene.get("potential", {}).get("rc", "?")
        return {"axes": axes, "tag": "MD", "reference": "reference (equilibrium MD)",
                "title": f"LJ rc = {rc:g} σ" if isinstance(rc, int | float) else "LJ"}  # fmt: skip

    def sound_speed(self, scene: dict) -> float | None:
        """No model sound speed: the campaign fits one to the reference Hugoniot."""
        return None

    def window_cpu_s(self, scene: dict) -> float:
        """CPU seconds of one control window at the fastest kernel rate: the window's atoms
        (``scale``) over ``window.window_time``/``shock.dt`` steps [s]."""
        steps = scene["window"]["window_time"] / scene["shock"]["dt"]
        return self.scale(scene)["n_window"] * steps * FASTEST_S_PER_ATOM_STEP

    def scale(self, scene: dict) -> dict[str, float]:
        """Particles in the window at ρ0 (ρ0 A L), its length in spacings ρ0^(-1/3)."""
        w, s = scene.get("window", {}), scene["sample"]
        L = float(w.get("length", math.nan))
        a = lattice_constant(s["rho0"])
        spacing = float(s["rho0"]) ** (-1.0 / 3.0)
        across = float(s["rho0"]) * s["cells"][1] * s["cells"][2] * a * a * spacing
        return {"n_window": across * L / spacing, "window_spacings": L / spacing,
                "spacing": spacing}  # fmt: skip


BACKEND = MDBackend()
