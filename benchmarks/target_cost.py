"""What an accuracy costs: the CPU a point needs to state D to a target relative error,
for AMW and for the piston, read from a run of ``config/target_cost.yaml``.

    .venv/bin/snakemake --cores 2 --configfile config/target_cost.yaml
    .venv/bin/python benchmarks/target_cost.py results_target_cost --out docs/figures
    .venv/bin/python benchmarks/target_cost.py results_target_cost --laws src/hugomap/cost_laws.json
    .venv/bin/python benchmarks/target_cost.py --rows docs/figures/target_cost.jsonl --laws ...

- **AMW** (scene ``tc_amw``) was asked for the tightest target and recorded, chunk by chunk of
  its steady average, the relative error of D it stated and the CPU it had spent, its loading
  and window set-up counted (``chunk_*``). The CPU of a looser target is that of the first
  chunk whose error meets it: a run asked for that target stops there (the same run up to
  there). ``how``: ``run``.
- **The piston** (scenes ``tc_piston_<cells>``): its error is fixed by its sample, so each
  length is one (CPU, error) pair; the CPU of a target is read on the power law
  CPU = c err^m fitted through the lengths of that u_p (``how``: ``interpolated`` inside the
  measured errors, ``extrapolated`` outside them).
- Each point's D against the reference (the equilibrium-MD Hugoniot of the same potential,
  ``results/<scene>/reference.nc``) at its jump's u_p, in units of the combined error
  (``pull``): a stated error is worth its CPU only if it holds.

Output: JSON lines, one per (u_p, scheme, target), then one per point (``kind: point``), then
one line per scheme and u_p with the cost law CPU = c t^m fitted over that u_p's targets
(``kind: law``), each with the machine; ``--out`` draws CPU against the target, one curve
per scheme and u_p, with each piston run at its own stated error; ``--laws`` writes the
laws as the cost data ``schemes: [auto]`` reads. ``--rows`` reads the rows of an earlier
run's ``target_cost.jsonl`` in place of its results folder (the laws refitted from them).
"""

from __future__ import annotations

import argparse
import datetime
import json
import math
import platform
from pathlib import Path

import md_lj  # benchmarks/ is on sys.path when a script here runs
import numpy as np
import xarray as xr

from hugomap.campaign import reference_at, reference_deviation

TARGETS = (0.01, 0.005, 0.003, 0.002, 0.001)  # relative standard errors of D


def _machine() -> str:
    m = md_lj.machine()
    return f"{platform.node()} {m['cpu']} {m['nproc']} cpus, {platform.python_version()}"


def _f(ds: xr.Dataset, k: str) -> float:
    return float(ds[k]) if k in ds else math.nan


def _reference(scene_dir: Path) -> tuple[np.ndarray, dict]:
    """The scene's reference Hugoniot as ``campaign.reference_at`` reads it."""
    path = scene_dir / "reference.nc"
    if not path.exists():
        return np.empty(0), {}
    with xr.open_dataset(path) as ds:
        ds = ds.load()
    u = ds["u_p"].values.astype(float)
    cols = {k: ds[k].values.astype(float) for k in ("D", "P")}
    for k in ("D", "P", "u_p"):
        cols[k + "_err"] = ds[k + "_err"].values.astype(float) if k + "_err" in ds else 0 * u
    ok = np.isfinite(u) & (u > 0) & np.isfinite(cols["D"])
    order = np.argsort(u[ok])
    out = {k: v[ok][order] for k, v in cols.items()}
    out["P0_err"] = np.zeros(int(ok.sum()))
    return u[ok][order], out


def point(path: Path) -> dict:
    """A point file's row: scheme, u_p, status, CPU, D and its relative error, its pull
    against the reference, the sample length and the chunk record of a window."""
    with xr.open_dataset(path) as ds:
        ds = ds.load()
    scene = json.loads(ds.attrs.get("scene_config", "{}"))
    u_jump = _f(ds, "u_p_jump")
    ru, ref = _reference(path.parents[1])
    dev = (math.nan, math.nan)
    if ru.size and math.isfinite(u_jump):
        dev = reference_deviation(_f(ds, "D"), _f(ds, "D_err"), reference_at(u_jump, ru, ref),
                                  "D", _f(ds, "u_p_jump_err"))  # fmt: skip
    row = {
        "kind": "point", "scene": path.parents[1].name, "scheme": path.stem,
        "u_p": _f(ds, "piston_velocity"), "status": str(ds["status"].values),
        "cells_x": scene.get("sample", {}).get("cells", [math.nan])[0],
        "cpu_s": _f(ds, "cpu_s"), "D": _f(ds, "D"), "D_rel_err": _f(ds, "D_err") / _f(ds, "D"),
        "dev_D": dev[0], "dev_D_err": dev[1],
        "pull_D": dev[0] / dev[1] if dev[1] > 0 else math.nan,
        "P_rel_err": _f(ds, "P_err") / abs(_f(ds, "P") - _f(ds, "P0")),
        "average_time": _f(ds, "average_time"),
    }  # fmt: skip
    if "chunk_cpu_s" in ds:
        row["chunks"] = {k: ds["chunk_" + k].values.astype(float).tolist()
                         for k in ("T", "D_rel_err", "P_rel_err", "cpu_s")}  # fmt: skip
    return row


