"""Window stages of the workflow: the window checkpoint, AMW and MW points, and the dichotomy.

Every stage starts from the piston's "load to target" checkpoint, through one window
checkpoint per (scene, u_p) (``window_start``), and writes a point file in the same format as
the piston's (``io.dataset.point_dataset``) with ``scheme`` set, plus the control history and
the steady profile in the window frame. Reduced LJ units (σ, τ, ε; m = 1).
"""

from __future__ import annotations

import json
import logging
import os
import time
from pathlib import Path

import numpy as np
import xarray as xr

from .analysis.shock import analyse_piston, front_position, region_state
from .analysis.stats import CorrelatedSlope, line_fit
from .failures import SolverUnstable, WindowError
from .io.atomic import write_json, write_netcdf
from .io.dataset import POLE_VARS, control_vars, point_dataset, scalar_vars
from .md.profiles import fields_from_sums
from .md.simulation import MDSimulation
from .md.window import MDWindow, make_reservoir
from .pipeline import _cpu, _failure, _history_from, _pole_from
from .window import dichotomy as dich
from .window.methods import ControlHistory, OmegaSignal, amw, fixed_run, mw

log = logging.getLogger("hugomap")


def _failed(out, scheme, scene, status, diagnostic, values=None) -> Path:
    log.error("%s: %s", status, diagnostic)
    ds = point_dataset(
        values or {}, {}, None, scheme, scene.get("name", ""), status, diagnostic, scene
    )
    return write_netcdf(ds, out)


