"""Progress lines of long runs: step, simulated time, fraction done and ETA.

Reference: a front moving at constant speed towards a far wall that closes in — after half
of the distance it had to go, half the drive is done and the ETA equals the time spent.
"""

from __future__ import annotations

import logging
from types import SimpleNamespace

import numpy as np
import pytest

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


if __name__ == "__main__":  # pragma: no cover
    pytest.main([__file__])
