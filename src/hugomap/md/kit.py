"""What the moving window and its inflow reservoir need to know of the numba MD backend
(``MDKit``, a ``particles.kit.ParticleKit``); ``lammps.window.LammpsKit`` is LAMMPS's.
"""

from __future__ import annotations

import os

import numpy as np
import xarray as xr

from ..io.checkpoint import MD_WINDOW_CHECKPOINT, CheckpointKind
from .live_inflow import MDLiveReservoir
from .potential import LJParams
from .sample import fcc_state
from .simulation import MDSimulation
from .state import MDState

__all__ = ["MDKit"]


class MDKit:
    """What the window needs to know of the numba MD backend (``ParticleKit``): reduced LJ
    units, the potential ``lj`` (its cutoff rc and list range rc + skin [σ]), checkpoint
    kind ``MD_WINDOW_CHECKPOINT``; simulations are ``MDSimulation``s."""

    window_kind: CheckpointKind = MD_WINDOW_CHECKPOINT
    units = ("sigma", "sigma tau^-1")  # lengths, velocities (checkpoint attributes)
    scale = 1.0  # σ: the unit of the set-up's fixed lengths

    def __init__(self, lj: LJParams | None = None) -> None:
        self.lj = lj

    def rc(self, sim) -> float:
        """The cutoff of ``sim``'s potential [σ]."""
        return float(sim.lj.rc)

    def rlist(self) -> float:
        """rc + skin [σ]: the reservoir is at least 4 of these long."""
        return float(self.lj.rlist)

    def kT(self, T: float) -> float:
        """k_B T [ε] of a temperature T [ε/k_B]."""
        return T

    m_kin = 1.0  # m·(velocity² → energy): K = ½ m_kin Σ v²

    def reservoir(
        self, cells: tuple[int, int, int], rho0: float, T0: float, dt: float, seed: int,
        tau_bath: float,
    ) -> MDSimulation:  # fmt: skip
        """A fully periodic FCC box at (ρ0, T0) under the CSVR thermostat."""
        state = fcc_state(cells, rho0, T0, seed, periodic_x=True)
        return MDSimulation(state, self.lj, dt, T_bath=T0, tau_bath=tau_bath, seed=seed)

    def periodic(self, x: np.ndarray, v: np.ndarray, L: np.ndarray, dt: float) -> MDSimulation:
        """A fully periodic NVE box of these atoms (the snapshot, its pole run)."""
        st = MDState(x=x, v=v, L=L.copy(), periodic=np.array([True, True, True]))
        return MDSimulation(st, self.lj, dt)

    def bulk_fields(self, run: MDSimulation, L: np.ndarray) -> tuple[float, float, float]:
        """(P_xx, (P_yy + P_zz)/2, T) of a periodic box: one bin over all of it."""
        from ..particles.profiles import fields_from_sums

        f = fields_from_sums(run.profile_sums(float(L[0])), float(np.prod(L)))
        return float(f["Pxx"][0]), 0.5 * float(f["Pyy"][0] + f["Pzz"][0]), float(f["T"][0])

    def domain(
        self, like: MDSimulation, x: np.ndarray, v: np.ndarray, ids: np.ndarray, L: np.ndarray,
        walls0: np.ndarray,
    ) -> MDSimulation:  # fmt: skip
        """The window's domain: periodic across, walls along x, the clock and time step of
        ``like`` (the piston run it is cut from)."""
        s = like.state
        state = MDState(x=x, v=v, L=L, periodic=np.array([False, True, True]), walls0=walls0,
                        ids=ids)  # fmt: skip
        state.time, state.step = s.time, s.step
        return MDSimulation(state, like.lj, like.dt)

    def load(self, ds: xr.Dataset, source: str | os.PathLike | None) -> MDSimulation:
        return MDSimulation.from_dataset(ds, source)

    def skip_force_rows(self, sim: MDSimulation, n: int) -> None:
        """``MDSimulation.skip_force_rows``: the inflow copy leaves the force loop."""
        sim.skip_force_rows(n)

    def live_reservoir(
        self, x: np.ndarray, v: np.ndarray, L: np.ndarray, dt: float, seam_work: str
    ) -> MDLiveReservoir:
        """The live inflow (``md.live_inflow.MDLiveReservoir``): these atoms, positions [σ]
        and velocities [σ/τ] in the reservoir's rest frame, as a periodic NVE box of side
        ``L`` [σ] stepped by ``dt`` [τ] beside the window; ``seam_work`` "returned" or
        "kept"."""
        return MDLiveReservoir(self.periodic(x, v, L, dt), seam_work=seam_work)

    def load_live(self, ds: xr.Dataset, source: str | os.PathLike | None) -> MDLiveReservoir | None:
        """The live reservoir a window checkpoint holds, or None."""
        return MDLiveReservoir.from_dataset(ds, source)
