"""The inflow reservoir's screen (``particles.reservoir.make_reservoir`` with an
``InflowScreen``): which candidate snapshot it keeps.

The flow each candidate feeds in (``inflow_drift``, a uniform-flow window run) is replaced
here by a scripted one, so the rule itself is what is tested: candidates are tried nearest
the pole's energy first; the first whose flow is within ``tolerance``·``speed`` of the
inflow's is kept, else the one closest to it; the pole carries the kept flow, its error and
the number tried. The snapshots themselves are real (a 448-atom LJ box, a few steps).
"""

from __future__ import annotations

import numpy as np
import pytest

import hugomap.particles.reservoir as mdw
from hugomap.md.kit import MDKit
from hugomap.md.potential import LJParams

LJ = LJParams(rc=2.5, shift=True, skin=0.3)
SPEED = 10.0


def _reservoir(screen, drifts=None, monkeypatch=None):
    """make_reservoir on a small box; with ``drifts``, the i-th candidate screened flows at
    ``drifts[i]`` (error 0.001) and the positions of each screened snapshot are recorded."""
    seen: list[np.ndarray] = []
    if drifts is not None:

        def fake(kit, snap, scr):
            seen.append(snap.state.x.copy())
            return drifts[len(seen) - 1], 0.001

        monkeypatch.setattr(mdw, "inflow_drift", fake)
    snap, pole = mdw.make_reservoir(MDKit(LJ), (4, 4), 0.8, 2.0, 0.002, seed=3,
                                    equilibrate_time=0.02, n_candidates=6, every=2,
                                    pole_time=0.01, E0_target=-2.0, screen=screen)  # fmt: skip
    return snap, pole, seen


def _screen(candidates: int) -> mdw.InflowScreen:
    return mdw.InflowScreen(SPEED, 8.0, 24.0, 3.0, 2.0, 25, 12.0, candidates, 0.001)


def test_the_first_candidate_within_tolerance_is_kept(monkeypatch) -> None:
    # tolerance 0.001 × 10 = 0.01: the third (0.004) passes, the fourth is never tried
    snap, pole, seen = _reservoir(_screen(6), [0.05, -0.03, 0.004, 0.0], monkeypatch)
    assert len(seen) == 3 and pole["screened"] == 3
    assert pole["du"] == pytest.approx(0.004) and pole["du_err"] == pytest.approx(0.001)
    assert np.array_equal(snap.state.x, seen[2])


def test_without_one_within_tolerance_the_closest_is_kept(monkeypatch) -> None:
    snap, pole, seen = _reservoir(_screen(3), [0.05, -0.02, 0.03], monkeypatch)
    assert len(seen) == 3 and pole["screened"] == 3
    assert pole["du"] == pytest.approx(-0.02)
    assert np.array_equal(snap.state.x, seen[1])


def test_candidates_are_tried_nearest_the_pole_energy_first(monkeypatch) -> None:
    """Unscreened, the snapshot is the one nearest the target energy: the screen's first."""
    plain, pole0, _ = _reservoir(None)
    assert "du" not in pole0
    _, _, seen = _reservoir(_screen(2), [0.5, 0.5], monkeypatch)
    assert np.array_equal(plain.state.x, seen[0])
    assert not np.array_equal(seen[0], seen[1])
    # every candidate reaches the pole's energy per atom (velocities rescaled)
    assert pole0["E0"] == pytest.approx(-2.0, abs=1e-9)


def test_a_scene_without_candidates_has_no_screen() -> None:
    """The screen samples the window's state-ahead slab: from gap to (1 − front_fraction)
    L − gap upstream of the inflow seam (``analysis.shock.measure_point``'s ahead slab)."""
    w = {"length": 100.0, "front_fraction": 0.6, "ghost_width": 3.0, "cut_every": 2.0,
         "sync_steps": 25, "reservoir_segment": 40.0,
         "reservoir_screen": {"candidates": 0, "tolerance": 0.001, "average_time": 12.0}}  # fmt: skip
    assert mdw.inflow_screen(w, 8.0, SPEED) is None
    w["reservoir_screen"]["candidates"] = 4
    scr = mdw.inflow_screen(w, 8.0, 9.5)
    assert scr is not None and scr.speed == 9.5 and scr.candidates == 4
    assert (scr.near, scr.far) == (8.0, pytest.approx(32.0))
    assert scr.segment == 40.0  # the screen lays the inflow as the window will


def test_a_candidate_that_cannot_reach_the_pole_energy_is_passed_over(monkeypatch) -> None:
    """The second candidate cannot be rescaled to E0 (``WindowError`` reservoir_energy): the
    screen goes on to the third; the nearest one failing so still stops the stage."""
    from hugomap.failures import WindowError

    real = mdw._snapshot
    calls = {"n": 0}

    def second_fails(*args, **kwargs):
        calls["n"] += 1
        if calls["n"] == which:
            raise WindowError("reservoir_energy", "scripted")
        return real(*args, **kwargs)

    monkeypatch.setattr(mdw, "_snapshot", second_fails)
    which = 2
    _, pole, seen = _reservoir(_screen(6), [0.05, 0.004], monkeypatch)
    assert len(seen) == 2 and pole["screened"] == 3 and pole["du"] == pytest.approx(0.004)
    calls["n"], which = 0, 1
    with pytest.raises(WindowError):
        _reservoir(_screen(6), [0.0], monkeypatch)
