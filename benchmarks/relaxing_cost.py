"""Cost at equal stated error in a material that relaxes: the moving window against the piston.

A piston's sample must hold the whole distance its front travels, so a point that needs the
front's structure to settle for a time T_s and then an average over T_a costs

    cpu_piston = k · L_p · (T_s + T_a),   L_p = D (T_s + T_a) + l_far,

with k the piston's CPU per unit length of sample per unit simulated time (c_p n_x/Δt: its
CPU per particle-step c_p, particles per unit length n_x, time step Δt), measured on the
sweep's own piston runs as cpu_s/(L_sample T_run); D the shock speed (the sample's far end
closes on the front at D in the piston frame, so the length the front and the far end use
up together is D (T_s + T_a)) and l_far what stays ahead at the end (MD: ``shock.
rear_margin``, CSPH: the (1 − ``shock.end_fraction``) of the sample a run leaves, and the
slab ahead): it grows as T², where a window of fixed length grows as T (SEED-en.md;
``benchmarks/window_cost.py`` measures both laws on the LJ liquid). T_s is measured on the
window itself: the simulated time from the start of the piston drive (the window keeps the
piston run's clock) to the start of its steady average, i.e. loading, the window's settling
and the control windows until ω was calm.

Input: the point files of a finished sweep, e.g. of ``config/lj_fcc.yaml``
(``results/<scene>/up<u>/{amw,mw,dichotomy,piston}.nc`` with the ``loaded.nc`` beside them);
optionally those of a piston run on a sample long enough to reach the same state
(``--piston-root``: a second results folder). Each point gives a row:

    case, scheme, u_p, kind ("run" | "extrapolated"), status, cpu_s, sim_time [τ or s],
    atom_steps, D_rel_err, P_rel_err, T_s, T_a

and for every window point that is ``ok`` an extrapolated piston row at the same T_s and T_a,
on the assumption that a piston's slab of the same length averaged over the same T_a states
the same error (a run of ``--piston-root`` checks it: its row stands beside). k comes from
the piston points of the same sweep (the median of their cpu_s over their sample's length
and their run's simulated time; c_p, their cpu_s over atom_steps, is reported beside it).
Then one ``ratio`` row per window point: the piston's CPU over the window's.

    python benchmarks/relaxing_cost.py results_lj_fcc --case lj_fcc_strong
    python benchmarks/relaxing_cost.py results_a results_b --piston-root results_long \
        --case lj_fcc --scenes lj_fcc_strong lj_fcc_weak --out docs/figures

Output: JSON lines on stdout (the machine named in each), the same lines in
``<out>/relaxing_cost_<case>.jsonl`` and a figure ``<out>/relaxing_cost_<case>.png``: CPU
against the stated relative error in P, window points and piston points (run and
extrapolated), with the piston's T² curve over T_a and the window's linear one, and where
they cross.
"""

from __future__ import annotations

import argparse
import json
import platform
from pathlib import Path

import md_lj  # benchmarks/ is on sys.path when a script here runs
import numpy as np
import xarray as xr

from hugomap.keys import MIN_SLAB_BINS
from hugomap.lammps.units import METAL
from hugomap.particles.fcc import lattice_constant

WINDOW_SCHEMES = ("amw", "mw", "dichotomy")


def _machine() -> str:
    m = md_lj.machine()
    return f"{platform.node()} {m['cpu']} {m['nproc']} cpus, {platform.python_version()}"


def _scalar(ds: xr.Dataset, k: str) -> float:
    return float(ds[k]) if k in ds else float("nan")


def _loading(loaded: Path) -> tuple[float, float | None]:
    """From a point's loading checkpoint: the simulated time at which the piston started
    (its first sample) and the lattice constant a crystal's sample was built at where a
    search chose it (``sample.lattice_pressure``: the ``backend_info`` every checkpoint
    carries; else None, the scene's)."""
    if not loaded.exists():
        return float("nan"), None
    with xr.open_dataset(loaded) as ds:
        t = ds["hist_t"].values if "hist_t" in ds else np.array([np.nan])
        info = json.loads(ds.attrs.get("backend_info", "{}"))
    t0 = float(t[0]) if t.size else float("nan")
    return t0, info.get("lattice", {}).get("lattice_constant")


