"""A moving window holds a crystal's shock: the small version of ``config/lj_fcc.yaml``.

The LJ FCC crystal (ρ0 1.05, T0 0.1) shocked along [100] at u_p = 3 σ/τ, a 4 × 4-cell
cross-section: AMW in a 50-σ window cut from the loading checkpoint, its slab 12 σ behind
the front (past the plastic wave's relaxation zone, 15-20 σ at u_p = 3 on a 6 × 6 section,
shorter here where the front is thinner) and the state ahead read 4 σ ahead of it
(``shock.ahead_gap``).

What must hold, and why these bounds:
- the inflow continues the lattice (``MDWindow.from_piston``'s registry for a crystal): the
  state ahead of the front is the pole, ρ within 1 % (the slab's bins count whole planes a/2
  = 0.78 σ apart against 1-σ bins: up to one plane over the 12 bins read, ~1 %), P and E
  within 1 % of the jump;
- the front is held and the wave is steady on the Rayleigh line: the mass and momentum
  residuals close within 1 % (``shock.residual_tol``), as they do on the 6 × 6 section
  (0.02 % and 0.01 % at u_p = 3);
- the crystal keeps a shear stress behind the front (P_xx above the mean lateral stress),
  and its D lies 3 % of the 6 × 6 section's window point, 14.79 ± 0.03 σ/τ: a small
  cross-section shifts the plastic wave by about that much.
"""

from __future__ import annotations

from pathlib import Path

import pytest
import xarray as xr

from hugomap import stages
from hugomap.config import validate_config

pytestmark = pytest.mark.slow
UP = 3.0


def _scene() -> dict:
    cfg = {
        "threads": 1,
        "schemes": ["amw"],
        "scenes": {
            "xtal": {
                "solver": "md",
                "phase": "crystal",
                "potential": {"rc": 2.5, "shift": True, "skin": 0.3},
                "sample": {"rho0": 1.05, "T0": 0.1, "cells": [60, 4, 4], "seed": 2,
                           "equilibrate_time": 2.0, "pole_time": 1.0},
                "shock": {"u_p": [UP], "dt": 0.003, "sample_every": 20, "gap": 12.0,
                          "ahead_gap": 4.0, "avg_length": 12.0, "load_fraction": 0.5,
                          "rear_margin": 6.0},
                "window": {"length": 50.0, "front_fraction": 0.6, "outflow_gap": 4.0,
                           "settle_time": 3.0, "window_time": 1.5, "calm_windows": 2,
                           "max_windows": 8, "average_time": 4.0, "sample_every": 20,
                           "reservoir_length": 0.0},
                "reference": {"compressions": [1.1, 1.2], "cells": 4},
            }
        },
    }  # fmt: skip
    scene = validate_config(cfg)["scenes"]["xtal"]
    scene["name"] = "xtal"
    return scene


def test_amw_holds_a_crystal_shock_with_the_lattice_fed_in(tmp_path: Path) -> None:
    scene = _scene()
    stages.prepare_sample(scene, tmp_path / "sample.nc")
    stages.load_to_target(tmp_path / "sample.nc", scene, UP, tmp_path / "loaded.nc")
    stages.window_start(tmp_path / "loaded.nc", scene, UP, tmp_path / "window.nc")
    stages.control_point(tmp_path / "window.nc", scene, UP, tmp_path / "amw.nc", "amw")
    with xr.open_dataset(tmp_path / "amw.nc") as ds:
        r = {k: float(ds[k]) for k in ds.data_vars if ds[k].ndim == 0 and ds[k].dtype.kind == "f"}
        status, diagnostic = str(ds["status"].values), str(ds["diagnostic"].values)
    assert status in ("ok", "not_converged"), (status, diagnostic)
    jump = r["P"] - r["P0"]
    assert abs(r["ahead_rho"] / r["rho0"] - 1) < 0.01, r["ahead_rho"]
    assert abs(r["ahead_P"] - r["P0"]) < 0.01 * jump, (r["ahead_P"], r["P0"])
    assert abs(r["ahead_E"] - r["E0"]) < 0.01 * (r["E"] - r["E0"]), (r["ahead_E"], r["E0"])
    assert abs(r["residual_mass"]) < 0.01 and abs(r["residual_momentum"]) < 0.01, diagnostic
    assert r["shear_stress"] > 0.02 * jump
    assert abs(r["D"] / 14.79 - 1) < 0.03, r["D"]
