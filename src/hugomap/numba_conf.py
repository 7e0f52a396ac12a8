"""Numba flags, in one place (PySDM habit).

``cache=True`` matters here: every Snakemake job is a fresh Python process, so without an
on-disk cache every job would recompile every kernel. ``fastmath`` lets LLVM vectorise the
branch-free pair loops; it is given as a flag set without ``nnan``/``ninf``, because with those
LLVM may delete the ``x != x`` and ``isinf`` tests that stop an unstable run with status
``nan``. ``error_model='numpy'`` removes the division-by-zero checks.
Set ``NUMBA_DISABLE_JIT=1`` to run every kernel as plain Python (the unit tests do).
"""

from __future__ import annotations

import functools
import hashlib
import os
from pathlib import Path

import numba
from numba.core import caching

# numba's OpenMP threads spin while they wait for the next parallel loop (GNU libgomp's
# default). When another process holds one of the cores (a second Snakemake job, a test
# beside a run), a spinning thread delays every barrier by a scheduler slice: 400 steps of
# 8,000 LJ atoms on 2 threads took 9.5 s instead of 0.85 s with the other core busy. Passive
# waiting costs a thread wake-up per loop (tens of µs). libgomp reads the variable when it is
# loaded, at the first parallel loop; a user's own setting wins.
os.environ.setdefault("OMP_WAIT_POLICY", "PASSIVE")

PACKAGE = Path(__file__).resolve().parent


@functools.cache
def cache_dir() -> str:
    """The folder hugomap's kernels are cached in: ``$XDG_CACHE_HOME/hugomap`` (default
    ``~/.cache/hugomap``) ``/numba-<hash of every source file>-t<NUMBA_NUM_THREADS>``."""
    # numba's cache=True only notices edits to a kernel's own file, not to the kernels it
    # calls from other files (numba#1833): a stale cache then runs old neighbour-list code
    # silently. Keying the cache folder on a hash of every source file makes any edit
    # compile afresh.
    h = hashlib.sha256()
    for f in sorted(PACKAGE.rglob("*.py")):
        h.update(f.read_bytes())
    base = Path(os.environ.get("XDG_CACHE_HOME", Path.home() / ".cache"))
    # One folder per thread count too: processes with different NUMBA_NUM_THREADS (a 1-thread
    # Snakemake job beside a 2-thread pytest) compiling at once wrote entries with the same
    # file names for different code into one folder, and a later load segfaulted.
    threads = os.environ.get("NUMBA_NUM_THREADS", str(os.cpu_count() or 1))
    return str(base / "hugomap" / f"numba-{h.hexdigest()[:16]}-t{threads}")


class HugomapCacheLocator(caching._SourceFileBackedLocatorMixin, caching._CacheLocator):
    """numba's cache locator for hugomap's own kernels: those defined in a file of this
    package are cached under ``cache_dir()``, laid out as numba lays out ``NUMBA_CACHE_DIR``.

    The rule: only hugomap's kernels are redirected, and only while numba has no cache
    folder of its own (``numba.config.CACHE_DIR``, from ``NUMBA_CACHE_DIR``): a user's own
    setting wins for every kernel. numba has no per-function cache folder, and setting
    ``NUMBA_CACHE_DIR`` on import (as hugomap did) sent the importing program's own kernels,
    and every child process's, into hugomap's folder; a locator asked first, that declines
    every other file, leaves them where numba would put them. Without it numba would cache
    hugomap's kernels in the package's ``__pycache__``, keyed on each kernel's own file only
    (stale caches were seen to segfault)."""

    def __init__(self, py_func, py_file: str) -> None:
        self._py_file = py_file
        self._lineno = py_func.__code__.co_firstlineno
        self._cache_path = os.path.join(cache_dir(), self.get_suitable_cache_subpath(py_file))

    def get_cache_path(self) -> str:
        return self._cache_path

    @classmethod
    def from_function(cls, py_func, py_file: str):
        if numba.config.CACHE_DIR or not Path(py_file).resolve().is_relative_to(PACKAGE):
            return None  # numba's own locators decide
        return super().from_function(py_func, py_file)


# Asked first, before numba's own locators (every kernel module imports this one before it
# decorates its kernels, which is when numba picks a locator).
if HugomapCacheLocator not in caching.CacheImpl._locator_classes:
    caching.CacheImpl._locator_classes.insert(0, HugomapCacheLocator)

FASTMATH: set[str] = {"nsz", "arcp", "contract", "afn", "reassoc"}
JIT_FLAGS: dict = {"cache": True, "fastmath": FASTMATH, "error_model": "numpy", "nogil": True}
PARALLEL_FLAGS: dict = {**JIT_FLAGS, "parallel": True}


def njit(func):
    """Compile ``func`` serially with the project's flags."""
    return numba.njit(**JIT_FLAGS)(func)


def pjit(func):
    """Compile ``func`` with ``parallel=True`` (``prange`` loops run on numba's threads)."""
    return numba.njit(**PARALLEL_FLAGS)(func)


prange = numba.prange


def num_threads() -> int:
    """Number of numba threads in use (1 when the JIT is disabled)."""
    try:
        return int(numba.get_num_threads())
    except Exception:  # pragma: no cover - numba without threading layer
        return 1