def point_row(path: Path, case: str) -> dict | None:
    """One point file as a row (module docstring); None for a file without a value."""
    with xr.open_dataset(path) as ds:
        if "status" not in ds or "D" not in ds:
            return None
        scene = json.loads(ds.attrs.get("scene_config", "{}"))
        t = ds["history_t"].values if "history_t" in ds else np.array([])
        if "history_stage" in ds:  # the averaged samples: a piston's drive, a window's all
            t = t[ds["history_stage"].values == 1]
        row = {
            "case": case,
            "scheme": path.stem,
            "u_p": _scalar(ds, "piston_velocity"),
            "kind": "run",
            "status": str(ds["status"].values),
            "cpu_s": _scalar(ds, "cpu_s"),
            "atom_steps": _scalar(ds, "atom_steps"),
            "D": _scalar(ds, "D"),
            "D_err": _scalar(ds, "D_err"),
            "D_rel_err": _scalar(ds, "D_err") / abs(_scalar(ds, "D")),
            "P": _scalar(ds, "P"),
            "P_err": _scalar(ds, "P_err"),
            "P_rel_err": _scalar(ds, "P_err") / abs(_scalar(ds, "P") - _scalar(ds, "P0")),
            "average_time": _scalar(ds, "average_time"),
            "u_p_jump": _scalar(ds, "u_p_jump"),
            "u_p_measured": _scalar(ds, "u_p_measured"),
        }
        if scene.get("solver") == "csph" and "alpha" in ds:
            row.update(_compaction_reference(ds, scene))
    t0, lattice = _loading(path.with_name("loaded.nc"))
    if t.size:
        row["T_s"] = float(t[0] - t0)  # from the piston's start to the steady average
        row["T_a"] = float(t[-1] - t[0])
        row["sim_time"] = float(t[-1] - t0)
    row["_scene"] = scene
    row["_lattice"] = lattice
    return row


def _compaction_reference(ds: xr.Dataset, scene: dict) -> dict:
    """A porous point's slab (u_p, α, P) and the Hugoniot at its own distention
    (``CSPHBackend.point_references``) with McQueen's full compaction at its u_p [SI]."""
    from hugomap.analysis.porous import MGSolid, porous_hugoniot_from_up
    from hugomap.sph.backend import CSPHBackend

    keys = ("alpha", "alpha_err", "u_p_jump", "u_p_jump_err", "u_p_measured",
            "u_p_measured_err", "rho0")  # fmt: skip
    one = xr.Dataset({k: ((), _scalar(ds, k)) for k in keys})
    ref = CSPHBackend().point_references(one, scene)
    e = scene["material"]["eos"]
    u = _scalar(ds, "u_p_jump")
    u = u if np.isfinite(u) else _scalar(ds, "u_p_measured")
    alpha0 = e["rho0"] / _scalar(ds, "rho0")
    solid = MGSolid(e["rho0"], e["c0"], e["s"], e["gamma0"])
    full = porous_hugoniot_from_up(u, alpha0, solid) if u > 0 else None
    return {
        "u_p_slab": u, "alpha": _scalar(ds, "alpha"), "alpha_err": _scalar(ds, "alpha_err"),
        "D_ref": float(ref["D_compaction_ref"]), "D_ref_err": float(ref["D_compaction_ref_err"]),
        "P_ref": float(ref["P_compaction_ref"]), "P_ref_err": float(ref["P_compaction_ref_err"]),
        "D_full_compaction": float(full.D) if full else float("nan"), "alpha0": alpha0,
    }  # fmt: skip


def _to_frame(scene: dict) -> float:
    """The factor from a scene's lengths to its points' (LAMMPS units metal: the scene in Å,
    the points in SI, 1e-10 m/Å; otherwise 1)."""
    metal = scene.get("solver") == "lammps" and scene.get("model", {}).get("units") == "metal"
    return METAL.length_m if metal else 1.0


