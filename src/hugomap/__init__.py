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


def _lock_cache_saves() -> None:
    """Serialise numba's cache writes across processes: each save (read the index, pick a
    file number for a new signature, write index and data) runs under an flock on the
    folder's ``.lock``. Two processes saving new signatures of one kernel at once both
    read the same index, pick the same number, and the last index and the last data file
    need not be the same process's, so a later load runs one signature's code for the
    other's (numba 0.68's ``IndexDataCacheFile.save``). Loads stay unlocked: numba
    replaces each file atomically. A numba without that class keeps its own behaviour."""
    try:
        import fcntl

        from numba.core.caching import IndexDataCacheFile
    except ImportError:  # no POSIX locks, or numba's cache moved: as numba does it
        return
    save = IndexDataCacheFile.save
    if getattr(save, "_hugomap_locked", False):
        return

    def locked_save(self, key, data):
        os.makedirs(self._cache_path, exist_ok=True)
        with open(os.path.join(self._cache_path, ".lock"), "a") as fh:
            fcntl.flock(fh, fcntl.LOCK_EX)
            save(self, key, data)

    locked_save._hugomap_locked = True
    IndexDataCacheFile.save = locked_save


# A user's own NUMBA_CACHE_DIR wins. numba reads the variable when it is first imported; if
# it was imported before hugomap, its config is set too (it is read when a kernel is
# decorated), or the kernels would load stale caches from __pycache__ (seen: a segfault).
if "NUMBA_CACHE_DIR" not in os.environ:
    os.environ["NUMBA_CACHE_DIR"] = _numba_cache_dir()
    if "numba" in sys.modules:
        sys.modules["numba"].config.CACHE_DIR = os.environ["NUMBA_CACHE_DIR"]
_lock_cache_saves()
