"""Every failure mode of the stability map is detected and labelled, not written as a point
real runs of the stages on a 1D CSPH window, pushed into each failure.

Set-up: 1D copper without strength (200 particles of 10 µm), u_p = 1000 m/s, the window
(100 dx, front at 0.6 L) cut by ``window_start`` with ``window.start_offset = 0.02``: a frame
2 % slower than the loading stage's D guess, so the front runs at ~110 m/s through the
window until a scheme corrects it. Forced failures, one per cause (``failures.FAILURES``):

- AMW β = 3: each shift overshoots by 2×, the slopes alternate and grow → ``diverged``;
- AMW β = 2: each shift reverses the front speed exactly → ``oscillating``;
- AMW β = 0.05 over 3 windows: the slope stays significant → ``never_steady``;
- (``too_noisy`` cannot be forced here: the window counts particles by the fraction of their
  extent inside it, so ω of this deterministic solver resolves the front even in 1-ns
  windows, measured ``ok``; it fires on noisy ω, tested in
  tests/unit/test_window_methods.py);
- MW with gains 10 and 3: the first correction throws the front out → ``front_left_window``;
- the dichotomy with a ±1 m/s bracket and no expansion: both trials run the same way →
  ``bracket_not_found``;
- one particle's velocity set to NaN in the saved window → the solver stops: ``nan``
  (class "unstable solver").

Each point file must carry the status, its diagnostic and no value (D, P NaN); the campaign
dataset built from them must label each with the class and cause of ``FAILURES`` and give no
error. (That the detectors fire on the right signals is tested on exact synthetic fronts in
tests/unit/test_window_methods.py and test_dichotomy.py; here they fire in real runs.)
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest
import xarray as xr

from hugomap import stages as ps
from hugomap.campaign import campaign_dataset
from hugomap.config import validate_config
from hugomap.failures import FAILURES
from hugomap.sph.window import SPHWindow
from hugomap.stages import aggregate

pytestmark = pytest.mark.slow
UP, OFFSET = 1000.0, 0.98


def _base(**window) -> dict:
    return {
        "solver": "csph", "dim": 1, "schemes": ["amw", "mw", "dichotomy"],
        "material": {"strength": {"model": "none"}},
        "sample": {"length": 2e-3, "dx": 1e-5},
        "shock": {"u_p": [UP], "load_fraction": 0.45, "sample_every": 5},
        "window": {"length": 1e-3, "front_fraction": 0.6, "calm_windows": 2,
                   "max_windows": 12, "average_time": 1e-6, **window},
    }  # fmt: skip


def _scene(**window) -> dict:
    scene = validate_config({"scenes": {"cu": _base(**window)}})["scenes"]["cu"]
    scene["name"] = "cu"
    return scene


@pytest.fixture(scope="module")
def windows(tmp_path_factory) -> dict[str, Path]:
    """The window checkpoint in the offset frame, and a copy with one NaN velocity."""
    d = tmp_path_factory.mktemp("fail")
    scene = _scene(start_offset=1.0 - OFFSET)
    ps.prepare_sample(scene, d / "sample.nc")
    ps.load_to_target(d / "sample.nc", scene, UP, d / "loaded.nc")
    ps.window_start(d / "loaded.nc", scene, UP, d / "shifted.nc")
    ds = xr.load_dataset(d / "shifted.nc")
    assert ds.attrs["status"] == "ok", ds.attrs.get("diagnostic")
    keep = ("stage", "u_p", "scene_config", "status", "D_guess", "omega_signal", "pole", "cost")
    attrs = {k: ds.attrs[k] for k in keep}
    win = SPHWindow.from_dataset(ds, d / "shifted.nc")
    # the offset frame: u_in = -(1 - start_offset) D_guess
    assert win.u_in == pytest.approx(-OFFSET * float(ds.attrs["D_guess"]), rel=1e-12)
    mobile = np.flatnonzero(~win.sim.frozen) if win.sim.frozen is not None else [0]
    win.sim.state.v[mobile[len(mobile) // 2], 0] = np.nan
    win.save(d / "nan.nc", attrs=attrs)
    return {"shifted": d / "shifted.nc", "nan": d / "nan.nc"}


CONTROL = {
    "diverged": ("amw", {"amw": {"beta": 3.0}}),
    "oscillating": ("amw", {"amw": {"beta": 2.0}}),
    "never_steady": ("amw", {"amw": {"beta": 0.05}, "max_windows": 3}),
    "front_left_window": ("mw", {"mw": {"gain_rate": 10.0, "gain_position": 3.0}}),
}


def _assert_failed_point(path: Path, status: str) -> xr.Dataset:
    ds = xr.load_dataset(path)
    assert str(ds["status"].values) == status, str(ds["diagnostic"].values)
    assert str(ds["diagnostic"].values), "a failure without a diagnostic"
    assert math.isnan(float(ds["D"])) and math.isnan(float(ds["P"]))
    # the layout of a usable point: the errors are there, NaN (io.dataset.ALWAYS_WITH_ERR)
    assert math.isnan(float(ds["D_err"])) and math.isnan(float(ds["P_err"]))
    return ds


def _dichotomy(window: Path, scene: dict, d: Path) -> Path:
    """The dichotomy's loop as the workflow runs it: state, trials, state …, point."""
    trials: list[str] = []
    prev = None
    for k in range(4):
        state = ps.dichotomy_state(window, scene, k, prev, trials, d / f"state{k}.json")
        s = json.loads(Path(state).read_text())
        if s["done"]:
            break
        new = [str(ps.dichotomy_trial(window, scene, str(state), i, d / f"trial{k}_{i}.json"))
               for i in range(len(s["pending"]))]  # fmt: skip
        trials += new
        prev = str(state)
    return ps.dichotomy_point(window, scene, UP, str(state), trials, d / "dichotomy.nc")