def window_rows(p: dict) -> list[dict]:
    """The CPU of each target on one window run's chunk record (module docstring)."""
    c = p["chunks"]
    err, cpu = np.asarray(c["D_rel_err"]), np.asarray(c["cpu_s"])
    out = []
    for t in TARGETS:
        hit = np.flatnonzero(err <= t)
        row = {"kind": "target", "scheme": p["scheme"], "u_p": p["u_p"], "target_D": t}
        if hit.size:
            k = int(hit[0])
            row.update(cpu_s=float(cpu[k]), D_rel_err=float(err[k]), how="run",
                       average_time=float(c["T"][k]))  # fmt: skip
        else:
            row.update(cpu_s=math.nan, D_rel_err=float(err[-1]), how="not reached")
        out.append(row)
    return out


def fit_law(cpu: np.ndarray, err: np.ndarray) -> tuple[float, float]:
    """(c, m) of CPU = c err^m through the pairs (log–log least squares); NaN with fewer
    than two usable pairs."""
    use = np.isfinite(cpu) & np.isfinite(err) & (cpu > 0) & (err > 0)
    if use.sum() < 2 or np.ptp(np.log(err[use])) == 0:
        return math.nan, math.nan
    m, logc = np.polyfit(np.log(err[use]), np.log(cpu[use]), 1)
    return float(math.exp(logc)), float(m)


def piston_rows(points: list[dict], u_p: float) -> list[dict]:
    """The CPU of each target on the power law through one u_p's piston lengths."""
    ps = [p for p in points if p["scheme"] == "piston" and p["u_p"] == u_p]
    cpu = np.array([p["cpu_s"] for p in ps])
    err = np.array([p["D_rel_err"] for p in ps])
    c, m = fit_law(cpu, err)
    lo, hi = (float(np.nanmin(err)), float(np.nanmax(err))) if ps else (math.nan, math.nan)
    out = []
    for t in TARGETS:
        how = "interpolated" if lo <= t <= hi else "extrapolated"
        out.append({"kind": "target", "scheme": "piston", "u_p": u_p, "target_D": t,
                    "cpu_s": c * t**m, "how": how, "law_m": m})  # fmt: skip
    return out


def laws(rows: list[dict]) -> list[dict]:
    """Per scheme and u_p, CPU = c t^m over that u_p's targets that a run reached (a window)
    or that lie inside the measured errors (the piston)."""
    out = []
    for scheme in sorted({r["scheme"] for r in rows}):
        for u in sorted({r["u_p"] for r in rows if r["scheme"] == scheme}):
            use = [r for r in rows if r["scheme"] == scheme and r["u_p"] == u
                   and r["how"] in ("run", "interpolated")]  # fmt: skip
            ts = np.array([r["target_D"] for r in use])
            c, m = fit_law(np.array([r["cpu_s"] for r in use]), ts)
            out.append({"kind": "law", "scheme": scheme, "u_p": u, "c": c, "m": m,
                        "quantity": "D", "targets": [float(ts.min()), float(ts.max())]
                        if use else [], "n": len(use)})  # fmt: skip
    return out


def write_laws(law_rows: list[dict], machine: str, date: str, path: Path) -> None:
    """The cost data ``schemes: [auto]`` reads (``hugomap.cost_laws``): per scheme its laws
    at each u_p with finite c and m."""
    md: dict[str, list] = {}
    for r in law_rows:
        if math.isfinite(r["c"]) and math.isfinite(r["m"]):
            md.setdefault(r["scheme"], []).append(
                {"u_p": r["u_p"], "c": r["c"], "m": r["m"], "targets": r["targets"]}
            )
    data = {
        "about": "CPU a point needs to state D to a relative error t at a piston velocity "
        "u_p [sigma/tau]: cpu_s = c t^m per u_p, measured by benchmarks/target_cost.py on "
        "config/target_cost.yaml (LJ liquid, rho0 0.80, T0 2.0, a 10.3-sigma section)",
        "machine": machine, "date": date, "solvers": {"md": md},
    }  # fmt: skip
    path.write_text(json.dumps(data, indent=2) + "\n")


