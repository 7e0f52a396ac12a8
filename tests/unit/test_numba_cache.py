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
