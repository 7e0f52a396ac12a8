"""The validation campaign through Snakemake (``snakemake campaign``) on a tiny 1D copper
case (``tests/workflow/tiny_campaign``), then the analysis notebook on its results.

Reference: D = c0 + s u_p = 5430 m/s and P = rho0 D u_p, exact for the Mie–Grüneisen EOS
referenced to that line. Tolerance 1 % on the RMS errors of every setting: the CSPH solver's
own lag at 1000 m/s is −0.4 % at 10 µm (tests/workflow/test_sph_workflow.py) and grows with
dx, to about −0.6 % at 15 µm; a window point adds its statistical error (~0.05 %).
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import xarray as xr

from hugomap.failures import FAILURES

ROOT = Path(__file__).resolve().parents[2]
CONFIG = ROOT / "tests" / "workflow" / "tiny_campaign" / "config.yaml"


def snakemake(workdir: Path, *targets: str) -> subprocess.CompletedProcess:
    env = dict(os.environ, PYTHONPATH=str(ROOT / "src"))
    # targets before --configfile, which takes every word after it as a file
    cmd = [sys.executable, "-m", "snakemake", "-s", str(ROOT / "Snakefile"), "--directory",
           str(workdir), "--cores", "2", *targets, "--configfile", str(CONFIG)]  # fmt: skip
    return subprocess.run(cmd, capture_output=True, text=True, env=env, cwd=workdir, timeout=600)


@pytest.mark.slow
def test_tiny_campaign_end_to_end(tmp_path: Path) -> None:
    r = snakemake(tmp_path, "campaign")
    assert r.returncode == 0, r.stdout[-3000:] + r.stderr[-3000:]
    res = tmp_path / "results"
    # the target built only what the campaign needs: no history figures
    assert not list((res / "figures").glob("*/*_history.png"))
    ds = xr.load_dataset(res / "campaign" / "tiny.nc")
    assert ds.sizes["point"] == 2 * 2 + 1  # (piston, amw) x (fine, coarse) + the beta point
    assert set(ds["scene"].values) == {"cu__fine", "cu__coarse", "cu__beta1"}
    for k in ("err_D", "err_P", "cpu_s", "u_p_over_c0"):
        assert "units" in ds[k].attrs
    assert json.loads(ds.attrs["cases"])["cu"]["c0"] == 3940.0
    assert ds["u_p_over_c0"].values == pytest.approx(1000.0 / 3940.0)
    # every setting of the resolution study converged on the model's Hugoniot
    assert ds.sizes["setting"] == 4
    for i in range(ds.sizes["setting"]):
        what = (str(ds["setting_scheme"].values[i]), str(ds["setting_variant"].values[i]))
        assert ds["setting_n_usable"].values[i] == 1, what
        assert abs(float(ds["setting_err_D"].values[i])) < 0.01, what
        assert abs(float(ds["setting_err_P"].values[i])) < 0.01, what
        assert float(ds["setting_cpu_s"].values[i]) > 0.0, what
    assert ds["setting_pareto_D"].values.sum() >= 1
    # the stability point: AMW with beta = 2.5, started 2 % off, overshoots by 1.5x per
    # window (error ~ |1 - beta|^k): a control failure, labelled, with no value
    beta = ds.isel(point=list(ds["axis"].values).index("beta"))
    assert float(beta["axis_value"]) == 2.5
    status = str(beta["status"].values)
    assert FAILURES.get(status, ("",))[0] == "control", status
    assert (str(beta["failure_class"].values), str(beta["cause"].values)) == FAILURES[status]
    assert np.isnan(float(beta["err_D"])) and np.isnan(float(beta["err_P"]))
    assert json.loads(ds.attrs["axes"])["cu"]["beta"]["base_row"] == 0
    for png in ("tiny_speed_accuracy.png", "tiny_stability.png"):
        assert (res / "campaign" / png).stat().st_size > 10_000
    # `hugomap status` with the campaign config lists the campaign's scenes
    st = subprocess.run([sys.executable, "-m", "hugomap", "status", "--results", str(res),
                         "--config", str(CONFIG), "--json"], capture_output=True, text=True,
                        env=dict(os.environ, PYTHONPATH=str(ROOT / "src")))  # fmt: skip
    assert st.returncode == 0, st.stderr
    scenes = {s["scene"]: s["counts"] for s in json.loads(st.stdout)["scenes"]}
    assert set(scenes) == {"cu__fine", "cu__coarse", "cu__beta1"}
    assert all(c["done"] + c["failed"] == c["total"] for c in scenes.values())
    _notebook_redraws_the_campaign(res)


def _notebook_redraws_the_campaign(results: Path) -> None:
    """The analysis notebook on the campaign's results: every cell runs, the chart and the
    map are redrawn, the table of fronts names settings of the campaign."""
    import jupytext
    import nbclient

    nb = jupytext.read(ROOT / "notebooks" / "hugoniot_analysis.py")
    env_old = os.environ.get("HUGOMAP_RESULTS")
    os.environ["HUGOMAP_RESULTS"] = str(results)
    try:
        nbclient.NotebookClient(nb, timeout=300, kernel_name="python3",
                                resources={"metadata": {"path": str(ROOT)}}).execute()  # fmt: skip
    finally:
        if env_old is None:
            del os.environ["HUGOMAP_RESULTS"]
        else:
            os.environ["HUGOMAP_RESULTS"] = env_old
    for png in ("tiny_speed_accuracy.png", "tiny_stability.png"):
        assert (results / "figures" / "notebook" / png).stat().st_size > 10_000, png
    fronts = next(c for c in nb.cells if c.source.rstrip().endswith("\nfronts"))
    assert "cu" in fronts.outputs[0]["data"]["text/plain"]
