"""Workflow stages of CSPH scenes (``solver: csph``): file in, file out, SI units throughout
(m, s, kg, Pa, J/kg; 1D per unit cross-section, 2D plane strain per metre of depth).

prepare_sample → load_to_target_stage (checkpoint) → piston_point, and
window_start → control_point (AMW and MW: ``window.methods.amw``/``mw`` unchanged, on
``SPHWindow`` in 1D, ``SPHWindow2D`` in 2D) and window_start → dichotomy_state ⇄ dichotomy_trial → dichotomy_point (the loop
of ``window.dichotomy``, trials by ``window.methods.fixed_run``); reference_stage gives the
model's own Hugoniot. ``pipeline`` and ``pipeline_window`` dispatch here on the scene's
``solver``. Point files have the MD layout (``io.dataset.point_dataset``) with SI units.

Piston (lab frame): the sample at rest, the left wall (the piston) moves at u_p from t = 0, the
far end is free. Every ``shock.sample_every`` steps the profile along x (bins of
``shock.bin_width`` from the sample's left end: Σm, ΣV, Σmv_x, Σme, ΣVσ_xx, ΣVσ_yy, ΣVP ...,
``CSPHSimulation.profile_sums``) is recorded and the front located where the bin velocity
falls through u_p/2 (the last bin from the piston side above it; linear interpolation to the
next). Loading ends when the front has crossed ``shock.load_fraction`` of the sample, the
point run when it has crossed ``shock.end_fraction``.

The point: D = slope of the front position against time over the point run (lab frame, the
upstream at rest: the shock speed relative to the pole material; error from
``stats.CorrelatedSlope``); the shocked state is the slab [x_f − gap − avg_length, x_f − gap]
(kept ``gap`` clear of the piston), the state ahead the slab [x_f + gap, x_f + gap +
avg_length], each per sample as volume averages of stress (ρ = Σm/ΣV, σ = ΣVσ/ΣV) and mass
averages of u and e, then block-averaged over the samples (``stats.block_average``). Reported:
P = −σ_xx (the longitudinal stress, EOS pressure plus the deviator: P = P_eos − S_xx) and
P_eos separately, ρ, V = 1/ρ, E = e, E − E0, u_p_measured = u − u_ahead. Jump residuals
from state 1 (the pole, or the state ahead when an elastic precursor runs, ``two_wave``):

    mass      ρ (D − u) / (ρ1 (D − u1)) − 1,
    momentum  (P − P1) / (ρ1 (D − u1)(u − u1)) − 1,
    energy    (E − E1) / (½ (P + P1)(1/ρ1 − 1/ρ)) − 1,

with errors propagated to first order from the errors of D, ρ, u, P, E (independent).
Pole: ρ0 of the sample (for a porous one ρ00 = ρ_solid/α measured on its porous core),
P0 = 0, E0 = 0 (the sample is made at rest, unstressed, at e = 0).
"""

from __future__ import annotations

import json
import logging
import os
import time
from pathlib import Path

import numpy as np
import xarray as xr

from .analysis.stats import CorrelatedSlope, block_average, line_fit
from .config import fill_csph_defaults
from .eos import EOS
from .failures import SlabError, SPHUnstable
from .io.atomic import write_json, write_netcdf
from .io.dataset import control_vars, point_dataset, scalar_vars, solver_tables
from .sph import checkpoint as ckpt
from .sph.sample import Sample, SampleError, lattice_1d, lattice_2d, porous_2d, porous_tile_2d
from .sph.simulation import CSPHSimulation, profile_fields
from .sph.state import SPHState
from .sph.window import InflowTile, SPHWindow, SPHWindow2D, window_from_dataset
from .strength import Strength
from .window import dichotomy as dich
from .window.methods import OmegaSignal, amw, fixed_run, mw

log = logging.getLogger("hugomap")
TWO_WAVE_FRACTION = 0.05  # the state ahead carries > 5 % of P (and u): an elastic precursor
POLE_NAMES = ("rho0", "P0", "E0", "T0", "Pyy0")


def _cpu() -> float:
    import resource

    r = resource.getrusage(resource.RUSAGE_SELF)
    return r.ru_utime + r.ru_stime


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


def make_sample(scene: dict) -> Sample:
    """The scene's sample: a line (dim 1), a full-density square lattice or a porous one."""
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


def _failure(out, status: str, diagnostic: str, attrs: dict) -> Path:
    log.error("%s: %s", status, diagnostic)
    return write_netcdf(
        xr.Dataset(attrs={**attrs, "status": status, "diagnostic": diagnostic}), out
    )


def _pole_vars(pole: dict) -> xr.Dataset:
    return xr.Dataset(scalar_vars(pole, solver_tables("csph")[1]))


def _pole_from(ds: xr.Dataset) -> dict[str, float]:
    names = [*POLE_NAMES, *(k + "_err" for k in POLE_NAMES)]
    return {k: float(ds[k]) for k in names if k in ds}


def prepare_sample(scene: dict, out: str | os.PathLike) -> Path:
    """Build the sample and save it as a checkpoint of a simulation at rest, piston (left wall)
    at the sample's left end, free far end, periodic in y in 2D. Pole: ρ0 = the measured mean
    density (porous: ρ00 = ρ_solid/α_core over the porous core), P0 = 0, E0 = 0 (exact)."""
    fill_csph_defaults(scene)
    attrs = {"stage": "sample", "scene_config": json.dumps(scene)}
    try:
        sample = make_sample(scene)
    except SampleError as exc:
        return _failure(out, "bad_config", str(exc), attrs)
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
        dev_mean=num["dev_mean"], **extra,
    )  # fmt: skip
    rho_pole = sample.rho_solid / sample.distention_core
    pole = {"rho0": rho_pole, "rho0_err": 0.0, "P0": 0.0, "P0_err": 0.0, "E0": 0.0,
            "E0_err": 0.0}  # fmt: skip
    log.info(
        "sample: %d particles, alpha = %.5f (core %.5f), %d pores; pole rho0 = %.6g kg/m^3",
        sample.n, sample.distention, sample.distention_core, sample.pore_radii.size, rho_pole,
    )  # fmt: skip
    info = {"n_particles": sample.n, "distention": sample.distention,
            "distention_core": sample.distention_core, "n_pores": int(sample.pore_radii.size),
            "x_lo": sample.x_lo, "x_hi": sample.x_hi, "y_lo": sample.y_lo, "y_hi": sample.y_hi,
            "core_x_lo": sample.core_x_lo, "core_x_hi": sample.core_x_hi}  # fmt: skip
    return ckpt.save_simulation(
        sim, out, extra=_pole_vars(pole),
        attrs={**attrs, "status": "ok", "sample": json.dumps(info)},
    )  # fmt: skip