def sample_length(scene: dict, lattice: float | None = None) -> float:
    """The length of a scene's sample along x in its points' units [σ | m]: particles, cells
    along x times the FCC cell (``lattice``, the one the sample was built at, where given;
    else a = (4/ρ0)^(1/3)); CSPH, ``sample.length``."""
    s = scene["sample"]
    if scene.get("solver") == "csph":
        return float(s["length"])
    a = lattice if lattice else lattice_constant(s["rho0"])
    return s["cells"][0] * a * _to_frame(scene)


def _room_ahead(scene: dict, front_travel: float) -> float:
    """What a piston run leaves ahead of its front at the end: the slab ahead, 2
    ``shock.ahead_gap`` (default ``shock.gap``) and its length (MD: ``MIN_SLAB_BINS``
    bins, CSPH: ``shock.avg_length``), and MD's ``shock.rear_margin``; CSPH's run ends when
    its front has crossed ``shock.end_fraction`` of the sample, so at least the rest of it."""
    sh = scene["shock"]
    gap = sh.get("ahead_gap") or sh["gap"]
    if scene.get("solver") == "csph":
        slab = 2.0 * gap + sh["avg_length"]
        return max(slab, front_travel * (1.0 / sh["end_fraction"] - 1.0))
    return (sh["rear_margin"] + 2.0 * gap + MIN_SLAB_BINS * sh["bin_width"]) * _to_frame(scene)


def piston_rate(row: dict) -> float:
    """A piston run's CPU per unit length of sample per unit simulated time, k [s/(σ τ) |
    s/(m s)]: its cpu_s over its sample's length and its run's simulated time."""
    length = sample_length(row["_scene"], row.get("_lattice"))
    return row["cpu_s"] / (length * row.get("sim_time", np.nan))


def piston_extrapolated(win: dict, k: float, case: str) -> dict:
    """The piston's CPU for the window point ``win``'s T_s and T_a (module docstring)."""
    T = win["T_s"] + win["T_a"]
    L_p = win["D"] * T + _room_ahead(win["_scene"], win["D"] * T)
    return {
        "case": case, "scheme": "piston", "u_p": win["u_p"], "kind": "extrapolated",
        "status": "extrapolated", "cpu_s": k * L_p * T, "sample_length": L_p, "sim_time": T,
        "T_s": win["T_s"], "T_a": win["T_a"], "D_rel_err": win["D_rel_err"],
        "P_rel_err": win["P_rel_err"], "k": k, "from_scheme": win["scheme"],
    }  # fmt: skip


def _ok_pistons(rows: list[dict], u_p: float) -> list[dict]:
    """The piston runs at ``u_p`` that are ``ok``."""
    return [r for r in rows if r["scheme"] == "piston" and r["kind"] == "run"
            and r["status"] == "ok" and r["u_p"] == u_p]  # fmt: skip


def piston_run_as_good(win: dict, rows: list[dict]) -> dict | None:
    """The cheapest piston run at the window point ``win``'s u_p that is ``ok`` and states
    relative errors in D and P no larger than the window's: a piston that reached the same
    state at the same stated error, whatever the extrapolation says; None if there is none."""
    good = [r for r in _ok_pistons(rows, win["u_p"])
            if r["D_rel_err"] <= win["D_rel_err"] and r["P_rel_err"] <= win["P_rel_err"]]  # fmt: skip
    return min(good, key=lambda r: r["cpu_s"]) if good else None


def piston_scaled(win: dict, rows: list[dict], k: float, case: str) -> dict | None:
    """A piston that states the window point ``win``'s errors, scaled from an ``ok`` piston
    run at its u_p: the run's own settling T_s (it was steady from there) and its average
    T_a stretched by the worst of (e_piston/e_window)² in D and P (a stated error falls as
    T_a^(-1/2)), priced as ``piston_extrapolated``; None without such a run. Where the
    front relaxes quickly (EAM copper at u_p ≥ 1.5 km/s) this, not the window's own T_s,
    is what a piston needs."""
    runs = [r for r in _ok_pistons(rows, win["u_p"]) if np.isfinite(r.get("T_a", np.nan))]
    if not runs:
        return None
    best = None
    for run in runs:
        f = max((run[f"{q}_rel_err"] / win[f"{q}_rel_err"]) ** 2 for q in ("D", "P"))
        p = piston_extrapolated({**win, "T_s": run["T_s"], "T_a": run["T_a"] * f}, k, case)
        p.update(kind="scaled", status="scaled", from_run_cpu_s=run["cpu_s"])
        best = p if best is None or p["cpu_s"] < best["cpu_s"] else best
    return best


