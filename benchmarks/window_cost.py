"""Cost of a Hugoniot point: piston against the moving windows (AMW, MW, dichotomy).

The claim of the source (SEED-en.md) is that a window holds the shock in a domain of fixed
length, so the cost of a point grows linearly with the simulated time, while a piston's
sample must grow with the run, so its cost grows with the square. This script measures both
on the lj_liquid pole (ρ0* = 0.80, T0* = 2.0, rc = 2.5 σ shifted) at u_p = 2 σ/τ, with the
library's own stages (the same code the workflow runs):

- piston: samples of 40, 80, 160 (and with ``--long`` 320) fcc cells along x (6 × 6 across),
  each loaded and driven to the far end (``stages.load_to_target`` +
  ``piston_point``): simulated time ∝ sample length;
- windows: one 50-σ window cut from the 80-cell loading checkpoint (``window_start``), then
  AMW and MW points with ``average_time`` = 5, 10, 20, 40 τ, and one dichotomy loop
  (trials) whose root is averaged for 5, 10, 20, 40 τ.

Each row: CPU seconds of the point (this process, all threads; the stages' own ``cpu_s``),
the simulated time it covered, atom-steps, and P, D with their standard errors. Then, per
scheme, the exponent p of cpu ∝ T_sim^p and of P_err ∝ T_sim^(−q) (least squares in
log–log), and the CPU seconds each scheme needs to reach the same standard error in P
(interpolated in log–log between its measured rows; ``null`` when outside them). The
window's set-up (``window_start``, shared by every window scheme at one u_p) is a row of
its own and is added to the window schemes' cost at equal error.

    python benchmarks/window_cost.py            # about 10 min of CPU on one core
    python benchmarks/window_cost.py --long     # adds the 320-cell piston (about 4x longer)
    python benchmarks/window_cost.py --quick    # one row per scheme: checks that it runs
    python benchmarks/window_cost.py --replot docs/figures/window_cost.jsonl --out docs/figures
                                                # redraw the committed figure from its rows

Output: JSON lines on stdout, the same lines in ``results/benchmarks/window_cost.jsonl`` and
a figure ``results/benchmarks/window_cost.png`` (cost against simulated time, cost against
the standard error in P).
"""

from __future__ import annotations

import argparse
import json
import logging
import os
import platform
import tempfile
import time
from pathlib import Path

import md_lj  # benchmarks/ is on sys.path when a script here runs
import numpy as np
import xarray as xr

U_P = 2.0
AVERAGES = (5.0, 10.0, 20.0, 40.0)


def _machine() -> str:
    m = md_lj.machine()  # md_lj's: the CPU model from /proc/cpuinfo and the usable cores
    return f"{platform.node()} {m['cpu']} {m['nproc']} cpus, {platform.python_version()}"


def _scene(nx: int, average_time: float = 10.0) -> dict:
    from hugomap.config import validate_config

    cfg = {
        "threads": 1,
        "scenes": {
            "bench": {
                "solver": "md",
                "phase": "liquid",
                "potential": {"rc": 2.5, "shift": True, "skin": 0.3},
                "sample": {"rho0": 0.8, "T0": 2.0, "cells": [nx, 6, 6], "seed": 5},
                "shock": {"u_p": [U_P], "dt": 0.002},
                "window": {
                    "average_time": average_time,
                    "dichotomy": {"final_time": average_time},
                },
            }
        },
    }
    scene = validate_config(cfg)["scenes"]["bench"]
    scene["name"] = "bench"
    return scene


def _row(path: Path, scheme: str, extra: dict) -> dict:
    with xr.open_dataset(path) as ds:
        get = {k: float(ds[k]) for k in ("cpu_s", "atom_steps", "P", "P_err", "D", "D_err")
               if k in ds}  # fmt: skip
        status = str(ds["status"].values)
    return {"scheme": scheme, "status": status, **get, **extra}


def _emit(row: dict, sink: list) -> None:
    sink.append(row)
    print(json.dumps(row), flush=True)


def _fit(x, y) -> tuple[float, float]:
    """Least squares log y = a + p log x: returns (p, a)."""
    x, y = np.log(np.asarray(x, float)), np.log(np.asarray(y, float))
    ok = np.isfinite(x) & np.isfinite(y)
    if ok.sum() < 2:
        return float("nan"), float("nan")
    p, a = np.polyfit(x[ok], y[ok], 1)
    return float(p), float(a)


