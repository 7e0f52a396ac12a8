"""Progress lines of long runs: step, simulated time, fraction done and ETA.

Reference: a front moving at constant speed towards a far wall that closes in — after half
of the distance it had to go, half the drive is done and the ETA equals the time spent.
"""

from __future__ import annotations

import logging
from types import SimpleNamespace

import numpy as np
import pytest

from hugomap.methods.piston import History
from hugomap.stages.load import LoadingProgress
from hugomap.stages.piston import loading_rate, log_drive_start
from hugomap.stages.piston import log_progress as _log_progress


class _Sim:
    def __init__(self, step: int, t: float, walls: tuple[float, float]):
        self.steps = step
        self.time = t
        self._walls = walls

    def wall_positions(self) -> tuple[float, float]:
        return self._walls


def test_progress_line_gives_fraction_and_eta(caplog):
    p = SimpleNamespace(rear_margin=10.0, far_end=None)
    x_start: list = [None]
    h = SimpleNamespace(front=[20.0])
    with caplog.at_level(logging.INFO, logger="hugomap"):
        _log_progress(_Sim(100, 1.0, (0.0, 110.0)), h, p, x_start, wall=5.0)
        # The front moved 20 σ and the far wall 20 σ closer: 40 of the 80 σ gap
        # (110 − 20 − 10) closed, in 20 s of wall time.
        h.front.append(40.0)
        _log_progress(_Sim(600, 5.0, (0.0, 90.0)), h, p, x_start, wall=25.0)
    lines = [r.getMessage() for r in caplog.records if "progress" in r.getMessage()]
    assert len(lines) == 2
    assert "step 600" in lines[1] and "t = 5," in lines[1]
    assert "50 % of the drive" in lines[1] and "ETA 20 s" in lines[1]


def test_no_line_without_a_front(caplog):
    h = SimpleNamespace(front=[np.nan])
    with caplog.at_level(logging.INFO, logger="hugomap"):
        _log_progress(
            _Sim(1, 0.1, (0.0, 50.0)),
            h,
            SimpleNamespace(rear_margin=5.0, far_end=None),
            [None],
            1.0,
        )
    assert not [r for r in caplog.records if "progress" in r.getMessage()]


def _loading(n: int = 20) -> History:
    """A loading history: the front at 5 t from the piston at 0, the far wall at 200 − 1 t,
    a sample every 0.5 (so the gap closes at 6 per unit time)."""
    h = History()
    for i in range(1, n + 1):
        t = 0.5 * i
        h.t.append(t), h.front.append(5.0 * t), h.x_left.append(0.0)
        h.x_right.append(200.0 - t), h.stage.append(0), h.sums.append(np.zeros((1, 1)))
    return h


def test_loading_rate() -> None:
    """Gap speed from the samples; wall per unit time from the checkpoint's own rate, else
    its whole cost over its simulated time (20 samples of 0.5: 10 units)."""
    assert loading_rate(_loading(), {"wall_s": 30.0}, 2.0) == pytest.approx((6.0, 2.0))
    assert loading_rate(_loading(), {"wall_s": 30.0}) == pytest.approx((6.0, 3.0))
    assert loading_rate(_loading(3), {"wall_s": 30.0}) is None  # too few samples
    assert loading_rate(_loading(), {}) is None  # no wall time


def test_eta_from_the_first_line(caplog) -> None:
    """The drive's first line and its first progress line (before any progress) give the
    loading stage's ETA: gap / gap speed × wall per unit time; later lines the drive's own."""
    frame = SimpleNamespace(rear_margin=10.0, far_end=None)
    h = _loading()  # front at 50, far wall at 190: 130 to go
    rate = loading_rate(h, {"wall_s": 30.0}, 2.0)
    x_start: list = [None]
    with caplog.at_level(logging.INFO, logger="hugomap"):
        log_drive_start(_Sim(1000, 10.0, (0.0, 190.0)), h, frame, rate, x_start)
        _log_progress(_Sim(1000, 10.0, (0.0, 190.0)), h, frame, x_start, wall=1.0, rate=rate)
        h.front.append(115.0)  # half of the 130 closed in 10 s
        _log_progress(_Sim(2000, 20.0, (0.0, 190.0)), h, frame, x_start, wall=10.0, rate=rate)
    lines = [r.getMessage() for r in caplog.records]
    assert lines[0].startswith("drive: step 1000, t = 10, front 50, 130 to go, ETA 43 s")
    assert "ETA 43 s (loading stage's rate)" in lines[1]  # 130 / 6 × 2
    assert "50 % of the drive, ETA 10 s" in lines[2]


def test_loading_logs_a_few_lines(caplog) -> None:
    """One line at the start and one per quarter of the loading distance, however many
    samples; the ETA and ``wall_per_time`` count from the first sample (a cold start's
    compile time in the first chunk is left out)."""
    frame = SimpleNamespace(load_distance=100.0, x_origin=0.0, sample_every=10)
    h = History()
    sim = _Sim(0, 0.0, (0.0, 200.0))
    clock = [0.0]
    with caplog.at_level(logging.INFO, logger="hugomap"):
        progress = LoadingProgress(sim, frame, h, lambda: clock[0])
        for i in range(1, 101):  # front at i, 1 s of wall per sample, 30 s before the first
            sim.steps, sim.time = 10 * i, 0.1 * i
            clock[0] = 30.0 + i
            h.front.append(float(i))
            progress()
    lines = [r.getMessage() for r in caplog.records]
    assert len(lines) == 4 and lines[0].startswith("loading: until the front has travelled 100")
    assert "25 % of the loading distance, 55 s so far, ETA 75 s" in lines[1]
    assert "75 % of the loading distance" in lines[3] and "ETA 25 s" in lines[3]
    assert progress.wall_per_time() == pytest.approx(10.0)  # 99 s over 9.9 units


if __name__ == "__main__":  # pragma: no cover
    pytest.main([__file__])
