"""The CSPH workflow, run for real: Snakemake on a tiny 1D copper scene (``tests/workflow/
tiny_cu``: 300 particles of 10 µm, no strength, u_p = 1000 m/s, piston and AMW).

Reference: D = c0 + s u_p = 5430 m/s, exact for the Mie–Grüneisen EOS referenced to that
line; tolerance 1 % (the project's requirement), measured −0.4 % (piston) and −0.4 % (AMW). Also the
layout: the aggregate has dims scheme × u_p with SI units on every variable, the model's
reference Hugoniot (ref_*), the snapshot of the piston run in extended XYZ.
"""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest
import xarray as xr

from hugomap.failures import FAILURES

ROOT = Path(__file__).resolve().parents[2]
TINY_CU = ROOT / "tests" / "workflow" / "tiny_cu" / "config.yaml"


def snakemake(workdir: Path, *args: str, config: Path = TINY_CU) -> subprocess.CompletedProcess:
    env = dict(os.environ, PYTHONPATH=str(ROOT / "src"))
    cmd = [sys.executable, "-m", "snakemake", "-s", str(ROOT / "Snakefile"), "--directory",
           str(workdir), "--configfile", str(config), "--cores", "2", *args]  # fmt: skip
    return subprocess.run(cmd, capture_output=True, text=True, env=env, cwd=workdir, timeout=600)


@pytest.mark.slow
def test_tiny_copper_sweep_end_to_end(tmp_path: Path) -> None:
    r = snakemake(tmp_path)
    assert r.returncode == 0, r.stdout[-3000:] + r.stderr[-3000:]
    agg = tmp_path / "results" / "hugoniot" / "tiny_cu.nc"
    with xr.open_dataset(agg, engine="netcdf4") as ds:
        ds = ds.load()
    assert ds["P"].dims == ("scheme", "u_p")
    assert list(ds["scheme"].values) == ["piston", "amw"]
    assert ds["u_p"].attrs["units"] == "m s-1"  # UDUNITS (CF-1.11)
    units = {"D": "m s-1", "rho": "kg m-3", "V": "m3 kg-1", "P": "Pa", "P_eos": "Pa",
             "E_minus_E0": "J kg-1", "rho0": "kg m-3", "ref_P": "Pa", "ref_V": "m3 kg-1",
             "cpu_s": "s"}  # fmt: skip
    for name, unit in units.items():
        assert ds[name].attrs.get("units") == unit, (name, ds[name].attrs)
        assert ds[name].attrs.get("long_name"), name
    assert "sigma" not in str({k: v.attrs.get("units") for k, v in ds.data_vars.items()})
    us = 3940.0 + 1.49 * 1000.0
    for scheme in ("piston", "amw"):
        d = ds.sel(scheme=scheme, u_p=1000.0)
        status = str(d["status"].values)
        assert status in {"ok", "not_converged", *FAILURES}, status
        if scheme == "piston" or status == "ok":
            assert status == "ok", str(d["diagnostic"].values)
            assert abs(float(d["D"]) / us - 1.0) < 0.01, float(d["D"])
            assert abs(float(d["P"]) / (8930.0 * us * 1000.0) - 1.0) < 0.02
    point = tmp_path / "results" / "tiny_cu" / "up1000"
    assert (point / "piston_snapshot.extxyz").read_text().splitlines()[0].strip() == "300"
    for png in ("tiny_cu_PV.png", "tiny_cu_D_up.png"):
        assert (tmp_path / "results" / "figures" / png).stat().st_size > 10_000
    r2 = snakemake(tmp_path, "-n")
    assert "Nothing to be done" in r2.stdout + r2.stderr
