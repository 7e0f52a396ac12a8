"""The NPT run that finds a crystal's lattice constant at ``sample.lattice_pressure`` and T0
(the rule, its keys and where its result is used: ``lattice``'s module docstring). A module of
its own: it runs a ``shockframe.FrameBox``, and ``shockframe`` checks its box's pole with
``lattice``'s rule.
"""

from __future__ import annotations

import logging
import math
import time
from typing import Any

import numpy as np

from ..analysis.stats import block_average
from ..particles.fcc import lattice_constant
from .lattice import pressure_units
from .shockframe import FrameBox
from .units import unit_system

log = logging.getLogger("hugomap")

N_BLOCKS = 8
SAMPLE_EVERY = 10  # steps between samples of the NPT box's volume and pressure
SEED_OFFSET = 15485863  # the search box's velocity seed: sample.seed + this


def search_lattice(scene: dict) -> dict[str, Any]:
    """The FCC lattice constant of the scene's model at T0 and ``sample.lattice_pressure``
    (``lattice``'s module docstring), from a periodic NPT box (``shockframe.FrameBox``) on
    the scene's MPI ranks (global thermo values only). Returns: ``lattice_constant`` a and its ``_err`` [σ |
    Å], ``number_density`` 4/a³ [σ⁻³ | Å⁻³], ``nominal_lattice_constant`` [σ | Å], the
    requested ``pressure`` and the run's mean hydrostatic ``pressure_measured`` with its
    ``_err`` [ε σ⁻³ | GPa] (``pressure_unit``), ``T0`` and the run's mean
    ``temperature_measured`` [ε/k_B | K], ``cells``, ``run_time`` [τ | ps], ``pdamp`` [τ | ps],
    ``atom_steps`` and this process's ``cpu_s``, ``wall_s`` [s]."""
    s, model = scene["sample"], scene["model"]
    q = s["lattice_search"]
    usys = unit_system(model)
    _, to_lammps, unit = pressure_units(usys)
    p, T0, dt = float(s["lattice_pressure"]), float(s["T0"]), float(s["dt"])
    p_native = p * to_lammps
    cells = tuple(int(c) for c in q["cells"])
    n_half = max(int(round(0.5 * float(q["run_time"]) / dt)), 2 * N_BLOCKS * SAMPLE_EVERY)
    cpu0, wall0 = time.process_time(), time.perf_counter()
    box = FrameBox(model, cells, float(s["rho0"]), 2.0 * T0, dt, int(s["seed"]) + SEED_OFFSET)
    try:
        box.commands([
            f"fix hm_npt all npt temp {T0!r} {T0!r} {float(s['thermostat_tau'])!r} "
            f"iso {p_native!r} {p_native!r} {float(q['pdamp'])!r}",
        ])  # fmt: skip
        box.run(n_half)
        series = box.sample(n_half // SAMPLE_EVERY, SAMPLE_EVERY)
        atom_steps = float(box.n * box.steps)
    finally:
        box.close()
    a_i = (series["vol"] / math.prod(cells)) ** (1.0 / 3.0)
    a, a_err = block_average(a_i, N_BLOCKS)
    p_i = (series["pxx"] + series["pyy"] + series["pzz"]) / 3.0 / to_lammps
    p_mean, p_err = block_average(p_i, N_BLOCKS)
    out = {
        "lattice_constant": a, "lattice_constant_err": a_err, "number_density": 4.0 / a**3,
        "nominal_lattice_constant": lattice_constant(s["rho0"]),
        "pressure": p, "pressure_unit": unit, "pressure_measured": p_mean,
        "pressure_measured_err": p_err, "T0": T0,
        "temperature_measured": float(np.mean(series["temp"])), "cells": list(cells),
        "run_time": float(q["run_time"]), "pdamp": float(q["pdamp"]), "atom_steps": atom_steps,
        "cpu_s": time.process_time() - cpu0, "wall_s": time.perf_counter() - wall0,
    }  # fmt: skip
    log.info("lattice at %g %s and T0 = %g: a = %.6g +- %.2g (nominal %.6g), %.0f s of CPU",
             p, unit, T0, a, a_err, out["nominal_lattice_constant"], out["cpu_s"])  # fmt: skip
    return out
