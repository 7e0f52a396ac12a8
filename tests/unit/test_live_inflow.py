"""The window's live inflow (``MDWindow.from_piston(inflow="live")``, ``md.live_inflow``).

A frozen snapshot repeats its own acoustic pattern at every pass and feeds a flow of its own
(±0.06 σ/τ at 40 σ); the live reservoir runs the snapshot on beside the window and the copy
behind ``x_hi`` follows its trajectories, each atom released as it crosses ``x_hi``. What is
checked here is the bookkeeping that makes the copy the reservoir's images: the copy sits on
the reservoir's trajectories, every atom is released once per pass, in order, with the
reservoir's own state, and a checkpoint resumes bit for bit.
"""

from __future__ import annotations

import hashlib

import numpy as np
import pytest

from hugomap.md.kit import MDKit
from hugomap.md.potential import LJParams
from hugomap.md.sample import fcc_state
from hugomap.md.simulation import MDSimulation
from hugomap.md.window import MDWindow
from hugomap.particles.reservoir import make_reservoir

LJ = LJParams(rc=2.5, shift=True, skin=0.3)
DT = 0.002
V = 8.0  # σ/τ: the inflow's speed (u_p = 0: a uniform flow)


@pytest.fixture(scope="module")
def window():
    sample = fcc_state((30, 4, 4), 0.8, 2.0, seed=5, periodic_x=False)
    sim = MDSimulation(sample, LJ, DT, T_bath=2.0, tau_bath=0.2, seed=5)
    sim.advance(300)
    sim.T_bath = None
    res, _ = make_reservoir(MDKit(LJ), (4, 4), 0.8, 2.0, DT, seed=6, equilibrate_time=0.5,
                            min_length=20.0)  # fmt: skip
    win = MDWindow.from_piston(
        sim, res, x_front=25.0, u_p=0.0, D_guess=V, length=20.0, front_fraction=0.5,
        ghost_width=3.0, cut_every=2.0, sync_steps=25, inflow="live",
    )  # fmt: skip
    return win, res


def _digest(win: MDWindow) -> str:
    s = win.sim.state
    o = np.argsort(s.ids)
    return hashlib.sha1(s.x[o].tobytes() + s.v[o].tobytes() + s.ids[o].tobytes()).hexdigest()


def _copy_error(win: MDWindow) -> float:
    """Largest distance [σ] between a copy atom and its reservoir image (y, z periodic)."""
    s = win.sim.state
    copy = (s.ids < 0) & (s.ids >= -win.n_res)
    d = win.live.images(-1 - s.ids[copy], win.x_face_in) - s.x[copy]
    d[:, 1:] -= s.L[1:] * np.rint(d[:, 1:] / s.L[1:])
    return float(np.abs(d).max())


def test_the_copy_follows_the_reservoir_and_each_atom_is_released_once_a_pass(window) -> None:
    win, res = window
    g, live = win.geom, win.live
    n = live.n
    assert win.n_res == n == res.state.n
    s = win.sim.state
    copy = (s.ids < 0) & (s.ids >= -n)
    assert sorted(-1 - s.ids[copy]) == list(range(n))  # one image of every atom
    start = win.next_id
    passes = 1.6
    for _ in range(int(passes * g.res_length / V / (g.sync_steps * DT))):
        win.advance(g.sync_steps)
        # the copy sits on the reservoir's trajectories (to rounding), all behind x_hi
        assert _copy_error(win) < 1e-9
        assert np.all(live.image_x(win.x_face_in) >= g.x_hi)
        s = win.sim.state
        copy = (s.ids < 0) & (s.ids >= -n)
        assert copy.sum() == n
    # released images: image k of every atom before image k + 1 of any (one pass at a time)
    assert live.image.max() - live.image.min() <= 1
    assert win.next_id - start == int(live.image.sum())
    assert 1 <= live.image.mean() <= passes + 0.5


def test_a_released_atom_carries_the_reservoirs_state(window) -> None:
    """At release (the boundary update ending ``advance``) an atom is where its reservoir
    image is, with the reservoir's velocity plus u_in: the material fed in is the
    reservoir's, not a frozen snapshot's."""
    win, _ = window
    live = win.live
    before = live.image.copy()
    first = win.next_id
    win.advance(win.geom.sync_steps)
    gone = np.nonzero(live.image != before)[0]
    assert gone.size > 0
    s = win.sim.state
    new = np.nonzero(s.ids >= first)[0]
    assert new.size == gone.size
    where = live.images(gone, win.x_face_in) - [live.L[0], 0.0, 0.0]  # the released image
    v_res = live.velocities()[gone] + [win.u_in, 0.0, 0.0]
    for p, vr in zip(where, v_res, strict=True):
        d = s.x[new] - p
        d[:, 1:] -= s.L[1:] * np.rint(d[:, 1:] / s.L[1:])
        k = new[np.argmin(np.einsum("ij,ij->i", d, d))]
        assert np.abs(d[np.argmin(np.einsum("ij,ij->i", d, d))]).max() < 1e-9
        np.testing.assert_allclose(s.v[k], vr, rtol=0, atol=1e-12)


