"""The numba cache: writes serialised across processes (``hugomap._lock_cache_saves``).

numba's ``IndexDataCacheFile.save`` reads the index, picks a file number for a new
signature and writes index and data; two processes doing that at once into one folder can
leave an index whose entry points at the other's code. hugomap runs each save under an
flock on the folder's ``.lock``: this test holds that lock and checks that a process
compiling a cached kernel into the folder waits for it, then saves a cache that loads."""

from __future__ import annotations

import fcntl
import os
import subprocess
import sys
import time

import hugomap  # noqa: F401  (wraps numba's cache saves)

KERNEL = """
import sys
sys.path.insert(0, sys.argv[1])
import hugomap, numba, kern
print(kern.twice(21), sum(kern.twice.stats.cache_hits.values()), flush=True)
"""
SOURCE = """
from hugomap.numba_conf import njit

@njit
def twice(x):
    return 2 * x
"""


def _run(code_dir, env):
    return subprocess.Popen([sys.executable, "-c", KERNEL, str(code_dir)], env=env,
                            stdout=subprocess.PIPE, text=True)  # fmt: skip


def test_a_cache_save_waits_for_the_folder_lock(tmp_path):
    from numba.core.caching import IndexDataCacheFile

    assert getattr(IndexDataCacheFile.save, "_hugomap_locked", False)
    code = tmp_path / "code"
    code.mkdir()
    (code / "kern.py").write_text(SOURCE)
    cache = tmp_path / "cache"
    env = {**os.environ, "NUMBA_CACHE_DIR": str(cache)}
    env.pop("NUMBA_DISABLE_JIT", None)
    # the kernel's folder under the cache root, as numba names it: created by a first run
    first = _run(code, env)
    out, _ = first.communicate(timeout=120)
    assert out.split() == ["42", "0"], out
    (folder,) = {p.parent for p in cache.rglob("*.nbi")}
    for p in folder.glob("kern.*"):
        p.unlink()  # the next run compiles and saves again
    with open(folder / ".lock", "a") as fh:
        fcntl.flock(fh, fcntl.LOCK_EX)
        proc = _run(code, env)
        time.sleep(8.0)  # far longer than compiling one small kernel takes
        assert proc.poll() is None, "the save did not wait for the lock"
        assert not list(folder.glob("kern.*.nbc"))
    out, _ = proc.communicate(timeout=120)
    assert proc.returncode == 0 and out.split()[0] == "42"
    assert list(folder.glob("kern.*.nbc"))
    # and what it saved loads: a third process hits the cache
    third = _run(code, env)
    out, _ = third.communicate(timeout=120)
    assert out.split() == ["42", "1"], out
