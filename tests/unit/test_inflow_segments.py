"""The window's inflow laid a segment at a time (``MDWindow.from_piston(segment=...)``).

A long reservoir snapshot feeds in a flow closer to u_in than a short one (its own
disturbance shrinks with its length), but frozen whole behind the inflow it would fill the
box. So it is laid frozen a segment at a time: the segments are consecutive pieces of the
snapshot, each laid right behind the last, so the material fed in is the snapshot itself,
seamless, and after the last segment comes the first again (the snapshot's periodic image).
Not the default: on a 240-σ snapshot AMW oscillated (docs/window-methods.md).
"""

from __future__ import annotations

import numpy as np
import pytest

from hugomap.md.kit import MDKit
from hugomap.md.potential import LJParams
from hugomap.md.sample import fcc_state
from hugomap.md.simulation import MDSimulation
from hugomap.md.window import MDWindow
from hugomap.particles.reservoir import make_reservoir
from hugomap.particles.window import WindowGeometry, _inflow_copy

LJ = LJParams(rc=2.5, shift=True, skin=0.3)
DT = 0.002


def test_segments_laid_end_to_end_are_the_snapshot() -> None:
    rng = np.random.default_rng(0)
    Lr = 36.0
    res_x = rng.uniform(0.0, 1.0, (500, 3)) * [Lr, 7.0, 7.0]
    res_x[:3, 0] = [0.0, 12.0 - 1e-12, Lr - 1e-12]  # atoms on the segment edges
    g = WindowGeometry(5.0, 30.0, 3.0, 2.0, 25, Lr, 12.0)
    assert g.n_segments == 3 and g.segment == 12.0
    face = 30.0
    parts = [_inflow_copy(res_x, g, j, face + j * g.segment, -6.0) for j in range(3)]
    x = np.concatenate([p[0] for p in parts])
    ids = np.concatenate([p[2] for p in parts])
    assert sorted(ids) == sorted(-1 - np.arange(500))  # every atom once
    order = np.argsort(-1 - ids)
    np.testing.assert_allclose(x[order], res_x + [face, 0.0, 0.0], atol=1e-12)
    v = np.concatenate([p[1] for p in parts])
    assert np.all(v[:, 0] == -6.0) and np.all(v[:, 1:] == 0.0)
    # each segment lies within one segment length behind its face
    for j, (xj, _, _) in enumerate(parts):
        lo = face + j * g.segment
        assert xj[:, 0].min() >= lo and xj[:, 0].max() < lo + g.segment


def test_whole_snapshot_without_segments() -> None:
    g = WindowGeometry(5.0, 30.0, 3.0, 2.0, 25, 36.0)
    assert g.segment == 36.0 and g.n_segments == 1


@pytest.fixture(scope="module")
def window():
    sample = fcc_state((30, 4, 4), 0.8, 2.0, seed=5, periodic_x=False)
    sim = MDSimulation(sample, LJ, DT, T_bath=2.0, tau_bath=0.2, seed=5)
    sim.advance(500)
    sim.T_bath = None
    res, _ = make_reservoir(MDKit(LJ), (4, 4), 0.8, 2.0, DT, seed=6, equilibrate_time=0.5,
                            min_length=34.0)  # fmt: skip
    win = MDWindow.from_piston(
        sim, res, x_front=25.0, u_p=0.0, D_guess=8.0, length=20.0, front_fraction=0.5,
        ghost_width=3.0, cut_every=2.0, sync_steps=25, segment=13.0,
    )  # fmt: skip
    return win, res


def test_a_segmented_inflow_feeds_the_snapshot_in_order(window) -> None:
    """Segment after segment, then the first again; one cycle releases every snapshot atom
    once; the window's box holds one segment beyond the inflow, not the whole snapshot."""
    win, res = window
    g = win.geom
    assert g.n_segments == 2 and g.segment == pytest.approx(g.res_length / 2)
    assert win.sim.state.L[0] < g.x_hi + 2 * g.res_length
    seen, released = [win.seg_index], []
    n_mobile = win.next_id
    for _ in range(int(2.5 * g.res_length / 8.0 / (25 * DT))):
        win.advance(25)
        if win.seg_index != seen[-1]:
            seen.append(win.seg_index)
            released.append(win.next_id - n_mobile)
            n_mobile = win.next_id
    assert seen[:5] == [0, 1, 0, 1, 0]
    # a full cycle (two releases) hands over every atom of the snapshot once
    assert released[0] + released[1] == res.state.n
    assert released[1] + released[2] == res.state.n
    frozen = win.sim.state.ids
    inflow = frozen[(frozen < 0) & (frozen >= -win.n_res)]
    assert inflow.size in (released[0], released[1])


def test_the_segment_survives_a_checkpoint(window) -> None:
    win, _ = window
    back = MDWindow.from_dataset(win.to_dataset())
    assert back.seg_index == win.seg_index
    assert back.geom == win.geom
