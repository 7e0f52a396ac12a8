"""The sweep lock: one sweep at a time in a working directory, and a killed sweep's lock
taken over by the next run.

The workflow profile turns Snakemake's own directory lock off (``nolock``), because a hard
kill leaves it behind and Snakemake cannot tell a stale lock from a live one. This lock can:
it records its owner, and the next run checks whether that owner still runs.

The rule:

- The Snakefile takes the lock in its ``onstart`` handler, i.e. in the main Snakemake process
  of a run that is about to start jobs. A dry run (``-n``), ``--lint``, ``--unlock``,
  ``--summary``, a run with "Nothing to be done" and the jobs Snakemake spawns (they re-read
  the Snakefile, with ``--no-hooks``) take no lock; so a dry run beside a running sweep
  shows what is left to do, and ``--no-hooks`` turns the guard off.
- The lock is the file ``.snakemake/hugomap.lock`` in the working directory (``LOCK_NAME``),
  created with ``O_CREAT | O_EXCL`` and holding, as JSON, the owner's host name, process id,
  the time it took the lock, the process's start time (``/proc/<pid>/stat``, clock ticks
  after boot), the machine's boot id and its command line.
- If the file exists, its owner is judged (``owner_state``): on this host, alive if the
  process id exists and has the recorded start time and boot id (a process id reused after
  the owner died, or a reboot, is not the owner); then the run is refused with
  ``SweepLocked``, naming the owner. A dead owner's lock (a sweep killed hard: SIGKILL, a
  power cut) is taken over with a log line. A lock from another host cannot be checked from
  here: the run is refused, and the message says to remove the file if that host's sweep
  is gone.
- The check and the take-over happen under an ``flock`` on a guard file beside the lock
  (``.snakemake/hugomap.lock.guard``), so two runs that find the same dead owner cannot both
  take it over, and a run never reads a lock file being written.
- ``release`` removes the file if it is still this process's lock; the Snakefile calls it from
  ``onsuccess`` and ``onerror``, and ``acquire`` registers it with ``atexit`` too. A process
  killed without running its exit handlers leaves the file; the next run takes it over.
"""

from __future__ import annotations

import atexit
import contextlib
import fcntl
import json
import logging
import os
import socket
import time
from collections.abc import Callable, Iterator
from dataclasses import asdict, dataclass
from datetime import datetime
from pathlib import Path

#: The lock file, relative to the working directory (beside Snakemake's own metadata).
LOCK_NAME = Path(".snakemake") / "hugomap.lock"

_log = logging.getLogger(__name__)


class SweepLocked(RuntimeError):
    """Another sweep holds the working directory's lock (or its owner cannot be checked);
    the message names the owner and says how to proceed."""


@dataclass(frozen=True)
class Owner:
    """Who holds a lock: ``host``, ``pid``, ``since`` (ISO time the lock was taken),
    ``proc_start`` (the process's start, clock ticks after boot; None where ``/proc`` is
    missing), ``boot_id`` (None likewise) and ``command`` (its command line)."""

    host: str
    pid: int
    since: str
    proc_start: int | None
    boot_id: str | None
    command: str

    def describe(self) -> str:
        """The owner in words: process, host, since when, command."""
        cmd = f"; command: {self.command}" if self.command else ""
        return f"process {self.pid} on host {self.host}, since {self.since}{cmd}"


_held: dict[Path, Owner] = {}  # the locks this process holds: absolute path -> its record


def _proc_start(pid: int) -> int | None:
    """Start time of process ``pid`` in clock ticks after boot (``/proc/<pid>/stat`` field
    22), or None if it cannot be read."""
    try:
        stat = Path(f"/proc/{pid}/stat").read_text()
        return int(stat.rsplit(")", 1)[1].split()[19])
    except (OSError, IndexError, ValueError):
        return None


def _boot_id() -> str | None:
    """This boot's id (Linux), or None."""
    try:
        return Path("/proc/sys/kernel/random/boot_id").read_text().strip() or None
    except OSError:
        return None


def _command(pid: int) -> str:
    """Command line of process ``pid`` (``/proc/<pid>/cmdline``), or ``""``."""
    try:
        raw = Path(f"/proc/{pid}/cmdline").read_bytes()
    except OSError:
        return ""
    return " ".join(a.decode(errors="replace") for a in raw.split(b"\0") if a)


def _pid_exists(pid: int) -> bool:
    """Whether a process ``pid`` exists on this host (``os.kill(pid, 0)``; a process of
    another user exists too)."""
    if pid <= 0:
        return False
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True
    return True


def this_process() -> Owner:
    """The owner record of the calling process, taking the lock now."""
    pid = os.getpid()
    return Owner(
        host=socket.gethostname(),
        pid=pid,
        since=datetime.now().astimezone().isoformat(timespec="seconds"),
        proc_start=_proc_start(pid),
        boot_id=_boot_id(),
        command=_command(pid),
    )


def owner_state(owner: Owner) -> str:
    """``"alive"``, ``"dead"`` or ``"foreign"`` (another host: cannot be checked).

    On this host the owner is alive if its process id exists and, where recorded and
    readable, has the recorded start time and the machine the recorded boot id; a process id
    that exists with another start time is a new process that reused the number. Without
    ``/proc`` an existing process id counts as alive."""
    if owner.host != socket.gethostname():
        return "foreign"
    boot = _boot_id()
    if owner.boot_id and boot and owner.boot_id != boot:
        return "dead"  # the machine rebooted since
    if not _pid_exists(owner.pid):
        return "dead"
    start = _proc_start(owner.pid)
    if owner.proc_start is not None and start is not None and start != owner.proc_start:
        return "dead"  # the process id was reused
    return "alive"


