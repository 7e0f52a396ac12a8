"""hugomap: shock Hugoniots from molecular dynamics and contact SPH in moving windows."""

import hashlib
import os
import sys
from pathlib import Path

__version__ = "0.1.0"


def _numba_cache_dir() -> str:
    # numba's cache=True only notices edits to a kernel's own file, not to the kernels it
    # calls from other files (numba#1833): a stale cache then runs old neighbour-list code
    # silently. Keying the cache folder on a hash of every source file makes any edit
    # compile afresh.
    h = hashlib.sha256()
    for f in sorted(Path(__file__).parent.rglob("*.py")):
        h.update(f.read_bytes())
    base = Path(os.environ.get("XDG_CACHE_HOME", Path.home() / ".cache"))
    # One folder per thread count too: processes with different NUMBA_NUM_THREADS (a 1-thread
    # Snakemake job beside a 2-thread pytest) compiling at once wrote entries with the same
    # file names for different code into one folder, and a later load segfaulted.
    threads = os.environ.get("NUMBA_NUM_THREADS", str(os.cpu_count() or 1))
    return str(base / "hugomap" / f"numba-{h.hexdigest()[:16]}-t{threads}")


def _claim_slot(folder: str) -> str:
    """The first of ``folder``-s0, -s1, … whose lock no other live process holds, locked
    for this process's life (the lock goes with the process, however it ends). numba's
    cache is not safe for two writers: two processes compiling different signatures of one
    kernel into a fresh folder each numbered its entry 0, the last index won, and a later
    load ran the other's code (a segfault in the neighbour-list build under pytest-xdist).
    One writer per folder; a process finds a warm folder whenever one is free."""
    try:
        import fcntl
    except ImportError:  # no POSIX locks: one folder, as before
        return folder
    for k in range(64):
        slot = f"{folder}-s{k}"
        os.makedirs(slot, exist_ok=True)
        fd = os.open(os.path.join(slot, ".lock"), os.O_CREAT | os.O_RDWR, 0o644)
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError:
            os.close(fd)
            continue
        _SLOT_LOCKS.append(fd)
        return slot
    return f"{folder}-p{os.getpid()}"


_SLOT_LOCKS: list[int] = []
# Set by hugomap when it chose the folder: a child process (a Snakemake job a test started,
# an MPI rank) inherits NUMBA_CACHE_DIR from it and must claim its own slot.
_OURS = "HUGOMAP_NUMBA_CACHE_DIR"

# A user's own NUMBA_CACHE_DIR wins. numba reads the variable when it is first imported; if
# it was imported before hugomap, its config is set too (it is read when a kernel is
# decorated), or the kernels would load stale caches from __pycache__ (seen: a segfault).
if "NUMBA_CACHE_DIR" not in os.environ or os.environ["NUMBA_CACHE_DIR"] == os.environ.get(_OURS):
    os.environ["NUMBA_CACHE_DIR"] = os.environ[_OURS] = _claim_slot(_numba_cache_dir())
    if "numba" in sys.modules:
        sys.modules["numba"].config.CACHE_DIR = os.environ["NUMBA_CACHE_DIR"]