SE_TARGETS = (0.2, 0.1, 0.05, 0.02)  # standard errors of P [ε σ⁻³] for the equal-error rows


def _laws(rows: list[dict], add: float) -> dict:
    """cpu = C T^p and P_err = A T^(−q) fitted to one scheme's rows; the CPU seconds at
    standard error e follow as C ((A/e)^(1/q))^p (+ the shared set-up ``add``)."""
    T = [r["sim_time"] for r in rows]
    p, lc = _fit(T, [r["cpu_s"] for r in rows])
    mq, la = _fit(T, [r["P_err"] for r in rows])
    q = -mq
    errs = [r["P_err"] for r in rows]
    out = {"cpu_exponent": p, "P_err_exponent": q, "cpu_s_at_P_err": {}}
    for e in SE_TARGETS:
        if not (q > 0.05 and np.isfinite(p)):
            out["cpu_s_at_P_err"][f"{e:g}"] = None
            continue
        t = np.exp((la - np.log(e)) / q)
        out["cpu_s_at_P_err"][f"{e:g}"] = {
            "cpu_s": float(np.exp(lc) * t**p + add),
            "sim_time": float(t),
            "extrapolated": not (min(errs) <= e <= max(errs)),
        }
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--long", action="store_true", help="add the 320-cell piston")
    ap.add_argument("--quick", action="store_true", help="one short row per scheme")
    ap.add_argument("--out", default="results/benchmarks", help="folder for jsonl and png")
    ap.add_argument("--replot", metavar="JSONL",
                    help="only redraw the figure from the rows of an earlier run (into --out)")  # fmt: skip
    args = ap.parse_args()
    if args.replot:
        rows = [json.loads(ln) for ln in Path(args.replot).read_text().splitlines() if ln]
        setup = next(r["cpu_s"] for r in rows if r.get("scheme") == "window_start")
        out = Path(args.out)
        out.mkdir(parents=True, exist_ok=True)
        _figure(rows, setup, out / "window_cost.png", rows[0].get("machine", ""))
        return
    averages = (5.0, 10.0) if args.quick else AVERAGES
    logging.basicConfig(level=logging.WARNING)
    from hugomap import stages
    from hugomap.md.window import MDWindow

    rows: list[dict] = []
    machine = _machine()
    _emit({"benchmark": "window_cost", "machine": machine, "u_p": U_P,
           "numba_threads": os.environ.get("NUMBA_NUM_THREADS", "default")}, rows)  # fmt: skip
    lengths = (40, 80, 160, 320) if args.long else (40, 80, 160)
    if args.quick:
        lengths = (40, 80)
    with tempfile.TemporaryDirectory(prefix="hugomap-cost-") as tmp:
        d = Path(tmp)
        loaded80 = None
        for nx in lengths:
            scene = _scene(nx)
            sample = stages.prepare_sample(scene, d / f"sample{nx}.nc")
            loaded = stages.load_to_target(sample, scene, U_P, d / f"loaded{nx}.nc")
            with xr.open_dataset(loaded) as ds:
                load_cost = json.loads(ds.attrs["cost"])
                t_load = float(ds["hist_t"].values[-1])
            point = stages.piston_point(loaded, scene, U_P, d / f"piston{nx}.nc")
            with xr.open_dataset(point) as ds:
                t = ds["history_t"].values
            row = _row(
                point,
                "piston",
                {
                    "cells_x": nx,
                    "sim_time": float(t[-1] - t[0]),
                    "load_cpu_s": load_cost["cpu_s"],
                    "t_load": t_load,
                },
            )
            _emit(row, rows)  # fmt: skip
            if nx == 80:
                loaded80 = loaded
        scene = _scene(80)
        c0 = time.process_time()
        w0 = stages.window_start(loaded80, scene, U_P, d / "window.nc")
        setup = time.process_time() - c0
        t_w0 = MDWindow.load_path(w0).time
        _emit({"scheme": "window_start", "cpu_s": setup, "status": "ok"}, rows)
        for scheme in ("amw", "mw"):
            for avg in averages:
                sc = _scene(80, avg)
                p = stages.control_point(w0, sc, U_P, d / f"{scheme}{avg}.nc", scheme)
                with xr.open_dataset(p) as ds:
                    t_end = float(ds["history_t"].values[-1]) if "history_t" in ds else np.nan
                _emit(_row(p, scheme, {"average_time": avg, "sim_time": t_end - t_w0}), rows)
        # The dichotomy: its loop once (the trials), then the final average at the root.
        k, trials = 0, []
        st = stages.dichotomy_state(w0, scene, 0, None, [], d / "state0.json")
        while not json.loads(Path(st).read_text())["done"]:
            pending = json.loads(Path(st).read_text())["pending"]
            new = [stages.dichotomy_trial(w0, scene, st, i, d / f"trial{k}_{i}.json")
                   for i in range(len(pending))]  # fmt: skip
            trials += new
            k += 1
            st = stages.dichotomy_state(w0, scene, k, str(st), [str(f) for f in new],
                                                 d / f"state{k}.json")  # fmt: skip
        n_trials = len(trials)
        trial_time = scene["window"]["dichotomy"]["trial_time"]
        for avg in averages:
            sc = _scene(80, avg)
            p = stages.dichotomy_point(w0, sc, U_P, str(st), [str(f) for f in trials],
                                                d / f"dich{avg}.nc")  # fmt: skip
            _emit(_row(p, "dichotomy", {"average_time": avg, "trials": n_trials,
                                        "sim_time": n_trials * trial_time + avg}), rows)  # fmt: skip
    summary = _summarise(rows, setup)
    for s in summary:
        _emit(s, rows)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    (out / "window_cost.jsonl").write_text("".join(json.dumps(r) + "\n" for r in rows))
    _figure(rows, setup, out / "window_cost.png", machine)