def read_owner(path: str | os.PathLike) -> Owner | None:
    """The owner recorded in lock file ``path``; None if the file is missing, or not a lock
    record (empty, cut short, foreign)."""
    try:
        data = json.loads(Path(path).read_text())
        return Owner(
            host=str(data["host"]),
            pid=int(data["pid"]),
            since=str(data["since"]),
            proc_start=None if data.get("proc_start") is None else int(data["proc_start"]),
            boot_id=data.get("boot_id"),
            command=str(data.get("command", "")),
        )
    except (OSError, ValueError, TypeError, KeyError):
        return None


@contextlib.contextmanager
def _guard(path: Path, timeout: float = 30.0) -> Iterator[None]:
    """An exclusive ``flock`` on ``<path>.guard`` for the check-and-take of the lock; held a
    few milliseconds by whoever has it, so waiting ``timeout`` seconds in vain means a
    process stopped while holding it (``SweepLocked``)."""
    fd = os.open(f"{path}.guard", os.O_RDWR | os.O_CREAT, 0o666)
    try:
        t0 = time.monotonic()
        while True:
            try:
                fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
                break
            except BlockingIOError:
                if time.monotonic() - t0 > timeout:
                    raise SweepLocked(
                        f"{path}.guard stayed locked for {timeout:g} s: a sweep in this folder "
                        "is stopped while taking or releasing its lock (resume it, or end it)"
                    ) from None
                time.sleep(0.02)
        yield
    finally:
        os.close(fd)  # closing releases the flock


def _refusal(path: Path, owner: Owner, state: str) -> str:
    if state == "alive":
        return (
            f"another sweep runs in this folder: {owner.describe()} (lock {path}). Wait "
            "for it to end or stop it (`python -m hugomap status` shows its jobs), then run "
            "the same command again; a dry run (-n) is not locked."
        )
    return (
        f"the sweep lock {path} belongs to {owner.describe()}, which cannot be checked from "
        f"host {socket.gethostname()}. If that sweep still runs, wait for it to end. If it "
        f"is gone (a lost node, a killed job), remove the lock and run again: rm {path}"
    )


def acquire(
    path: str | os.PathLike | None = None,
    *,
    log: Callable[[str], object] | None = None,
    at_exit: bool = True,
) -> Owner:
    """Take the sweep lock ``path`` (default ``LOCK_NAME`` in the working directory) for this
    process and return its owner record.

    Refused with ``SweepLocked`` (naming the owner) if a live process on this host holds it,
    or a process on another host; a dead owner's lock, or this process's own from an
    earlier run (the Python API), is taken over, with a line to ``log`` (default: this
    module's logger). ``at_exit``: release the lock when the process exits."""
    lock = Path(path if path is not None else LOCK_NAME).absolute()
    say = log if log is not None else _log.warning
    lock.parent.mkdir(parents=True, exist_ok=True)
    me = this_process()
    with _guard(lock):
        while True:
            try:
                fd = os.open(lock, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o644)
            except FileExistsError:
                pass
            else:
                with os.fdopen(fd, "w") as fh:
                    fh.write(json.dumps(asdict(me), indent=1) + "\n")
                    fh.flush()
                    os.fsync(fh.fileno())
                break
            owner = _read_settled(lock)
            if owner is None and not lock.exists():
                continue  # released meanwhile (by a process on another host)
            if owner is None:
                raise SweepLocked(
                    f"the sweep lock {lock} is not a lock record (empty or damaged). If no "
                    f"sweep runs in this folder, remove it and run again: rm {lock}"
                )
            mine = (owner.host, owner.pid, owner.proc_start) == (
                me.host,
                me.pid,
                me.proc_start,
            )
            state = "dead" if mine else owner_state(owner)
            if state != "dead":
                raise SweepLocked(_refusal(lock, owner, state))
            what = "this process's earlier run" if mine else "a sweep that is gone"
            say(f"taking over the sweep lock {lock} of {what}: {owner.describe()}")
            with contextlib.suppress(FileNotFoundError):
                os.unlink(lock)
    if at_exit and lock not in _held:
        atexit.register(release, lock)
    _held[lock] = me
    return me


def _read_settled(lock: Path, tries: int = 5, wait: float = 0.2) -> Owner | None:
    """``read_owner``, retried a few times: a lock from another host may be mid-write there
    (the guard's flock need not reach across hosts)."""
    for i in range(tries):
        owner = read_owner(lock)
        if owner is not None or not lock.exists():
            return owner
        if i < tries - 1:
            time.sleep(wait)
    return None


def release(path: str | os.PathLike | None = None) -> bool:
    """Remove the sweep lock ``path`` (default: every lock this process took) if this
    process holds it and the file still names it; True if one was removed. Safe to call
    twice (the Snakefile's onsuccess or onerror, then ``atexit``)."""
    if path is None:
        return any([release(p) for p in list(_held)])
    lock = Path(path).absolute()
    me = _held.pop(lock, None)
    if me is None or not lock.parent.is_dir():
        return False
    with _guard(lock):
        if read_owner(lock) != me:
            return False  # taken over meanwhile (its owner judged this one dead): not ours
        with contextlib.suppress(FileNotFoundError):
            os.unlink(lock)
    return True