# -- front tracking and slab states ---------------------------------------------------------


def front_position(fields: dict, x0: float, width: float, u_hi: float, u_lo: float) -> float:
    """Where the bin velocity falls through (u_hi + u_lo)/2 going away from the piston: the
    last bin above it, linearly interpolated to the next bin [m]; NaN if none."""
    u = fields["u"]
    mid = 0.5 * (u_hi + u_lo)
    sign = 1.0 if u_hi > u_lo else -1.0
    above = np.nonzero(np.isfinite(u) & (sign * (u - mid) > 0))[0]
    if above.size == 0:
        return float("nan")
    k = int(above.max())
    xk = x0 + (k + 0.5) * width
    if k + 1 >= u.size or not np.isfinite(u[k + 1]) or u[k + 1] == u[k]:
        return xk
    return xk + (mid - u[k]) / (u[k + 1] - u[k]) * width


def slab_state(
    sums: np.ndarray, x0: float, width: float, a: float, b: float, depth: float | None = None
) -> dict | None:
    """State of the bins whose centres lie in [a, b] [m]; None if no bin or no mass.

    1D (``depth`` None): ρ = Σm/ΣV, σ_xx, σ_yy, P_eos = ΣVσ/ΣV (the particles fill the line).
    2D (``depth`` = the periodic width W [m]): the bins' geometric area A = n_bins·width·W is
    the volume, so that pores count: ρ = Σm/A (the mean density of a porous slab, not the
    matrix's), σ = ΣVσ/A (a pore carries no stress: the mean stress across the section).
    Both: u = Σmv/Σm, e = Σme/Σm, eps_p = Σmε_p/Σm; P_zz = 3 P_eos − P_xx − P_yy (trace)."""
    centres = x0 + (np.arange(sums.shape[0]) + 0.5) * width
    sel = (centres >= a) & (centres <= b)
    if not sel.any():
        return None
    s = sums[sel].sum(axis=0)
    m = s[1]
    vol = s[2] if depth is None else np.count_nonzero(sel) * width * depth
    if not (m > 0 and vol > 0):
        return None
    Pxx, Peos, Pyy = -s[6] / vol, s[8] / vol, -s[7] / vol
    return {"rho": m / vol, "u": s[3] / m, "e": s[5] / m, "P": Pxx, "P_eos": Peos, "Pyy": Pyy,
            "Pzz": 3.0 * Peos - Pxx - Pyy, "eps_p": s[9] / m}  # fmt: skip


def jump(D: float, one: dict, two: dict) -> dict[str, float]:
    """Relative jump-condition residuals from state ``one`` to ``two`` (module docstring)."""
    r1, u1, P1, E1 = one["rho"], one["u"], one["P"], one["E"]
    r2, u2, P2, E2 = two["rho"], two["u"], two["P"], two["E"]
    j = r1 * (D - u1)
    with np.errstate(divide="ignore", invalid="ignore"):
        return {
            "mass": r2 * (D - u2) / j - 1.0,
            "momentum": (P2 - P1) / (j * (u2 - u1)) - 1.0,
            "energy": (E2 - E1) / (0.5 * (P2 + P1) * (1.0 / r1 - 1.0 / r2)) - 1.0,
        }


def jump_with_errors(D, D_err, one, one_err, two, two_err) -> dict[str, float]:
    """``jump`` with first-order propagated standard errors (inputs independent)."""
    base = jump(D, one, two)
    var = dict.fromkeys(base, 0.0)

    def add(d: dict) -> None:
        for k in var:
            if np.isfinite(d[k]):
                var[k] += (d[k] - base[k]) ** 2

    if D_err and np.isfinite(D_err):
        add(jump(D + D_err, one, two))
    for st, err, first in ((one, one_err, True), (two, two_err, False)):
        for k, e in err.items():
            if e and np.isfinite(e):
                moved = dict(st, **{k: st[k] + e})
                add(jump(D, moved, two) if first else jump(D, one, moved))
    out = {}
    for k, v in base.items():
        out["residual_" + k] = float(v)
        out["residual_" + k + "_err"] = float(np.sqrt(var[k]))
    return out


class _Recorder:
    """Front history and profiles of a piston run (lab frame)."""

    def __init__(self, x0: float, width: float, u_p: float):
        self.x0, self.width, self.u_p = float(x0), float(width), float(u_p)
        self.t: list[float] = []
        self.front: list[float] = []
        self.piston: list[float] = []
        self.stage: list[int] = []
        self.sums: list[np.ndarray] = []

    def sample(self, sim: CSPHSimulation, stage: int, keep_sums: bool) -> float:
        sums = sim.profile_sums(self.width, x0=self.x0)
        f = profile_fields(sums)
        xf = front_position(f, self.x0, self.width, self.u_p, 0.0)
        self.t.append(sim.time)
        self.front.append(xf)
        self.piston.append(float(sim.walls[0]))
        self.stage.append(stage)
        if keep_sums:
            self.sums.append(sums)
        return xf

    def history(self) -> dict[str, np.ndarray]:
        return {"t": np.asarray(self.t), "front": np.asarray(self.front),
                "stage": np.asarray(self.stage, dtype=np.int8)}  # fmt: skip


