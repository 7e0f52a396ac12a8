"""The 1D CSPH moving window: protocol bookkeeping and bit-exact checkpoints.

A small copper piston run (no strength, u_p = 500 m/s) is cut into a window in the frame
moving at c0 + s u_p. Checks: the frame (u_p = u_out − u_in, u_in = −W), inflow particles
released and replenished, outflow cuts, Galilean shift, and that a run saved and loaded part
way continues bit for bit (the same arrays as an uninterrupted run: exact equality).
"""

from __future__ import annotations

import numpy as np
import pytest

from hugomap.eos import copper
from hugomap.failures import CheckpointError
from hugomap.sph.simulation import CSPHSimulation
from hugomap.sph.state import SPHState
from hugomap.sph.window import SPHWindow

DX = 1e-5
UP = 500.0


def _window() -> SPHWindow:
    rho0 = 8930.0
    n = 90
    st = SPHState(x=(np.arange(n) + 0.5) * DX, v=np.zeros(n), m=rho0 * DX, rho=rho0, e=0.0)
    sim = CSPHSimulation(st, copper(), walls=(0.0, UP, None, 0.0))
    us = 3940.0 + 1.49 * UP
    sim.run_until(35 * DX / us)
    v = st.v[:, 0]
    xf = st.x[int(np.nonzero(v > 0.5 * UP)[0].max()), 0]
    return SPHWindow.from_piston(sim, xf, UP, us, 30 * DX, cut_every=3 * DX, sync_steps=5)


def test_window_frame_and_boundaries():
    w = _window()
    us = 3940.0 + 1.49 * UP
    assert w.u_in == pytest.approx(-us) and w.u_out - w.u_in == pytest.approx(UP)
    assert w.geom.length == pytest.approx(30 * DX)
    n0 = w.sim.state.n
    w.advance(60)
    st = w.sim.state
    assert st.n != n0 or w.sim.n_builds > 1  # particles came in / went out
    assert np.count_nonzero(w.sim.frozen) >= w.geom.n_inflow // 2 + 1
    assert np.all(st.x[w.sim.frozen, 0] >= w.geom.x_hi)
    assert np.all(st.v[w.sim.frozen, 0] == w.u_in)
    assert w.sim.walls[0] >= w.geom.x_lo - w.geom.cut_every - 1e-12
    c = w.count_in_window()
    assert 0 < c <= w.n_particles
    sums = w.profile_sums(5 * DX)
    # the fractional count differs from the whole particles in the bins by the two edge
    # particles' parts at most
    assert sums.shape[0] == 6 and abs(sums[:, 0].sum() - c) <= 2.0
    w.galilean_shift(100.0)
    assert w.u_out - w.u_in == pytest.approx(UP) and w.sim.walls[1] == w.u_out
    w.set_outflow(w.u_out - 10.0)
    assert w.sim.walls[1] == w.u_out


def test_checkpoint_continues_bit_for_bit(tmp_path):
    a = _window()
    a.advance(20)
    path = a.save(tmp_path / "w.nc")
    a.advance(40)
    b = SPHWindow.load(path)
    b.advance(40)
    assert b.n_updates >= 2  # the continuation crossed inflow releases and outflow cuts
    assert a.time == b.time and a.sim.state.n == b.sim.state.n
    for k in ("x", "v", "rho", "e", "S", "l"):
        assert np.array_equal(getattr(a.sim.state, k), getattr(b.sim.state, k)), k
    assert np.array_equal(a.sim.walls, b.sim.walls)


def test_altered_checkpoint_refused(tmp_path):
    w = _window()
    ds = w.to_dataset()
    ds["sim_rho"].values[3] *= 1.0000001  # the simulation inside (sph.checkpoint layout)
    with pytest.raises(CheckpointError, match="checksum"):
        SPHWindow.from_dataset(ds, "mem")
    ds = w.to_dataset()
    ds.attrs["window_format"] = "other"
    with pytest.raises(CheckpointError, match="not an SPH window"):
        SPHWindow.from_dataset(ds, "mem")
