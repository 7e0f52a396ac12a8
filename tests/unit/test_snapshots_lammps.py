"""MD snapshots and trajectories read back by ASE, LAMMPS data files out of and into MD
states, the window stages' snapshot hook, and the command line's user verbs.

References: ASE's extended-XYZ reader (``ase.io.read(..., index=":")``: positions, cell,
pbc, per-atom arrays, velocities from ``momenta``/``masses``); the LAMMPS ``read_data``
format (title line, header counts and box, ``Masses``, ``Atoms # atomic``, ``Velocities``),
parsed here by a reader written from that description alone. Reals are written with 17
significant digits, so every float64 value comes back exactly.
"""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest
import xarray as xr

from hugomap.cli import main
from hugomap.md.backend import BACKEND as MD
from hugomap.md.lammps_data import LammpsDataError
from hugomap.md.potential import LJParams
from hugomap.md.sample import data_state, fcc_state
from hugomap.md.simulation import MDSimulation

CELLS, RHO, T0 = (6, 4, 4), 0.8, 1.0


def _scene(**shock) -> dict:
    return {"name": "lj", "shock": {"bin_width": 1.0, "snapshots": True, "snapshot_every": 0,
                                    **shock}}  # fmt: skip


@pytest.fixture(scope="module")
def sim() -> MDSimulation:
    s = MDSimulation(fcc_state(CELLS, RHO, T0, 3, periodic_x=False), LJParams(), 0.004)
    s.advance(20)
    return s


def _ase_frames(path: Path):
    ase_io = pytest.importorskip("ase.io")
    return ase_io.read(path, index=":", format="extxyz")


def test_md_snapshot_read_by_ase(sim, tmp_path):
    MD.extras(sim, tmp_path / "piston.nc", _scene(), 1.5, {})
    path = tmp_path / "piston_snapshot.extxyz"
    assert sorted(p.name for p in tmp_path.iterdir()) == [path.name]  # no trajectory asked
    (atoms,) = _ase_frames(path)
    s = sim.state
    assert np.array_equal(atoms.positions, s.x)
    assert np.array_equal(atoms.get_velocities(), s.v)  # masses 1: momenta = velo
    assert np.array_equal(atoms.arrays["velo"], s.v)  # OVITO's Velocity column
    assert np.array_equal(np.diag(atoms.cell.array)[1:], s.L[1:])
    assert atoms.cell.array[0, 0] >= s.x[:, 0].max() - s.x[:, 0].min()
    assert list(atoms.pbc) == [False, True, True]
    assert np.array_equal(atoms.arrays["id"], s.ids) and not atoms.arrays["frozen"].any()
    assert atoms.info["length_unit"] == "sigma" and atoms.info["time_unit"] == "tau"
    assert "P_xx:epsilon/sigma^3" in atoms.info["units"] and atoms.info["u_p"] == 1.5
    assert atoms.info["Time"] == s.time and atoms.info["run"] == "piston"
    # the frame of the velocities: the piston's, the far wall moving at -frame_velocity
    assert atoms.info["velocity_frame"] == "piston"
    assert atoms.info["frame_velocity"] == pytest.approx(-s.walls0[3], abs=1e-12)
    # Per-atom P_xx averages to the profile's P_xx in every bin; e to its e.
    from hugomap.particles.profiles import fields_from_sums

    prof = fields_from_sums(sim.profile_sums(1.0), s.L[1] * s.L[2] * 1.0)
    b = np.floor(s.x[:, 0]).astype(int)
    for k in np.unique(b)[1:-1]:
        sel = b == k
        assert atoms.arrays["P_xx"][sel].mean() == pytest.approx(prof["Pxx"][k], rel=1e-12)
        assert atoms.arrays["e"][sel].mean() == pytest.approx(prof["e"][k], rel=1e-12)
    assert np.all(atoms.arrays["T"] >= 0)


def test_md_trajectory_every_n_samples(sim, tmp_path):
    scene = _scene(snapshot_every=2)
    prof = MD.profile(sim, scene)
    times = []
    for _ in range(5):
        sim.advance(2)
        prof.sums(sim)
        times.append(sim.time)
    MD.window_extras(sim, tmp_path / "amw.nc", scene, 1.5, "amw", {})
    frames = _ase_frames(tmp_path / "amw_trajectory.extxyz")
    assert [f.info["Time"] for f in frames] == [times[1], times[3]]
    assert all(f.info["run"] == "trajectory" for f in frames)
    assert frames[-1].arrays["velo"].shape == (sim.state.n, 3)
    assert _ase_frames(tmp_path / "amw_snapshot.extxyz")[0].info["run"] == "amw"
    # a loading run takes no trajectory (its stage ends in a checkpoint, not in extras)
    sim.loading = True
    try:
        assert not hasattr(MD.profile(sim, scene), "_trajectory")
    finally:
        del sim.loading