def crossover_time(win: dict, k: float) -> float:
    """The simulated time T* [τ or s] below which a piston is cheaper than the window point
    ``win``'s own cost law, cpu_w = (cpu/sim_time) T: where the piston's cost per unit T,
    k L_p(T*), equals the window's rate (bisection: L_p grows with T)."""
    rate = win["cpu_s"] / win["sim_time"]

    def gap(T: float) -> float:
        return k * (win["D"] * T + _room_ahead(win["_scene"], win["D"] * T)) - rate

    lo, hi = 0.0, win["sim_time"]
    if gap(lo) >= 0:
        return 0.0
    while gap(hi) < 0:
        hi *= 2.0
    for _ in range(100):
        mid = 0.5 * (lo + hi)
        lo, hi = (lo, mid) if gap(mid) >= 0 else (mid, hi)
    return 0.5 * (lo + hi)


def _label(root: Path) -> str:
    """A results folder as the rows name it: as given when relative, else its last two
    parts (a scratch folder's full path means nothing to a reader of the rows)."""
    return str(root) if not root.is_absolute() else "/".join(root.parts[-2:])


def collect(roots: list[Path], case: str, scenes: list[str]) -> list[dict]:
    """The point rows of ``scenes`` (results/<scene>/up*/<scheme>.nc) under each root,
    labelled ``case``, each with its root and scene."""
    rows = []
    for root in roots:
        for scene in scenes:
            for path in sorted(root.glob(f"{scene}/up*/*.nc")):
                if path.stem in ("piston", *WINDOW_SCHEMES):
                    r = point_row(path, case)
                    if r is not None:
                        r.update(root=_label(root), scene=scene)
                        rows.append(r)
    return rows


def _reference_points(roots: list[Path], scheme: str) -> dict[tuple, list[dict]]:
    """The sweep's ``scheme`` points by (root, scene): each its own u_p (``u_p_measured``,
    the velocity its box reached; else the scene's), D, P with their errors and its pole."""
    refs: dict[tuple, list[dict]] = {}
    for root in roots:
        for path in root.glob(f"*/up*/{scheme}.nc"):
            with xr.open_dataset(path) as ds:
                if "D" not in ds:
                    continue
                pt = {k: _scalar(ds, k) for k in ("D", "D_err", "P", "P_err", "rho0", "P0")}
                u = _scalar(ds, "u_p_measured")
                pt["u"] = u if np.isfinite(u) else _scalar(ds, "piston_velocity")
                refs.setdefault((_label(root), path.parts[-3]), []).append(pt)
    return refs


def reference_at(points: list[dict], u: float) -> dict | None:
    """The reference Hugoniot at particle velocity ``u``: D linear in u through the two
    reference points nearest in u (Us–up is linear to a few 0.1 % over their spacing; EAM
    copper's nphug points 1500 and 2000 m/s apart by 500 m/s), its error from theirs with
    the interpolation's weights, and P = P0 + ρ0 D u on the reference's own Rayleigh line
    (momentum, exact for a shock-frame box). None with fewer than two points."""
    pts = sorted(points, key=lambda p: abs(p["u"] - u))[:2]
    if len(pts) < 2 or pts[0]["u"] == pts[1]["u"]:
        return None
    p1, p2 = pts
    w2 = (u - p1["u"]) / (p2["u"] - p1["u"])
    D = (1.0 - w2) * p1["D"] + w2 * p2["D"]
    D_err = float(np.hypot((1.0 - w2) * p1["D_err"], w2 * p2["D_err"]))
    rho0, P0 = p1["rho0"], p1["P0"]
    return {"D": D, "D_err": D_err, "P": P0 + rho0 * D * u, "P_err": rho0 * abs(u) * D_err}


