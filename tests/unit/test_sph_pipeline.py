"""The CSPH backend's pure parts (``sph.backend``) and the CSPH checkpoint.

References: the exact Hugoniot of the Mie–Grüneisen EOS referenced to D = c0 + s u_p (copper,
LASL) satisfies the three jump conditions exactly (residuals 0 to round-off); a slab's mean
density in 2D counts the pores (Σm over the geometric area); the front of a sharp step lies on
the step (the change-point tracker's refinement is exact for a step); the SI units table; a
CSPH checkpoint continues bit for bit (exact equality with the uninterrupted run).
"""

from __future__ import annotations

import json

import numpy as np
import pytest
import xarray as xr

from hugomap.analysis.porous import COPPER, porous_hugoniot_from_up, snowplow_hugoniot
from hugomap.analysis.shock import (
    bin_edges,
    jump_residual_errors,
    jump_residuals,
    slab_state,
    track_front,
)
from hugomap.io.dataset import POINT_VARS
from hugomap.md.backend import MDBackend
from hugomap.sph.backend import CSPHBackend, SPHProfile
from hugomap.stages import reference_stage

RHO0, C0, S = 8930.0, 3940.0, 1.49


@pytest.mark.parametrize("up", [100.0, 1000.0, 2000.0])
def test_exact_hugoniot_has_zero_residuals(up):
    D = C0 + S * up
    r = jump_residuals(RHO0, 0.0, 0.0, D, up, RHO0 * D / (D - up), RHO0 * D * up, 0.5 * up * up)
    assert max(abs(v) for v in r.values()) < 1e-12
    # from a precursor state: the jump from (1) to (2) with D relative to the lab
    u1, P1, rho1 = 20.0, 0.3e9, RHO0 * 1.004
    E1 = 0.5 * u1 * u1
    j = rho1 * (D - u1)
    rho2 = j / (D - up)
    P2 = P1 + j * (up - u1)
    E2 = E1 + 0.5 * (P1 + P2) * (1 / rho1 - 1 / rho2)
    r2 = jump_residuals(rho1, P1, E1, D, up, rho2, P2, E2, u1=u1)
    assert max(abs(v) for v in r2.values()) < 1e-12


def test_residual_errors_propagate():
    D, up = 5430.0, 1000.0
    vals = dict(rho1=RHO0, P1=0.0, E1=0.0, D=D, u=up, rho=RHO0 * D / (D - up),
                P=RHO0 * D * up, E=0.5 * up * up, u1=0.0)  # fmt: skip
    r = jump_residual_errors(vals, {"D": 0.01 * D})
    # d(mass residual)/dD · σ_D: ρ2(D − u)/(ρ1 D) changes by about u/(D − u)·σ_D/D
    assert r["mass"] == pytest.approx(0.01 * up / (D - up), rel=0.05)
    assert r["energy"] == 0.0


def test_slab_state_counts_pores_in_2d():
    """Two bins of width 1e-5 m and depth 4e-5 m; particles fill 3/4 of the area."""
    w, depth, rho_s = 1e-5, 4e-5, 8930.0
    vol = 0.75 * w * depth  # particle volume per bin (pores: the rest)
    m = rho_s * vol
    sums = np.zeros((2, 10))
    sums[:, 0], sums[:, 1], sums[:, 2] = 3, m, vol
    sums[:, 3] = m * 50.0  # u = 50 m/s
    sums[:, 6] = vol * -1e9  # σ_xx = −1 GPa in the matrix
    sums[:, 8] = vol * 0.9e9
    p2 = SPHProfile(0.0, w, depth)
    s2 = slab_state(p2, sums, bin_edges(p2, 2), 0.0, 2e-5)
    assert s2["rho"] == pytest.approx(0.75 * rho_s)
    assert s2["P"] == pytest.approx(0.75e9)  # the section's mean stress: pores carry none
    assert s2["u"] == pytest.approx(50.0)
    p1 = SPHProfile(0.0, w, None)  # 1D meaning: the matrix itself
    s1 = slab_state(p1, sums, bin_edges(p1, 2), 0.0, 2e-5)
    assert s1["rho"] == pytest.approx(rho_s) and s1["P"] == pytest.approx(1e9)


