"""The sweep lock (hugomap.io.sweep_lock): a live owner on this host or an owner on another
host refuses, naming it; a dead owner's lock (or one whose process id was reused) is taken
over; release removes only this process's own lock."""

from __future__ import annotations

import json
import os
import socket
import subprocess
import sys
from collections.abc import Iterator
from dataclasses import asdict, replace
from pathlib import Path

import pytest

from hugomap.io import sweep_lock
from hugomap.io.sweep_lock import Owner, SweepLocked


@pytest.fixture
def lock(tmp_path: Path) -> Iterator[Path]:
    path = tmp_path / ".snakemake" / "hugomap.lock"
    path.parent.mkdir()
    yield path
    sweep_lock.release(path)


@pytest.fixture
def child() -> Iterator[subprocess.Popen]:
    """A live process of this host (not this one), stopped at the end."""
    proc = subprocess.Popen([sys.executable, "-c", "import time; time.sleep(120)"])
    yield proc
    proc.kill()
    proc.wait()


def _owner(pid: int, host: str | None = None, **kw) -> Owner:
    return Owner(
        host=host or socket.gethostname(),
        pid=pid,
        since="2026-12-01T10:00:00+00:00",
        proc_start=kw.get("proc_start", sweep_lock._proc_start(pid)),
        boot_id=sweep_lock._boot_id(),
        command="python -m snakemake --cores 2",
    )


def _write(path: Path, owner: Owner) -> None:
    path.write_text(json.dumps(asdict(owner)))


def test_free_lock_is_taken_and_released(lock: Path) -> None:
    me = sweep_lock.acquire(lock, at_exit=False)
    assert (me.pid, me.host) == (os.getpid(), socket.gethostname())
    assert sweep_lock.read_owner(lock) == me
    assert sweep_lock.release(lock)
    assert not lock.exists()
    assert not sweep_lock.release(lock)  # a second call (atexit after onsuccess) is harmless


def test_live_owner_refuses_naming_it(lock: Path, child: subprocess.Popen) -> None:
    owner = _owner(child.pid)
    assert sweep_lock.owner_state(owner) == "alive"
    _write(lock, owner)
    before = lock.read_text()
    with pytest.raises(SweepLocked) as err:
        sweep_lock.acquire(lock, at_exit=False)
    msg = str(err.value)
    assert f"process {child.pid} on host {socket.gethostname()}" in msg
    assert "since 2026-12-01T10:00:00+00:00" in msg and str(lock) in msg
    assert lock.read_text() == before  # the owner's lock is left as it was


def test_dead_owner_is_taken_over(lock: Path, child: subprocess.Popen) -> None:
    owner = _owner(child.pid)
    child.kill()
    child.wait()
    assert sweep_lock.owner_state(owner) == "dead"
    _write(lock, owner)
    said: list[str] = []
    me = sweep_lock.acquire(lock, log=said.append, at_exit=False)
    assert sweep_lock.read_owner(lock) == me and me.pid == os.getpid()
    assert len(said) == 1 and "taking over" in said[0] and f"process {child.pid}" in said[0]


def test_reused_pid_is_not_the_owner(lock: Path, child: subprocess.Popen) -> None:
    """A live process id with another start time than the one recorded: the owner died and
    the number was given to a new process."""
    start = sweep_lock._proc_start(child.pid)
    if start is None:
        pytest.skip("no /proc on this system")
    owner = _owner(child.pid, proc_start=start - 1)
    assert sweep_lock.owner_state(owner) == "dead"
    _write(lock, owner)
    said: list[str] = []
    sweep_lock.acquire(lock, log=said.append, at_exit=False)
    assert sweep_lock.read_owner(lock).pid == os.getpid() and said


def test_another_host_refuses(lock: Path) -> None:
    owner = _owner(os.getpid(), host="node17.cluster.example")
    assert sweep_lock.owner_state(owner) == "foreign"
    _write(lock, owner)
    with pytest.raises(SweepLocked) as err:
        sweep_lock.acquire(lock, at_exit=False)
    msg = str(err.value)
    assert f"process {os.getpid()} on host node17.cluster.example" in msg
    assert f"rm {lock}" in msg
    assert sweep_lock.read_owner(lock) == owner


def test_damaged_lock_refuses(lock: Path) -> None:
    lock.write_text("")
    with pytest.raises(SweepLocked, match="not a lock record"):
        sweep_lock.acquire(lock, at_exit=False)


def test_release_leaves_a_lock_taken_over(lock: Path, child: subprocess.Popen) -> None:
    """If this process's lock was taken over meanwhile, release leaves the new owner's."""
    me = sweep_lock.acquire(lock, at_exit=False)
    other = replace(_owner(child.pid), since=me.since)
    _write(lock, other)
    assert not sweep_lock.release(lock)
    assert sweep_lock.read_owner(lock) == other


def test_own_earlier_lock_is_taken_again(lock: Path) -> None:
    """A second run in the same process (the Python API) after one that did not release."""
    first = sweep_lock.acquire(lock, at_exit=False)
    said: list[str] = []
    second = sweep_lock.acquire(lock, log=said.append, at_exit=False)
    assert second.pid == first.pid and sweep_lock.read_owner(lock) == second
    assert said and "this process's earlier run" in said[0]