def with_reference(rows: list[dict], roots: list[Path], scheme: str) -> None:
    """Each row's deviation from the same sweep's ``scheme`` Hugoniot (e.g. nphug: the same
    potential's Hugoniot at the same pole, in a periodic box) at the row's own jump velocity
    (``u_p_jump``: a window's slab moves at its own u, up to 0.8 % off the scene's u_p on
    EAM copper, and its point is the Hugoniot's there; a piston's is its velocity),
    ``reference_at``: ``D_ref``, ``P_ref`` with their errors, ``u_ref``, ``D_dev`` =
    D/D_ref − 1 and ``P_dev`` likewise, each with its combined standard error
    (``*_dev_err``)."""
    refs = _reference_points(roots, scheme)
    for r in rows:
        # the jump's velocity; a shock-frame box's own; else the scene's
        u = next((v for v in (r.get("u_p_jump", np.nan), r.get("u_p_measured", np.nan), r["u_p"])
                  if np.isfinite(v)), r["u_p"])  # fmt: skip
        ref = reference_at(refs.get((r["root"], r["scene"]), []), u)
        if ref is None:
            continue
        r["reference_scheme"], r["u_ref"] = scheme, float(u)
        for q in ("D", "P"):
            value = r[q] if q in r else float("nan")
            r[f"{q}_ref"], r[f"{q}_ref_err"] = ref[q], ref[f"{q}_err"]
            r[f"{q}_dev"] = value / ref[q] - 1.0
            mine = r.get(f"{q}_err", float("nan"))
            r[f"{q}_dev_err"] = float(
                np.hypot(mine / ref[q], value * ref[f"{q}_err"] / ref[q] ** 2)
            )


def _curves(ax, win: dict, k: float) -> None:
    """The window's cost line and the piston's T² curve against T_a, both in terms of the
    stated relative P error ∝ T_a^(-1/2) from the window point's own."""
    T_a0, e0 = win["T_a"], win["P_rel_err"]
    T_a = np.geomspace(0.1 * T_a0, 10 * T_a0, 60)
    e = e0 * np.sqrt(T_a0 / T_a)
    rate = win["cpu_s"] / win["sim_time"]  # the window: linear in the simulated time
    cpu_w = rate * (win["T_s"] + T_a)
    cpu_p = [piston_extrapolated({**win, "T_a": t}, k, "")["cpu_s"] for t in T_a]
    ax.plot(e, cpu_w, "-", color="C1", lw=1, alpha=0.6)
    ax.plot(e, cpu_p, "--", color="C0", lw=1, alpha=0.6)


