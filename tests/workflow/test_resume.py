"""Kill and resume, on the tiny sweep with a hard kill: SIGKILL to the
whole process group (Snakemake and every job it runs).

1. A run that asks for one dichotomy point is killed in the middle of its loop (a trial of
   iteration k >= 1 running, states 0..k written).
2. The plain command (README form) resumes it; it is killed in the middle of a piston run
   that has a periodic checkpoint (``<out>.part.nc``), once some point is finished.
3. The plain command again: it completes.

The reruns are the README's command (with ``--workflow-profile workflow/profiles/default``,
whose settings make Snakemake rerun incomplete jobs); they add no flag.
Checked: each rerun takes over the sweep lock the killed run left (hugomap.io.sweep_lock),
and the last run releases it; the last run completes; no file finished before a kill is written again (same inode
and mtime: loop states, checkpoints, points); the killed piston run resumed from its periodic
checkpoint (its log names the file and the step it holds); the loop ends, its states
consistent; every netCDF file opens. "Finished" is Snakemake's own account: the outputs of
the jobs its log reports finished (it reports a job after recording its outputs complete).
The first run asks for one point only so that both kills happen whatever order Snakemake
picks: the piston runs all come after it.
"""

from __future__ import annotations

import json
import os
import re
import signal
import subprocess
import sys
import time
from collections.abc import Callable, Iterator
from pathlib import Path

import pytest
import xarray as xr
import yaml

ROOT = Path(__file__).resolve().parents[2]
TINY = ROOT / "tests" / "workflow" / "tiny" / "config.yaml"
TIMEOUT = 600.0  # s per run; the tiny sweep takes about a minute on 2 cores


def _config(tmp_path: Path) -> Path:
    """The tiny sweep (without MW), checkpointing its piston runs every 2 samples (0.12 tau),
    so that a periodic checkpoint exists early in each run."""
    cfg = yaml.safe_load(TINY.read_text())
    cfg["scenes"]["tiny"]["shock"]["checkpoint_every"] = 2
    cfg["schemes"] = ["piston", "amw", "dichotomy"]  # MW adds nothing to resume
    path = tmp_path / "resume.yaml"
    path.write_text(yaml.safe_dump(cfg))
    return path


