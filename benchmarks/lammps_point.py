"""Cost of one Hugoniot point through the numba MD backend and through the LAMMPS backend.

The same scene through both (``solver: md`` and ``solver: lammps`` with the same model):
the LJ liquid pole (ρ0* = 0.80, T0* = 2.0, lj/cut 2.5 σ shifted, skin 0.3 σ), an fcc start
of ``--cells`` (default 80 × 6 × 6, the default sweep's: 11,520 atoms), u_p = 2 σ/τ,
Δt = 0.002 τ, and the workflow's own stages: ``prepare_sample``, ``load_to_target``,
``piston_point`` and, unless ``--no-window``, ``window_start`` + the AMW point. Each backend
runs in its own subprocess on one core (numba: ``NUMBA_NUM_THREADS=1``; LAMMPS: one MPI
rank), the backends one after the other, and ``--repeat`` rounds alternate their order.

Rows (JSON lines, one per backend, stage and round): the stage's CPU seconds as the point
files record them (``cpu_s``: this process, all threads; a piston point counts its loading,
a window point its loading and the window's set-up), its atom-steps, CPU µs per atom-step,
and D, P with their errors; then one ``ratio`` line per stage: LAMMPS's CPU per atom-step
over numba's (the best round of each). The machine is named in every row; compare ratios,
not seconds, between machines.

    python benchmarks/lammps_point.py                 # one round, about 6 min of CPU
    python benchmarks/lammps_point.py --repeat 3 --no-window
    python benchmarks/lammps_point.py --cells 40 6 6 --quick   # checks that it runs
"""

from __future__ import annotations

import argparse
import copy
import json
import os
import subprocess
import sys
import tempfile
from pathlib import Path

import md_lj  # benchmarks/ is on sys.path when a script here runs

U_P = 2.0
MODEL = {
    "md": {"potential": {"rc": 2.5, "shift": True, "skin": 0.3}},
    "lammps": {
        "model": {"units": "lj", "pair_style": "lj/cut 2.5", "pair_coeff": ["* * 1.0 1.0"],
                  "pair_modify": ["shift yes"], "mass": 1.0, "skin": 0.3},
    },
}  # fmt: skip


def scene(solver: str, cells: list[int], window: bool) -> dict:
    """The benchmark's scene for ``solver``, validated and with every default resolved."""
    from hugomap.config import validate_config

    raw = {
        "solver": solver, "phase": "liquid", **copy.deepcopy(MODEL[solver]),
        "schemes": ["piston", "amw"] if window else ["piston"],
        "sample": {"rho0": 0.80, "T0": 2.0, "cells": list(cells), "seed": 1},
        "shock": {"u_p": [U_P], "dt": 0.002},
        "window": {"window_time": 6.0},
    }  # fmt: skip
    if solver == "md":
        raw["shock"]["snapshots"] = False
    cfg = validate_config({"threads": 1, "scenes": {"bench": raw}})
    return dict(cfg["scenes"]["bench"], name="bench")


def run_backend(solver: str, cells: list[int], window: bool, d: Path) -> list[dict]:
    """Run the stages of one point in this process; a row per stage."""
    import xarray as xr

    from hugomap import stages

    sc = scene(solver, cells, window)
    stages.prepare_sample(sc, d / "sample.nc")
    stages.load_to_target(d / "sample.nc", sc, U_P, d / "loaded.nc")
    stages.piston_point(d / "loaded.nc", sc, U_P, d / "piston.nc")
    files = {"piston": d / "piston.nc"}
    if window:
        stages.window_start(d / "loaded.nc", sc, U_P, d / "window.nc")
        stages.control_point(d / "window.nc", sc, U_P, d / "amw.nc", "amw")
        files["amw"] = d / "amw.nc"
    rows = []
    for stage, path in files.items():
        with xr.open_dataset(path) as ds:
            v = {k: float(ds[k]) for k in ("cpu_s", "atom_steps", "D", "D_err", "P", "P_err")}
            v["status"] = str(ds["status"].values)
        v["us_per_atom_step"] = 1e6 * v["cpu_s"] / v["atom_steps"]
        rows.append({"backend": solver, "stage": stage, **v})
    return rows


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--cells", type=int, nargs=3, default=[80, 6, 6])
    ap.add_argument("--repeat", type=int, default=1)
    ap.add_argument("--no-window", action="store_true", help="the piston point only")
    ap.add_argument("--quick", action="store_true", help="one round, the piston only")
    ap.add_argument("--worker", nargs=2, metavar=("SOLVER", "DIR"), help=argparse.SUPPRESS)
    a = ap.parse_args()
    window = not (a.no_window or a.quick)
    if a.worker:
        for row in run_backend(a.worker[0], a.cells, window, Path(a.worker[1])):
            print("ROW " + json.dumps(row), flush=True)
        return
    m = md_lj.machine()
    machine = f"{m['cpu']}, {m['nproc']} cpus"
    env = {**os.environ, "NUMBA_NUM_THREADS": "1", "OMP_NUM_THREADS": "1"}
    best: dict[tuple[str, str], dict] = {}
    order = ["md", "lammps"]
    for k in range(1 if a.quick else a.repeat):
        for solver in order if k % 2 == 0 else order[::-1]:
            with tempfile.TemporaryDirectory() as tmp:
                argv = [sys.executable, __file__, "--cells", *map(str, a.cells),
                        "--worker", solver, tmp]  # fmt: skip
                if not window:
                    argv.append("--no-window")
                load = os.getloadavg()[0]
                out = subprocess.run(argv, env=env, capture_output=True, text=True, check=True)
            for line in out.stdout.splitlines():
                if not line.startswith("ROW "):
                    continue
                row = {**json.loads(line[4:]), "round": k, "cells": a.cells,
                       "loadavg_1min_before": load, "machine": machine}  # fmt: skip
                print(json.dumps(row), flush=True)
                key = (solver, row["stage"])
                if key not in best or row["us_per_atom_step"] < best[key]["us_per_atom_step"]:
                    best[key] = row
    for stage in sorted({s for _, s in best}):
        if ("md", stage) in best and ("lammps", stage) in best:
            lm, md = best[("lammps", stage)], best[("md", stage)]
            print(json.dumps({
                "ratio": "lammps/md cpu per atom-step", "stage": stage,
                "value": lm["us_per_atom_step"] / md["us_per_atom_step"],
                "cpu_s_lammps": lm["cpu_s"], "cpu_s_md": md["cpu_s"], "machine": machine,
            }), flush=True)  # fmt: skip


if __name__ == "__main__":
    main()
