"""Where numba caches kernels once hugomap is imported (``numba_conf.HugomapCacheLocator``).

Each case runs in a fresh interpreter (numba reads ``NUMBA_CACHE_DIR`` once, when it is
imported) with its own ``XDG_CACHE_HOME``: importing hugomap sets no environment variable;
hugomap's kernels are cached in hugomap's folder, a program's own ``cache=True`` kernel in
numba's usual place beside its file; a user's ``NUMBA_CACHE_DIR`` takes every kernel.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

SCRIPT = """
import json, os, sys
import hugomap
env_after_import = os.environ.get("NUMBA_CACHE_DIR")
import numpy as np
from hugomap.eos import ideal_gas
from hugomap.numba_conf import cache_dir
import user_kernels
ideal_gas.pressure(1.0, 2.0, np.array([1.4]))
user_kernels.double(2.0)
print(json.dumps({"env": env_after_import, "cache_dir": cache_dir()}))
"""

USER_KERNELS = """
import numba


@numba.njit(cache=True)
def double(x):
    return 2.0 * x
"""


def _run(tmp_path: Path, user_cache: Path | None) -> dict:
    """Run ``SCRIPT`` in a fresh interpreter; returns what it printed."""
    (tmp_path / "user_kernels.py").write_text(USER_KERNELS)
    env = {k: v for k, v in os.environ.items() if not k.startswith("NUMBA_")}
    env.update(XDG_CACHE_HOME=str(tmp_path / "xdg"), NUMBA_NUM_THREADS="1",
               PYTHONPATH=str(tmp_path))  # fmt: skip
    if user_cache is not None:
        env["NUMBA_CACHE_DIR"] = str(user_cache)
    out = subprocess.run([sys.executable, "-c", SCRIPT], env=env, cwd=tmp_path,
                         capture_output=True, text=True, timeout=300)  # fmt: skip
    assert out.returncode == 0, out.stderr
    return json.loads(out.stdout.strip().splitlines()[-1])


def _indexes(folder: Path) -> set[str]:
    """The numba index files under ``folder``, by name."""
    return {p.name for p in folder.rglob("*.nbi")}


def test_import_sets_no_cache_dir_and_only_hugomap_kernels_use_its_own(tmp_path: Path) -> None:
    got = _run(tmp_path, None)
    assert got["env"] is None  # nothing set for the process (or its children)
    ours = Path(got["cache_dir"])
    assert ours.is_relative_to(tmp_path / "xdg" / "hugomap") and ours.name.endswith("-t1")
    hugomap_index = {n for n in _indexes(ours) if n.startswith("ideal_gas.pressure-")}
    assert len(hugomap_index) == 1, _indexes(ours)
    assert not any(n.startswith("user_kernels.") for n in _indexes(ours))
    # the program's own kernel: numba's default, the __pycache__ beside its file
    assert any(n.startswith("user_kernels.double-") for n in _indexes(tmp_path / "__pycache__"))


def test_a_users_numba_cache_dir_wins_for_every_kernel(tmp_path: Path) -> None:
    mine = tmp_path / "my_cache"
    got = _run(tmp_path, mine)
    assert got["env"] == str(mine)
    found = _indexes(mine)
    assert any(n.startswith("ideal_gas.pressure-") for n in found), found
    assert any(n.startswith("user_kernels.double-") for n in found), found
    assert not (tmp_path / "xdg").exists()


RACE = """
import os, sys, time
from hugomap.numba_conf import cache_dir
from numba.core import caching

key, hold_index, hold_data, start, go = sys.argv[1:6]
folder = os.path.join(cache_dir(), "race")
os.makedirs(folder, exist_ok=True)
# numba's save: read the index, pick a free data-file number, write the index, write the
# data; each step held back here so that two saves interleave as two compiling processes can
load_index, save_data = caching.IndexDataCacheFile._load_index, caching.IndexDataCacheFile._save_data
def slow_load(self):
    out = load_index(self)
    time.sleep(float(hold_index))
    return out
def slow_save(self, name, data):
    time.sleep(float(hold_data))
    save_data(self, name, data)
caching.IndexDataCacheFile._load_index = slow_load
caching.IndexDataCacheFile._save_data = slow_save
f = caching.IndexDataCacheFile(folder, "kernel", "stamp")
open(go + "." + key, "w").close()  # imported and ready
while not os.path.exists(go):
    time.sleep(0.01)
time.sleep(float(start))
f.save(key, "code of " + key)
"""


def test_concurrent_saves_keep_each_signature_with_its_own_code(tmp_path: Path) -> None:
    """Two processes save different signatures into one kernel's cache at once, their
    steps interleaved by holding each back (the comments below): each signature must load
    its own code. Without the folder's lock (``numba_conf._locked``) both pick
    ``kernel.1.nbc``, the index ends naming it for one signature while the file holds the
    other's code (the mismatch that segfaulted a loaded kernel)."""
    env = {**os.environ, "XDG_CACHE_HOME": str(tmp_path / "xdg")}
    env.pop("NUMBA_CACHE_DIR", None)
    script = tmp_path / "race.py"
    script.write_text(RACE)
    import time

    go = str(tmp_path / "go")
    # both imported; each reads the index and holds 0.6 s before writing it, the second
    # starting 0.3 s later (so it too reads no entry), and the first holds its data write
    # 0.6 s more: the index ends as the second wrote it, the data file as the first did
    first = subprocess.Popen([sys.executable, str(script), "A", "0.6", "0.6", "0", go], env=env)
    second = subprocess.Popen([sys.executable, str(script), "B", "0.6", "0", "0.3", go], env=env)
    deadline = time.time() + 60
    while not all(Path(f"{go}.{k}").exists() for k in "AB") and time.time() < deadline:
        time.sleep(0.01)
    Path(go).touch()
    assert first.wait(60) == 0 and second.wait(60) == 0
    check = (
        "import os, json\n"
        "from hugomap.numba_conf import cache_dir\n"
        "from numba.core import caching\n"
        "f = caching.IndexDataCacheFile(os.path.join(cache_dir(), 'race'), 'kernel', 'stamp')\n"
        "print(json.dumps({k: f.load(k) for k in ('A', 'B')}))\n"
    )
    out = subprocess.run([sys.executable, "-c", check], env=env, capture_output=True,
                         text=True, check=True).stdout  # fmt: skip
    loaded = json.loads(out)
    assert loaded == {"A": "code of A", "B": "code of B"}, loaded