def window_start(
    loaded: str | os.PathLike, scene: dict, u_p: float, out: str | os.PathLike
) -> Path:
    """Cut the window out of the loading checkpoint and save it (the branching state).

    D is first guessed from the loading stage's front speed (line fit over its second half),
    and the window runs ``window.settle_time`` at that guess before it is saved;
    ω is normalised by the pole (upstream: ρ0, P0) and the shocked state measured in the new
    window (the slab between the outflow edge and the front, ``shock.gap`` clear of both).
    With ``window.start_offset`` ε ≠ 0 every velocity then gets ε D_guess: the saved frame is
    off by that much, the front runs at about ε D, and each scheme must find D itself.
    A CSPH scene (1D) goes to ``pipeline_sph.window_start``.
    """
    if scene.get("solver") == "csph":
        from . import pipeline_sph

        return pipeline_sph.window_start(loaded, scene, u_p, out)
    with xr.open_dataset(loaded, engine="netcdf4") as ds:
        ds.load()
    attrs = {"stage": "window", "u_p": u_p, "scene_config": json.dumps(scene)}
    if ds.attrs.get("status", "ok") != "ok":
        return _failure(out, ds.attrs["status"], ds.attrs.get("diagnostic", ""), attrs)
    w, sh, s = scene["window"], scene["shock"], scene["sample"]
    sim = MDSimulation.from_dataset(ds)
    h = _history_from(ds).arrays()
    n = h["t"].size
    a, *_ = line_fit(h["t"][n // 2 :], h["front"][n // 2 :])
    if not np.isfinite(a):
        a, *_ = line_fit(h["t"], h["front"])
    D_guess = float(a + u_p)
    if not (np.isfinite(D_guess) and D_guess > u_p):
        return _failure(
            out, "no_front_speed", f"the loading stage gives no front speed ({n} samples)", attrs
        )
    # A fluid's inflow is made at the piston sample's measured (ρ0, E0), so both schemes
    # share one pole; a crystal's keeps the nominal lattice (the seam needs its registry)
    # and T0, its energy set by the lattice.
    piston_pole = _pole_from(ds)
    fluid = scene["phase"] != "crystal"
    try:
        res, inflow = make_reservoir(
            (s["cells"][1], s["cells"][2]), piston_pole["rho0"] if fluid else s["rho0"],
            s["T0"], sim.lj, sim.dt, s["seed"] + 7919, w["reservoir_equilibrate_time"],
            s["thermostat_tau"], E0_target=piston_pole["E0"] if fluid else None,
        )  # fmt: skip
    except WindowError as exc:
        return _failure(out, exc.status, exc.diagnostic, attrs)
    log.info("inflow pole: %s", json.dumps(inflow))
    try:
        win = MDWindow.from_piston(
            sim, res, float(h["front"][-1]), u_p, D_guess, w["length"], w["front_fraction"],
            w["ghost_width"], w["cut_every"], w["sync_steps"],
            crystal=scene["phase"] == "crystal", lattice=(4.0 / s["rho0"]) ** (1.0 / 3.0),
        )  # fmt: skip
    except WindowError as exc:
        return _failure(out, exc.status, exc.diagnostic, attrs)
    o = w["outflow"]
    if o["kind"] == "absorbing":
        # Z = ρ0 D and the averages started at the jump condition's P0 + ρ0 D u_p
        rho0 = piston_pole["rho0"] if fluid else inflow["rho0"]
        p0 = piston_pole["P0"] if fluid else inflow["P0"]
        win.set_absorbing(rho0 * D_guess, o["tau_fast"], o["tau_slow"], p0 + rho0 * D_guess * u_p)
    try:
        # Let the set-up transient (new boundaries, the first seam) pass at the guessed D:
        # every scheme branches from this settled state.
        win.advance(int(round(w["settle_time"] / win.dt)))
    except (SolverUnstable, WindowError) as exc:
        return _failure(out, exc.status, exc.diagnostic, attrs)
    if w["start_offset"]:
        # a deliberately wrong frame (stability maps): the front runs at ~start_offset D
        win.galilean_shift(w["start_offset"] * D_guess)
    g, bw = win.geom, sh["bin_width"]
    sums = win.profile_sums(bw)
    edges = np.arange(sums.shape[0] + 1) * bw
    ux = fields_from_sums(sums, win.area * bw)["ux"]
    x_f = front_position(ux, sums[:, 0], edges, g.x_lo, g.x_hi, win.u_out, win.u_in)
    if not np.isfinite(x_f):
        x_f = g.x_lo + w["front_fraction"] * g.length
    shocked = region_state(sums, edges, g.x_lo + 0.5 * sh["gap"], x_f - 0.5 * sh["gap"], win.area)
    # The window's pole is the inflow material's state. For a fluid that is the piston
    # sample's (ρ0, E0), so the sample's more precise P0, T0 are kept; the inflow's own
    # measurement (a ~1000-atom box over 2 τ) is stored beside them as a check.
    pole = piston_pole if fluid else inflow
    upstream = {"n": pole["rho0"], "Pxx": pole["P0"]}
    sig = OmegaSignal.from_states(w["omega"], g.length, win.area, upstream, shocked, bw)
    extra = xr.Dataset(scalar_vars(pole, POLE_VARS))
    return win.save(
        out,
        extra=extra,
        attrs={
            **attrs, "status": "ok", "D_guess": D_guess, "start_offset": w["start_offset"],
            **{f"inflow_{k}": v for k, v in inflow.items()},
            "omega_signal": json.dumps({"kind": sig.kind, "q_up": sig.q_up, "q_sh": sig.q_sh,
                                        "bin_width": sig.bin_width}),
        },
    )  # fmt: skip


def _open(path: str | os.PathLike) -> tuple[MDWindow, OmegaSignal, dict, xr.Dataset]:
    with xr.open_dataset(path, engine="netcdf4") as ds:
        ds.load()
    if ds.attrs.get("status", "ok") != "ok":
        raise WindowError(ds.attrs["status"], ds.attrs.get("diagnostic", ""))
    win = MDWindow.from_dataset(ds)
    sig = OmegaSignal(**json.loads(ds.attrs["omega_signal"]))
    return win, sig, _pole_from(ds), ds


def steady_state(
    win: MDWindow, scene: dict, pole: dict, duration: float, signal: OmegaSignal
) -> tuple[dict, dict, dict]:
    """Average the steady wave in the window frame for ``duration`` [τ] (the frame held).

    Each sample: the profile sums and the front (velocity change point inside the window);
    then ``analysis.shock.analyse_piston`` with the window edges as the boundaries, the
    upstream velocity u_in and the downstream u_out known exactly: D = L dω/dt-like front
    drift − u_in, u_p = u_out − u_in; ``pole`` is the inflow material's state (saved in the
    window checkpoint). The front's drift is L dω/dt over the whole average (ω from
    ``signal``, error corrected for correlated samples): the window's mass balance, which
    stays sharp for a broad weak front where the change-point tracker wanders (at u_p = 0.5
    the tracker gave D 4 % low while ω was flat); the tracker's D is kept as ``D_front``.
    Returns the point values, the profile history and that pole."""
    sh, w = scene["shock"], scene["window"]
    bw, every = sh["bin_width"], w["sample_every"]
    g = win.geom
    n = max(16, int(round(duration / (every * win.dt))))
    t, front, sums_all, omega = [], [], [], []
    for _ in range(n):
        win.advance(every)
        omega.append(signal(win))
        sums = win.profile_sums(bw)
        edges = np.arange(sums.shape[0] + 1) * bw
        ux = fields_from_sums(sums, win.area * bw)["ux"]
        t.append(win.time)
        front.append(front_position(ux, sums[:, 0], edges, g.x_lo, g.x_hi, win.u_out, win.u_in))
        sums_all.append(sums)
    a, se, _ = CorrelatedSlope().fit(np.asarray(t), np.asarray(omega))
    h = {
        "t": np.asarray(t), "front": np.asarray(front), "stage": np.ones(n, dtype=np.int8),
        "x_left": np.full(n, g.x_lo), "x_right": np.full(n, g.x_hi), "sums": np.asarray(sums_all),
    }  # fmt: skip
    r = analyse_piston(
        h, pole, win.area, bw, sh["gap"], residual_tol=sh["residual_tol"],
        avg_length=sh["avg_length"], u_upstream=win.u_in, u_piston=win.u_out,
        front_speed=(g.length * a, g.length * se),
    )  # fmt: skip
    r["omega_drift"], r["omega_drift_err"] = g.length * a, g.length * se
    # u_p = u_out − u_in is what the boundaries impose; u_p_measured (u_s − u_a) checks it.
    r["u_p_set"] = r.pop("u_p")
    r.pop("u_p_err")
    return r, h, pole


def _profile_vars(h: dict, bw: float, area: float) -> dict:
    """The mean steady profile along the window (ρ, u, P_xx, T per bin), window frame."""
    mean = np.asarray(h["sums"]).mean(axis=0)
    f = fields_from_sums(mean, area * bw)
    x = (np.arange(mean.shape[0]) + 0.5) * bw
    units = {
        "n": "sigma^-3",
        "ux": "sigma tau^-1",
        "Pxx": "epsilon sigma^-3",
        "T": "epsilon k_B^-1",
    }
    out = {"profile_x": ("bin", x, {"units": "sigma", "long_name": "bin centre (window frame)"})}
    for k, u in units.items():
        out["profile_" + k] = ("bin", f[k], {"units": u, "long_name": f"steady profile: {k}"})
    return out


def _finish_point(
    out, scheme: str, scene: dict, u_p: float, pole: dict, win: MDWindow, values: dict,
    h: dict | None, control: ControlHistory | None, status: str, diagnostic: str,
    t0: float, c0: float, step0: int, prior_cost: dict | None = None,
    extra_vars: dict | None = None,
) -> Path:  # fmt: skip
    """Write a window point; ``prior_cost`` (wall_s, cpu_s, atom_steps of earlier jobs, e.g.
    the dichotomy's trials) is added to this job's, ``extra_vars`` go into the file as is."""
    prior = prior_cost or {}
    values = dict(values, piston_velocity=u_p)
    values["wall_s"] = time.perf_counter() - t0 + prior.get("wall_s", 0.0)
    values["cpu_s"] = _cpu() - c0 + prior.get("cpu_s", 0.0)
    values["atom_steps"] = float(win.n_particles * (win.sim.state.step - step0)) + prior.get(
        "atom_steps", 0.0
    )
    hist = None if h is None else {k: h[k] for k in ("t", "front", "stage")}
    ds = point_dataset(values, pole, hist, scheme, scene.get("name", ""), status, diagnostic,
                       scene)  # fmt: skip
    extra = dict(extra_vars or {})
    if h is not None:
        extra.update(_profile_vars(h, scene["shock"]["bin_width"], win.area))
    if control is not None and control.t:
        extra.update(control_vars(control, "tau", "sigma tau^-1"))
    ds = ds.assign(extra)
    ds.attrs.update(u_in=win.u_in, u_out=win.u_out, window_length=win.geom.length)
    return write_netcdf(ds, out)


def control_point(
    window0: str | os.PathLike, scene: dict, u_p: float, out: str | os.PathLike, scheme: str
) -> Path:
    """An AMW or MW point: control until steady, then average the steady state (a CSPH
    scene: ``pipeline_sph.control_point``)."""
    if scene.get("solver") == "csph":
        from . import pipeline_sph

        return pipeline_sph.control_point(window0, scene, u_p, out, scheme)
    t0, c0 = time.perf_counter(), _cpu()
    try:
        win, sig, pole, _ = _open(window0)
    except WindowError as exc:
        return _failed(out, scheme, scene, exc.status, exc.diagnostic, {"piston_velocity": u_p})
    w = scene["window"]
    step0 = win.sim.state.step
    common = dict(
        window_time=w["window_time"], calm_windows=w["calm_windows"],
        max_windows=w["max_windows"], every=w["sample_every"], z=w["z"],
        max_drift=w["drift_fraction"] * win.geom.length / w["average_time"],
    )  # fmt: skip
    try:
        if scheme == "amw":
            result, hist = amw(win, sig, beta=w["amw"]["beta"], **common)
        else:
            result, hist = mw(
                win, sig, gain_rate=w["mw"]["gain_rate"],
                gain_position=w["mw"]["gain_position"], target=w["front_fraction"], **common,
            )  # fmt: skip
        if not result.converged:
            return _finish_point(out, scheme, scene, u_p, pole, win, {}, None, hist,
                                 result.status, result.diagnostic, t0, c0, step0)  # fmt: skip
        values, h, pole = steady_state(win, scene, pole, w["average_time"], sig)
    except (SolverUnstable, WindowError) as exc:
        return _finish_point(out, scheme, scene, u_p, pole, win, {}, None, None, exc.status,
                             exc.diagnostic, t0, c0, step0)  # fmt: skip
    status = str(values["status"])
    diagnostic = "" if status == "ok" else _residual_text(values)
    return _finish_point(out, scheme, scene, u_p, pole, win, values, h, hist, status,
                         diagnostic, t0, c0, step0)  # fmt: skip


def _residual_text(values: dict) -> str:
    return "jump residuals: " + ", ".join(
        f"{k} {values['residual_' + k]:+.3%}" for k in ("mass", "momentum", "energy")
    )


def dichotomy_state(
    window0: str | os.PathLike, scene: dict, k: int, previous: str | None, trials: list[str],
    out: str | os.PathLike,
) -> Path:  # fmt: skip
    """Iteration k of the dichotomy's loop state (``window.dichotomy``): k = 0 proposes the
    bracket; k ≥ 1 folds in the trials run on iteration k − 1's proposals (a CSPH scene:
    ``pipeline_sph.dichotomy_state``)."""
    if scene.get("solver") == "csph":
        from . import pipeline_sph

        return pipeline_sph.dichotomy_state(window0, scene, k, previous, trials, out)
    p = dich.params_from_config(scene["window"])
    if k == 0:
        with xr.open_dataset(window0, engine="netcdf4") as ds:
            status = ds.attrs.get("status", "ok")
            if status != "ok":
                s = dich.initial_state(float("nan"), p)
                s.update(done=True, status=status, reason=ds.attrs.get("diagnostic", ""),
                         pending=[])  # fmt: skip
                return write_json(s, out)
            u_out0 = json.loads(ds.attrs["window_state"])["u_out"]
        return write_json(dich.initial_state(u_out0, p), out)
    prev = json.loads(Path(previous).read_text())
    new = [json.loads(Path(f).read_text()) for f in trials]
    return write_json(dich.update(prev, new, p), out)


def dichotomy_trial(
    window0: str | os.PathLike, scene: dict, state: str, index: int, out: str | os.PathLike
) -> Path:
    """One trial: from the window checkpoint at u_out = state.pending[index] (u_p held),
    run ``dichotomy.trial_time`` and fit ⟨dω/dt⟩ (a CSPH scene: ``pipeline_sph``)."""
    if scene.get("solver") == "csph":
        from . import pipeline_sph

        return pipeline_sph.dichotomy_trial(window0, scene, state, index, out)
    t0, c0 = time.perf_counter(), _cpu()
    u_out = float(json.loads(Path(state).read_text())["pending"][index])
    win, sig, _, _ = _open(window0)
    win.galilean_shift(u_out - win.u_out)
    d = scene["window"]["dichotomy"]
    step0 = win.sim.state.step
    try:
        r = fixed_run(win, sig, d["trial_time"], scene["window"]["sample_every"])
    except (SolverUnstable, WindowError) as exc:
        # An unstable trial has no slope: take its sign from where the front was heading.
        r = {"u_out": u_out, "slope": float("nan"), "status": exc.status,
             "diagnostic": exc.diagnostic}  # fmt: skip
    r = {k: (v.tolist() if isinstance(v, np.ndarray) else v) for k, v in r.items()}
    r.update(wall_s=time.perf_counter() - t0, cpu_s=_cpu() - c0,
             atom_steps=float(win.n_particles * (win.sim.state.step - step0)))  # fmt: skip
    return write_json(r, out)


def dichotomy_point(
    window0: str | os.PathLike, scene: dict, u_p: float, state: str, trials: list[str],
    out: str | os.PathLike,
) -> Path:  # fmt: skip
    """The final refinement: at the root u_out of the bisection, a longer steady average (a
    CSPH scene: ``pipeline_sph.dichotomy_point``)."""
    if scene.get("solver") == "csph":
        from . import pipeline_sph

        return pipeline_sph.dichotomy_point(window0, scene, u_p, state, trials, out)
    t0, c0 = time.perf_counter(), _cpu()
    s = json.loads(Path(state).read_text())
    scheme = "dichotomy"
    prior = [json.loads(Path(f).read_text()) for f in trials]
    cost = {k: sum(float(t.get(k, 0.0)) for t in prior) for k in ("wall_s", "cpu_s", "atom_steps")}
    if s["status"] != "ok":
        return _failed(out, scheme, scene, s["status"], s["reason"],
                       {"piston_velocity": u_p, **cost})  # fmt: skip
    try:
        win, sig, pole, _ = _open(window0)
    except WindowError as exc:
        return _failed(out, scheme, scene, exc.status, exc.diagnostic, {"piston_velocity": u_p})
    win.galilean_shift(float(s["u_out"]) - win.u_out)
    step0 = win.sim.state.step
    try:
        values, h, pole = steady_state(
            win, scene, pole, scene["window"]["dichotomy"]["final_time"], sig
        )
    except (SolverUnstable, WindowError) as exc:
        return _finish_point(out, scheme, scene, u_p, pole, win, {}, None, None, exc.status,
                             exc.diagnostic, t0, c0, step0)  # fmt: skip
    status = str(values["status"])
    diagnostic = "" if status == "ok" else _residual_text(values)
    # The bisection's trials are part of the point's cost, and their sequence is kept.
    bis = np.array([[t["u_out"], t.get("slope", np.nan)] for t in s["trials"]], dtype=float)
    trials_vars = {
        "dichotomy_u_out": ("trial", bis[:, 0], {"units": "sigma tau^-1", "long_name": "trial u_out"}),
        "dichotomy_slope": ("trial", bis[:, 1], {"units": "tau^-1", "long_name": "trial <domega/dt>"}),
    }  # fmt: skip
    return _finish_point(out, scheme, scene, u_p, pole, win, values, h, None, status,
                         diagnostic, t0, c0, step0, prior_cost=cost,
                         extra_vars=trials_vars)  # fmt: skip
