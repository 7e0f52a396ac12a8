"""Numba flags, in one place (PySDM habit).

``cache=True`` matters here: every Snakemake job is a fresh Python process, so without an
on-disk cache every job would recompile every kernel. ``fastmath`` lets LLVM vectorise the
branch-free pair loops; it is given as a flag set without ``nnan``/``ninf``, because with those
LLVM may delete the ``x != x`` and ``isinf`` tests that stop an unstable run with status
``nan``. ``error_model='numpy'`` removes the division-by-zero checks.
Set ``NUMBA_DISABLE_JIT=1`` to run every kernel as plain Python (the unit tests do).
"""

from __future__ import annotations

import os

import numba

# numba's OpenMP threads spin while they wait for the next parallel loop (GNU libgomp's
# default). When another process holds one of the cores (a second Snakemake job, a test
# beside a run), a spinning thread delays every barrier by a scheduler slice: 400 steps of
# 8,000 LJ atoms on 2 threads took 9.5 s instead of 0.85 s with the other core busy. Passive
# waiting costs a thread wake-up per loop (tens of µs). libgomp reads the variable when it is
# loaded, at the first parallel loop; a user's own setting wins.
os.environ.setdefault("OMP_WAIT_POLICY", "PASSIVE")

# LLVM at -O2 rather than numba's default -O3: the kernels run as fast (the LJ forces and
# list build, the CSPH step: benchmarks/README.md) and compile in about a tenth less time,
# which every fresh install waits for before its first run. Set before the first compile
# (the optimisation level is read then); a user's own NUMBA_OPT wins.
if "NUMBA_OPT" not in os.environ:
    try:
        numba.config.OPT = numba.core.config._OptLevel(2)
    except AttributeError:  # pragma: no cover - a numba without that class: its own level
        pass

FASTMATH: set[str] = {"nsz", "arcp", "contract", "afn", "reassoc"}
JIT_FLAGS: dict = {"cache": True, "fastmath": FASTMATH, "error_model": "numpy", "nogil": True}
PARALLEL_FLAGS: dict = {**JIT_FLAGS, "parallel": True}


def njit(func):
    """Compile ``func`` serially with the project's flags."""
    return numba.njit(**JIT_FLAGS)(func)


def ijit(func):
    """Compile ``func`` with the project's flags, inlined into its callers in numba's IR: a
    helper of a hot loop's set-up (``md.forces._gather_row``), where a call LLVM keeps cost
    its caller the proof that its scratch rows alias nothing (5-9 % of the LJ forces)."""
    return numba.njit(inline="always", **JIT_FLAGS)(func)


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
