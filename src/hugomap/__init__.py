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


# A user's own NUMBA_CACHE_DIR wins. numba reads the variable when it is first imported; if
# it was imported before hugomap, its config is set too (it is read when a kernel is
# decorated), or the kernels would load stale caches from __pycache__ (seen: a segfault).
if "NUMBA_CACHE_DIR" not in os.environ:
    os.environ["NUMBA_CACHE_DIR"] = _numba_cache_dir()
    if "numba" in sys.modules:
        sys.modules["numba"].config.CACHE_DIR = os.environ["NUMBA_CACHE_DIR"]
