"""The pole of a prepared particle sample, for both particle backends: measured on the
sample between its walls (``measure_pole``), and the state its reference Hugoniot is
computed at (``reference_pole``).
"""

from __future__ import annotations

import numpy as np

from ..analysis.shock import bin_edges, slab_state
from ..analysis.stats import block_average
from ..states import Pole, Profile
from .kit import ParticleSim

POLE_EVERY = 25  # steps between pole samples
#: A slab state's quantity → the pole's name for it.
POLE_KEYS = {"rho": "rho0", "P": "P0", "E": "E0", "T": "T0", "Pyy": "Pyy0"}
MIN_SAMPLES = 16  # pole samples at least, however short ``pole_time``


def measure_pole(
    run: ParticleSim, view: ParticleSim, prof: Profile, length: float, layer: float,
    pole_time: float, dt: float, every: int = POLE_EVERY,
) -> dict[str, float]:  # fmt: skip
    """The pole of a sample between two walls, its thermostat off: n = max(round(pole_time
    / (dt · every)), ``MIN_SAMPLES``) times, ``run`` advances ``every`` steps and the slab
    state of the bins between ``layer`` and ``length`` − ``layer`` is read
    (``analysis.shock.slab_state``: ``prof`` over the nb = ⌊length/w + 10⁻⁹⌋ whole bins of
    width w from x = 0, read on ``view``); each quantity's pole is the block average of its
    n values with its standard error (``analysis.stats.block_average``):

        rho0, P0 = P_xx, E0, T0, Pyy0  and  rho0_err, …, Pyy0_err,

    in ``prof``'s units (reduced LJ units, or SI through an SI view). ``run`` is the
    simulation, ``view`` what ``prof`` reads (the simulation, or its SI view); ``length``
    (L_x) and ``layer`` (kept clear of each wall) in ``prof``'s length unit [σ | m];
    ``pole_time``, ``dt`` in the simulation's time unit [τ | ps]."""
    n_samples = max(int(round(pole_time / (dt * every))), MIN_SAMPLES)
    series: dict[str, list[float]] = {k: [] for k in POLE_KEYS}
    nb = int(np.floor(length / prof.bin_width + 1e-9))
    edges = bin_edges(prof, nb)
    for _ in range(n_samples):
        run.advance(every)
        st = slab_state(prof, prof.sums(view)[:nb], edges, layer, length - layer)
        for k in POLE_KEYS:
            series[k].append(st[k])
    pole = {}
    for k, name in POLE_KEYS.items():
        pole[name], pole[name + "_err"] = block_average(np.asarray(series[k]))
    return pole


def reference_pole(scene: dict, pole: Pole) -> dict[str, float]:
    """The (ρ0 [σ⁻³], T0 [ε/k_B]) an equilibrium reference is computed at, with their
    standard errors: the sample's measured T0 and, for a fluid, its measured bulk ρ0. A
    crystal keeps the lattice's ρ0 (``sample.rho0``; ``sizing.size_bulk`` does not resize
    it): its atoms stay on their sites, so the bulk density is the lattice's exactly, while
    the slab measurement counts whole bins against planes a/2 apart and is off by up to one
    plane in the slab (+0.34 % on the default crystal)."""
    fluid = scene["phase"] != "crystal"
    return {
        "rho0": float(pole.rho0) if fluid else float(scene["sample"]["rho0"]),
        "rho0_err": float(pole.rho0_err) if fluid else 0.0,
        "T0": float(pole.T0),
        "T0_err": float(pole.T0_err),
    }
