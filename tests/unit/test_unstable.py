"""Runs that break raise SolverUnstable with the right status."""

from __future__ import annotations

import numpy as np
import pytest

from hugomap.failures import SolverUnstable
from hugomap.md.potential import LJParams
from hugomap.md.sample import fcc_state
from hugomap.md.simulation import MDSimulation
from hugomap.md.state import MDState


def _gas(v0, walls0=(0.0, 0.0, 10.0, 0.0), dt=0.005):
    """Four atoms far apart (no forces) in a 10 × 6 × 6 box walled in x."""
    x = np.array([[9.88, 3.0, 3.0], [5.0, 0.5, 0.5], [2.0, 3.0, 0.5], [5.0, 3.5, 5.0]])
    v = np.zeros_like(x)
    v[0] = v0
    st = MDState(
        x=x, v=v, L=np.array([10.0, 6.0, 6.0]), periodic=np.array([False, True, True]),
        walls0=np.array(walls0, dtype=float),
    )  # fmt: skip
    return MDSimulation(st, LJParams(), dt=dt)


def test_absurd_dt():
    st = fcc_state((3, 3, 3), 0.8, 1.5, 1, periodic_x=True)
    sim = MDSimulation(st, LJParams(rc=2.2), dt=0.5)
    with pytest.raises(SolverUnstable) as err:
        sim.advance(10)
    assert err.value.status in ("cfl", "nan")
    assert "dt" in str(err.value) or "NaN" in str(err.value)
    assert sim.state.step == 0  # the failed step is not counted


def test_absurd_velocity_is_cfl():
    # 1000 σ/τ × 0.005 τ = 5 σ in one step, far beyond skin/2 = 0.15 σ.
    sim = _gas([1000.0, 0.0, 0.0], walls0=(0.0, 0.0, 10.0, 0.0))
    sim.state.x[0, 0] = 2.0
    with pytest.raises(SolverUnstable) as err:
        sim.advance(5)
    assert err.value.status == "cfl"
    assert "reduce dt" in err.value.diagnostic


@pytest.mark.parametrize("bad", [np.nan, np.inf])
def test_non_finite_velocity_is_nan(bad):
    sim = _gas([bad, 0.0, 0.0])
    with pytest.raises(SolverUnstable) as err:
        sim.advance(3)
    assert sim.state.step == 0
    assert err.value.status == "nan"


def test_atom_lost():
    # The right wall retreats at 40 σ/τ (0.2 σ per step) beyond the box edge L_x = 10; atom 0
    # follows at 10 σ/τ (0.05 σ per step, no CFL) from 9.88: after 2 steps it is at x = 9.98 (still
    # in the box), after the 3rd at 10.03 > L_x, not yet at the wall (10.6): lost.
    sim = _gas([10.0, 0.0, 0.0], walls0=(0.0, 0.0, 10.0, 40.0))
    with pytest.raises(SolverUnstable) as err:
        sim.advance(10)
    assert err.value.status == "atom_lost"
    assert sim.state.step == 2


def test_healthy_gas_runs():
    # The same gas with a static wall bounces and runs on (the failures above are real).
    sim = _gas([10.0, 0.0, 0.0])
    sim.advance(20)
    assert sim.state.step == 20 and sim.state.impulse[1] == -20.0


def test_bad_setup_rejected():
    st = fcc_state((2, 2, 2), 0.8, 1.5, 1, periodic_x=True)  # L = 3.4 < 2 (rc + skin)
    with pytest.raises(ValueError, match="minimum image"):
        MDSimulation(st, LJParams(), dt=0.005)
    st = fcc_state((3, 3, 3), 0.8, 1.5, 1, periodic_x=True)
    with pytest.raises(ValueError, match="dt"):
        MDSimulation(st, LJParams(rc=2.2), dt=0.0)
