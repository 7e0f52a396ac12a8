"""Bit-exact checkpoints of a ``CSPHSimulation`` (the piston runs of the workflow; SI units).

A checkpoint is a netCDF dataset holding every array of ``CSPHSimulation.checkpoint_arrays``
(state, walls, neighbour list and its reference positions), the solver's scalars and
parameters (EOS and strength with their sources, θ, C, k_comp, walls present, periodicity,
gradient correction, ``dev_mean``, the density update), optional extra variables (the pole, the front history) and
a SHA-256 checksum over all of it: an ``io.checkpoint.CSPH_CHECKPOINT``. ``load_simulation``
refuses a foreign, altered or truncated file with ``CheckpointError`` naming it, and the
continuation of a loaded run is bit for bit the uninterrupted one (same thread count).
"""

from __future__ import annotations

import json
import os
from pathlib import Path

import numpy as np
import xarray as xr

from ..eos import EOS
from ..io.atomic import write_netcdf
from ..io.checkpoint import CSPH_CHECKPOINT, read_checkpoint, seal_checkpoint, verify_checkpoint
from ..strength import Strength
from .simulation import CSPHSimulation


def solver_params(sim: CSPHSimulation) -> dict:
    """The parameters that rebuild ``sim`` (JSON-able)."""
    return {
        "eos": sim.eos.name, "eos_params": sim.eos.params.tolist(), "eos_source": sim.eos.source,
        "strength": sim.strength.name, "strength_params": sim.strength.params.tolist(),
        "strength_source": sim.strength.source, "theta": sim.theta, "cfl": sim.cfl,
        "k_comp": sim.k_comp, "grad_correction": sim.grad_correction,
        "dev_mean": sim.dev_mean, "density": sim.density_mode, "skin": sim.skin, "dt_floor": sim.dt_floor,
        "escape": sim.escape, "extent": list(sim.extent),
        "has_wall": [bool(b) for b in sim.has_wall], "periodic": [bool(b) for b in sim.periodic],
        "lo": sim.lo.tolist(), "length": sim.length.tolist(),
    }  # fmt: skip


def to_dataset(
    sim: CSPHSimulation, extra: xr.Dataset | None = None, attrs: dict | None = None
) -> xr.Dataset:
    """The checkpoint of ``sim`` with ``extra`` variables and ``attrs``, sealed
    (``io.checkpoint.seal_checkpoint``: format version and checksum)."""
    data = {}
    for k, a in sim.checkpoint_arrays().items():
        a = a.astype(np.int8) if a.dtype == np.bool_ else a
        data["sim_" + k] = (tuple(f"sim_{k}_{d}" for d in range(a.ndim)), a)
    ds = xr.Dataset(data)
    if extra is not None:
        ds = xr.merge([ds, extra])
    ds.attrs.update(attrs or {})
    ds.attrs.update(
        sim_format=CSPH_CHECKPOINT.format,
        sim_scalars=json.dumps(sim.checkpoint_scalars()),
        sim_solver=json.dumps(solver_params(sim)),
    )
    return seal_checkpoint(ds, CSPH_CHECKPOINT)


def save_simulation(
    sim: CSPHSimulation,
    path: str | os.PathLike,
    extra: xr.Dataset | None = None,
    attrs: dict | None = None,
) -> Path:
    """Write the checkpoint atomically (``io.atomic``)."""
    return write_netcdf(to_dataset(sim, extra, attrs), path)


def from_dataset(ds: xr.Dataset, source: str | os.PathLike | None = None) -> CSPHSimulation:
    """Rebuild the simulation saved in ``ds``; ``CheckpointError`` naming ``source`` (default:
    the file ``ds`` was opened from) if it is foreign or altered."""
    verify_checkpoint(ds, source, CSPH_CHECKPOINT)
    sol = json.loads(ds.attrs["sim_solver"])
    sc = json.loads(ds.attrs["sim_scalars"])
    arrays = {k[4:]: ds[k].values for k in ds.data_vars if k.startswith("sim_")}
    if "frozen" in arrays:
        arrays["frozen"] = arrays["frozen"].astype(bool)
    eos = EOS(sol["eos"], np.array(sol["eos_params"]), sol["eos_source"])
    strength = Strength(sol["strength"], np.array(sol["strength_params"]), sol["strength_source"])
    from .state import SPHState

    st = SPHState(x=arrays["x"], v=arrays["v"], m=arrays["m"], rho=arrays["rho"],
                  e=arrays["e"], S=arrays["S"], eps_p=arrays["eps_p"], l=arrays["l"],
                  time=float(sc["time"]))  # fmt: skip
    w = arrays["walls"]
    hw = sol["has_wall"]
    sim = CSPHSimulation(
        st, eos, strength, theta=sol["theta"], cfl=sol["cfl"], k_comp=sol["k_comp"],
        walls=(float(w[0]) if hw[0] else None, float(w[1]), float(w[2]) if hw[1] else None,
               float(w[3])),
        periodic=tuple(sol["periodic"]), lo=tuple(sol["lo"]), length=tuple(sol["length"]),
        grad_correction=sol["grad_correction"], dev_mean=sol["dev_mean"], skin=sol["skin"],
        dt_floor=sol["dt_floor"], escape_distance=sol["escape"],
        # a checkpoint written before the density choice existed ran the continuity equation
        density=sol.get("density", "continuity"),
    )  # fmt: skip
    sim.extent = tuple(sol["extent"])
    sim.restore(arrays, sc)
    return sim


def load_simulation(path: str | os.PathLike) -> tuple[CSPHSimulation, xr.Dataset]:
    """(simulation, dataset) of a checkpoint file (the dataset holds the extra variables); an
    unreadable, foreign or altered file raises ``CheckpointError`` naming it."""
    ds = read_checkpoint(path, verify=False)
    return from_dataset(ds, path), ds
