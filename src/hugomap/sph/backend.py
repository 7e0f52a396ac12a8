"""The CSPH backend: contact SPH with strength behind ``hugomap.backend.Backend``.

SI units throughout (m, s, kg, Pa, J/kg; 1D per unit cross-section, 2D plane strain per metre
of depth). The sample is a line (1D), a square lattice or a porous packing (2D) at rest,
unstressed, at e = 0; the piston runs in the lab frame (the left wall moves at u_p, the far
end is free); the window is ``sph.window.SPHWindow`` (1D) or ``SPHWindow2D`` (2D, its inflow an
``InflowTile``); the reference is the material model's own Hugoniot (``analysis.porous``).

Pole: ρ0 of the sample (porous: ρ00 = ρ_solid/α measured on its porous core), P0 = 0,
E0 = 0 (exact).

Profiles: bins of ``shock.bin_width`` from the sample's left end (piston) or from the window's
outflow edge x_lo, holding Σm, ΣV, Σmv_x, Σme, ΣVσ_xx, ΣVσ_yy, ΣVP, Σmε_p
(``CSPHSimulation.profile_sums``). A slab's state: 1D ρ = Σm/ΣV and σ = ΣVσ/ΣV (the particles
fill the line); 2D the bins' geometric area A = n_bins·width·W is the volume, so that pores
count: ρ = Σm/A (the mean density of a porous slab, not the matrix's) and σ = ΣVσ/A (a pore
carries no stress: the mean stress across the section). Both: u = Σmv/Σm, E = Σme/Σm,
ε_p = Σmε_p/Σm, P = −σ_xx, P_yy = −σ_yy, P_eos = ΣVP/vol, P_zz = 3 P_eos − P_xx − P_yy, and
the slab's distention α = vol/ΣV (1 in 1D; in 2D the pores still open). Behind porous copper
(α00 = 1.35) at 100 m/s the loading stage's 100-µm bins read ρ 8216–8796 kg/m³ from 0.45 to
0.25 mm behind the front, α ≈ 1.02–1.09 against the compressed solid's ~8945 kg/m³: the
compaction is partial and uneven on the pores' scale, so a slab's V, and the energy jump
½P(V00 − V) built on it (V00 − V is 3.7e-5 m³/kg: 1 % in ρ is 3 % of it), carry that
unevenness; ``alpha`` says how far a point's slab is from full compaction (the McQueen
reference's assumption).
"""

from __future__ import annotations

import json
import logging
import os
from pathlib import Path
from typing import Any

import numpy as np
import xarray as xr

from ..analysis.linear_hugoniot import shock_velocity
from ..backend import lengthened
from ..eos import EOS
from ..failures import StageFailed
from ..io.dataset import si_units
from ..io.extxyz import VelocityFrame
from ..states import ControlParams, PistonFrame, Pole, Resources, SlabState, WindowStart
from ..strength import Strength

log = logging.getLogger("hugomap")

CSPH_EXTRA_VARS: dict[str, tuple[str, str]] = {
    "P_eos": ("Pa", "EOS (mean) pressure behind the front; P = P_eos - S_xx adds the deviator"),
    "ahead_P_eos": ("Pa", "EOS pressure just ahead of the tracked front"),
    "eps_p": ("1", "mass-mean accumulated plastic strain behind the front"),
    "ahead_eps_p": ("1", "mass-mean accumulated plastic strain just ahead of the front"),
    "alpha": (
        "1",
        "distention behind the front: slab area over its particles' volume (1: no pores)",
    ),
    "ahead_alpha": ("1", "distention just ahead of the front"),
}

# Cost model: particles x steps at a measured-rate bound.
BASE_MB = 1024  # Python + numba + xarray/netCDF
S_PER_PARTICLE_STEP = 3.0e-6  # 1D ~1e-6 s, 2D porous ~2e-6 s on one core, x1.5-3
BYTES_PER_PARTICLE = 8192  # state, pair list (~30 neighbours in 2D), profile history
STARTUP_S = 300.0  # imports, numba compile when its cache is cold, file writes


def material(scene: dict) -> tuple[EOS, Strength]:
    """The scene's EOS and strength model (``material`` block; SI)."""
    e = scene["material"]["eos"]
    eos = EOS(e["model"], np.array([e["rho0"], e["c0"], e["s"], e["gamma0"]]), e["source"])
    s = scene["material"]["strength"]
    if s["model"] == "none":
        return eos, Strength("none")
    return eos, Strength(
        "von_mises", np.array([s["shear_modulus"], s["yield_stress"]]), s["source"]
    )