def test_a_live_window_resumes_bit_for_bit(window) -> None:
    win, _ = window
    back = MDWindow.from_dataset(win.to_dataset())
    assert back.live is not None
    np.testing.assert_array_equal(back.live.unwrap, win.live.unwrap)
    np.testing.assert_array_equal(back.live.image, win.live.image)
    win.advance(300)
    back.advance(300)
    assert _digest(back) == _digest(win)


def test_a_live_copy_is_the_whole_snapshot_and_a_bad_kind_is_refused(window) -> None:
    sample = fcc_state((30, 4, 4), 0.8, 2.0, seed=5, periodic_x=False)
    sim = MDSimulation(sample, LJ, DT)
    _, res = window
    kw = dict(x_front=25.0, u_p=0.0, D_guess=V, length=20.0, front_fraction=0.5,
              ghost_width=3.0, cut_every=2.0, sync_steps=25, segment=0.4 * res.state.L[0])  # fmt: skip
    win = MDWindow.from_piston(sim, res, inflow="live", **kw)
    assert win.geom.n_segments == 1  # segments lay a frozen snapshot; a live one is whole
    assert MDWindow.from_piston(sim, res, **kw).geom.n_segments == 2
    with pytest.raises(ValueError, match="frozen' or 'live"):
        MDWindow.from_piston(sim, res, inflow="thawed", **kw)


def test_the_seams_excess_work_is_taken_back_with_momentum_kept(window) -> None:
    """``MDLiveReservoir.return_seam_work``: each released atom by the seam has a twin, its
    reservoir atom carried on from the image it left, which sits where the atom was released
    (round-off: 1e-9 σ); the window's atoms there lose exactly the copy's excess work W = dt
    (``pair_power`` on them − on their twins), taken from those within rc of the copy (their
    kinetic energy about their mean falls by W), their momentum is kept and no other atom
    moves; the twins and the work returned so far
    travel in the checkpoint, which resumes bit for bit. Round-off bounds: 1e-12 of the
    kinetic energy and of the momentum's scale."""
    from hugomap.md.forces import pair_power

    win = MDWindow.from_dataset(window[0].to_dataset())  # a copy: the fixture stays as it is
    assert win.live.seam_work == "kept" and win.live.twins.shape == (0, 3)  # the default
    win.live.seam_work = "returned"
    win.advance(25)  # one boundary update: the first twins
    s, g, dt = win.sim.state, win.geom, win.sim.dt
    tw = win.live.twins
    assert tw.shape[0] > 10
    new = tw[:, 0] >= tw[:, 0].max() - 5  # released at the last update, where they were put
    at = np.array([np.flatnonzero(s.ids == i)[0] for i in tw[new, 0]])
    d = s.x[at] - win.live.twin_positions(tw[new], win.x_face_in)
    d[:, 1:] -= s.L[1:] * np.rint(d[:, 1:] / s.L[1:])
    assert np.abs(d).max() < 1e-9, np.abs(d).max()
    win.advance(50)  # the twins drift off
    copy = (s.ids < 0) & (s.ids >= -win.n_res)
    lag = -win.u_in * g.sync_steps * dt
    rc = LJ.rc
    tw = win.live.twins
    zone = (s.ids >= 0) & (s.x[:, 0] > g.x_hi - lag - rc) & np.isin(s.ids, tw[:, 0])
    a = np.flatnonzero(zone)
    rows = np.array([tw[tw[:, 0] == i][0] for i in s.ids[a]])
    near = copy & (s.x[:, 0] < s.x[a, 0].max() + rc)
    vb = win.live.velocities()[-1 - s.ids[near]]  # the copy's own frame
    xt = win.live.twin_positions(rows, win.x_face_in)
    args = (s.x[near], vb, s.L, s.periodic, rc * rc)
    expect = dt * (pair_power(s.x[a], *args) - pair_power(xt, *args))
    d = s.x[a][:, None, :] - s.x[near][None, :, :]
    d[..., 1:] -= s.L[1:] * np.rint(d[..., 1:] / s.L[1:])
    took = np.zeros_like(zone)  # the zone's atoms within rc of the copy: the work went to them
    took[a[((d**2).sum(-1) < rc * rc).any(axis=1)]] = True
    assert 1 < took.sum() <= zone.sum()
    zone = took
    v0 = s.v.copy()
    kin0 = 0.5 * np.sum((v0[zone] - v0[zone].mean(axis=0)) ** 2)
    before = win.live.returned
    work = win.live.return_seam_work(s, copy, g.x_hi, lag, win.x_face_in, dt)
    assert abs(work - expect) < 1e-12 * kin0 and abs(work) > 0
    kin1 = 0.5 * np.sum((s.v[zone] - s.v[zone].mean(axis=0)) ** 2)
    assert abs(kin0 - kin1 - work) < 1e-12 * kin0
    np.testing.assert_allclose(s.v[zone].sum(axis=0), v0[zone].sum(axis=0), rtol=0,
                               atol=1e-12 * np.abs(v0[zone]).sum())  # fmt: skip
    np.testing.assert_array_equal(s.v[~zone], v0[~zone])
    assert win.live.returned == before + work
    back = MDWindow.from_dataset(win.to_dataset())
    assert (back.live.seam_work, back.live.returned) == ("returned", win.live.returned)
    np.testing.assert_array_equal(back.live.twins, win.live.twins)
    win.advance(100)
    back.advance(100)
    assert _digest(back) == _digest(win) and back.live.returned == win.live.returned