def _summarise(rows: list[dict], setup: float) -> list[dict]:
    out = []
    for s in ("piston", "amw", "mw", "dichotomy"):
        rs = [r for r in rows if r.get("scheme") == s and r.get("status") in ("ok", "not_converged")
              and r.get("P_err", 0) > 0 and np.isfinite(r.get("sim_time", np.nan))]  # fmt: skip
        if len(rs) < 2:
            out.append({"summary": s, "note": "fewer than 2 usable rows"})
            continue
        out.append({"summary": s, **_laws(rs, 0.0 if s == "piston" else setup)})
    return out


def _figure(rows: list[dict], setup: float, path: Path, machine: str) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.ticker import FormatStrFormatter, LogLocator, NullFormatter

    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(10, 4.2))
    marks = {"piston": "o-", "amw": "s-", "mw": "^-", "dichotomy": "D-"}
    for s, m in marks.items():
        rs = [r for r in rows if r.get("scheme") == s and "sim_time" in r
              and r.get("status") in ("ok", "not_converged")]  # fmt: skip
        if not rs:
            continue
        rs.sort(key=lambda r: r["sim_time"])
        add = 0.0 if s == "piston" else setup
        T = np.array([r["sim_time"] for r in rs])
        c = np.array([r["cpu_s"] + add for r in rs])
        e = np.array([r["P_err"] for r in rs])
        p, _ = _fit(T, [r["cpu_s"] for r in rs])
        ax1.loglog(T, c, m, label=f"{s}: cpu ∝ T^{p:.2f}")
        ax2.loglog(e, c, m[0], label=s)  # markers only: errors scatter
    ax1.set_xlabel("simulated time of the point T [τ] (loading stage excluded)")
    ax1.set_ylabel("CPU time of the point [s]")
    ax1.legend(fontsize=8)
    # the error grows to the right, as on every other axis (more accurate: further left)
    ax2.set_xlabel("standard error of P [ε σ⁻³] (smaller: more accurate)")
    ax2.set_ylabel("CPU time of the point [s]")
    ax2.legend(fontsize=8)
    for ax in (ax1, ax2):  # plain numbers at 1, 2, 5 per decade: no overlapping labels
        for axis in (ax.xaxis, ax.yaxis):
            axis.set_major_locator(LogLocator(base=10.0, subs=(1.0, 2.0, 5.0)))
            axis.set_major_formatter(FormatStrFormatter("%g"))
            axis.set_minor_formatter(NullFormatter())
        ax.grid(True, which="major", alpha=0.25)
    fig.suptitle(f"LJ liquid, u_p = {U_P} σ/τ: cost of a Hugoniot point\n{machine}", fontsize=9)
    fig.tight_layout()
    fig.savefig(path, dpi=120)


if __name__ == "__main__":
    main()
