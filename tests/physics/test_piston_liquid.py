"""A piston shock in the LJ liquid: jump conditions and agreement with equilibrium MD.

References and tolerances:
- The Rankine–Hugoniot jump conditions (mass, momentum, energy) are exact for a steady
  front between uniform states, and the shocked slab is at rest relative to the piston;
  the measured residuals carry statistical errors. On this 40,000-atom sample at seed 11
  their propagated standard errors (``residual_*_err``, with the errors that hold against
  replicas) are 0.2 % (mass), 1.2 % (momentum), 0.9 % (energy) and 0.7 % (flow); over seeds
  11, 12, 13 the largest |residual| was 1.5 % (energy). So the 2 % bound is met with room at about 2.5 sigma of the noisiest
  one, while a broken front tracker, stress or energy accounting (errors of 5 % and more)
  fails it. A 6,000-atom sample was too small: its energy error was 1.1–1.5 %, and one seed
  failed the bound at −2.3 % (CI run of 0d15548).
- The equilibrium-MD Hugoniot (hugomap.md.reference: NVT states at which
  E − E0 = ½(P + P0)(V0 − V)) for the same potential (rc = 2.5 σ, shifted) and pole: a shocked
  simple fluid is hydrostatic, so its P at the measured V must agree within 2 % (the project's
  bound; the reference's own statistical error is about 0.5 %).
"""

from __future__ import annotations

import copy
from pathlib import Path

import numpy as np
import pytest
import xarray as xr

from hugomap import stages
from hugomap.config import validate_config
from hugomap.md.potential import LJParams
from hugomap.md.reference import interpolate_P, reference_hugoniot

SCENE = {
    "solver": "md",
    "phase": "liquid",
    "potential": {"rc": 2.5, "shift": True, "skin": 0.3},
    "sample": {
        "rho0": 0.80,
        "T0": 2.0,
        "cells": [100, 10, 10],
        "seed": 11,
        "equilibrate_time": 6.0,
        "pole_time": 4.0,
    },
    "shock": {"u_p": [2.0], "dt": 0.002, "gap": 6.0, "avg_length": 24.0, "load_fraction": 0.3},
}


@pytest.fixture(scope="module")
def point(tmp_path_factory) -> xr.Dataset:
    cfg = validate_config({"scenes": {"liq": copy.deepcopy(SCENE)}})
    scene = dict(cfg["scenes"]["liq"], name="liq")
    d: Path = tmp_path_factory.mktemp("piston")
    stages.prepare_sample(scene, d / "sample.nc")
    stages.load_to_target(d / "sample.nc", scene, 2.0, d / "loaded.nc")
    stages.piston_point(d / "loaded.nc", scene, 2.0, d / "point.nc")
    with xr.open_dataset(d / "point.nc") as ds:
        return ds.load()


@pytest.mark.slow
def test_jump_conditions_hold_within_2_percent(point: xr.Dataset) -> None:
    # The 2 % bound (module docstring) and 3 errors, for the three jump conditions and the
    # slab's flow. Not the point's own 1 % residual_tol: this sample's momentum noise is
    # ±1.2 %, so its status depends on the trajectory (on one numba thread seed 11 gave
    # momentum +1.02 ± 1.24 %, not_converged; on two it had passed).
    diag = str(point["diagnostic"].values)
    assert str(point["status"].values) in ("ok", "not_converged"), diag
    for k in ("mass", "momentum", "energy", "flow"):
        r, e = float(point[f"residual_{k}"]), float(point[f"residual_{k}_err"])
        assert abs(r) < 0.02, (k, r, diag)
        assert abs(r) <= max(3.0 * e, 1e-4), (k, r, e, diag)
    # The shocked liquid is hydrostatic: transverse stresses equal the longitudinal one
    # within their statistical errors (a few tenths of a percent; 2 % bound).
    P = float(point["P"])
    for k in ("Pyy", "Pzz"):
        assert abs(float(point[k]) / P - 1) < 0.02


@pytest.mark.slow
def test_agrees_with_equilibrium_reference_within_2_percent(point: xr.Dataset) -> None:
    rho = float(point["rho"])
    ratio = rho / SCENE["sample"]["rho0"]
    ref = reference_hugoniot(
        SCENE["sample"]["rho0"], SCENE["sample"]["T0"], LJParams(rc=2.5, shift=True, skin=0.3),
        compressions=np.array([ratio - 0.04, ratio + 0.04]), cells=(6, 6, 6), dt=0.004,
        n_equil=500, n_prod=3000, seed=5,
    )  # fmt: skip
    P_ref = float(interpolate_P(ref, float(point["V"])))
    assert abs(float(point["P"]) / P_ref - 1) < 0.02, (float(point["P"]), P_ref)
