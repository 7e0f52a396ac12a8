"""``window.start_offset`` (stability maps): the saved MD window is the same window in a frame
off by start_offset·D_guess, so the front runs at about that speed until a scheme corrects it.

Two windows are cut from one loading checkpoint of the tiny LJ scene (tests/workflow/tiny),
with start_offset 0 and 0.03. ``window_start`` is deterministic (seeded reservoir, the same
settle run), and a Galilean shift after settling changes only x velocities and the boundary
speeds, so the two windows must agree to round-off in positions and differ by exactly
0.03·D_guess in every mobile velocity, u_in and u_out.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import xarray as xr
import yaml

from hugomap import stages
from hugomap.config import validate_config
from hugomap.md.window import MDWindow

pytestmark = pytest.mark.slow
ROOT = Path(__file__).resolve().parents[2]
EPS, UP = 0.03, 2.5


def _scene(offset: float) -> dict:
    cfg = yaml.safe_load((ROOT / "tests/workflow/tiny/config.yaml").read_text())
    cfg["scenes"]["tiny"]["window"]["start_offset"] = offset
    scene = validate_config(cfg)["scenes"]["tiny"]
    scene["name"] = "tiny"
    return scene


def test_offset_window_is_the_same_window_in_a_shifted_frame(tmp_path: Path) -> None:
    scene = _scene(0.0)
    stages.prepare_sample(scene, tmp_path / "sample.nc")
    stages.load_to_target(tmp_path / "sample.nc", scene, UP, tmp_path / "loaded.nc")
    wins = {}
    for eps in (0.0, EPS):
        out = tmp_path / f"window_{eps:g}.nc"
        stages.window_start(tmp_path / "loaded.nc", _scene(eps), UP, out)
        with xr.open_dataset(out) as ds:
            ds.load()
        assert ds.attrs["status"] == "ok", ds.attrs.get("diagnostic")
        assert float(ds.attrs["start_offset"]) == eps
        wins[eps] = (MDWindow.from_dataset(ds), float(ds.attrs["D_guess"]))
    (w0, d0), (w1, d1) = wins[0.0], wins[EPS]
    assert d0 == d1
    du = EPS * d0
    assert w1.u_in == pytest.approx(w0.u_in + du, abs=1e-12)
    assert w1.u_out == pytest.approx(w0.u_out + du, abs=1e-12)
    s0, s1 = w0.sim.state, w1.sim.state
    np.testing.assert_array_equal(s0.x, s1.x)
    np.testing.assert_allclose(s1.v[:, 0] - s0.v[:, 0], du, atol=1e-12)
    np.testing.assert_array_equal(s1.v[:, 1:], s0.v[:, 1:])
    # the front runs toward the inflow: material enters slower than the shock moves
    assert -w1.u_in < d0