def test_every_failure_is_labelled_and_has_no_value(windows, tmp_path):
    files: dict[str, list[str]] = {}
    for status, (scheme, window) in CONTROL.items():
        out = ps.control_point(windows["shifted"], _scene(**window), UP,
                               tmp_path / f"{status}.nc", scheme)  # fmt: skip
        _assert_failed_point(out, status)
        files[status] = [str(out)]
    dich = _scene(dichotomy={"half_width": 1.0, "tolerance": 0.5, "max_expansions": 0,
                             "trial_time": 1e-6})  # fmt: skip
    out = _dichotomy(windows["shifted"], dich, tmp_path)
    _assert_failed_point(out, "bracket_not_found")
    files["bracket_not_found"] = [str(out)]
    out = ps.control_point(windows["nan"], _scene(), UP, tmp_path / "nan.nc", "amw")
    _assert_failed_point(out, "nan")
    files["nan"] = [str(out)]
    assert FAILURES["nan"][0] == "unstable solver"

    # the campaign dataset: one resolution per failure, each labelled by FAILURES
    cfg = {"campaign": {"cases": {"cu": {
        "scene": _base(), "resolutions": {s.replace("_", ""): {} for s in files},
    }}}}  # fmt: skip
    cfg = validate_config(cfg)
    ref = tmp_path / "reference.nc"
    ps.reference_stage(cfg["scenes"]["cu__nan"], ref)
    aggs = {f"cu__{s.replace('_', '')}": aggregate(f, str(ref), cfg, s, tmp_path / f"{s}_agg.nc")
            for s, f in files.items()}  # fmt: skip
    ds = campaign_dataset(cfg, aggs)
    assert ds.sizes["point"] == len(files)
    for i in range(ds.sizes["point"]):
        status = str(ds["status"].values[i])
        assert status.replace("_", "") == str(ds["variant"].values[i])
        assert (str(ds["failure_class"].values[i]), str(ds["cause"].values[i])) == FAILURES[status]
        assert math.isnan(float(ds["err_D"].values[i])) and math.isnan(float(ds["err_P"][i]))
    assert np.isnan(ds["setting_err_D"].values).all()
    assert not ds["setting_pareto_D"].values.any()