def _run_front(sim, rec: _Recorder, scene: dict, target: float, stage: int, keep: bool) -> None:
    """Advance in blocks of ``shock.sample_every`` steps until the front passes ``target``
    [m]; raise SPHUnstable (status max_time) past ``shock.max_time``."""
    sh = scene["shock"]
    while True:
        sim.advance(sh["sample_every"])
        xf = rec.sample(sim, stage, keep)
        if np.isfinite(xf) and xf >= target:
            return
        if sim.time > sh["max_time"]:
            raise SPHUnstable(
                "max_time", f"the front ({xf:.4g} m) did not reach {target:.4g} m within "
                f"shock.max_time = {sh['max_time']:.3g} s",
            )  # fmt: skip


def _sample_info(ds: xr.Dataset) -> dict:
    return json.loads(ds.attrs["sample"])


def load_to_target_stage(
    sample: str | os.PathLike, scene: dict, u_p: float, out: str | os.PathLike
) -> Path:
    """Drive the piston at u_p [m/s] until the front has crossed ``shock.load_fraction`` of
    the sample; save the simulation and the front history (the branching checkpoint)."""
    fill_csph_defaults(scene)
    t0, c0 = time.perf_counter(), _cpu()
    attrs = {"stage": "loaded", "u_p": u_p, "scene_config": json.dumps(scene)}
    with xr.open_dataset(sample, engine="netcdf4") as ds:
        ds.load()
    if ds.attrs.get("status", "ok") != "ok":
        return _failure(out, ds.attrs["status"], ds.attrs.get("diagnostic", ""), attrs)
    sim = ckpt.from_dataset(ds, sample)
    info = _sample_info(ds)
    sh = scene["shock"]
    sim.set_walls(u_p, 0.0)
    rec = _Recorder(info["x_lo"], sh["bin_width"], u_p)
    L = info["x_hi"] - info["x_lo"]
    try:
        _run_front(sim, rec, scene, info["x_lo"] + sh["load_fraction"] * L, 0, False)
    except SPHUnstable as exc:
        return _failure(out, exc.status, exc.diagnostic, attrs)
    cost = {"wall_s": time.perf_counter() - t0, "cpu_s": _cpu() - c0,
            "atom_steps": float(sim.state.n * sim.steps)}  # fmt: skip
    h = rec.history()
    extra = xr.merge([
        _pole_vars(_pole_from(ds)),
        xr.Dataset({"hist_t": ("sample", h["t"]), "hist_front": ("sample", h["front"]),
                    "hist_piston": ("sample", np.asarray(rec.piston))}),
    ])  # fmt: skip
    log.info("loaded: t = %.4g s, %d steps, front %.4g m", sim.time, sim.steps, h["front"][-1])
    return ckpt.save_simulation(
        sim, out, extra=extra,
        attrs={**attrs, "status": "ok", "cost": json.dumps(cost), "sample": ds.attrs["sample"]},
    )  # fmt: skip


def _average(states: list[dict], keys: tuple) -> tuple[dict, dict]:
    mean, err = {}, {}
    for k in keys:
        mean[k], err[k] = block_average(np.array([s[k] for s in states], dtype=float))
    return mean, err


def analyse(
    t: np.ndarray, front: np.ndarray, slabs: list[tuple[dict, dict]], pole: dict,
    u_up: float, D_override: tuple[float, float] | None, residual_tol: float,
) -> dict:  # fmt: skip
    """The point from front history and per-sample (behind, ahead) slab states (lab frame
    velocities, upstream at ``u_up``): D, the shocked state, residuals, status."""
    if D_override is None:
        a, se, _ = CorrelatedSlope().fit(t, front)
        D, D_err = float(a - u_up), float(se)
    else:
        D, D_err = D_override
    keys = ("rho", "u", "e", "P", "P_eos", "Pyy", "Pzz", "eps_p")
    beh, beh_err = _average([s[0] for s in slabs], keys)
    aheads = [s[1] for s in slabs if s[1] is not None]
    ahd, ahd_err = _average(aheads, keys) if len(aheads) >= 2 else (None, None)
    rho0, P0, E0 = pole["rho0"], pole.get("P0", 0.0), pole.get("E0", 0.0)
    u = beh["u"] - u_up
    v = {
        "D": D, "D_err": D_err, "u_p_measured": u, "u_p_measured_err": beh_err["u"],
        "rho": beh["rho"], "rho_err": beh_err["rho"],
        "V": 1.0 / beh["rho"], "V_err": beh_err["rho"] / beh["rho"] ** 2,
        "P": beh["P"], "P_err": beh_err["P"], "P_eos": beh["P_eos"], "P_eos_err": beh_err["P_eos"],
        "Pyy": beh["Pyy"], "Pyy_err": beh_err["Pyy"], "Pzz": beh["Pzz"], "Pzz_err": beh_err["Pzz"],
        "E": beh["e"], "E_err": beh_err["e"], "E_minus_E0": beh["e"] - E0,
        "E_minus_E0_err": beh_err["e"], "eps_p": beh["eps_p"],
        "shear_stress": 0.5 * (beh["P"] - 0.5 * (beh["Pyy"] + beh["Pzz"])),
        "P_rh": P0 + rho0 * D * u, "n_samples": len(slabs),
    }  # fmt: skip
    one = {"rho": rho0, "u": 0.0, "P": P0, "E": E0}
    one_err = {}
    two_wave = False
    if ahd is not None:
        ua = ahd["u"] - u_up
        v.update(ahead_rho=ahd["rho"], ahead_P=ahd["P"], ahead_E=ahd["e"], ahead_u=ua,
                 ahead_P_eos=ahd["P_eos"], ahead_eps_p=ahd["eps_p"])  # fmt: skip
        two_wave = bool(ahd["P"] > TWO_WAVE_FRACTION * beh["P"] and ua > TWO_WAVE_FRACTION * u)
        if two_wave:
            one = {"rho": ahd["rho"], "u": ua, "P": ahd["P"], "E": ahd["e"]}
            one_err = {"rho": ahd_err["rho"], "u": ahd_err["u"], "P": ahd_err["P"],
                       "E": ahd_err["e"]}  # fmt: skip
    v["two_wave"] = float(two_wave)
    two = {"rho": beh["rho"], "u": u, "P": beh["P"], "E": beh["e"]}
    two_err = {"rho": beh_err["rho"], "u": beh_err["u"], "P": beh_err["P"], "E": beh_err["e"]}
    v.update(jump_with_errors(D, D_err, one, one_err, two, two_err))
    res = [v[f"residual_{k}"] for k in ("mass", "momentum", "energy")]
    v["converged"] = bool(all(np.isfinite(r) and abs(r) < residual_tol for r in res))
    v["status"] = "ok" if v["converged"] else "not_converged"
    return v


