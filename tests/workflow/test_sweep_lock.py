"""Two sweeps started at once in one folder: the second is refused, names the first, and
starts no job; a dry run beside the first is not locked.

The first sweep (the synthetic scene: no MD) is stopped (SIGSTOP to its process group) once it
holds the lock and has started a job, so it is alive, and still holds the lock, however fast
its jobs would be; it is killed at the end. The first sweep's lock is left as it was. The take-over of a killed
sweep's lock is checked by test_resume.py (each rerun after a SIGKILL takes it over)."""

from __future__ import annotations

import json
import os
import re
import signal
import socket
import subprocess
import sys
import time
from collections.abc import Iterator
from pathlib import Path

import pytest

from hugomap.io import sweep_lock

ROOT = Path(__file__).resolve().parents[2]
CONFIG = ROOT / "tests" / "workflow" / "tiny_synthetic" / "config.yaml"


def _command(workdir: Path, *extra: str) -> list[str]:
    return [sys.executable, "-m", "snakemake", "-s", str(ROOT / "Snakefile"), "--directory",
            str(workdir), "--configfile", str(CONFIG), "--cores", "1",
            "--workflow-profile", str(ROOT / "workflow" / "profiles" / "default"),
            *extra]  # fmt: skip


@pytest.fixture
def first(tmp_path: Path) -> Iterator[subprocess.Popen]:
    """The first sweep, in its own process group; killed (with its jobs) at the end."""
    env = dict(os.environ, PYTHONPATH=str(ROOT / "src"))
    with open(tmp_path / "first.log", "w") as out:
        proc = subprocess.Popen(
            _command(tmp_path), cwd=tmp_path, env=env, stdout=out, stderr=subprocess.STDOUT,
            stdin=subprocess.DEVNULL, start_new_session=True,
        )  # fmt: skip
    yield proc
    os.killpg(proc.pid, signal.SIGKILL)
    proc.wait()


def _run(workdir: Path, *extra: str) -> subprocess.CompletedProcess:
    env = dict(os.environ, PYTHONPATH=str(ROOT / "src"))
    return subprocess.run(
        _command(workdir, *extra), cwd=workdir, env=env, stdin=subprocess.DEVNULL,
        capture_output=True, text=True, timeout=300,
    )  # fmt: skip


@pytest.mark.slow
def test_second_sweep_refused(tmp_path: Path, first: subprocess.Popen) -> None:
    lock = tmp_path / ".snakemake" / "hugomap.lock"
    t0 = time.monotonic()
    # the lock written and the guard's flock let go: a job of the first sweep has started
    while sweep_lock.read_owner(lock) is None or not re.search(
        r"^\s*jobid: \d+$", (tmp_path / "first.log").read_text(), re.M
    ):
        if first.poll() is not None:
            log = (tmp_path / "first.log").read_text()[-3000:]
            pytest.fail(f"the first sweep ended (rc {first.returncode}) too soon:\n{log}")
        if time.monotonic() - t0 > 120:
            pytest.fail("the first sweep started no job within 120 s")
        time.sleep(0.05)
    os.killpg(first.pid, signal.SIGSTOP)  # alive and holding the lock, its job too stopped
    held = lock.read_text()
    owner = json.loads(held)
    assert owner["pid"] == first.pid and owner["host"] == socket.gethostname()

    second = _run(tmp_path)
    out = second.stdout + second.stderr
    assert second.returncode != 0, out[-3000:]
    assert "another sweep runs in this folder" in out, out[-3000:]
    assert f"process {first.pid} on host {socket.gethostname()}, since {owner['since']}" in out
    # it started no job (Snakemake prints a job's rule block when it starts it)
    assert not re.search(r"^\s*(local)?(rule|checkpoint) \w+:$", out, re.M), out[-3000:]
    assert lock.read_text() == held

    dry = _run(tmp_path, "-n")
    assert dry.returncode == 0, (dry.stdout + dry.stderr)[-3000:]
    assert lock.read_text() == held
