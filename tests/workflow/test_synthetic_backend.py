"""A third backend touches only its own folder and one registry line: the synthetic test
backend (``hugomap.synthetic``: a front with an exact answer) runs through the same stages
and through Snakemake as the real solvers.

Reference: the model's own Hugoniot, D = c0 + s u_p with the jump states exact
(``synthetic.model.shocked_state``). Tolerances: the window schemes hold the front to the
slope resolution of their fits on a noiseless signal, and their D is the frame speed plus
L dω/dt, exact to 1e-9 relative (AMW, dichotomy; MW to its settled amplitude); the piston's
D is the Theil–Sen slope of the tracked front, whose sub-bin refinement weighs the straddling
bin by mass rather than length (a bias that oscillates as the front crosses each bin, up to
1e-4 relative here), so 1e-3; jump residuals of exact states vanish to 1e-4 (the piston's
front error enters D).
"""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import xarray as xr

from hugomap import registry
from hugomap.synthetic.model import shocked_state

ROOT = Path(__file__).resolve().parents[2]
CONFIG = ROOT / "tests" / "workflow" / "tiny_synthetic" / "config.yaml"
C0, S = 4.0, 1.5


def test_the_backend_lives_in_its_folder_and_one_registry_line() -> None:
    assert registry.REGISTRY["synthetic"] == "hugomap.synthetic"
    src = ROOT / "src" / "hugomap"
    mentions = [p for p in src.rglob("*.py") if "synthetic" in p.read_text()
                and "synthetic" not in p.relative_to(src).parts[0]
                and p.name not in ("registry.py", "synthetic.py")]  # fmt: skip
    # methods/synthetic.py is the methods' own test front the backend builds on
    assert mentions == [], mentions


def _snakemake(workdir: Path) -> subprocess.CompletedProcess:
    env = dict(os.environ, PYTHONPATH=str(ROOT / "src"))
    cmd = [sys.executable, "-m", "snakemake", "-s", str(ROOT / "Snakefile"), "--directory",
           str(workdir), "--configfile", str(CONFIG), "--cores", "2"]  # fmt: skip
    return subprocess.run(cmd, capture_output=True, text=True, env=env, cwd=workdir, timeout=900)


@pytest.mark.slow
def test_synthetic_sweep_through_snakemake(tmp_path: Path) -> None:
    r = _snakemake(tmp_path)
    assert r.returncode == 0, r.stdout[-3000:] + r.stderr[-3000:]
    with xr.open_dataset(tmp_path / "results" / "hugoniot" / "exact.nc") as ds:
        ds = ds.load()
    assert list(ds["scheme"].values) == ["piston", "amw", "mw", "dichotomy"]
    for scheme in ("piston", "amw", "mw", "dichotomy"):
        p = ds.sel({"scheme": scheme})
        assert list(p["status"].values) == ["ok"], (scheme, p["diagnostic"].values)
        u = p["u_p_set"].values if scheme != "piston" else p["u_p"].values
        D_exact = C0 + S * u
        tol = 1e-3 if scheme == "piston" else 1e-9
        assert np.allclose(p["D"].values, D_exact, rtol=tol), (scheme, p["D"].values, D_exact)
        _, rho, P, _ = shocked_state(1.0, 0.0, 0.0, C0, S, u)
        assert np.allclose(p["rho"].values, rho, rtol=1e-9)
        assert np.allclose(p["P"].values, P, rtol=1e-9)
        for k in ("mass", "momentum", "energy"):
            assert np.all(np.abs(p[f"residual_{k}"].values) < 1e-4), (scheme, k)
        # the scene's target, recorded with the errors reached (config: 0.1 %)
        assert np.all(p["target_D"].values == 0.001) and np.all(p["target_P"].values == 0.001)
        assert np.all(p["D_rel_err"].values <= 0.001), (scheme, p["D_rel_err"].values)
        assert np.all(p["P_rel_err"].values <= 0.001), (scheme, p["P_rel_err"].values)
        assert np.all(np.isfinite(p["time_to_target"].values))
    assert np.allclose(ds["ref_D"].values, C0 + S * ds["ref_u_p"].values)
    for png in ("exact_PV.png", "exact_D_up.png"):
        assert (tmp_path / "results" / "figures" / png).stat().st_size > 10_000