def _residual_text(v: dict) -> str:
    return "jump residuals: " + ", ".join(
        f"{k} {v['residual_' + k]:+.3%}" for k in ("mass", "momentum", "energy")
    )


def _snapshots(sim: CSPHSimulation, out: Path, scene: dict, info: dict, u_p: float) -> None:
    """Extended XYZ (OVITO/ASE) and, in 2D, a PNG with plastically deformed particles green."""
    from .sph.snapshot import write_extxyz, write_png

    st = sim.state
    pressure = -sim.stress_xx()
    box = (info["x_lo"], float(max(st.x[:, 0].max(), info["x_hi"])))
    if st.dim == 2:
        box = (*box, info["y_lo"], info["y_hi"])
    stem = out.parent / "piston_snapshot"
    write_extxyz(
        stem.with_suffix(".extxyz"), st.x,
        {"vel": st.v, "rho": st.rho, "e": st.e, "P_xx": pressure, "eps_p": st.eps_p},
        box, {"scene": scene.get("name", ""), "u_p": u_p},
        time=st.time, units={"vel": "m/s", "rho": "kg/m^3", "e": "J/kg", "P_xx": "Pa",
                             "eps_p": "1"},
        periodic=(False, st.dim == 2, False), radius=0.5 * st.l,
    )  # fmt: skip
    if st.dim == 2:
        write_png(
            stem.with_suffix(".png"), st.x, st.eps_p, 1e-4, pressure, field_label="P_xx",
            box=box,
            title=f"{scene.get('name', '')}: u_p = {u_p:g} m/s, t = {st.time * 1e6:.3f} µs",
        )  # fmt: skip


def piston_point(
    loaded: str | os.PathLike, scene: dict, u_p: float, out: str | os.PathLike,
    scheme: str = "piston",
) -> Path:  # fmt: skip
    """Continue the piston from the loading checkpoint until the front has crossed
    ``shock.end_fraction`` of the sample, then measure the point (module docstring)."""
    fill_csph_defaults(scene)
    t0, c0 = time.perf_counter(), _cpu()
    sh, name = scene["shock"], scene.get("name", "")
    with xr.open_dataset(loaded, engine="netcdf4") as ds:
        ds.load()
    base = {"piston_velocity": u_p}
    if ds.attrs.get("status", "ok") != "ok":
        return write_netcdf(point_dataset(base, {}, None, scheme, name, ds.attrs["status"],
                                          ds.attrs.get("diagnostic", ""), scene), out)  # fmt: skip
    sim = ckpt.from_dataset(ds, loaded)
    info, pole = _sample_info(ds), _pole_from(ds)
    cost = json.loads(ds.attrs.get("cost", "{}"))
    steps0 = sim.steps
    rec = _Recorder(info["x_lo"], sh["bin_width"], u_p)
    L = info["x_hi"] - info["x_lo"]
    status, diagnostic = "ok", ""
    try:
        _run_front(sim, rec, scene, info["x_lo"] + sh["end_fraction"] * L, 1, True)
    except SPHUnstable as exc:
        status, diagnostic = exc.status, exc.diagnostic
        log.error("%s: %s", status, diagnostic)
    values = dict(base)
    values["wall_s"] = cost.get("wall_s", 0.0) + time.perf_counter() - t0
    values["cpu_s"] = cost.get("cpu_s", 0.0) + _cpu() - c0
    values["atom_steps"] = cost.get("atom_steps", 0.0) + sim.state.n * (sim.steps - steps0)
    h = {"t": np.concatenate([ds["hist_t"].values, rec.t]),
         "front": np.concatenate([ds["hist_front"].values, rec.front]),
         "stage": np.concatenate([np.zeros(ds["hist_t"].size, np.int8),
                                  np.ones(len(rec.t), np.int8)])}  # fmt: skip
    if status == "ok":
        slabs = []
        gap, avg, w = sh["gap"], sh["avg_length"], sh["bin_width"]
        depth = info["y_hi"] - info["y_lo"] if sim.state.dim == 2 else None
        for xf, xp, sums in zip(rec.front, rec.piston, rec.sums, strict=True):
            a, b = max(xp + gap, xf - gap - avg), xf - gap
            if b - a < 0.5 * avg:
                continue
            beh = slab_state(sums, rec.x0, w, a, b, depth)
            ahd = slab_state(sums, rec.x0, w, xf + gap, min(xf + gap + avg, info["x_hi"]), depth)
            if beh is not None:
                slabs.append((beh, ahd))
        t, xf = np.asarray(rec.t), np.asarray(rec.front)
        if len(slabs) < 16 or np.count_nonzero(np.isfinite(xf)) < 8:
            status = "too_few_samples"
            diagnostic = f"{len(slabs)} profile samples with a full slab behind the front"
        else:
            v = analyse(t, xf, slabs, pole, 0.0, None, sh["residual_tol"])
            values.update(v)
            status = v["status"]
            if status != "ok":
                diagnostic = _residual_text(v)
            log.info(
                "point: D = %.2f +- %.2f m/s, u = %.2f m/s, P = %.5g Pa, P_eos = %.5g Pa, "
                "rho = %.2f kg/m^3, %s", v["D"], v["D_err"], v["u_p_measured"], v["P"],
                v["P_eos"], v["rho"], _residual_text(v),
            )  # fmt: skip
    if sh["snapshots"]:
        try:
            _snapshots(sim, Path(out), scene, info, u_p)
        except (ValueError, OSError) as exc:  # a snapshot is an extra: keep the point
            log.warning("snapshot not written: %s", exc)
    ds_out = point_dataset(values, pole, h, scheme, name, status, diagnostic, scene)
    return write_netcdf(ds_out, out)


