"""The tiny sweep through a real SLURM cluster .

A one-node cluster (munge + slurmctld + slurmd, tests/workflow/slurm_cluster.py) runs the
tiny sweep through Snakemake's SLURM executor with the project's profile
(workflow/profiles/slurm); the aggregated dataset must equal a local run's.

Reference for the comparison: the MD is deterministic for a given thread count
(ARCHITECTURE.md: list rows written by the thread that owns them, bit-exact checkpoints);
both runs use the tiny config's `threads: 1`, so every variable except the measured cost
(wall_s, cpu_s) must be bit-identical, attributes included (config, hash, commit).
"""

from __future__ import annotations

import os
import re
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest
import xarray as xr
import yaml

sys.path.insert(0, str(Path(__file__).resolve().parent))  # tests/workflow is no package
from slurm_cluster import SlurmCluster, ensure_installed  # noqa: E402

ROOT = Path(__file__).resolve().parents[2]
TINY = ROOT / "tests" / "workflow" / "tiny" / "config.yaml"
PROFILE = ROOT / "workflow" / "profiles" / "slurm"
# Without accounting, the executor's default `sacct` polling hangs:
# poll with squeue, which sees finished jobs for the cluster's MinJobAge (3600 s >= 3 x 2 s).
NO_ACCOUNTING = ("--slurm-no-account", "--slurm-status-command", "squeue",
                 "--slurm-init-seconds-before-status-checks", "2",
                 "--seconds-between-status-checks", "1")  # fmt: skip
COST = ["wall_s", "cpu_s"]  # measured time: differs between any two runs
MD_RULES = {"prepare_sample": 1, "reference": 1, "load_to_target": 1, "piston_point": 1}
# sbatch --comment of a job: rule_<rule>[_wildcards_<values joined by _>]
GROUPED = {"rule_aggregate_wildcards_tiny", "rule_figures_wildcards_tiny"}
GROUP_COMMENT = "rule_summary_aggregate_figures"  # group <name>_<rules>
LOCAL_ONLY = {"rule_all"}  # a rule with no action is never submitted

pytestmark = [pytest.mark.slow, pytest.mark.slurm]


@pytest.fixture(scope="module")
def cluster():
    reason = ensure_installed()
    if reason is not None:
        pytest.skip(f"no SLURM cluster possible here: {reason}")
    c = SlurmCluster.start()
    try:
        yield c
    finally:
        c.stop()
    assert not c.running(), f"daemons still running after stop(): {c.running()}"


def snakemake(workdir: Path, *args: str, env: dict[str, str]) -> subprocess.Popen:
    """Start Snakemake on the tiny config in ``workdir`` (own session; output to files)."""
    env = dict(env, PYTHONPATH=str(ROOT / "src"))
    # The tiny sweep without AMW and MW: the dichotomy's checkpoint loop is what a cluster
    # run must get right, and the two control schemes add minutes, not coverage.
    cfg = yaml.safe_load(TINY.read_text())
    cfg["schemes"] = ["piston", "dichotomy"]
    # Two bisection steps instead of four: the loop still runs through several checkpoint
    # iterations, at half the jobs (the suite must stay under CI's 15 minutes).
    cfg["scenes"]["tiny"]["window"]["dichotomy"]["tolerance"] = 0.3
    # One piston velocity: every rule and the loop still run; a second point only doubles
    # the jobs (the suite must stay under CI's 15 minutes; test_workflow.py runs both).
    cfg["scenes"]["tiny"]["shock"]["u_p"] = [2.5]
    config = workdir / "tiny_slurm.yaml"
    config.write_text(yaml.safe_dump(cfg))
    cmd = [sys.executable, "-m", "snakemake", "-s", str(ROOT / "Snakefile"), "--directory",
           str(workdir), "--configfile", str(config), *args]  # fmt: skip
    with open(workdir / "snakemake.out", "wb") as out:
        # stdin closed: the executor must not wait on a terminal
        return subprocess.Popen(cmd, stdin=subprocess.DEVNULL, stdout=out,
                                stderr=subprocess.STDOUT, env=env, cwd=workdir,
                                start_new_session=True)  # fmt: skip


def finish(p: subprocess.Popen, timeout: float = 1200.0) -> int:
    """Wait for ``p``; on timeout end its process group (SIGTERM lets jobs finish)."""
    try:
        return p.wait(timeout)
    except subprocess.TimeoutExpired:
        stop(p)
        raise


def stop(p: subprocess.Popen) -> None:
    if p.poll() is None:
        os.killpg(p.pid, signal.SIGTERM)
        try:
            p.wait(60)
        except subprocess.TimeoutExpired:
            os.killpg(p.pid, signal.SIGKILL)
            p.wait()


def _job_logs(workdir: Path, tail: int = 1500) -> str:
    """The SLURM job logs the executor kept (those of failed jobs), for a failure message."""
    logs = sorted((workdir / ".snakemake" / "slurm_logs").rglob("*.log"))
    return "".join(f"\n--- {f} ---\n{f.read_text(errors='replace')[-tail:]}" for f in logs)