def test_front_of_a_step_lies_on_the_step():
    """Bins 0-3 move at u_p = 100 m/s, bins 4-9 are at rest: the front is at the edge of
    bin 4; in the window frame (u_out = −4000 behind, u_in = −5000 ahead) the same."""
    for behind, ahead in ((100.0, 0.0), (-4000.0, -5000.0)):
        sums = np.zeros((10, 10))
        sums[:, 0], sums[:, 1], sums[:, 2] = 2, 1.0, 1e-4
        sums[:, 3] = np.where(np.arange(10) < 4, behind, ahead)
        prof = SPHProfile(0.0, 1.0, None)
        assert track_front(prof, sums, 0.0, 10.0, behind, ahead) == pytest.approx(4.0)


def test_units_tables():
    md = MDBackend().units
    assert md.point is POINT_VARS and md.axes["velocity"] == "sigma tau^-1"
    u = CSPHBackend().units
    point, pole, axes = u.point, u.pole, u.axes
    assert point["D"][0] == "m s-1" and point["P"][0] == "Pa" and point["rho"][0] == "kg m-3"
    assert point["V"][0] == "m3 kg-1" and point["E"][0] == "J kg-1"
    assert "mass density" in point["rho"][1] and pole["rho0"][0] == "kg m-3"
    assert point["P_eos"][0] == "Pa" and axes == {"velocity": "m s-1", "time": "s", "length": "m"}
    assert not any("sigma" in u or "epsilon" in u for u, _ in (*point.values(), *pole.values()))


def _scene(porous: bool) -> dict:
    from hugomap.config import validate_config

    sample = {"length": 2e-3, "dx": 1e-5}
    if porous:
        sample.update(width=4e-4, porous={"distention": 1.35, "pore_radius": [3e-5, 6e-5]})
    sc = {"solver": "csph", "dim": 2 if porous else 1, "schemes": ["piston"], "sample": sample,
          "shock": {"u_p": [100.0, 500.0]}}  # fmt: skip
    return validate_config({"scenes": {"cu": sc}})["scenes"]["cu"]


def test_reference_stage_solid_and_porous(tmp_path):
    ds = xr.load_dataset(reference_stage(_scene(False), tmp_path / "solid.nc"))
    u = ds["u_p"].values
    assert np.allclose(ds["D"].values, C0 + S * u)
    assert np.allclose(ds["P"].values, RHO0 * (C0 + S * u) * u)
    assert ds["P"].attrs["units"] == "Pa" and "solid" in ds.attrs["reference_model"]
    # the scene's own u_p are points of the curve (the grid steps by 625/60 m/s)
    assert {100.0, 500.0} <= set(u.tolist()) and np.all(np.diff(u) > 0)
    dp = xr.load_dataset(reference_stage(_scene(True), tmp_path / "porous.nc"))
    h = porous_hugoniot_from_up(dp["u_p"].values, 1.35, COPPER)
    assert np.allclose(dp["P"].values, h.P) and np.allclose(dp["D"].values, h.D)
    sp = snowplow_hugoniot(dp["u_p"].values, 1.35, RHO0)
    assert np.allclose(dp["snowplow_P"].values, sp.P)
    assert dp.attrs["alpha"] == 1.35 and json.loads(dp.attrs["scene_config"])["dim"] == 2


def test_csph_checkpoint_continues_bit_for_bit(tmp_path):
    from hugomap.eos import copper
    from hugomap.sph import checkpoint as ckpt
    from hugomap.sph.simulation import CSPHSimulation
    from hugomap.sph.state import SPHState
    from hugomap.strength import copper as cu_strength

    n, dx = 60, 1e-5
    st = SPHState(x=(np.arange(n) + 0.5) * dx, v=np.zeros(n), m=RHO0 * dx, rho=RHO0, e=0.0)
    sim = CSPHSimulation(st, copper(), cu_strength(), walls=(0.0, 300.0, None, 0.0),
                         dev_mean=True)  # fmt: skip
    sim.advance(10)
    path = ckpt.save_simulation(sim, tmp_path / "c.nc", attrs={"stage": "test"})
    again, _ = ckpt.load_simulation(path)
    assert again.dev_mean and not again.has_wall[1] and again.strength.name == "von_mises"
    sim.advance(15)
    again.advance(15)
    for k in ("x", "v", "rho", "e", "S", "eps_p"):
        assert np.array_equal(getattr(sim.state, k), getattr(again.state, k)), k
    with xr.open_dataset(path) as ds:
        bad = ds.load()
    bad["sim_e"].values[3] += 1.0
    with pytest.raises(Exception, match="checksum"):
        ckpt.from_dataset(bad, "altered.nc")