def figure(rows: list[dict], case: str, k: float, out: Path) -> Path:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(7.2, 5.0), layout="constrained")
    style = {("piston", "run"): ("s", "C0"), ("piston", "extrapolated"): ("D", "none"),
             ("piston", "scaled"): ("v", "none")}  # fmt: skip
    for r in rows:
        if r.get("kind") not in ("run", "extrapolated", "scaled") or not np.isfinite(
            r["P_rel_err"]
        ):
            continue
        if r["cpu_s"] < 1.0:  # a point that failed before it ran
            continue
        marker, face = style.get((r["scheme"], r["kind"]), ("o", "C1"))
        edge = "C0" if r["scheme"] == "piston" else "C1"
        ok = r["status"] == "ok"
        ax.plot(100 * r["P_rel_err"], r["cpu_s"], marker, mfc=face if ok else "none",
                mec=edge, ms=7)  # fmt: skip
        ax.annotate(f"{r['u_p']:g}", (100 * r["P_rel_err"], r["cpu_s"]), fontsize=7,
                    xytext=(3, 3), textcoords="offset points")  # fmt: skip
    for r in rows:
        if r.get("kind") == "run" and r["scheme"] in WINDOW_SCHEMES and r["status"] == "ok":
            _curves(ax, {**r, "P_rel_err": 100 * r["P_rel_err"]}, k)
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("stated relative error of P − P0 [%]")
    ax.set_ylabel("CPU of the point [s]")
    ax.set_title(f"{case}: window (circles, solid) against piston (squares, dashed: T²)",
                 fontsize=9)  # fmt: skip
    cross = [r for r in rows if r.get("kind") == "ratio"]
    note = "".join(f"\nu_p {r['u_p']:g}: piston {r['piston_over_window_cpu']:.1f}x the window;"
                   f"\n   cheaper only below T = {r['crossover_sim_time']:.3g}"
                   f" (the window's: {r['window_sim_time']:.3g})" for r in cross)  # fmt: skip
    ax.text(0.99, 0.99, note.strip(), transform=ax.transAxes, fontsize=7, ha="right",
            va="top")  # fmt: skip
    ax.text(0.01, 0.01, "squares: piston run (hollow: not ok)\ndiamonds: piston extrapolated"
            " (T² law)\ntriangles: piston scaled from an ok run\ncircles: window (hollow: not"
            " ok); labels: u_p",
            transform=ax.transAxes, fontsize=7)  # fmt: skip
    path = out / f"relaxing_cost_{case}.png"
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("root", type=Path, nargs="+", help="results folders of the sweep(s)")
    ap.add_argument("--case", required=True, help="the case's label (and its scene's name)")
    ap.add_argument("--scenes", nargs="+", help="the case's scenes (default: --case)")
    ap.add_argument("--piston-root", type=Path, help="results folder of a long piston run")
    ap.add_argument("--out", type=Path, default=Path("results/benchmarks"))
    ap.add_argument("--reference-scheme", help="compare each point with the same sweep's "
                    "point of this scheme at its u_p (e.g. nphug)")  # fmt: skip
    args = ap.parse_args()
    roots = list(args.root) + ([args.piston_root] if args.piston_root else [])
    rows = collect(roots, args.case, args.scenes or [args.case])
    if args.reference_scheme:
        with_reference(rows, roots, args.reference_scheme)
    pistons = [r for r in rows if r["scheme"] == "piston" and r["atom_steps"] > 0
               and np.isfinite(r.get("sim_time", np.nan))]  # fmt: skip
    k = float(np.median([piston_rate(r) for r in pistons])) if pistons else float("nan")
    c_p = (float(np.median([r["cpu_s"] / r["atom_steps"] for r in pistons]))
           if pistons else float("nan"))  # fmt: skip
    machine = _machine()
    out_rows = []
    for r in rows:
        out_rows.append(r)
        if r["scheme"] in WINDOW_SCHEMES and r["status"] == "ok" and np.isfinite(k):
            p = piston_extrapolated(r, k, args.case)
            p["c_p"] = c_p
            out_rows.append(p)
            ratio = {"case": args.case, "kind": "ratio", "scheme": r["scheme"], "u_p": r["u_p"],
                     "piston_over_window_cpu": p["cpu_s"] / r["cpu_s"], "piston_basis":
                     "extrapolated", "window_sim_time": r["sim_time"],
                     "crossover_sim_time": crossover_time(r, k)}  # fmt: skip
            scaled = piston_scaled(r, rows, k, args.case)
            if scaled is not None:
                scaled["c_p"] = c_p
                out_rows.append(scaled)
                if scaled["cpu_s"] < ratio["piston_over_window_cpu"] * r["cpu_s"]:
                    ratio.update(piston_over_window_cpu=scaled["cpu_s"] / r["cpu_s"],
                                 piston_basis="scaled from an ok piston run")  # fmt: skip
            run = piston_run_as_good(r, rows)
            if run is not None and run["cpu_s"] < ratio["piston_over_window_cpu"] * r["cpu_s"]:
                # a piston run that is ok and states no larger errors is the cost to beat
                ratio.update(piston_over_window_cpu=run["cpu_s"] / r["cpu_s"],
                             piston_basis="run")  # fmt: skip
            out_rows.append(ratio)
    args.out.mkdir(parents=True, exist_ok=True)
    lines = []
    for r in out_rows:
        clean = {k: v for k, v in r.items() if not k.startswith("_")}
        clean["machine"] = machine
        lines.append(json.dumps(clean))
        print(lines[-1], flush=True)
    (args.out / f"relaxing_cost_{args.case}.jsonl").write_text("\n".join(lines) + "\n")
    figure(out_rows, args.case, k, args.out)


if __name__ == "__main__":
    main()