def _local_jobs(workdir: Path) -> list[str]:
    """The jobs of a local run's output, named as the SLURM executor's --comment."""
    jobs, rule = [], None
    for line in (workdir / "snakemake.out").read_text().splitlines() + ["["]:
        m = re.match(r"local(?:rule|checkpoint) (\w+):$", line)
        if m or line.startswith("["):
            if rule is not None:
                jobs.append(rule)
            rule = f"rule_{m.group(1)}" if m else None
        elif rule is not None and line.strip().startswith("wildcards:"):
            values = [kv.split("=", 1)[1] for kv in line.split(":", 1)[1].split(",")]
            rule += "_wildcards_" + "_".join(v.strip() for v in values)
    return jobs


def _mb(mem: str) -> float:
    """squeue's memory ('1031M', '2G') in MB."""
    return float(mem[:-1]) * {"K": 1 / 1024, "M": 1, "G": 1024, "T": 1024**2}[mem[-1]]


def test_cluster_runs_a_job_and_stops() -> None:
    reason = ensure_installed()
    if reason is not None:
        pytest.skip(f"no SLURM cluster possible here: {reason}")
    with SlurmCluster.start() as c:
        pids = [p.pid for p in c.procs.values()]
        r = subprocess.run(["srun", "-n1", "hostname"], capture_output=True, text=True,
                           env=c.env, timeout=120)  # fmt: skip
        assert r.returncode == 0, r.stderr + c.logs()
        assert r.stdout.strip().split(".")[0] == c.node
        # after srun returns, slurmd finishes the job's clean-up with the node "completing"
        # for a moment (seen under load); it must then be idle, not drained or down
        deadline = time.monotonic() + 60.0
        while c.node_state() == "completing" and time.monotonic() < deadline:
            time.sleep(0.5)
        assert c.node_state() == "idle"
    assert c.running() == []
    for pid in pids:  # reaped, not merely signalled
        with pytest.raises(ProcessLookupError):
            os.kill(pid, 0)
    assert not c.root.exists()


def test_tiny_sweep_on_slurm_equals_local(cluster: SlurmCluster, tmp_path: Path) -> None:
    local, slurm = tmp_path / "local", tmp_path / "slurm"
    local.mkdir()
    slurm.mkdir()

    # Both at once: the SLURM run spends most of its time waiting on the executor's status
    # polls, the local one computing.
    t0 = time.perf_counter()
    local_run = snakemake(local, "--cores", "2", env=dict(os.environ))
    try:
        rc = finish(snakemake(slurm, "--profile", str(PROFILE), *NO_ACCOUNTING,
                              env=cluster.env))  # fmt: skip
        t_slurm = time.perf_counter() - t0
        out = (slurm / "snakemake.out").read_text(errors="replace")
        assert rc == 0, out[-4000:] + _job_logs(slurm) + "\n" + cluster.logs()
        rc = finish(local_run)
        t_local = time.perf_counter() - t0
        assert rc == 0, (local / "snakemake.out").read_text(errors="replace")[-4000:]
    finally:
        stop(local_run)
    print(f"SLURM run {t_slurm:.0f} s; both runs (concurrent) {t_local:.0f} s")

    # Every job the local run ran went through sbatch once (the controller still knows
    # them, all COMPLETED), except the scene's aggregate + figures: one group submission
    # (profile: groups). Each with its rule's resources: threads -> CPUs, mem_mb -> --mem,
    # runtime -> -t.
    jobs = cluster.jobs()
    assert {j["state"] for j in jobs} == {"COMPLETED"}, jobs
    expected = [c for c in _local_jobs(local) if c not in GROUPED | LOCAL_ONLY]
    assert sorted(j["comment"] for j in jobs) == sorted([*expected, GROUP_COMMENT]), jobs
    assert len(expected) >= sum(MD_RULES.values()), expected
    for rule, n in MD_RULES.items():
        assert sum(c.startswith(f"rule_{rule}_wildcards_") for c in expected) == n, expected
    for j in jobs:
        assert j["cpus"] == "1", j  # the tiny config's threads: 1
        assert _mb(j["mem"]) >= 1024, j  # the MD backend cost model: BASE_MB and up
        assert j["time_limit"] not in ("UNLIMITED", "INFINITE", ""), j
    assert "submitted with SLURM jobid" in out

    name = "results/hugoniot/tiny.nc"
    with xr.open_dataset(local / name) as a, xr.open_dataset(slurm / name) as b:
        for ds in (a, b):
            for v in COST:
                assert np.all(np.isfinite(ds[v].values)) and np.all(ds[v].values > 0), v
        assert set(a.variables) == set(b.variables)
        # Bit-identical, attributes and units included (see the module docstring), but for
        # the CF ``history`` line, which records when each file was written.
        assert a.attrs["history"].split(" ", 1)[1] == b.attrs["history"].split(" ", 1)[1]
        a.attrs.pop("history"), b.attrs.pop("history")
        xr.testing.assert_identical(a.drop_vars(COST), b.drop_vars(COST))
    for png in ("tiny_PV.png", "tiny_D_up.png"):
        assert (slurm / "results" / "figures" / png).stat().st_size > 10_000
