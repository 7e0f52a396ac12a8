"""Checkpoint integrity: a format version and a SHA-256 checksum in every MD and window
checkpoint; a corrupted (flipped bytes, truncated, edited attribute, dropped variable),
foreign, outdated or newer checkpoint is refused with ``CheckpointError`` naming the file
and the problem, never used. In the piston stage, a refused periodic checkpoint of a piston run
(``<out>.part.nc``) is logged and ignored: the run restarts from the loading checkpoint.
"""

from __future__ import annotations

import json
import logging
import os
import shutil
import time
from pathlib import Path

import netCDF4
import numpy as np
import pytest
import xarray as xr
import yaml

from hugomap import stages
from hugomap.config import validate_config
from hugomap.failures import CheckpointError
from hugomap.io.checkpoint import (
    MD_CHECKPOINT,
    MD_WINDOW_CHECKPOINT,
    checkpoint_checksum,
    read_checkpoint,
)
from hugomap.md.potential import LJParams
from hugomap.md.sample import fcc_state
from hugomap.md.simulation import MDSimulation
from hugomap.md.window import MDWindow
from hugomap.particles.window import WindowGeometry
from hugomap.registry import backend_named
from hugomap.stages import piston as piston_stage
from hugomap.stages.files import history_of
from hugomap.states import Pole

from ._reference import one_numba_thread

ROOT = Path(__file__).resolve().parents[2]
STATE_VARS = ("x", "v", "f", "x_ref", "ids", "L", "periodic", "walls0", "impulse")


def _sim() -> MDSimulation:
    st = fcc_state((3, 3, 3), 0.8, 1.5, 3, periodic_x=False)
    sim = MDSimulation(st, LJParams(rc=2.2), dt=0.005, T_bath=1.2, tau_bath=0.2, seed=5)
    sim.set_walls(0.5, -0.25)
    with one_numba_thread():
        sim.advance(10)
    return sim


def _extra() -> xr.Dataset:
    """Extra variables like a piston checkpoint's history (with NaN: no front found)."""
    return xr.Dataset({"hist_front": (("sample",), np.array([1.0, np.nan, 2.5]))})


@pytest.fixture
def ckpt(tmp_path: Path) -> tuple[MDSimulation, Path]:
    sim = _sim()
    return sim, sim.save(tmp_path / "ckpt.nc", extra=_extra(), attrs={"note": "x"})


