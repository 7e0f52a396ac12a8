"""A YAML syntax error in a config: where the user learns its line and column.

- In the default config (``config/config.yaml``, read by the Snakefile): the Snakefile's
  message gives them (Snakemake's own does not; the Snakefile reads the file again with
  ``hugomap.config.load_config``).
- In a ``--configfile``: Snakemake parses it before it reads the Snakefile, and its message
  has no line; the README's way to find it, ``--verbose``, shows the line in the traceback
  (``python -m hugomap check-config`` is tested in tests/unit/test_config_fuzz.py).
"""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
BROKEN = "schemes: [piston\nscenes:\n  x: {}\n"  # the list is not closed: line 2, column 7


def _snakemake(cwd: Path, snakefile: Path, *args: str) -> subprocess.CompletedProcess:
    env = dict(os.environ, PYTHONPATH=str(ROOT / "src"))
    cmd = [sys.executable, "-m", "snakemake", "-s", str(snakefile), "-n", "--cores", "1",
           "--workflow-profile", str(ROOT / "workflow" / "profiles" / "default"), *args]  # fmt: skip
    return subprocess.run(
        cmd, capture_output=True, text=True, env=env, cwd=cwd, stdin=subprocess.DEVNULL,
        timeout=300,
    )  # fmt: skip


def test_default_config_syntax_error_names_line(tmp_path: Path) -> None:
    """A copy of the workflow whose default config is broken."""
    shutil.copy(ROOT / "Snakefile", tmp_path / "Snakefile")
    shutil.copytree(ROOT / "workflow", tmp_path / "workflow")
    (tmp_path / "config").mkdir()
    bad = tmp_path / "config" / "config.yaml"
    bad.write_text(BROKEN)
    r = _snakemake(tmp_path, tmp_path / "Snakefile")
    out = r.stdout + r.stderr
    assert r.returncode != 0
    assert f"invalid config: {bad}: not valid YAML (line 2, column 7)" in out, out[-2000:]


def test_configfile_syntax_error_line_with_verbose(tmp_path: Path) -> None:
    bad = tmp_path / "bad.yaml"
    bad.write_text(BROKEN)
    r = _snakemake(tmp_path, ROOT / "Snakefile", "--configfile", str(bad), "--verbose")
    out = r.stdout + r.stderr
    assert r.returncode != 0
    assert f'in "{bad}", line 2, column 7' in out, out[-2000:]