def _parse_lammps(path: Path) -> dict:
    """A LAMMPS data file per the read_data description: title, header, sections."""
    lines = [ln.split("#")[0].strip() for ln in path.read_text().splitlines()[1:]]
    head, sections, name = {}, {}, None
    for ln in lines:
        if not ln:
            continue
        if re.fullmatch(r"[A-Z][A-Za-z ]*", ln):
            name = ln
            sections[name] = []
        elif name is None:
            words = ln.split()
            if words[-1].endswith("hi"):
                head[words[-2][0]] = (float(words[0]), float(words[1]))
            else:
                head[" ".join(words[1:])] = int(words[0])
        else:
            sections[name].append(ln.split())
    return {"head": head, "sections": sections}


def test_lammps_round_trip(sim, tmp_path):
    ckpt = sim.save(tmp_path / "sample.nc")
    assert main(["export-lammps", str(ckpt), str(tmp_path / "sample.data")]) == 0
    f = _parse_lammps(tmp_path / "sample.data")
    s = sim.state
    assert f["head"]["atoms"] == s.n and f["head"]["atom types"] == 2
    assert f["head"]["x"] == (0.0, s.L[0]) and f["head"]["z"] == (0.0, s.L[2])
    assert f["sections"]["Masses"] == [["1", "1"], ["2", "1"]]
    atoms = np.array(f["sections"]["Atoms"], dtype=float)
    vel = np.array(f["sections"]["Velocities"], dtype=float)
    assert np.array_equal(atoms[:, 0], s.ids + 1) and np.all(atoms[:, 1] == 1)
    assert np.array_equal(atoms[:, 2:5], s.x) and np.array_equal(vel[:, 1:], s.v)
    back = data_state(tmp_path / "sample.data")
    order = np.argsort(back.ids)
    ref = np.argsort(s.ids)
    assert np.array_equal(back.ids[order], s.ids[ref])
    assert np.array_equal(back.x[order], s.x[ref]) and np.array_equal(back.v[order], s.v[ref])
    assert np.array_equal(back.L, s.L) and np.array_equal(back.walls0, [0, 0, s.L[0], 0])


def test_lammps_frozen_atoms_are_type_2_and_refused_as_a_sample(sim, tmp_path):
    ds = sim.to_dataset()
    ids = ds["ids"].values.copy()
    ids[:5] = -1 - np.arange(5)
    ds = ds.assign(ids=(("atom",), ids))
    ds.attrs.pop("checksum")
    from hugomap.io.checkpoint import seal_checkpoint

    seal_checkpoint(ds).to_netcdf(tmp_path / "w.nc", engine="netcdf4")
    assert main(["export-lammps", str(tmp_path / "w.nc"), str(tmp_path / "w.data")]) == 0
    atoms = np.array(_parse_lammps(tmp_path / "w.data")["sections"]["Atoms"], dtype=float)
    assert np.all(atoms[:5, 1] == 2) and np.all(atoms[5:, 1] == 1)
    assert np.unique(atoms[:, 0]).size == sim.state.n and atoms[:5, 0].min() > ids.max() + 1
    with pytest.raises(LammpsDataError, match="type 2"):
        data_state(tmp_path / "w.data")


def test_lammps_title_line_is_short_numbers(tmp_path, capsys):
    """The title line carries step, time and walls as short plain numbers (no numpy reprs,
    no float noise such as 7.380000000000001), on one line."""
    from hugomap.md.lammps_data import checkpoint_to_data, read_data

    ds = xr.Dataset(
        {"x": (("atom", "xyz"), [[1.0, 0.5, 0.5], [2.0, 1.5, 1.5]]),
         "v": (("atom", "xyz"), np.zeros((2, 3))), "ids": (("atom",), np.array([0, 1])),
         "L": (("xyz",), np.array([10.0, 3.0, 3.0])),
         "walls0": (("wall",), np.array([0.1 + 0.2, -0.5, 10.0, 1.0 / 3.0]))},
        attrs={"time": 7.38 + 1e-15, "step": 1845},
    )  # fmt: skip
    assert repr(ds.attrs["time"]) == "7.380000000000001"
    title = checkpoint_to_data(ds).splitlines()[0]
    assert title.endswith(
        "step 1845 time 7.38 tau, walls at x = 0.3 + -0.5 t and 10 + 0.333333 t"
    ), title
    assert "np." not in title and "0000000" not in title
    path = tmp_path / "t.data"
    path.write_text(checkpoint_to_data(ds))
    assert read_data(path).title == title