# -- the 1D moving window -------------------------------------------------------------------


def _window_times(scene: dict, u_p: float) -> tuple[float, float]:
    """(window_time, average_time) [s]: configured, or L/(c0 + s u_p) and twice that."""
    w, e = scene["window"], scene["material"]["eos"]
    wt = w.get("window_time") or w["length"] / (e["c0"] + e["s"] * u_p)
    return wt, w.get("average_time") or 2.0 * wt


def window_start(
    loaded: str | os.PathLike, scene: dict, u_p: float, out: str | os.PathLike
) -> Path:
    """Cut the window (1D: ``SPHWindow.from_piston``; 2D: ``SPHWindow2D.from_piston``, see
    ``_inflow_tile``) out of the loading checkpoint in the frame of the loading stage's front
    speed (line fit over its second half), settle it for ``window.settle_time`` and save it
    with the ω normalisation: ω from the particle count, q_up = L A ρ0/m, q_sh = L A ρ_sh/m
    (A = 1 m² in 1D, the periodic width W in 2D; m the inflow particle's mass) with ρ_sh the
    slab behind the front at the end of loading (2D: mean density over the width, pores
    counted) and ρ0 the upstream density (2D: the inflow tile's mean density, which is also
    the window point's pole: it is the material the window feeds). With
    ``window.start_offset`` ε ≠ 0 every velocity then gets ε D_guess (a deliberately wrong
    frame: the front runs at ~ε D)."""
    fill_csph_defaults(scene)
    attrs = {"stage": "window", "u_p": u_p, "scene_config": json.dumps(scene)}
    with xr.open_dataset(loaded, engine="netcdf4") as ds:
        ds.load()
    if ds.attrs.get("status", "ok") != "ok":
        return _failure(out, ds.attrs["status"], ds.attrs.get("diagnostic", ""), attrs)
    sim = ckpt.from_dataset(ds, loaded)
    w, sh = scene["window"], scene["shock"]
    t, front = ds["hist_t"].values, ds["hist_front"].values
    n = t.size
    a, *_ = line_fit(t[n // 2 :], front[n // 2 :])
    if not (np.isfinite(a) and a > u_p):
        return _failure(out, "no_front_speed", f"the loading stage gives no front speed ({n} "
                        f"samples, slope {a:.4g} m/s)", attrs)  # fmt: skip
    pole = _pole_from(ds)
    info = _sample_info(ds)
    xf = float(front[-1])
    depth = info["y_hi"] - info["y_lo"] if sim.state.dim == 2 else None
    sums = sim.profile_sums(sh["bin_width"], x0=info["x_lo"])
    shocked = slab_state(sums, info["x_lo"], sh["bin_width"],
                         max(float(sim.walls[0]) + sh["gap"], xf - sh["gap"] - sh["avg_length"]),
                         xf - sh["gap"], depth)  # fmt: skip
    if shocked is None:
        return _failure(out, "no_front_speed", "no shocked slab behind the front", attrs)
    t0, c0 = time.perf_counter(), _cpu()
    extra: dict = {}
    try:
        if sim.state.dim == 1:
            win = SPHWindow.from_piston(
                sim, xf, u_p, float(a), w["length"], w["front_fraction"], w["cut_every"],
                w["sync_steps"], rho0=pole["rho0"], e0=pole.get("E0", 0.0),
            )  # fmt: skip
        else:
            tile, extra = _inflow_tile(scene, info)
            win = SPHWindow2D.from_piston(
                sim, xf, u_p, float(a), w["length"], w["front_fraction"], tile, w["cut_every"],
                w["sync_steps"], x_origin=info["x_lo"], e0=pole.get("E0", 0.0),
            )  # fmt: skip
            # the window's pole: the inflow material at rest (the sample's is kept beside it)
            extra["sample_rho0"] = pole["rho0"]
            pole = {**pole, "rho0": win.rho0, "rho0_err": 0.0}
        if w["settle_time"] > 0:
            # through the window's own steps: its inflow and outflow are updated meanwhile
            steps0, t_end = win.sim.steps, win.time + w["settle_time"]
            while win.time < t_end:
                win.advance(w["sync_steps"])
            log.info("settled %.3g s in %d steps", w["settle_time"], win.sim.steps - steps0)
        if w["start_offset"]:
            # a deliberately wrong frame (stability maps): the front runs at ~start_offset D
            win.galilean_shift(w["start_offset"] * float(a))
    except (ValueError, SampleError) as exc:
        return _failure(out, "no_inflow", str(exc), attrs)
    except SPHUnstable as exc:
        return _failure(out, exc.status, exc.diagnostic, attrs)
    L = win.geom.length
    sig = {"kind": "N", "q_up": L * win.area * win.rho0 / win.m0,
           "q_sh": L * win.area * shocked["rho"] / win.m0, "bin_width": sh["bin_width"]}  # fmt: skip
    cost = _cost(t0, c0, 0.0, json.loads(ds.attrs.get("cost", "{}")))
    return win.save(out, attrs={**attrs, "status": "ok", "D_guess": float(a),
                                "start_offset": w["start_offset"],
                                "omega_signal": json.dumps(sig), "pole": json.dumps(pole),
                                "cost": json.dumps(cost), "inflow": json.dumps(extra)})  # fmt: skip


def _inflow_tile(scene: dict, info: dict) -> tuple[InflowTile, dict]:
    """The 2D window's inflow tile: ``window.tile_length`` (default (1 − front_fraction) L,
    the part of the window ahead of the front, so that the particle count of the upstream
    part changes little as the tile slides through) by the sample's periodic width, same dx.
    Porous scenes: ``sph.sample.porous_tile_2d`` (pores wrapping round x and y), seed
    ``sample.porous.seed + 1``, distention = the sample's measured one over its porous core
    within ``sample.porous.tolerance`` (relative: tile and sample differ by at most that);
    full-density scenes: the square lattice. Returns the tile and what to record of it."""
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


def steady_state(win: SPHWindow, scene: dict, pole: dict, duration: float, signal) -> dict:
    """Average the steady wave in the window frame for ``duration`` [s]: per sample the
    profile from x_lo, the front (velocity through (u_in + u_out)/2), the slabs behind and
    ahead of it; D = −u_in + L dω/dt (``stats.CorrelatedSlope``), the tracker's D kept as
    D_front; u_p_set = u_out − u_in. A particle count that never changes over the average
    (the front moved less than one particle's worth) gets the error of that quantum instead
    of the fit's 0. A sample's slab behind the front counts when it spans
    at least avg_length/2 clear of x_lo + window.outflow_gap (default shock.gap); fewer than
    half the samples with one raise ``SlabError`` (status too_few_samples: the front sat too
    close to the outflow edge). 2D: slabs are means over the periodic width (``slab_state``
    with ``depth`` = W: ρ = Σm/(n_bins·width·W), the pores counted)."""
    sh, w = scene["shock"], scene["window"]
    bw, gap, avg = sh["bin_width"], sh["gap"], sh["avg_length"]
    gap_out = w.get("outflow_gap", gap)
    depth = getattr(win, "depth", None)  # 2D: the periodic width (pores count in ρ)
    g = win.geom
    n = max(16, int(round(duration / (w["sample_every"] * max(win.dt, 1e-30)))))
    t, om, fr, slabs = [], [], [], []
    for _ in range(n):
        win.advance(w["sample_every"])
        om.append(signal(win))
        sums = win.profile_sums(bw)
        f = profile_fields(sums)
        xf = front_position(f, g.x_lo, bw, win.u_out, win.u_in)
        t.append(win.time)
        fr.append(xf)
        a, b = max(g.x_lo + gap_out, xf - gap - avg), xf - gap
        if np.isfinite(xf) and b - a >= 0.5 * avg:
            beh = slab_state(sums, g.x_lo, bw, a, b, depth)
            ahd = slab_state(sums, g.x_lo, bw, xf + gap, min(xf + gap + avg, g.x_hi), depth)
            if beh is not None:
                slabs.append((beh, ahd))
    if len(slabs) < max(8, n // 2):
        raise SlabError(
            "too_few_samples",
            f"{len(slabs)} of {n} samples have a slab of at least shock.avg_length/2 behind "
            f"the front (front at {np.nanmedian(fr):.4g} m from x_lo, needs 2 shock.gap + "
            f"shock.avg_length/2 = {2 * gap + 0.5 * avg:.4g} m): move window.front_fraction "
            "up or lengthen the window",
        )  # fmt: skip
    t, om = np.asarray(t), np.asarray(om)
    a, se, _ = CorrelatedSlope().fit(t, om)
    D = -win.u_in + g.length * a
    if np.ptp(om) == 0 and signal.kind == "N":
        # The particle count never changed: the front moved less than one particle's worth,
        # L/(q_sh − q_up) [m], and the fit's error (0) says nothing. Take that quantum's
        # uncertainty over the average (two ends uniform within it: std quantum/√6).
        quantum = g.length / abs(signal.q_sh - signal.q_up)
        se = quantum / (np.sqrt(6.0) * g.length * max(t[-1] - t[0], 1e-300))
    v = analyse(t, np.asarray(fr), slabs, pole, win.u_in, (D, g.length * se),
                sh["residual_tol"])  # fmt: skip
    af, sf, _ = CorrelatedSlope().fit(t, np.asarray(fr))
    v.update(D_front=af - win.u_in, D_front_err=sf, omega_drift=g.length * a,
             omega_drift_err=g.length * se, u_p_set=win.u_out - win.u_in)  # fmt: skip
    return v


def _mw_gains(scene: dict, window_time: float) -> tuple[float, float]:
    """MW's (gain_rate [-], gain_position [1/s]) from the scene's dimensionless ``window.mw``
    gains. ``window.methods.mw`` applies Δu_out = −g_v L a_k − g_x L (ω̄_k − ω*) once per
    averaging window; with g_x = gain_position/window_time [1/s] a front off its target by
    δx = L (ω̄ − ω*) moves the outflow by gain_position δx/window_time per window, so the
    front's return (s Δu_out per window_time, D = c0 + s u_p) does not depend on the units or
    the window's length (the MD scenes give g_x in 1/τ directly)."""
    g = scene["window"]["mw"]
    return float(g["gain_rate"]), float(g["gain_position"]) / window_time


def _load(path: str | os.PathLike) -> xr.Dataset:
    with xr.open_dataset(path, engine="netcdf4") as ds:
        ds.load()
    return ds


def _window_point(
    out, scheme: str, scene: dict, u_p: float, pole: dict, win: SPHWindow | None,
    values: dict, status: str, diagnostic: str, cost: dict, extra_vars: dict | None = None,
) -> Path:  # fmt: skip
    """Write a window point: ``values`` with ``cost`` (wall_s, cpu_s [s], atom_steps: this
    job's and its earlier jobs', loading and trials included) and ``extra_vars`` as is."""
    if status not in ("ok", "not_converged"):
        log.error("%s: %s", status, diagnostic)
    values = {**values, **cost, "piston_velocity": u_p}
    ds = point_dataset(values, pole, None, scheme, scene.get("name", ""), status, diagnostic,
                       scene)  # fmt: skip
    if extra_vars:
        ds = ds.assign(extra_vars)
    if win is not None:
        ds.attrs.update(u_in=win.u_in, u_out=win.u_out, window_length=win.geom.length)
    return write_netcdf(ds, out)


def _cost(t0: float, c0: float, atom_steps: float, *prior: dict) -> dict[str, float]:
    """This job's wall/CPU seconds since (t0, c0) and ``atom_steps``, plus ``prior``'s."""
    c = {"wall_s": time.perf_counter() - t0, "cpu_s": _cpu() - c0, "atom_steps": atom_steps}
    for p in prior:
        for k in c:
            c[k] += float(p.get(k, 0.0))
    return c


def control_point(
    window0: str | os.PathLike, scene: dict, u_p: float, out: str | os.PathLike, scheme: str
) -> Path:
    """An AMW or MW point on the 1D CSPH window: ``window.methods.amw`` (the amplitude u_p =
    u_out − u_in held, the frame shifted by −β L a_k) or ``window.methods.mw`` (the inflow,
    so D = −u_in from the loading stage's guess, held and u_out steered by
    ``_mw_gains``) until steady, then the steady average (``steady_state``). MW's amplitude
    settles to the u_p whose shock runs at the held D: its point is (D, u_p_set), to be read
    against the EOS line D = c0 + s u_p, not against the nominal u_p."""
    fill_csph_defaults(scene)
    t0, c0 = time.perf_counter(), _cpu()
    ds = _load(window0)
    if ds.attrs.get("status", "ok") != "ok":
        return _window_point(out, scheme, scene, u_p, {}, None, {}, ds.attrs["status"],
                             ds.attrs.get("diagnostic", ""), {})  # fmt: skip
    if scheme not in ("amw", "mw"):
        return _window_point(out, scheme, scene, u_p, {}, None, {}, "bad_config",
                             f"scheme {scheme} is not a control scheme (amw, mw)", {})  # fmt: skip
    win = window_from_dataset(ds, window0)
    sig = OmegaSignal(**json.loads(ds.attrs["omega_signal"]))
    pole = json.loads(ds.attrs["pole"])
    w = scene["window"]
    wt, avg_t = _window_times(scene, u_p)
    steps0 = win.sim.steps
    values, hist = {}, None
    status, diagnostic = "ok", ""
    common = dict(
        window_time=wt, calm_windows=w["calm_windows"], max_windows=w["max_windows"],
        every=w["sample_every"], z=w["z"], max_drift=w["drift_fraction"] * win.geom.length / avg_t,
    )  # fmt: skip
    try:
        if scheme == "amw":
            res, hist = amw(win, sig, beta=w["amw"]["beta"], **common)
        else:
            g_rate, g_pos = _mw_gains(scene, wt)
            res, hist = mw(win, sig, gain_rate=g_rate, gain_position=g_pos,
                           target=w["front_fraction"], **common)  # fmt: skip
        if not res.converged:
            status, diagnostic = res.status, res.diagnostic
        else:
            v = steady_state(win, scene, pole, avg_t, sig)
            values.update(v)
            status = v["status"]
            diagnostic = "" if status == "ok" else _residual_text(v)
            log.info("%s: D = %.2f +- %.2f m/s, u_p = %.2f m/s, P = %.5g Pa, %s", scheme,
                     v["D"], v["D_err"], v["u_p_set"], v["P"], _residual_text(v))  # fmt: skip
    except (SPHUnstable, SlabError) as exc:
        status, diagnostic = exc.status, exc.diagnostic
    cost = _cost(t0, c0, float(win.n_particles * (win.sim.steps - steps0)),
                 json.loads(ds.attrs.get("cost", "{}")))  # fmt: skip
    extra = control_vars(hist, "s", "m s^-1") if hist is not None and hist.t else None
    return _window_point(out, scheme, scene, u_p, pole, win, values, status, diagnostic, cost,
                         extra)  # fmt: skip


# -- the dichotomy on the window (1D, 2D) -----------------------------------------------------


def _dichotomy_times(scene: dict, u_p: float) -> tuple[float, float]:
    """(trial_time, final_time) [s]: configured, or window_time and average_time
    (``_window_times``): a trial lasts as long as one AMW/MW averaging window, the final
    average as long as theirs."""
    d = scene["window"]["dichotomy"]
    wt, avg_t = _window_times(scene, u_p)
    return d.get("trial_time") or wt, d.get("final_time") or avg_t


def dichotomy_state(
    window0: str | os.PathLike, scene: dict, k: int, previous: str | None, trials: list[str],
    out: str | os.PathLike,
) -> Path:  # fmt: skip
    """Iteration k of the dichotomy's loop state on the CSPH window (``window.dichotomy``):
    k = 0 proposes the bracket u_out0 ± half_width [m/s] around the window checkpoint's u_out
    (its ``window`` attribute); k ≥ 1 folds in the trials run on iteration k − 1's proposals."""
    fill_csph_defaults(scene)
    p = dich.params_from_config(scene["window"])
    if k == 0:
        with xr.open_dataset(window0, engine="netcdf4") as ds:
            attrs = dict(ds.attrs)
        status = attrs.get("status", "ok")
        if status != "ok":
            s = dich.initial_state(float("nan"), p)
            s.update(done=True, status=status, reason=attrs.get("diagnostic", ""), pending=[])
            return write_json(s, out)
        return write_json(dich.initial_state(float(json.loads(attrs["window"])["u_out"]), p), out)
    prev = json.loads(Path(previous).read_text())
    new = [json.loads(Path(f).read_text()) for f in trials]
    return write_json(dich.update(prev, new, p), out)


def dichotomy_trial(
    window0: str | os.PathLike, scene: dict, state: str, index: int, out: str | os.PathLike
) -> Path:
    """One trial: from the window checkpoint shifted to u_out = state.pending[index] [m/s]
    (a Galilean shift: u_p = u_out − u_in held, the frame moves), run ``trial_time``
    (``_dichotomy_times``) and fit ⟨dω/dt⟩ [1/s] (``window.methods.fixed_run``)."""
    fill_csph_defaults(scene)
    t0, c0 = time.perf_counter(), _cpu()
    u_out = float(json.loads(Path(state).read_text())["pending"][index])
    ds = _load(window0)
    if ds.attrs.get("status", "ok") != "ok":
        r = {"u_out": u_out, "slope": float("nan"), "status": ds.attrs["status"],
             "diagnostic": ds.attrs.get("diagnostic", "")}  # fmt: skip
        return write_json({**r, **_cost(t0, c0, 0.0)}, out)
    win = window_from_dataset(ds, window0)
    sig = OmegaSignal(**json.loads(ds.attrs["omega_signal"]))
    trial_time, _ = _dichotomy_times(scene, float(ds.attrs["u_p"]))
    win.galilean_shift(u_out - win.u_out)
    steps0 = win.sim.steps
    try:
        r = fixed_run(win, sig, trial_time, scene["window"]["sample_every"])
    except SPHUnstable as exc:
        # no slope: dichotomy.update counts it on the negative side (window too fast)
        r = {"u_out": u_out, "slope": float("nan"), "status": exc.status,
             "diagnostic": exc.diagnostic}  # fmt: skip
        log.error("%s: %s", exc.status, exc.diagnostic)
    r = {k: (v.tolist() if isinstance(v, np.ndarray) else v) for k, v in r.items()}
    log.info("trial u_out = %.3f m/s: front velocity %s m/s, %s", u_out,
             r.get("front_velocity"), r["status"])  # fmt: skip
    return write_json({**r, **_cost(t0, c0, float(win.n_particles * (win.sim.steps - steps0)))},
                      out)  # fmt: skip


def dichotomy_point(
    window0: str | os.PathLike, scene: dict, u_p: float, state: str, trials: list[str],
    out: str | os.PathLike,
) -> Path:  # fmt: skip
    """The dichotomy's point: at the root u_out [m/s] of the bisection (the window frame
    shifted there, u_p held), the steady average over ``final_time`` (``steady_state``). The
    cost adds the loading stage's and every trial's; the trials' (u_out, ⟨dω/dt⟩) are kept as
    ``dichotomy_u_out``, ``dichotomy_slope``."""
    fill_csph_defaults(scene)
    t0, c0 = time.perf_counter(), _cpu()
    scheme = "dichotomy"
    s = json.loads(Path(state).read_text())
    prior = [json.loads(Path(f).read_text()) for f in trials]
    ds = _load(window0)
    if ds.attrs.get("status", "ok") != "ok":
        return _window_point(out, scheme, scene, u_p, {}, None, {}, ds.attrs["status"],
                             ds.attrs.get("diagnostic", ""), _cost(t0, c0, 0.0, *prior))  # fmt: skip
    pole = json.loads(ds.attrs["pole"])
    load_cost = json.loads(ds.attrs.get("cost", "{}"))
    bis = np.array([[t["u_out"], t.get("slope", np.nan)] for t in s["trials"]], dtype=float)
    bis = bis.reshape(-1, 2)
    trial_vars = {
        "dichotomy_u_out": ("trial", bis[:, 0], {"units": "m s^-1", "long_name": "trial u_out"}),
        "dichotomy_slope": ("trial", bis[:, 1], {"units": "s^-1",
                                                 "long_name": "trial <domega/dt>"}),
    }  # fmt: skip
    if s["status"] != "ok":
        return _window_point(out, scheme, scene, u_p, pole, None, {}, s["status"], s["reason"],
                             _cost(t0, c0, 0.0, load_cost, *prior), trial_vars)  # fmt: skip
    win = window_from_dataset(ds, window0)
    sig = OmegaSignal(**json.loads(ds.attrs["omega_signal"]))
    win.galilean_shift(float(s["u_out"]) - win.u_out)
    _, final_time = _dichotomy_times(scene, u_p)
    steps0 = win.sim.steps
    values: dict = {}
    try:
        values = steady_state(win, scene, pole, final_time, sig)
        status = str(values["status"])
        diagnostic = "" if status == "ok" else _residual_text(values)
        log.info("dichotomy: D = %.2f +- %.2f m/s, P = %.5g Pa, %s", values["D"],
                 values["D_err"], values["P"], _residual_text(values))  # fmt: skip
    except (SPHUnstable, SlabError) as exc:
        status, diagnostic = exc.status, exc.diagnostic
    cost = _cost(t0, c0, float(win.n_particles * (win.sim.steps - steps0)), load_cost, *prior)
    return _window_point(out, scheme, scene, u_p, pole, win, values, status, diagnostic, cost,
                         trial_vars)  # fmt: skip


# -- the model's own Hugoniot ---------------------------------------------------------------


def reference_stage(scene: dict, out: str | os.PathLike, n_points: int = 60) -> Path:
    """The scene model's Hugoniot (SI), in the layout ``aggregate`` reads (dim ``point``:
    u_p, D, P, V, rho, E): solid — D = c0 + s u_p, P = ρ0 D u_p, V = V0 (1 − u_p/D),
    E = u_p²/2 (exact for the Mie–Grüneisen EOS referenced to that line); porous (α > 1) —
    the McQueen full-compaction Hugoniot of the solid's EOS (``analysis.porous``), with the
    snowplow limit (``snowplow_*``) beside it. Hydrodynamic: the strength's deviator is not in
    it (with strength P = −σ_xx lies above it by about 2Y/3 behind a plastic wave)."""
    from .analysis.porous import (
        MGSolid,
        porous_hugoniot_from_up,
        snowplow_hugoniot,
        solid_hugoniot_from_up,
    )

    fill_csph_defaults(scene)
    e = scene["material"]["eos"]
    solid = MGSolid(e["rho0"], e["c0"], e["s"], e["gamma0"])
    # an even grid to 1.25 max(u_p), and the scene's own u_p (a weak one can lie below the
    # grid's first point, where the campaign's interpolation would give no error)
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
        eos_source=e["source"], alpha=alpha, scene_config=json.dumps(scene),
    )  # fmt: skip
    return write_netcdf(ds, out)