class Sweep:
    """One plain ``snakemake`` run (the README's command form, as test_workflow.py runs it)
    in its own process group, its output in a file that the test reads while it runs."""

    def __init__(self, workdir: Path, config: Path, name: str, targets: tuple[str, ...] = ()):
        self.workdir = workdir
        self.log = workdir / f"{name}.snakemake.log"
        env = dict(os.environ, PYTHONPATH=str(ROOT / "src"))
        cmd = [sys.executable, "-m", "snakemake", "-s", str(ROOT / "Snakefile"), "--directory",
               str(workdir), "--configfile", str(config), "--cores", "2",
               "--workflow-profile", str(ROOT / "workflow" / "profiles" / "default"),
               *targets]  # fmt: skip
        with open(self.log, "w") as out:
            self.proc = subprocess.Popen(
                cmd, cwd=workdir, env=env, stdout=out, stderr=subprocess.STDOUT,
                stdin=subprocess.DEVNULL, start_new_session=True,
            )  # fmt: skip

    def text(self) -> str:
        return self.log.read_text(errors="replace")

    def jobs(self) -> tuple[dict[str, tuple[str, list[str]]], set[str]]:
        """Jobs Snakemake started (jobid → rule, outputs) and those it reported finished
        (after recording their outputs as complete)."""
        started = {}
        rule, outputs = None, []
        for line in self.text().splitlines():
            m = re.match(r"^(?:local)?(?:rule|checkpoint) (\w+):$", line.strip())
            if m:
                rule, outputs = m.group(1), []
                continue
            m = re.match(r"^output: (.*)$", line.strip())
            if m and rule:
                outputs = [s.strip() for s in m.group(1).split(",")]
                continue
            m = re.match(r"^jobid: (\d+)$", line.strip())
            if m and rule:
                started[m.group(1)] = (rule, outputs)
                rule = None
        finished = set(re.findall(r"Finished jobid: (\d+)", self.text()))
        return started, finished

    def finished_files(self) -> dict[str, tuple[int, int]]:
        """(inode, mtime_ns) of every output of a finished job."""
        started, finished = self.jobs()
        out = {}
        for jid in finished & set(started):
            for f in started[jid][1]:
                p = self.workdir / f
                if p.is_file():
                    st = p.stat()
                    out[f] = (st.st_ino, st.st_mtime_ns)
        return out

    def running(self, rule: str) -> list[list[str]]:
        """Outputs of the jobs of ``rule`` started and not finished."""
        started, finished = self.jobs()
        return [o for j, (r, o) in started.items() if r == rule and j not in finished]

    def wait_for(self, what: str, cond: Callable[[], bool], timeout: float = TIMEOUT) -> None:
        t0 = time.monotonic()
        while not cond():
            if self.proc.poll() is not None:
                pytest.fail(f"the sweep ended (rc {self.proc.returncode}) before {what}:\n"
                            + self.text()[-3000:])  # fmt: skip
            if time.monotonic() - t0 > timeout:
                self.kill()
                pytest.fail(f"no {what} within {timeout} s:\n" + self.text()[-3000:])
            time.sleep(0.05)

    def kill(self) -> None:
        """SIGKILL to the whole process group (Snakemake and every job it started)."""
        try:
            os.killpg(self.proc.pid, signal.SIGKILL)
        except ProcessLookupError:
            pass
        self.proc.wait()
        for _ in range(100):  # the jobs die with it
            if not _live_members(self.proc.pid):
                return
            time.sleep(0.05)
        pytest.fail(f"processes of the killed sweep are alive: {_live_members(self.proc.pid)}")

    def finish(self, timeout: float = TIMEOUT) -> None:
        try:
            self.proc.wait(timeout=timeout)
        except subprocess.TimeoutExpired:
            self.kill()
            pytest.fail(f"the rerun did not finish within {timeout} s:\n" + self.text()[-3000:])
        assert self.proc.returncode == 0, self.text()[-4000:]


def _live_members(pgid: int) -> list[int]:
    """Processes of group ``pgid`` that are not zombies (an orphaned job is reaped by init
    only when init does so; a zombie has stopped, which is what counts here)."""
    live = []
    for stat in Path("/proc").glob("[0-9]*/stat"):
        try:
            fields = stat.read_text().rsplit(")", 1)[1].split()
        except OSError:
            continue
        if int(fields[2]) == pgid and fields[0] != "Z":
            live.append(int(stat.parent.name))
    return live


@pytest.fixture
def sweeps() -> Iterator[list[Sweep]]:
    """Runs started by the test; any still running at its end (a failure) is killed."""
    started: list[Sweep] = []
    yield started
    for s in started:
        if s.proc.poll() is None:
            s.kill()


def _unchanged(before: dict[str, tuple[int, int]], workdir: Path) -> None:
    for f, (ino, mtime) in before.items():
        st = (workdir / f).stat()
        assert (st.st_ino, st.st_mtime_ns) == (ino, mtime), f"{f} was written again"


def _step_time(part: Path) -> tuple[int, float]:
    with xr.open_dataset(part, engine="netcdf4") as ds:
        return int(ds.attrs["step"]), float(ds.attrs["time"])