def _flip_bytes_of(path: Path, values: np.ndarray) -> None:
    """Flip one bit inside the middle finite element of an array's raw bytes in the file (a
    flip inside a NaN that leaves it NaN is not a change of value, and is not caught)."""
    raw = bytearray(path.read_bytes())
    a = np.ascontiguousarray(values)
    needle = a.tobytes()
    at = raw.find(needle)
    assert at >= 0 and raw.find(needle, at + 1) < 0, "array not stored contiguously once"
    flat = a.ravel()
    finite = np.flatnonzero(np.isfinite(flat)) if flat.dtype.kind == "f" else np.arange(flat.size)
    i = int(finite[finite.size // 2])
    raw[at + i * a.itemsize + a.itemsize // 2] ^= 0x10
    path.write_bytes(bytes(raw))


def _refused(path: Path, *fragments: str) -> CheckpointError:
    with pytest.raises(CheckpointError) as info:
        MDSimulation.load(path)
    msg = str(info.value)
    assert str(path) in msg, msg
    for f in fragments:
        assert f in msg, msg
    assert isinstance(info.value, ValueError)
    return info.value


def test_intact_checkpoint_carries_version_and_checksum(ckpt) -> None:
    sim, path = ckpt
    with xr.open_dataset(path, engine="netcdf4") as ds:
        ds.load()
    assert ds.attrs["format"] == MD_CHECKPOINT.format == "hugomap-md-checkpoint/2"
    assert ds.attrs["checksum"] == "sha256:" + checkpoint_checksum(ds)
    assert len(ds.attrs["checksum"]) == len("sha256:") + 64
    back = MDSimulation.load(path)
    for k in STATE_VARS:
        assert np.array_equal(getattr(back.state, k), getattr(sim.state, k)), k
    assert back.state.step == sim.state.step and back.state.time == sim.state.time
    # The sealed dataset is a copy: running on does not change a dataset already made.
    ds_mem = sim.to_dataset()
    with one_numba_thread():
        sim.advance(2)
    assert MDSimulation.from_dataset(ds_mem).state.step == sim.state.step - 2


@pytest.mark.parametrize("var", ["x", "v", "ids", "walls0", "hist_front"])
def test_flipped_bytes_in_a_variable_are_refused(ckpt, var: str) -> None:
    sim, path = ckpt
    values = {"hist_front": _extra()["hist_front"].values}.get(var)
    if values is None:
        values = getattr(sim.state, var)
    _flip_bytes_of(path, values)
    _refused(path, "checksum mismatch", "altered or corrupted")


@pytest.mark.parametrize(
    ("name", "value"),
    [("time", 123.0), ("step", 999), ("dt", 0.004), ("note", "y"), ("lj", '{"rc": 2.5}')],
)
def test_an_edited_attribute_is_refused(ckpt, name: str, value: object) -> None:
    _, path = ckpt
    with netCDF4.Dataset(path, "r+") as nc:
        nc.setncattr(name, value)
    _refused(path, "checksum mismatch")


def test_an_edited_value_dropped_or_added_variable_is_refused(ckpt, tmp_path: Path) -> None:
    sim, path = ckpt
    with netCDF4.Dataset(path, "r+") as nc:
        nc["v"][0, 0] = nc["v"][0, 0] + 1e-12
    _refused(path, "checksum mismatch")
    ds = sim.to_dataset(_extra())
    sealed = dict(ds.attrs)
    dropped = ds.drop_vars("impulse")
    dropped.attrs.update(sealed)
    dropped.to_netcdf(tmp_path / "dropped.nc", engine="netcdf4")
    _refused(tmp_path / "dropped.nc", "checksum mismatch")
    added = ds.assign(bonus=("atom", np.zeros(sim.state.n)))
    added.attrs.update(sealed)
    added.to_netcdf(tmp_path / "added.nc", engine="netcdf4")
    _refused(tmp_path / "added.nc", "checksum mismatch")


@pytest.mark.parametrize("keep", [0.5, 0.98])
def test_a_truncated_file_is_refused(ckpt, keep: float) -> None:
    _, path = ckpt
    raw = path.read_bytes()
    path.write_bytes(raw[: int(len(raw) * keep)])
    err = _refused(path)
    assert "unreadable" in err.problem or "checksum mismatch" in err.problem, err.problem


def test_foreign_files_are_refused(tmp_path: Path) -> None:
    text = tmp_path / "notes.nc"
    text.write_text("not a netCDF file\n")
    _refused(text, "unreadable")
    _refused(tmp_path / "missing.nc", "unreadable")
    other = tmp_path / "other.nc"
    xr.Dataset({"x": (("atom", "xyz"), np.zeros((2, 3)))}, attrs={"format": "lammps/1"}).to_netcdf(
        other, engine="netcdf4"
    )
    _refused(other, "not an MD checkpoint", "'lammps/1'")
    bare = tmp_path / "bare.nc"
    xr.Dataset({"x": (("atom",), np.zeros(2))}).to_netcdf(bare, engine="netcdf4")
    _refused(bare, "not an MD checkpoint", "None")
    # an in-memory dataset is refused too, and the message says where it came from
    with pytest.raises(CheckpointError, match=r"\(in-memory dataset\): not an MD checkpoint"):
        MDSimulation.from_dataset(xr.Dataset(attrs={"format": "other"}))


def test_old_new_and_unsealed_versions_are_refused(tmp_path: Path) -> None:
    sim = _sim()
    ds = sim.to_dataset()
    old = ds.copy()
    old.attrs["format"] = "hugomap-md-checkpoint/1"  # as written before checksums
    del old.attrs["checksum"]
    old.to_netcdf(tmp_path / "old.nc", engine="netcdf4")
    _refused(tmp_path / "old.nc", "predates checkpoint checksums", "rerun the stage")
    new = ds.copy()
    new.attrs["format"] = "hugomap-md-checkpoint/3"
    new.to_netcdf(tmp_path / "new.nc", engine="netcdf4")
    _refused(tmp_path / "new.nc", "unsupported format version", "hugomap-md-checkpoint/3")
    unsealed = ds.copy()
    del unsealed.attrs["checksum"]
    unsealed.to_netcdf(tmp_path / "unsealed.nc", engine="netcdf4")
    _refused(tmp_path / "unsealed.nc", "no valid 'checksum' attribute")


# -- window checkpoints ------------------------------------------------------------------------


def _window() -> MDWindow:
    sim = _sim()
    rng = np.random.default_rng(1)
    res_x, res_v = rng.uniform(0, 6, (40, 3)), rng.normal(0, 1, (40, 3))
    geom = WindowGeometry(x_lo=1.0, x_hi=4.0, ghost_width=1.0, cut_every=0.5, sync_steps=5,
                          res_length=6.0)  # fmt: skip
    return MDWindow(sim, res_x, res_v, geom, -3.0, -1.0, 4.5, 1.0, 1000)


def test_window_checkpoint_roundtrip_and_refusals(tmp_path: Path) -> None:
    win = _window()
    path = win.save(tmp_path / "window.nc", attrs={"stage": "window"})
    with xr.open_dataset(path, engine="netcdf4") as ds:
        assert ds.attrs["window_format"] == MD_WINDOW_CHECKPOINT.format
        assert ds.attrs["format"] == MD_CHECKPOINT.format
    back = MDWindow.load_path(path)
    assert np.array_equal(back.res_x, win.res_x) and np.array_equal(back.res_v, win.res_v)
    assert (back.u_in, back.u_out, back.x_face_in, back.x_face, back.next_id) == (
        win.u_in, win.u_out, win.x_face_in, win.x_face, win.next_id,
    )  # fmt: skip
    assert np.array_equal(back.sim.state.x, win.sim.state.x)

    # flipped bytes in the reservoir snapshot (a window-only variable)
    bad = tmp_path / "flipped.nc"
    shutil.copy(path, bad)
    _flip_bytes_of(bad, win.res_x)
    with pytest.raises(CheckpointError, match="checksum mismatch") as info:
        MDWindow.load_path(bad)
    assert str(bad) in str(info.value)
    # an edited window attribute (the outflow speed)
    edited = tmp_path / "edited.nc"
    shutil.copy(path, edited)
    with netCDF4.Dataset(edited, "r+") as nc:
        st = json.loads(nc.getncattr("window_state"))
        nc.setncattr("window_state", json.dumps(st | {"u_out": -0.5}))
    with pytest.raises(CheckpointError, match="checksum mismatch"):
        MDWindow.load_path(edited)
    # an intact MD checkpoint that is not a window
    plain = _sim().save(tmp_path / "plain.nc")
    with pytest.raises(CheckpointError, match="not an MD window checkpoint") as info:
        MDWindow.load_path(plain)
    assert str(plain) in str(info.value)


# -- the piston stage's periodic checkpoint of a piston run --------------------------------------


class Killed(BaseException):
    """Stands for SIGKILL in the middle of a piston run (escapes every ``except``)."""


def _scene() -> dict:
    cfg = yaml.safe_load((ROOT / "tests/workflow/tiny/config.yaml").read_text())
    sc = cfg["scenes"]["tiny"]
    sc["sample"].update(cells=[24, 4, 4], equilibrate_time=0.5, pole_time=0.5)
    sc["shock"]["checkpoint_every"] = 2
    scene = validate_config(cfg)["scenes"]["tiny"]
    scene["name"] = "tiny"
    return scene


@pytest.fixture(scope="module")
def piston_run(tmp_path_factory: pytest.TempPathFactory) -> dict:
    """A loading checkpoint, the uninterrupted piston point from it, and the periodic
    checkpoint a run from it leaves when it is killed after 6 samples (3 checkpoints)."""
    d = tmp_path_factory.mktemp("piston")
    scene, u_p = _scene(), 2.5
    with one_numba_thread():
        stages.prepare_sample(scene, d / "sample.nc")
        loaded = stages.load_to_target(d / "sample.nc", scene, u_p, d / "loaded.nc")
        ref = stages.piston_point(loaded, scene, u_p, d / "ref.nc")
        assert not Path(str(ref) + ".part.nc").exists()  # removed once the point is written
        real_drive = piston_stage.drive

        def killed_drive(sim, frame, profile, h, on_sample=None):
            n = [0]

            def hook() -> None:
                on_sample()
                n[0] += 1
                if n[0] == 6:
                    raise Killed

            real_drive(sim, frame, profile, h, on_sample=hook)

        piston_stage.drive = killed_drive
        try:
            with pytest.raises(Killed):
                stages.piston_point(loaded, scene, u_p, d / "killed.nc")
        finally:
            piston_stage.drive = real_drive
    part = d / "killed.nc.part.nc"
    assert part.exists() and not (d / "killed.nc").exists()
    with xr.open_dataset(loaded) as ds:
        loaded_step = int(ds.attrs["step"])
    with xr.open_dataset(part) as ds:
        part_step = int(ds.attrs["step"])
    assert part_step == loaded_step + 6 * scene["shock"]["sample_every"]
    return {"dir": d, "scene": scene, "u_p": u_p, "loaded": loaded, "ref": ref, "part": part,
            "loaded_step": loaded_step, "part_step": part_step}  # fmt: skip


def _rerun(run: dict, part: Path | None, monkeypatch, caplog) -> tuple[Path, list[int], str]:
    """piston_point again with ``part`` as its periodic checkpoint; returns the point file,
    the step(s) the piston run started from, and the log."""
    d = run["dir"]
    out = d / "rerun.nc"
    out.unlink(missing_ok=True)
    mine = Path(str(out) + ".part.nc")
    mine.unlink(missing_ok=True)
    if part is not None:
        shutil.copy(part, mine)
    stray = d / ".rerun.nc.part.nc.x1y2z3.tmp"  # a checkpoint write killed a while ago
    stray.write_bytes(b"CDF\x01 half a file")
    os.utime(stray, (time.time() - 120, time.time() - 120))
    fresh = d / ".rerun.nc.part.nc.a4b5c6.tmp"  # a write in progress (another sweep)
    fresh.write_bytes(b"CDF\x01 being written")
    starts = []
    real_drive = piston_stage.drive

    def spy(sim, frame, profile, h, on_sample=None):
        starts.append(sim.state.step)
        real_drive(sim, frame, profile, h, on_sample=on_sample)

    monkeypatch.setattr(piston_stage, "drive", spy)
    caplog.clear()
    with caplog.at_level(logging.INFO, logger="hugomap"), one_numba_thread():
        stages.piston_point(run["loaded"], run["scene"], run["u_p"], out)
    assert not mine.exists() and not stray.exists()
    assert fresh.exists()
    fresh.unlink()
    return out, starts, caplog.text


def _same_point(a: Path, b: Path) -> None:
    with xr.open_dataset(a) as da, xr.open_dataset(b) as db:
        assert str(da["status"].values) == str(db["status"].values)
        assert np.isfinite(float(da["D"])) and da["history_t"].size > 10  # a measured point
        for k in ("D", "P", "rho", "E", "T", "history_t", "atom_steps"):
            if k in da:
                assert np.array_equal(da[k].values, db[k].values, equal_nan=True), k


def test_killed_piston_run_resumes_from_its_partial_checkpoint(
    piston_run: dict, monkeypatch, caplog
) -> None:
    out, starts, text = _rerun(piston_run, piston_run["part"], monkeypatch, caplog)
    assert starts == [piston_run["part_step"]]
    assert f"resuming from {Path(str(out) + '.part.nc')}" in text
    _same_point(out, piston_run["ref"])  # bit-for-bit the point of the uninterrupted run


def _flip(p: Path) -> None:
    # the velocities: the positions may be stored twice (x_ref equals x when the neighbour
    # list was rebuilt on the step before the checkpoint)
    v = read_checkpoint(p)["v"].values
    _flip_bytes_of(p, v)


def _truncate(p: Path) -> None:
    p.write_bytes(p.read_bytes()[: p.stat().st_size // 2])


def _edit_time(p: Path) -> None:
    with netCDF4.Dataset(p, "r+") as nc:
        nc.setncattr("time", float(nc.getncattr("time")) + 1.0)


def _foreign(p: Path) -> None:
    xr.Dataset({"x": ("a", [1.0])}, attrs={"format": "lammps/1"}).to_netcdf(p)


def _old(p: Path) -> None:
    ds = read_checkpoint(p)
    ds.attrs["format"] = "hugomap-md-checkpoint/1"
    del ds.attrs["checksum"]
    p.unlink()
    ds.to_netcdf(p, engine="netcdf4")


def _other_parent(p: Path) -> None:
    """An intact partial checkpoint, but from another loading checkpoint (e.g. a run killed
    before the config changed): its parent checksum does not match."""
    ds = read_checkpoint(p)
    sim = MDSimulation.from_dataset(ds)
    other = xr.Dataset(attrs={"checksum": "sha256:" + "0" * 64})
    h = history_of(ds)
    p.unlink()
    piston_stage.save_partial(backend_named("md"), sim, h, Pole(rho0=0.8),
                              json.loads(ds.attrs["cost"]), other, p)  # fmt: skip


@pytest.mark.parametrize(
    ("damage", "reason"),
    [
        (_flip, "checksum mismatch"),
        (_truncate, "unreadable"),
        (_edit_time, "checksum mismatch"),
        (_foreign, "not an MD checkpoint"),
        (_old, "predates checkpoint checksums"),
        (_other_parent, "descends from another loading checkpoint"),
    ],
    ids=["flipped", "truncated", "edited_attr", "foreign", "old_format", "other_parent"],
)
def test_refused_partial_checkpoint_is_ignored(
    piston_run: dict, tmp_path: Path, damage, reason: str, monkeypatch, caplog
) -> None:
    bad = tmp_path / "part.nc"
    shutil.copy(piston_run["part"], bad)
    damage(bad)
    out, starts, text = _rerun(piston_run, bad, monkeypatch, caplog)
    assert starts == [piston_run["loaded_step"]]  # restarted from the loading checkpoint
    assert "ignoring partial checkpoint" in text and reason in text, text
    assert "resuming from" not in text
    _same_point(out, piston_run["ref"])


def test_corrupted_loading_checkpoint_fails_the_point(piston_run: dict, tmp_path: Path) -> None:
    """The loading checkpoint is never ignored: its pole is used whatever the run resumes
    from, so a corrupted one stops the job with the file's name, even with a good part."""
    loaded = tmp_path / "loaded.nc"
    shutil.copy(piston_run["loaded"], loaded)
    with netCDF4.Dataset(loaded, "r+") as nc:
        nc["P0"].assignValue(float(nc["P0"][...]) * 1.01)
    out = tmp_path / "point.nc"
    shutil.copy(piston_run["part"], Path(str(out) + ".part.nc"))
    with pytest.raises(CheckpointError, match="checksum mismatch") as info:
        stages.piston_point(loaded, piston_run["scene"], piston_run["u_p"], out)
    assert str(loaded) in str(info.value)
    assert not out.exists()


def test_profile_of_the_loading_checkpoint(piston_run: dict, tmp_path: Path) -> None:
    """``hugomap profile`` of the loading checkpoint: in the piston frame the shocked liquid
    behind the front is at rest and the material ahead moves at −u_p (the frame is exact;
    the last 10 samples' mean over 6 σ either side has a thermal error of ~0.03 σ/τ, so 10 %
    of u_p fails only a wrong frame or a misplaced front), and the liquid is compressed
    behind it (ρ/ρ0 ≈ 1.35 at u_p = 2.5 on the tiny liquid; 1.15 bounds it from below)."""
    from hugomap.cli import main
    from hugomap.stages.profile import front_profile

    u_p = piston_run["u_p"]
    p = front_profile(piston_run["loaded"], samples=10, merge=1)
    x, u, rho = p["x"], p["u"], p["rho"]
    # 4 σ clear of the front's own width (its tracked position is mid-rise)
    behind, ahead = (x > -10.0) & (x < -4.0), (x > 4.0) & (x < 10.0)
    assert abs(np.nanmean(u[behind])) < 0.1 * u_p, (x, u)
    assert abs(np.nanmean(u[ahead]) + u_p) < 0.1 * u_p, (x, u)
    assert np.nanmean(rho[behind]) / np.nanmean(rho[ahead]) > 1.15, (x, rho)
    assert p["units"]["P"] == "epsilon sigma^-3" and p["samples"] == 10
    out = tmp_path / "profile.png"
    assert main(["profile", str(piston_run["loaded"]), "--out", str(out)]) == 0
    assert out.stat().st_size > 10_000
    # a point file has no profile history: refused with a message, exit status 2
    assert main(["profile", str(piston_run["ref"]), "--out", str(tmp_path / "x.png")]) == 2