def draw(rows: list[dict], points: list[dict], out: Path) -> None:
    """CPU against the target, one panel per u_p: each scheme's targets (filled where run or
    interpolated, hollow where extrapolated) and each piston run at its own stated error."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    ups = sorted({r["u_p"] for r in rows})
    fig, axes = plt.subplots(1, len(ups), figsize=(5 * len(ups), 4), squeeze=False)
    style = {"amw": ("tab:blue", "o"), "piston": ("tab:red", "s")}
    for ax, u in zip(axes[0], ups, strict=True):
        for scheme in sorted({r["scheme"] for r in rows}):
            rs = sorted((r for r in rows if r["u_p"] == u and r["scheme"] == scheme),
                        key=lambda r: r["target_D"])  # fmt: skip
            col, mk = style.get(scheme, ("k", "^"))
            t = np.array([100 * r["target_D"] for r in rs])
            y = np.array([r["cpu_s"] for r in rs])
            meas = np.array([r["how"] in ("run", "interpolated") for r in rs])
            ax.plot(t, y, "-", color=col, alpha=0.4)
            ax.plot(t[meas], y[meas], mk, color=col, label=f"{scheme}")
            ax.plot(t[~meas], y[~meas], mk, mfc="none", color=col,
                    label=f"{scheme} (extrapolated)" if (~meas).any() else None)  # fmt: skip
        runs = [p for p in points if p["scheme"] == "piston" and p["u_p"] == u]
        if runs:
            ax.plot([100 * p["D_rel_err"] for p in runs], [p["cpu_s"] for p in runs], "x",
                    color="tab:red", label="piston runs (stated error)")  # fmt: skip
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.invert_xaxis()
        ax.set_xlabel("relative standard error of D [%]: the target, or a run's own")
        ax.set_ylabel("CPU a point [s]")
        ax.set_title(f"LJ liquid, u_p = {u:g} σ/τ")
        ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(out / "target_cost.png", dpi=110)
    plt.close(fig)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("root", type=Path, nargs="?",
                    help="the results folder of config/target_cost.yaml")  # fmt: skip
    ap.add_argument("--rows", type=Path,
                    help="read the target and point rows of an earlier run's target_cost.jsonl "
                         "instead of a results folder (the laws refitted, the machine kept)")  # fmt: skip
    ap.add_argument("--date", help="the date of the run the rows come from (with --rows)")
    ap.add_argument("--out", type=Path, help="folder for target_cost.png and .jsonl")
    ap.add_argument("--laws", type=Path, help="write the cost laws here (JSON)")
    a = ap.parse_args()
    if (a.root is None) == (a.rows is None):
        ap.error("give a results folder or --rows, one of them")
    if a.rows is not None:
        old = [json.loads(line) for line in a.rows.read_text().splitlines() if line.strip()]
        rows = [r for r in old if r["kind"] == "target"]
        points = [r for r in old if r["kind"] == "point"]
        mach = next((r["machine"] for r in old if "machine" in r), _machine())
        date = a.date or datetime.date.fromtimestamp(a.rows.stat().st_mtime).isoformat()
    else:
        points = [point(p) for p in sorted(a.root.glob("tc_*/up*/*.nc"))
                  if p.stem in ("amw", "piston")]  # fmt: skip
        rows = []
        for p in points:
            if p["scheme"] == "amw" and "chunks" in p:
                rows += window_rows(p)
        for u in sorted({p["u_p"] for p in points if p["scheme"] == "piston"}):
            rows += piston_rows(points, u)
        mach, date = _machine(), datetime.date.today().isoformat()
    law_rows = laws(rows)
    lines = [*rows, *({k: v for k, v in p.items() if k != "chunks"} for p in points), *law_rows]
    for r in lines:
        r["machine"] = mach
        print(json.dumps(r))
    if a.out:
        a.out.mkdir(parents=True, exist_ok=True)
        (a.out / "target_cost.jsonl").write_text("".join(json.dumps(r) + "\n" for r in lines))
        draw(rows, points, a.out)
    if a.laws:
        write_laws(law_rows, mach, date, a.laws)


if __name__ == "__main__":
    main()
