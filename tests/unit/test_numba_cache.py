"""The numba cache folder: one writer at a time (``hugomap._claim_slot``).

numba's on-disk cache is not safe for two processes compiling into one fresh folder (their
entries share file numbers; a later load ran the other's code and segfaulted), so each live
process holds a lock on its own slot folder; these tests check that two processes at once,
and a child that inherited its parent's folder, get different slots, and that a slot is
reused once its holder has gone."""

from __future__ import annotations

import os
import subprocess
import sys

import hugomap

CHILD = "import os, hugomap; print(os.environ['NUMBA_CACHE_DIR'])"


def _child_dir(env: dict[str, str]) -> str:
    out = subprocess.run([sys.executable, "-c", CHILD], env=env, capture_output=True, text=True,
                         check=True)  # fmt: skip
    return out.stdout.strip()


def test_a_process_beside_a_live_holder_gets_another_slot(tmp_path):
    base = str(tmp_path / "numba-x-t1")
    mine = hugomap._claim_slot(base)
    assert mine == base + "-s0"
    env = {k: v for k, v in os.environ.items() if k not in ("NUMBA_CACHE_DIR", hugomap._OURS)}
    env["XDG_CACHE_HOME"] = str(tmp_path)
    first = _child_dir(env)
    # the child's folder is keyed on the sources and threads, under the same cache root
    assert first.startswith(str(tmp_path / "hugomap" / "numba-")) and first.endswith("-s0")
    # the child has exited, so its slot is free again; held here, a child that inherited
    # this folder (hugomap set it) claims the next one
    held = hugomap._claim_slot(first[: -len("-s0")])
    assert held == first
    env.update(NUMBA_CACHE_DIR=held, **{hugomap._OURS: held})
    assert _child_dir(env) == first[: -len("-s0")] + "-s1"
    # a user's own folder wins
    env.update(NUMBA_CACHE_DIR=str(tmp_path / "mine"))
    assert _child_dir(env) == str(tmp_path / "mine")


def test_two_live_processes_never_share_a_slot(tmp_path):
    base = str(tmp_path / "numba-y-t1")
    code = (
        "import sys, time, hugomap; print(hugomap._claim_slot(sys.argv[1]), flush=True); "
        "time.sleep(3)"
    )
    procs = [subprocess.Popen([sys.executable, "-c", code, base], stdout=subprocess.PIPE,
                              text=True) for _ in range(3)]  # fmt: skip
    slots = [p.stdout.readline().strip() for p in procs]
    for p in procs:
        p.wait(timeout=60)
    assert sorted(slots) == [base + f"-s{k}" for k in range(3)]