def test_export_refuses_a_foreign_file(tmp_path, capsys):
    xr.Dataset({"a": ("x", [1.0])}).to_netcdf(tmp_path / "f.nc", engine="netcdf4")
    assert main(["export-lammps", str(tmp_path / "f.nc"), str(tmp_path / "f.data")]) == 2
    assert "f.nc" in capsys.readouterr().err and not (tmp_path / "f.data").exists()


def _md_config(**sample) -> dict:
    return {"scenes": {"lj": {"solver": "md", "phase": "liquid", "schemes": ["piston"],
                              "sample": {"rho0": RHO, "T0": T0, "cells": list(CELLS), **sample},
                              "shock": {"u_p": [1.0], "gap": 2.0, "rear_margin": 2.0}}}}  # fmt: skip


def test_data_file_is_validated_before_any_job(sim, tmp_path):
    from hugomap.config import ConfigError, validate_config
    from hugomap.md.lammps_data import checkpoint_to_data, write_data

    good = write_data(tmp_path / "good.data", checkpoint_to_data(sim.to_dataset()))
    cfg = validate_config(_md_config(data_file=str(good)))
    assert cfg["scenes"]["lj"]["sample"]["data_file"] == str(good)
    with pytest.raises(ConfigError, match=r"sample\.data_file = .*missing\.data.*cannot be read"):
        validate_config(_md_config(data_file=str(tmp_path / "missing.data")))
    (tmp_path / "bad.data").write_text("title\n\n12 atoms\n")
    with pytest.raises(ConfigError, match=r"sample\.data_file.*bad\.data"):
        validate_config(_md_config(data_file=str(tmp_path / "bad.data")))
    with pytest.raises(ConfigError, match=r"sample\.cells"):  # the box is not the cells'
        validate_config(_md_config(data_file=str(good), rho0=0.85))


def test_window_stages_call_the_snapshot_hook(tmp_path, monkeypatch):
    from hugomap import stages as ps
    from hugomap.config import validate_config
    from hugomap.synthetic.backend import BACKEND as SYN

    calls = []
    monkeypatch.setattr(SYN, "window_extras", lambda win, out, scene, u_p, scheme, info:
                        calls.append((Path(out).name, scheme, u_p)), raising=False)  # fmt: skip
    sc = {"solver": "synthetic", "shock": {"u_p": [1.0]},
          "material": {"rho0": 1.0, "c0": 4.0, "s": 1.5, "P0": 0.0, "E0": 0.0}}  # fmt: skip
    scene = validate_config({"schemes": ["amw", "mw"], "scenes": {"x": sc}})["scenes"]["x"]
    scene["name"] = "x"
    ps.prepare_sample(scene, tmp_path / "sample.nc")
    ps.load_to_target(tmp_path / "sample.nc", scene, 1.0, tmp_path / "loaded.nc")
    ps.window_start(tmp_path / "loaded.nc", scene, 1.0, tmp_path / "window.nc")
    for scheme in ("amw", "mw"):
        ps.control_point(tmp_path / "window.nc", scene, 1.0, tmp_path / f"{scheme}.nc", scheme)
    assert calls == [("amw.nc", "amw", 1.0), ("mw.nc", "mw", 1.0)]


def test_cli_version_help_and_groups(capsys):
    from hugomap import __version__

    with pytest.raises(SystemExit) as exc:
        main(["--version"])
    assert exc.value.code == 0 and capsys.readouterr().out.strip() == f"hugomap {__version__}"
    assert main([]) == 0
    out = capsys.readouterr().out
    user, stages = out.split("user commands:")[1].split("workflow stages")
    assert "\n  export-lammps " in user and "\n  check-config " in user
    assert "\n  piston " not in user and "\n  piston " in stages
    assert "\n  dichotomy-trial " in stages and "\n  status " not in stages