@pytest.mark.slow
def test_killed_sweep_resumes(tmp_path: Path, sweeps: list[Sweep]) -> None:
    cfg = _config(tmp_path)
    res = tmp_path / "results" / "tiny"

    # 1. One dichotomy point, killed while a trial of iteration k >= 1 runs.
    loop = res / "up1.5" / "dichotomy"
    first = Sweep(
        tmp_path, cfg, "first", (str(loop.parent.relative_to(tmp_path) / "dichotomy.nc"),)
    )
    sweeps.append(first)

    def mid_loop() -> bool:
        return any(
            re.search(r"/trial([1-9]\d*)_\d+\.json$", o[0])
            for o in first.running("dichotomy_trial")
        )

    first.wait_for("a dichotomy trial of iteration k >= 1", mid_loop)
    first.kill()
    finished_1 = first.finished_files()
    states_1 = sorted((f for f in finished_1 if re.search(r"/state\d+\.json$", f)),
                      key=lambda f: int(Path(f).stem[5:]))  # fmt: skip
    assert len(states_1) >= 2, finished_1  # states 0 and 1 at least
    assert not (loop.parent / "dichotomy.nc").exists()
    assert not list(res.rglob("piston.nc*"))  # no piston run yet

    # 2. The plain command resumes; killed in a piston run with a periodic checkpoint, once
    # some point is finished.
    second = Sweep(tmp_path, cfg, "second")
    sweeps.append(second)
    assert _profile_note(second), (
        "Snakemake did not pick up the workflow profile given by the README's command"
        " (--workflow-profile workflow/profiles/default):\n" + second.text()[-2000:]
    )
    parts: list[Path] = []

    def piston_mid_run() -> bool:
        done = {**finished_1, **second.finished_files()}
        if not any(re.search(r"up[^/]+/(piston|amw|mw|dichotomy)\.nc$", f) for f in done):
            return False
        parts[:] = [
            res / Path(o[0]).parent.name / "piston.nc.part.nc"
            for o in second.running("piston_point")
        ]
        return any(p.exists() for p in parts)

    second.wait_for("a piston run with a periodic checkpoint beside a finished point",
                    piston_mid_run)  # fmt: skip
    second.kill()
    # the first run's sweep lock, left by the kill, was taken over (its owner is gone)
    assert re.search(rf"taking over the sweep lock .* process {first.proc.pid} ", second.text())
    finished_2 = second.finished_files()
    killed = {p: _step_time(p) for p in parts if p.exists()}
    assert killed
    for p in killed:
        assert not (p.parent / "piston.nc").exists()
    _unchanged(finished_1, tmp_path)

    # 3. The plain command again: it completes, writing nothing that was finished.
    third = Sweep(tmp_path, cfg, "third")
    sweeps.append(third)
    third.finish()
    assert re.search(rf"taking over the sweep lock .* process {second.proc.pid} ", third.text())
    assert not (tmp_path / ".snakemake" / "hugomap.lock").exists()  # released at the end
    _unchanged(finished_1, tmp_path)
    _unchanged(finished_2, tmp_path)
    points = [f for f in {**finished_1, **finished_2} if re.search(r"up[^/]+/\w+\.nc$", f)]
    assert any(re.search(r"(piston|amw|mw|dichotomy)\.nc$", f) for f in points), points

    # The killed piston runs resumed from their periodic checkpoints, which are gone.
    for part, (step, t) in killed.items():
        log = (tmp_path / "results/logs/tiny" / part.parent.name / "piston.log").read_text()
        # the stage logs t with %.6g: the same format here (repr(6.720000000000001) is not)
        assert f"resuming from {part.relative_to(tmp_path)} at t = {t:.6g} (step {step})" in log
        assert "ignoring partial checkpoint" not in log
        assert not part.exists()
    assert not list(res.rglob("*.part.nc"))

    # The loop went on from its kept states to the end.
    states = sorted(loop.glob("state*.json"), key=lambda p: int(p.stem[5:]))
    assert [str(p.relative_to(tmp_path)) for p in states[: len(states_1)]] == states_1
    last = json.loads(states[-1].read_text())
    assert last["done"] and last["k"] == len(states) - 1
    assert len(list(loop.glob("trial*.json"))) == len(last["trials"])

    # Every file is whole.
    for nc in sorted((tmp_path / "results").rglob("*.nc")):
        with xr.open_dataset(nc, engine="netcdf4") as ds:
            ds.load()
    with xr.open_dataset(tmp_path / "results/hugoniot/tiny.nc", engine="netcdf4") as ds:
        assert list(ds["scheme"].values) == ["piston", "amw", "dichotomy"]
        assert set(ds.sel({"scheme": "piston"})["status"].values) <= {"ok", "not_converged"}


def _profile_note(sweep: Sweep) -> bool:
    """Whether Snakemake reports a workflow profile (on its first line, before the DAG)."""
    t0 = time.monotonic()
    while time.monotonic() - t0 < 60:
        text = sweep.text()
        if "workflow specific profile" in text:
            return True
        if sweep.proc.poll() is not None or "Building DAG" in text:
            return False
        time.sleep(0.05)
    return False
