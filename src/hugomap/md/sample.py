"""Initial samples of the numba MD: an FCC lattice with Maxwell velocities
(``particles.fcc``), or a LAMMPS data file, as an ``MDState`` (reduced LJ units).

A data file (``sample.data_file``; ``md.lammps_data``) gives the positions, velocities and
box instead of the lattice (``data_state``). The equilibration between the walls that sizes
the box is both particle backends' (``particles.sizing.size_bulk``).
"""

from __future__ import annotations

import os

import numpy as np

from ..particles.fcc import fcc_positions, maxwell_velocities
from .lammps_data import FROZEN, LammpsDataError, read_data
from .state import MDState


def fcc_state(
    cells: tuple[int, int, int], rho: float, T: float, seed: int, periodic_x: bool
) -> MDState:
    """An FCC sample at (ρ, T). With ``periodic_x`` False the box is closed in x by two static
    walls at x = 0 and x = L_x; y and z are always periodic."""
    x, L = fcc_positions(cells, rho)
    v = maxwell_velocities(x.shape[0], T, seed)
    return MDState(
        x=x,
        v=v,
        L=L,
        periodic=np.array([periodic_x, True, True]),
        walls0=np.array([0.0, 0.0, L[0], 0.0]),
    )


def data_state(path: str | os.PathLike) -> MDState:
    """A sample from a LAMMPS data file (``md.lammps_data.read_data``: positions [σ],
    velocities [σ/τ], box): the box moved to start at the origin, y and z wrapped into
    [0, L) (periodic), x closed by two static walls at 0 and L_x; hugomap ids = LAMMPS
    ids − 1. Refused (``LammpsDataError``): frozen atoms (type 2: a sample has none) and
    atoms outside the box along x (the walls would not hold them)."""
    d = read_data(path)
    if np.any(d.types == FROZEN):
        raise LammpsDataError(
            f"LAMMPS data file {path}: {int(np.sum(d.types == FROZEN))} atoms of type 2 "
            "(frozen); a sample starts with mobile atoms only"
        )
    L = d.L
    x = d.x - d.lo
    if np.any(x[:, 0] < 0.0) or np.any(x[:, 0] > L[0]):
        raise LammpsDataError(
            f"LAMMPS data file {path}: atoms outside xlo xhi = {d.lo[0]!r} {d.hi[0]!r}; "
            "the sample's x walls are the box's x bounds"
        )
    x[:, 1:] = np.mod(x[:, 1:], L[1:])
    return MDState(
        x=x, v=d.v.copy(), L=L, periodic=np.array([False, True, True]),
        walls0=np.array([0.0, 0.0, L[0], 0.0]), ids=d.ids - 1,
    )  # fmt: skip


def initial_state(sample: dict) -> MDState:
    """The scene's starting state: ``data_state(sample["data_file"])`` when it is set, else
    ``fcc_state`` at (rho0, T0) with the scene's ``cells`` and ``seed`` between walls."""
    if sample.get("data_file"):
        return data_state(sample["data_file"])
    return fcc_state(tuple(sample["cells"]), sample["rho0"], sample["T0"], sample["seed"],
                     periodic_x=False)  # fmt: skip