def make_sample(scene: dict):
    """The scene's sample: a line (dim 1), a full-density square lattice or a porous one."""
    from .sample import lattice_1d, lattice_2d, porous_2d

    smp, rho0 = scene["sample"], scene["material"]["eos"]["rho0"]
    if scene["dim"] == 1:
        return lattice_1d(smp["length"], smp["dx"], rho0)
    por = smp.get("porous")
    if por is None:
        return lattice_2d(smp["length"], smp["width"], smp["dx"], rho0)
    return porous_2d(
        smp["length"], smp["width"], smp["dx"], rho0, pore_radius=tuple(por["pore_radius"]),
        distention=por["distention"], seed=por["seed"], tolerance=por["tolerance"],
    )  # fmt: skip


class SPHProfile:
    """Profile reader of a CSPH run (module docstring): bins of ``bin_width`` [m] from ``x0``,
    ``nbins`` of them (None: to the last particle); ``depth`` the periodic width W [m] in 2D
    (None in 1D)."""

    def __init__(self, x0: float, bin_width: float, depth: float | None,
                 nbins: int | None = None):  # fmt: skip
        self.x0, self.bin_width, self.depth, self.nbins = float(x0), float(bin_width), depth, nbins

    def sums(self, solver) -> np.ndarray:
        if hasattr(solver, "geom"):  # a window: bins from x_lo across the window
            return solver.profile_sums(self.bin_width)
        return solver.profile_sums(self.bin_width, x0=self.x0, nbins=self.nbins)

    def velocity(self, sums: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        with np.errstate(invalid="ignore", divide="ignore"):
            return sums[:, 3] / sums[:, 1], sums[:, 0]

    def state(self, summed: np.ndarray, n_bins: int) -> SlabState:
        s = summed
        m = s[1]
        vol = s[2] if self.depth is None else n_bins * self.bin_width * self.depth
        with np.errstate(invalid="ignore", divide="ignore"):
            Pxx, Peos, Pyy = -s[6] / vol, s[8] / vol, -s[7] / vol
            return SlabState(rho=m / vol, u=s[3] / m, P=Pxx, Pyy=Pyy, Pzz=3.0 * Peos - Pxx - Pyy,
                             E=s[5] / m, extra=(("P_eos", Peos), ("eps_p", s[9] / m),
                                                ("alpha", vol / s[2])))  # fmt: skip


def _depth(solver, info: dict) -> float | None:
    sim = getattr(solver, "sim", solver)
    return info["y_hi"] - info["y_lo"] if sim.state.dim == 2 else None


class CSPHBackend:
    """``Backend`` for ``solver: csph`` scenes (module docstring)."""

    name = "csph"
    units = si_units(CSPH_EXTRA_VARS)

    # -- sample and checkpoints ------------------------------------------------------------
    def prepare(self, scene: dict) -> tuple[Any, Pole, dict[str, Any]]:
        """Build the sample as a simulation at rest, piston (left wall) at its left end, free
        far end, periodic in y in 2D. Raises ``SampleError`` for a sample that cannot be
        made (a porous packing that does not reach its distention)."""
        from .simulation import CSPHSimulation
        from .state import SPHState

        sample = make_sample(scene)
        eos, strength = material(scene)
        num = scene["numerics"]
        state = SPHState(
            x=np.array(sample.x), v=np.zeros_like(sample.x), m=np.array(sample.m),
            rho=np.array(sample.rho), e=0.0, l=np.array(sample.l),
        )  # fmt: skip
        extra = {}
        if sample.dim == 2:
            extra = {"periodic": (False, True), "lo": (0.0, sample.y_lo),
                     "length": (1.0, sample.y_hi - sample.y_lo)}  # fmt: skip
        sim = CSPHSimulation(
            state, eos, strength, theta=num["theta"], cfl=num["cfl"], k_comp=num["k_comp"],
            walls=(sample.x_lo, 0.0, None, 0.0), grad_correction=num["grad_correction"],
            dev_mean=num["dev_mean"], density=num["density"], **extra,
        )  # fmt: skip
        pole = Pole(rho0=sample.rho_solid / sample.distention_core)
        log.info(
            "sample: %d particles, alpha = %.5f (core %.5f), %d pores; pole rho0 = %.6g kg/m^3",
            sample.n, sample.distention, sample.distention_core, sample.pore_radii.size,
            pole.rho0,
        )  # fmt: skip
        info = {"n_particles": sample.n, "distention": sample.distention,
                "distention_core": sample.distention_core, "n_pores": int(sample.pore_radii.size),
                "x_lo": sample.x_lo, "x_hi": sample.x_hi, "y_lo": sample.y_lo, "y_hi": sample.y_hi,
                "core_x_lo": sample.core_x_lo, "core_x_hi": sample.core_x_hi}  # fmt: skip
        return sim, pole, info

    def save(self, solver, out: str | os.PathLike, extra: xr.Dataset | None, attrs: dict) -> Path:
        if hasattr(solver, "geom"):  # a window: its own layout (the pole travels as attrs)
            if extra is not None and len(extra.data_vars):
                raise ValueError("a CSPH window checkpoint takes no extra variables")
            return solver.save(out, attrs=attrs)
        from .checkpoint import save_simulation

        return save_simulation(solver, out, extra=extra, attrs=attrs)

    def read_checkpoint(self, path: str | os.PathLike) -> xr.Dataset:
        from ..io.checkpoint import CSPH_CHECKPOINT, read_checkpoint

        return read_checkpoint(path, kind=CSPH_CHECKPOINT)

    def load(self, ds: xr.Dataset, source: str | os.PathLike | None = None):
        from .checkpoint import from_dataset

        return from_dataset(ds, source)

    def load_window(self, ds: xr.Dataset, source: str | os.PathLike | None = None):
        from .window import window_from_dataset

        return window_from_dataset(ds, source)

    # -- the piston ------------------------------------------------------------------------
    def start_piston(self, solver, scene: dict, u_p: float) -> None:
        """Lab frame: the left wall (the piston) moves at u_p from now on. The solver is
        marked ``loading`` (no trajectory: the loading stage ends in a checkpoint)."""
        solver.set_walls(u_p, 0.0)
        solver.loading = True

    def piston_frame(self, solver, scene: dict, u_p: float, info: dict) -> PistonFrame:
        """Lab frame, upstream at rest; the front's travel counts from the sample's left
        end, loading ends at ``shock.load_fraction`` of the sample, the run at
        ``shock.end_fraction`` (the free far end at the sample's right end)."""
        sh = scene["shock"]
        L = info["x_hi"] - info["x_lo"]
        return PistonFrame(
            u_behind=u_p, u_ahead=0.0, x_origin=info["x_lo"],
            load_distance=sh["load_fraction"] * L, rear_margin=(1.0 - sh["end_fraction"]) * L,
            max_time=sh["max_time"], sample_every=sh["sample_every"], far_end=info["x_hi"],
            ahead_gap=sh.get("ahead_gap"),
        )  # fmt: skip

    def profile(self, solver, scene: dict, info: dict) -> SPHProfile:
        """The profile reader; with ``shock.snapshot_every`` = N it also takes a trajectory
        frame every N samples (``io.extxyz.RecordingProfile``; not while loading, whose
        state is a checkpoint: ``start_piston`` marks it), which ``extras`` and
        ``window_extras`` write."""
        bw = scene["shock"]["bin_width"]
        if hasattr(solver, "geom"):
            prof = SPHProfile(solver.geom.x_lo, bw, getattr(solver, "depth", None))
        else:
            nb = int(np.ceil((info["x_hi"] - info["x_lo"]) / bw)) + 1
            prof = SPHProfile(info["x_lo"], bw, _depth(solver, info), nb)
        every = scene["shock"].get("snapshot_every", 0)
        if not every or getattr(solver, "loading", False):
            return prof
        from ..io.extxyz import RecordingProfile, Trajectory

        solver.trajectory = getattr(solver, "trajectory", None) or Trajectory(every)
        return RecordingProfile(prof, solver.trajectory,
                                lambda s: _frame(s, scene, info, {"run": "trajectory"}))  # fmt: skip

    # -- the window ------------------------------------------------------------------------
    def open_window(
        self, solver, loaded: xr.Dataset, scene: dict, u_p: float, front: float,
        D_guess: float, pole: Pole, info: dict,
    ) -> WindowStart:  # fmt: skip
        """Cut the window (1D: ``SPHWindow.from_piston``; 2D: ``SPHWindow2D.from_piston``
        with ``_inflow_tile``) out of the loading checkpoint in the frame of ``D_guess``,
        settle it for ``window.settle_time`` through its own steps, with the ω normalisation:
        ω from the particle count, q_up = L A ρ0/m, q_sh = L A ρ_sh/m (A = 1 m² in 1D, W in
        2D; m the inflow particle's mass), ρ_sh the slab behind the front at the end of
        loading (2D: pores counted), ρ0 the upstream density (2D: the inflow tile's mean
        density, which is also the window point's pole: it is the material the window
        feeds). Raises ``StageFailed`` (no_inflow) or ``SPHUnstable``."""
        try:
            return self._open_window(solver, scene, u_p, front, D_guess, pole, info)
        except ValueError as exc:  # SampleError too: the inflow cannot be made
            raise StageFailed("no_inflow", str(exc)) from None

    def _open_window(self, solver, scene, u_p, front, D_guess, pole, info) -> WindowStart:
        from ..analysis.shock import bin_edges, slab_state
        from ..methods.control import OmegaSignal
        from .window import SPHWindow, SPHWindow2D

        w, sh = scene["window"], scene["shock"]
        prof = self.profile(solver, scene, info)
        sums = prof.sums(solver)
        xp = float(solver.walls[0])
        shocked = slab_state(prof, sums, bin_edges(prof, sums.shape[0]),
                             max(xp + sh["gap"], front - sh["gap"] - sh["avg_length"]),
                             front - sh["gap"])  # fmt: skip
        if shocked is None:
            raise ValueError("no shocked slab behind the front")
        attrs: dict[str, Any] = {}
        if solver.state.dim == 1:
            win = SPHWindow.from_piston(
                solver, front, u_p, D_guess, w["length"], w["front_fraction"], w["cut_every"],
                w["sync_steps"], rho0=pole.rho0, e0=pole.E0,
            )  # fmt: skip
            wpole = pole
        else:
            tile, rec = _inflow_tile(scene, info)
            win = SPHWindow2D.from_piston(
                solver, front, u_p, D_guess, w["length"], w["front_fraction"], tile,
                w["cut_every"], w["sync_steps"], x_origin=info["x_lo"], e0=pole.E0,
            )  # fmt: skip
            # the window's pole: the inflow material at rest (the sample's is kept beside it)
            attrs["inflow"] = json.dumps({**rec, "sample_rho0": pole.rho0})
            wpole = pole.replace(rho0=win.rho0, rho0_err=0.0)
        if w["settle_time"] > 0:
            steps0, t_end = win.sim.steps, win.time + w["settle_time"]
            while win.time < t_end:
                win.advance(w["sync_steps"])
            log.info("settled %.3g s in %d steps", w["settle_time"], win.sim.steps - steps0)
        L = win.geom.length
        sig = OmegaSignal("N", L * win.area * win.rho0 / win.m0,
                          L * win.area * shocked["rho"] / win.m0, sh["bin_width"])  # fmt: skip
        return WindowStart(win, wpole, sig, attrs)

    def control_params(self, scene: dict, u_p: float, window) -> ControlParams:
        """Times default to the window's sound crossing: window_time = L/(c0 + s u_p),
        average_time = 2 window_time (``ControlParams.from_window`` for the rest)."""
        w, e = scene["window"], scene["material"]["eos"]
        wt = w.get("window_time") or w["length"] / shock_velocity(u_p, e["c0"], e["s"])
        avg = w.get("average_time") or 2.0 * wt
        sh = scene["shock"]
        return ControlParams.from_window(w, window.geom.length, sh["gap"], sh["avg_length"],
                                         times=(wt, avg), ahead_gap=sh.get("ahead_gap"))  # fmt: skip

    def reference_inputs(self, scene: dict) -> None:
        """None: the model's Hugoniot is computed per scene in milliseconds."""
        return None

    def reference(self, scene: dict, n_points: int = 60) -> xr.Dataset:
        """The scene model's Hugoniot (SI), dim ``point``: u_p, D, P, V, rho, E: solid —
        D = c0 + s u_p, P = ρ0 D u_p, V = V0 (1 − u_p/D), E = u_p²/2 (exact for the
        Mie–Grüneisen EOS referenced to that line); porous (α > 1) — the McQueen
        full-compaction Hugoniot of the solid's EOS (``analysis.porous``), with the snowplow
        limit (``snowplow_*``) beside it. Hydrodynamic: the strength's deviator is not in it
        (with strength P = −σ_xx lies above it by about 2Y/3 behind a plastic wave). An even
        grid to 1.25 max(u_p), and the scene's own u_p (a weak one can lie below the grid's
        first point)."""
        from ..analysis.porous import (
            MGSolid,
            porous_hugoniot_from_up,
            snowplow_hugoniot,
            solid_hugoniot_from_up,
        )

        e = scene["material"]["eos"]
        solid = MGSolid(e["rho0"], e["c0"], e["s"], e["gamma0"])
        grid = np.linspace(0.0, 1.25 * max(scene["shock"]["u_p"]), n_points + 1)[1:]
        ups = np.unique(np.concatenate([grid, np.asarray(scene["shock"]["u_p"], float)]))
        por = scene["sample"].get("porous") if scene["dim"] == 2 else None
        if por is None:
            h, model = solid_hugoniot_from_up(ups, solid), "solid D = c0 + s u_p"
            alpha, extra = 1.0, {}
        else:
            # the configured distention; the sample's measured one is within
            # sample.porous.tolerance of it (and is the pole rho0 of the point files)
            alpha = float(por["distention"])
            h = porous_hugoniot_from_up(ups, alpha, solid)
            model = f"McQueen porous, full compaction, alpha = {alpha:.5g}"
            sp = snowplow_hugoniot(ups, alpha, solid.rho0)
            extra = {
                "snowplow_P": ("point", sp.P, {"units": "Pa", "long_name": "snowplow limit P"}),
                "snowplow_D": ("point", sp.D, {"units": "m s^-1", "long_name": "snowplow limit D"}),
                "snowplow_V": ("point", sp.V, {"units": "m^3 kg^-1", "long_name": "snowplow V"}),
            }
        data = {
            "u_p": ("point", h.u_p, {"units": "m s^-1", "long_name": "particle velocity"}),
            "D": ("point", h.D, {"units": "m s^-1", "long_name": "shock velocity"}),
            "P": ("point", h.P, {"units": "Pa", "long_name": "pressure (hydrodynamic)"}),
            "V": ("point", h.V, {"units": "m^3 kg^-1", "long_name": "specific volume"}),
            "rho": ("point", h.rho, {"units": "kg m^-3", "long_name": "density"}),
            "E": ("point", h.E, {"units": "J kg^-1", "long_name": "specific internal energy jump"}),
            **extra,
        }
        ds = xr.Dataset(data)
        ds.attrs.update(
            title=f"Hugoniot of the CSPH material model ({model})", reference_model=model,
            eos_source=e["source"], alpha=alpha,
        )  # fmt: skip
        return ds

    def point_references(self, ds: xr.Dataset, scene: dict) -> xr.Dataset:
        """A porous scene's points beside the Hugoniot at each slab's own distention
        (``analysis.porous.partial_compaction_from_up``, Herrmann's P–α form on the solid's
        Mie–Grüneisen surface) at the slab's u_p (``u_p_jump``, else ``u_p_measured``) from
        the sample's measured distention ρ_solid/ρ0: ``D_compaction_ref``,
        ``P_compaction_ref`` [m s⁻¹, Pa] with standard errors from the slab's α and u_p errors
        and the deviator's range (0 to (2/3) Y/α, half of it taken as one error). Other scenes:
        ``ds`` unchanged. Points without a finite α or u_p, or too weak for the compaction
        (the matrix would stay uncompressed), get NaN."""
        por = scene["sample"].get("porous") if scene.get("dim") == 2 else None
        if por is None or "alpha" not in ds:
            return ds
        from ..analysis.porous import MGSolid, partial_compaction_from_up

        e, st = scene["material"]["eos"], scene["material"].get("strength", {})
        solid = MGSolid(e["rho0"], e["c0"], e["s"], e["gamma0"])
        Y = float(st.get("yield_stress", 0.0)) if st.get("model") == "von_mises" else 0.0
        alpha0 = e["rho0"] / float(ds["rho0"]) if "rho0" in ds else float(por["distention"])

        def col(k: str) -> np.ndarray:
            return ds[k].values.astype(float) if k in ds else np.full(ds["alpha"].shape, np.nan)

        u = np.where(np.isfinite(col("u_p_jump")), col("u_p_jump"), col("u_p_measured"))
        ue = np.where(np.isfinite(col("u_p_jump")), col("u_p_jump_err"), col("u_p_measured_err"))
        a, ae = col("alpha"), np.nan_to_num(col("alpha_err"))
        out = {k: np.full(a.shape, np.nan) for k in ("D", "D_err", "P", "P_err")}

        def state(uu: float, aa: float, tau: float) -> tuple[float, float]:
            h = partial_compaction_from_up(uu, alpha0, min(max(aa, 1.0), alpha0 - 1e-9), solid,
                                           deviator=tau)  # fmt: skip
            return float(h.D), float(h.P)

        for i in np.ndindex(a.shape):
            if not (np.isfinite(u[i]) and u[i] > 0 and np.isfinite(a[i])):
                continue
            try:
                half = 0.5 * (2.0 / 3.0) * Y / max(a[i], 1.0)
                D, P = state(u[i], a[i], half)
                dev = [state(u[i], a[i], t) for t in (0.0, 2.0 * half)]
                da = [state(u[i], a[i] + s * ae[i], half) for s in (-1.0, 1.0)]
                du = (
                    [state(u[i] + s * ue[i], a[i], half) for s in (-1.0, 1.0)]
                    if np.isfinite(ue[i]) and ue[i] > 0
                    else [(D, P), (D, P)]
                )
            except ValueError:
                continue
            for j, k in enumerate(("D", "P")):
                parts = [0.5 * abs(x[1][j] - x[0][j]) for x in (dev, da, du)]
                out[k][i], out[k + "_err"][i] = (D, P)[j], float(np.sqrt(np.sum(np.square(parts))))
        what = ("at the slab's own distention alpha (Herrmann P-alpha on the solid's "
                f"Mie-Grueneisen EOS, initial distention {alpha0:.5g})")  # fmt: skip
        attrs = {"D": ("m s-1", "shock velocity of the porous Hugoniot " + what),
                 "P": ("Pa", "P_xx of the porous Hugoniot " + what)}  # fmt: skip
        ds = ds.copy()
        for k, (unit, name) in attrs.items():
            ds[f"{k}_compaction_ref"] = (ds["alpha"].dims, out[k],
                                         {"units": unit, "long_name": name})  # fmt: skip
            ds[f"{k}_compaction_ref_err"] = (ds["alpha"].dims, out[k + "_err"],
                                             {"units": unit, "long_name": "standard error of "
                                              f"{k}_compaction_ref"})  # fmt: skip
        return ds

    def extras(self, solver, out: Path, scene: dict, u_p: float, info: dict) -> None:
        """A piston run's snapshots beside its point file: ``<stem>_snapshot.extxyz`` (the
        last state; ``sph.snapshot.sph_frame``) and, in 2D, ``<stem>_snapshot.png``
        (plastically deformed particles green) when ``shock.snapshots`` is set; the
        trajectory ``<stem>_trajectory.extxyz`` when ``shock.snapshot_every`` is set."""
        self._snapshots(solver, out, scene, info, {"run": "piston", "u_p": u_p}, png=True)

    def window_extras(
        self, window, out: Path, scene: dict, u_p: float, scheme: str, info: dict
    ) -> None:
        """A window run's snapshot (and trajectory) beside its point file, as ``extras``
        (no PNG)."""
        self._snapshots(window, out, scene, info, {"run": scheme, "u_p": u_p}, png=False)

    def _snapshots(self, solver, out: Path, scene: dict, info: dict, tags: dict,
                   png: bool) -> None:  # fmt: skip
        from ..io.extxyz import snapshot_paths, write_extxyz

        snap, traj = snapshot_paths(out)
        recorder = getattr(solver, "trajectory", None)
        if recorder is not None:
            recorder.save(traj)
        if not scene["shock"]["snapshots"]:
            return
        write_extxyz(snap, _frame(solver, scene, info, tags))
        sim = getattr(solver, "sim", solver)
        st = sim.state
        if png and st.dim == 2:
            from .snapshot import PLASTIC_THRESHOLD, write_png

            write_png(
                snap.with_suffix(".png"), st.x, st.eps_p, PLASTIC_THRESHOLD, -sim.stress_xx(),
                field_label="P_xx", box=_box(sim, info),
                title=f"{scene.get('name', '')}: u_p = {tags['u_p']:g} m/s, "
                f"t = {st.time * 1e6:.3f} µs",
            )  # fmt: skip

    # -- cost ------------------------------------------------------------------------------
    def _particles(self, scene: dict) -> float:
        s = scene["sample"]
        n = s["length"] / s["dx"]
        return n * (s["width"] / s["dx"] if scene["dim"] == 2 else 1.0)

    def _steps(self, scene: dict) -> float:
        """Upper bound of the steps of a piston stage: the front crosses the sample at its
        slowest speed (porous: the snowplow D = u_p alpha/(alpha - 1)) while dt is cfl dx
        over the fastest signal (c0 + s u_p)."""
        s, e, sh = scene["sample"], scene["material"]["eos"], scene["shock"]
        u_lo, u_hi = min(sh["u_p"]), max(sh["u_p"])
        d_min = shock_velocity(u_lo, e["c0"], e["s"])
        if "porous" in s:
            a = s["porous"]["distention"]
            d_min = min(d_min, u_lo * a / max(a - 1.0, 1e-9))
        dt = scene["numerics"]["cfl"] * s["dx"] / shock_velocity(u_hi, e["c0"], e["s"])
        return s["length"] / d_min / dt

    def longer_sample(self, scene: dict, factor: float) -> dict | None:
        """A longer ``sample.length`` (``backend.lengthened``); a porous sample draws its
        pores anew over the whole length."""
        return lengthened(scene, ("sample", "length"), factor)

    def cost(self, scene: dict, stage: str) -> Resources:
        n = self._particles(scene)
        mem = int(BASE_MB + n * BYTES_PER_PARTICLE / 2**20)
        steps = 0.0 if stage in ("prepare", "reference") else self._steps(scene)
        return Resources(mem, steps * n * S_PER_PARTICLE_STEP)

    # -- presentation ----------------------------------------------------------------------
    def figure_labels(self, scene: dict) -> dict:
        """SI, drawn as V [cm³/g] (×1e3 of m³/kg), P [GPa] (×1e-9 of Pa), velocities [m/s]."""
        axes = {"V": ("specific volume V [cm³/g]", 1e3),
                "P": ("longitudinal stress P = −σ_xx [GPa]", 1e-9),
                "u_p_measured": ("particle velocity u_p [m/s]", 1.0),
                "D": ("shock velocity D [m/s]", 1.0)}  # fmt: skip
        return {"axes": axes, "tag": "CSPH", "reference": "model Hugoniot", "title": "CSPH"}

    def sound_speed(self, scene: dict) -> float:
        """The EOS's c0 (the solid's, also for a porous sample) [m/s]."""
        return float(scene["material"]["eos"]["c0"])

    def scale(self, scene: dict) -> dict[str, float]:
        """Particles in the window (L/dx in 1D, L W/dx² in 2D), its length in dx."""
        s, w = scene["sample"], scene.get("window", {})
        spacing = float(s["dx"])
        across = float(s["width"]) / spacing if scene.get("dim") == 2 else 1.0
        L = float(w.get("length", np.nan))
        return {"n_window": across * L / spacing, "window_spacings": L / spacing,
                "spacing": spacing}  # fmt: skip


def _box(sim, info: dict) -> tuple[float, ...]:
    """The snapshot's box [m]: x over the particles and the sample's ends in ``info`` (a
    window's particles lie beyond its edges), y the periodic width in 2D."""
    x = np.concatenate([sim.state.x[:, 0], [info[k] for k in ("x_lo", "x_hi") if k in info]])
    lo, hi = (float(x.min()), float(x.max())) if x.size else (0.0, 0.0)
    if not hi > lo:
        hi = lo + float(sim.state.l.max(initial=1e-6))
    if sim.state.dim == 1:
        return (lo, hi)
    return (lo, hi, float(sim.lo[1]), float(sim.lo[1] + sim.length[1]))


def velocity_frame(solver) -> VelocityFrame:
    """The frame of a CSPH run's velocities (``io.extxyz.VelocityFrame``, SI): a piston run's
    is the lab frame, the upstream material at rest (``lab``, frame velocity 0); a window's
    (it has a ``geom``, as ``profile`` tells them apart) moves with the window, the upstream
    flowing in at u_in (``window``, frame velocity −u_in [m/s], edges x_lo, x_hi [m])."""
    if hasattr(solver, "geom"):
        g = solver.geom
        return VelocityFrame("window", -float(solver.u_in), float(g.x_lo), float(g.x_hi))
    return VelocityFrame("lab", 0.0)


def _frame(solver, scene: dict, info: dict, tags: dict) -> str:
    """An extended-XYZ frame of a CSPH run (``sph.snapshot.sph_frame``: Å, Å/fs, fs): velo,
    ρ [kg/m³], e [J/kg], P_xx = −σ_xx [Pa], eps_p [-], ``plastic`` (eps_p >
    ``PLASTIC_THRESHOLD``), ``frozen`` (boundary particles of a window), radius l/2; the
    velocities' frame (``velocity_frame``)."""
    from .snapshot import PLASTIC_THRESHOLD, sph_frame

    sim = getattr(solver, "sim", solver)
    st = sim.state
    frozen = getattr(sim, "frozen", None)
    frozen = np.zeros(st.n, dtype=bool) if frozen is None else np.asarray(frozen, dtype=bool)
    fields = {"rho": st.rho, "e": st.e, "P_xx": -sim.stress_xx(), "eps_p": st.eps_p,
              "plastic": st.eps_p > PLASTIC_THRESHOLD, "frozen": frozen}  # fmt: skip
    return sph_frame(
        st.x, st.v, fields, _box(sim, info), masses=st.m,
        mass_unit="kg/m" if st.dim == 2 else "kg/m^2", time=st.time,
        units={"rho": "kg/m^3", "e": "J/kg", "P_xx": "Pa", "eps_p": "1"},
        periodic=(False, bool(sim.periodic[1]), False), radius=0.5 * st.l,
        info={"scene": scene.get("name", ""), **tags, "step": int(solver.steps)},
        frame=velocity_frame(solver),
    )  # fmt: skip


def _inflow_tile(scene: dict, info: dict):
    """The 2D window's inflow tile: ``window.tile_length`` (default (1 − front_fraction) L,
    the part of the window ahead of the front, so that the particle count of the upstream
    part changes little as the tile slides through) by the sample's periodic width, same dx.
    Porous scenes: ``sph.sample.porous_tile_2d`` (pores wrapping round x and y), seed
    ``sample.porous.seed + 1``, distention = the sample's measured one over its porous core
    within ``sample.porous.tolerance``; full-density scenes: the square lattice. Returns the
    tile and what to record of it."""
    from .sample import SampleError, lattice_2d, porous_tile_2d
    from .window import InflowTile

    smp, w = scene["sample"], scene["window"]
    dx, rho_s = smp["dx"], scene["material"]["eos"]["rho0"]
    lt = w.get("tile_length") or (1.0 - w["front_fraction"]) * w["length"]
    width = info["y_hi"] - info["y_lo"]
    por = smp.get("porous")
    if por is None:
        tile = lattice_2d(lt, width, dx, rho_s)
    else:
        tile = porous_tile_2d(
            lt, width, dx, rho_s, pore_radius=tuple(por["pore_radius"]),
            distention=info["distention_core"], seed=por["seed"] + 1, tolerance=por["tolerance"],
        )  # fmt: skip
    if abs(tile.y_hi - tile.y_lo - width) > 1e-9 * width:
        raise SampleError(f"the inflow tile's width {tile.y_hi - tile.y_lo:.6g} m differs from "
                          f"the sample's {width:.6g} m")  # fmt: skip
    rec = {"tile_length": tile.x_hi - tile.x_lo, "tile_distention": tile.distention,
           "tile_n_pores": int(tile.pore_radii.size), "tile_n_particles": tile.n,
           "sample_distention_core": info.get("distention_core", 1.0)}  # fmt: skip
    log.info("inflow tile: %.4g x %.4g m, %d particles, %d pores, alpha %.5f (sample core %.5f)",
             rec["tile_length"], width, tile.n, rec["tile_n_pores"], tile.distention,
             rec["sample_distention_core"])  # fmt: skip
    return InflowTile.from_sample(tile), rec


BACKEND = CSPHBackend()
