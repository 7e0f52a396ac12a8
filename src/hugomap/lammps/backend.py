"""The LAMMPS backend: ``hugomap.backend.Backend`` with the LAMMPS library doing the MD
(``solver: lammps``; ``lammps.simulation.LammpsSimulation``).

This slice: units lj (σ, ε, m = 1, τ = σ√(m/ε), k_B = 1), the piston scheme. The sample is
the MD backend's: an FCC lattice (``md.sample.fcc_positions``, Maxwell velocities at T0)
between a reflecting wall at x = 0 and a one-sided harmonic wall at L_x, y and z periodic,
equilibrated with a CSVR thermostat (LAMMPS ``fix temp/csvr``) while ``md.sample.size_bulk``
sizes a fluid's box so its bulk is at ρ0 and ends at the canonical mean energy of T0; then
an NVE run measures the pole away from the walls (block averages, ``analysis.stats``).
The piston runs in the MD backend's frame (drift removed, every atom at −u_p, the piston
wall at rest, the far wall moving at −u_p with the upstream material), so u_p is exact and
the shared analysis (``window.piston``, ``analysis.shock.measure_point``) measures the point
from the profile sums (``md.profiles.SUM_FIELDS``, read by the MD backend's ``MDProfile``).

Not yet: the moving-window schemes (``open_window``, ``load_window``, ``control_params``,
``window_extras`` raise ``NotImplementedError``; validation refuses such scenes), units
metal, trajectories (``extras`` writes the last frame only), a LAMMPS reference (an lj/cut
scene's reference is the MD backend's equilibrium MD of the same potential).
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

from ..analysis.shock import bin_edges, slab_state
from ..analysis.stats import block_average
from ..io.dataset import lj_units
from ..states import ControlParams, PistonFrame, Pole, Resources, WindowStart
from .scene_config import pair_style_name

log = logging.getLogger("hugomap")
WALL_LAYER = 4.0  # sigma kept clear of a wall when measuring the pole (the MD backend's)
POLE_EVERY = 25  # steps between pole samples (the MD backend's)

# Cost model, measured on the 2-core development machine (one rank, one OpenMP thread):
# LJ rc 2.5 at rho 0.8 ran 1.5e-6 s per atom-step under load (``run`` of 1920 atoms);
# x2 for the per-sample gathering in Python and a loaded machine.
BASE_MB = 1024  # Python + xarray + liblammps
BYTES_PER_ATOM = 2048  # LAMMPS arrays, ghosts and neighbour lists, x4 margin
S_PER_ATOM_STEP = 3.0e-6

NOT_YET = (
    "solver lammps runs the piston scheme only (the moving-window schemes are a later "
    "slice; validation refuses scenes that ask for them)"
)


def _area(solver) -> float:
    return float(solver.L[1] * solver.L[2])


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
    units = lj_units()

    # -- sample and checkpoints ------------------------------------------------------------
    def prepare(self, scene: dict) -> tuple[Any, Pole, dict[str, Any]]:
        """FCC at (ρ0, T0) between the walls, thermostatted (CSVR) for
        ``sample.equilibrate_time`` while ``md.sample.size_bulk`` sizes the box (a fluid:
        L_x stretched so the bulk, ``WALL_LAYER`` from the walls, is at ρ0; a crystal keeps
        its lattice) and ends at the canonical mean energy of T0; then NVE for
        ``sample.pole_time`` while the pole is measured between ``WALL_LAYER`` and
        L_x − ``WALL_LAYER``: ρ0 [σ⁻³], P0 = P_xx, Pyy0 [ε σ⁻³], E0 [ε per atom], T0
        [ε/k_B], block averages (8 blocks) with standard errors. Info: what the sizing
        measured (``sizing``)."""
        from ..md.backend import MDProfile
        from ..md.sample import fcc_positions, maxwell_velocities, size_bulk
        from .simulation import LammpsSimulation

        s = scene["sample"]
        x, L = fcc_positions(tuple(s["cells"]), s["rho0"])
        v = maxwell_velocities(x.shape[0], s["T0"], s["seed"])
        sim = LammpsSimulation(
            x, v, np.arange(x.shape[0]), L, np.array([0.0, 0.0, L[0], 0.0]), scene["model"],
            s["dt"], T_bath=s["T0"], tau_bath=s["thermostat_tau"], seed=s["seed"],
        )  # fmt: skip
        n_eq = int(round(s["equilibrate_time"] / s["dt"]))
        info: dict[str, Any] = {}
        if n_eq > 0:
            info = size_bulk(sim, s["rho0"], s["T0"], n_eq, WALL_LAYER,
                             resize=scene["phase"] != "crystal")  # fmt: skip
            log.info("sample sized: %s", json.dumps(info))
        sim.T_bath = None
        prof = MDProfile(_area(sim), scene["shock"]["bin_width"])
        nsamples = max(int(round(s["pole_time"] / (s["dt"] * POLE_EVERY))), 16)
        keys = {"rho": "rho0", "P": "P0", "E": "E0", "T": "T0", "Pyy": "Pyy0"}
        series: dict[str, list[float]] = {k: [] for k in keys}
        Lx = float(sim.L[0])
        nb = int(np.floor(Lx / prof.bin_width + 1e-9))
        edges = bin_edges(prof, nb)
        for _ in range(nsamples):
            sim.advance(POLE_EVERY)
            st = slab_state(prof, prof.sums(sim)[:nb], edges, WALL_LAYER, Lx - WALL_LAYER)
            for k in keys:
                series[k].append(st[k])
        pole = {}
        for k, name in keys.items():
            pole[name], pole[name + "_err"] = block_average(np.asarray(series[k]))
        return sim, Pole.from_dict(pole), {"sizing": info}

    def save(self, solver, out: str | os.PathLike, extra: xr.Dataset, attrs: dict) -> Path:
        return solver.save(out, extra=extra, attrs=attrs)

    def read_checkpoint(self, path: str | os.PathLike) -> xr.Dataset:
        from ..io.checkpoint import read_checkpoint
        from .simulation import LAMMPS_CHECKPOINT

        return read_checkpoint(path, kind=LAMMPS_CHECKPOINT)

    def load(self, ds: xr.Dataset, source: str | os.PathLike | None = None):
        """A new LAMMPS instance from a verified checkpoint (``LammpsSimulation.from_dataset``:
        the same state, not bit-exact on resume)."""
        from .simulation import LammpsSimulation

        return LammpsSimulation.from_dataset(ds, source)

    def load_window(self, ds: xr.Dataset, source: str | os.PathLike | None = None):
        raise NotImplementedError(NOT_YET)

    # -- the piston ------------------------------------------------------------------------
    def start_piston(self, solver, scene: dict, u_p: float) -> None:
        """The MD backend's piston frame: the sample's mean x velocity (a thermal drift of
        order √(T/N)) removed, every atom at −u_p; the piston wall (a static ``fix
        wall/reflect``, specular) stays at rest, the far wall moves at −u_p with the
        upstream material. The upstream flow is −u_p exactly and the shocked material
        behind the front is at rest, so the particle-velocity jump is u_p exactly."""
        solver.dt = scene["shock"]["dt"]
        solver.T_bath = None
        solver.galilean_shift(-u_p - solver.mean_velocity())
        solver.set_walls(0.0, -u_p)

    def piston_frame(self, solver, scene: dict, u_p: float, info: dict) -> PistonFrame:
        sh = scene["shock"]
        return PistonFrame(
            u_behind=0.0, u_ahead=-u_p, x_origin=solver.wall_positions()[0],
            load_distance=sh["load_fraction"] * float(solver.L[0]),
            rear_margin=sh["rear_margin"], max_time=sh["max_time"],
            sample_every=sh["sample_every"],
        )  # fmt: skip

    def profile(self, solver, scene: dict, info: dict | None = None):
        """The MD backend's reader (``md.backend.MDProfile``): bins from x = 0 across
        L_y L_z, fields by ``md.profiles.fields_from_sums`` (units lj, m = 1)."""
        from ..md.backend import MDProfile

        return MDProfile(_area(solver), scene["shock"]["bin_width"])

    # -- the window: a later slice ---------------------------------------------------------
    def open_window(
        self, solver, loaded: xr.Dataset, scene: dict, u_p: float, front: float,
        D_guess: float, pole: Pole, info: dict,
    ) -> WindowStart:  # fmt: skip
        raise NotImplementedError(NOT_YET)

    def control_params(self, scene: dict, u_p: float, window) -> ControlParams:
        raise NotImplementedError(NOT_YET)

    def window_extras(
        self, window, out: Path, scene: dict, u_p: float, scheme: str, info: dict
    ) -> None:
        raise NotImplementedError(NOT_YET)

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
        """The MD backend's rule (``MDBackend.reference_pole``): the measured T0 and, for a
        fluid, the measured ρ0 (a crystal: the lattice's)."""
        from ..md.backend import MDBackend

        return MDBackend().reference_pole(scene, pole)

    def reference(self, scene: dict, pole: Pole | None = None) -> xr.Dataset:
        """The equilibrium-MD Hugoniot of the same potential (``MDBackend.reference`` on the
        scene's lj/cut model: rc from ``pair_style``, shift from ``pair_modify shift yes``,
        the skin); its ``reference_inputs`` attribute is this backend's. Other models:
        ``NotImplementedError`` (a LAMMPS reference is a later slice)."""
        from ..md.backend import MDBackend

        ds = MDBackend().reference(md_view(scene), pole)
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
        if not scene["shock"].get("snapshots", True):
            return
        from ..io.extxyz import format_frame, snapshot_paths, write_extxyz

        x, v, ids = solver.arrays()
        pe = solver.per_atom_energy_virial()[0][np.argsort(solver._ids(), kind="stable")]
        xl, xr = solver.wall_positions()
        lo = min(float(x[:, 0].min()), xl, 0.0)
        hi = max(float(x[:, 0].max()), xr, lo + 1.0)
        text = format_frame(
            x, (hi - lo, solver.L[1], solver.L[2]), velocities=v, masses=1.0,
            fields={"id": ids, "pe": pe}, species="Ar", origin=(lo, 0.0, 0.0),
            pbc=(False, True, True), time=float(solver.time), length_unit="sigma",
            time_unit="tau", units={"masses": "m", "momenta": "m*sigma/tau", "pe": "epsilon"},
            info={"scene": scene.get("name", ""), "run": "piston", "u_p": u_p,
                  "step": int(solver.steps), "solver": "lammps",
                  "pair_style": scene["model"]["pair_style"]},
        )  # fmt: skip
        write_extxyz(snapshot_paths(out)[0], text)

    # -- cost ------------------------------------------------------------------------------
    def cost(self, scene: dict, stage: str) -> Resources:
        """Memory: LAMMPS's per-atom storage plus the profile history (samples x bins x 11
        float64, held and copied once); CPU: an upper bound of atom-steps at
        ``S_PER_ATOM_STEP`` (prepare: equilibration and pole; load/piston: up to
        ``shock.max_time``; reference: as the MD backend's)."""
        s, sh = scene["sample"], scene["shock"]
        if stage == "reference":
            from ..md.backend import MDBackend

            return MDBackend().cost(md_view(scene), stage)
        n = 4 * s["cells"][0] * s["cells"][1] * s["cells"][2]
        if stage == "prepare":
            steps = (s["equilibrate_time"] + s["pole_time"]) / s["dt"]
            return Resources(int(BASE_MB + n * BYTES_PER_ATOM / 2**20), n * steps * S_PER_ATOM_STEP)
        length = s["cells"][0] * (4.0 / s["rho0"]) ** (1.0 / 3.0)
        hist = sh["max_time"] / sh["dt"] / sh["sample_every"] * (length / sh["bin_width"] + 1) * 88
        mem = int(BASE_MB + (n * BYTES_PER_ATOM + 2 * hist) / 2**20)
        return Resources(mem, n * sh["max_time"] / sh["dt"] * S_PER_ATOM_STEP)

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

    def scale(self, scene: dict) -> dict[str, float]:
        """As the MD backend's: atoms in a window of ``window.length`` (none here: NaN) at
        ρ0, its length in spacings ρ0^(-1/3)."""
        s = scene["sample"]
        L = float(scene.get("window", {}).get("length", math.nan))
        a = (4.0 / float(s["rho0"])) ** (1.0 / 3.0)
        spacing = float(s["rho0"]) ** (-1.0 / 3.0)
        across = float(s["rho0"]) * s["cells"][1] * s["cells"][2] * a * a * spacing
        return {"n_window": across * L / spacing, "window_spacings": L / spacing,
                "spacing": spacing}  # fmt: skip


BACKEND = LammpsBackend()
