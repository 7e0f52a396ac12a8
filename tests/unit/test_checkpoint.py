"""Checkpoints: a resumed run continues bit-for-bit, and files are written atomically."""

from __future__ import annotations

import numpy as np
import pytest
import xarray as xr

from hugomap.io.checkpoint import MD_CHECKPOINT
from hugomap.md.potential import LJParams
from hugomap.md.sample import fcc_state
from hugomap.md.simulation import MDSimulation
from hugomap.md.state import MDState

from ._reference import NO_JIT

pytestmark = pytest.mark.usefixtures("serial_numba")

# Steps before and after the checkpoint: several list rebuilds (every ~8 steps here).
N = 30 if NO_JIT else 60
FIELDS = ("x", "v", "f", "ids", "x_ref", "impulse")


def _make(kind: str, thermostat: bool) -> MDSimulation:
    st = fcc_state((3, 3, 3), 0.8, 1.5, 3, periodic_x=(kind == "periodic"))
    sim = MDSimulation(
        st, LJParams(rc=2.2), dt=0.005, T_bath=1.2 if thermostat else None, tau_bath=0.2, seed=5
    )
    if kind == "piston":  # both walls move in: pistons from the left and from the right
        sim.set_walls(0.5, -0.25)
    return sim


def _assert_same(a: MDSimulation, b: MDSimulation) -> None:
    for k in FIELDS:
        assert np.array_equal(getattr(a.state, k), getattr(b.state, k)), k
    assert a.state.step == b.state.step
    assert a.state.time == b.state.time
    assert np.array_equal(a.state.walls0, b.state.walls0)


def _resumed(kind, thermostat, tmp_path, n1, n2):
    b = _make(kind, thermostat)
    b.advance(n1)
    path = b.save(tmp_path / "ckpt.nc")
    c = MDSimulation.load(path)
    assert c.list_builds >= 1 and c.T_bath == b.T_bath and c.seed == b.seed
    c.advance(n2)
    return c


@pytest.mark.parametrize("thermostat", [False, True], ids=["nve", "csvr"])
@pytest.mark.parametrize("kind", ["periodic", "walled"])
def test_resume_is_bit_for_bit(tmp_path, kind, thermostat):
    a = _make(kind, thermostat)
    a.advance(2 * N)
    c = _resumed(kind, thermostat, tmp_path, N, N)
    _assert_same(a, c)
    assert a.list_builds > 4  # the checkpoint fell between rebuilds, lists were rebuilt after


@pytest.mark.parametrize("thermostat", [False, True], ids=["nve", "csvr"])
def test_resume_with_piston_matches_the_same_split_run(tmp_path, thermostat):
    """With moving walls, checkpoint + load is invisible: identical to advance(N) twice."""
    a = _make("piston", thermostat)
    a.advance(N)
    a.advance(N)
    c = _resumed("piston", thermostat, tmp_path, N, N)
    _assert_same(a, c)
    assert c.state.impulse[0] > 0  # the piston did hit atoms


def test_resume_with_piston_and_thermostat_matches_uninterrupted_run(tmp_path):
    n = 60  # (a split that does change the last bits, with or without the JIT)
    a = _make("piston", True)
    a.advance(2 * n)
    c = _resumed("piston", True, tmp_path, n, n)
    _assert_same(a, c)


def test_split_advance_is_bit_for_bit_with_moving_walls():
    """One atom, no forces, bouncing between two moving walls: 400 steps in one call or in
    400 calls must give the same atom, impulse and clock."""

    def bounce():
        st = MDState(
            x=np.array([[5.0, 3.0, 3.0]]),
            v=np.array([[20.0, 0.0, 0.0]]),
            L=np.array([10.0, 6.0, 6.0]),
            periodic=np.array([False, True, True]),
            walls0=np.array([0.0, 0.5, 10.0, -0.5]),
        )
        return MDSimulation(st, LJParams(), dt=0.005)

    a = bounce()
    a.advance(400)
    b = bounce()
    for _ in range(400):
        b.advance(1)
    assert a.state.impulse[0] > 0 and a.state.impulse[1] < 0  # it bounced off both
    assert b.state.time == a.state.time == 400 * 0.005
    assert np.array_equal(a.state.x, b.state.x)
    assert np.array_equal(a.state.v, b.state.v)


def test_checkpoint_contents(tmp_path):
    sim = _make("piston", True)
    sim.advance(10)
    path = sim.save(tmp_path / "c.nc", attrs={"note": "x"})
    with xr.open_dataset(path) as ds:
        assert ds.attrs["format"] == MD_CHECKPOINT.format
        assert ds.attrs["step"] == 10 and ds.attrs["note"] == "x"
        np.testing.assert_array_equal(ds["x"].values, sim.state.x)
        np.testing.assert_array_equal(ds["walls0"].values, sim.state.walls0)
    with pytest.raises(ValueError, match="not an MD checkpoint"):
        MDSimulation.from_dataset(xr.Dataset(attrs={"format": "other"}))


def test_save_is_atomic(tmp_path, monkeypatch):
    sim = _make("walled", False)
    path = tmp_path / "ckpt.nc"
    sim.save(path)
    sim.advance(5)
    sim.save(path)  # overwrite
    assert sorted(p.name for p in tmp_path.iterdir()) == ["ckpt.nc"]  # no stray temp files
    good = path.read_bytes()
    assert MDSimulation.load(path).state.step == 5

    def failing_to_netcdf(self, target, *args, **kwargs):
        with open(target, "wb") as fh:  # a partial file at the target, then the failure
            fh.write(b"CDF\x01 half a file")
        raise OSError("disk full")

    monkeypatch.setattr(xr.Dataset, "to_netcdf", failing_to_netcdf)
    sim.advance(5)
    with pytest.raises(OSError, match="disk full"):
        sim.save(path)
    assert path.read_bytes() == good  # the old checkpoint is intact
    assert sorted(p.name for p in tmp_path.iterdir()) == ["ckpt.nc"]
    with pytest.raises(OSError):
        sim.save(tmp_path / "new.nc")  # a failed first write leaves nothing behind
    assert sorted(p.name for p in tmp_path.iterdir()) == ["ckpt.nc"]
    monkeypatch.undo()
    assert MDSimulation.load(path).state.step == 5
