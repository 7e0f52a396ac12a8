"""The moving window on LAMMPS: the one particle window (``particles.window.ParticleWindow``)
over a ``LammpsSimulation``, through ``LammpsKit``; in units metal seen in SI through
``si.WindowSIView``.

``LammpsKit`` is what ``ParticleWindow`` and ``particles.reservoir.make_reservoir`` need
beyond the simulation's interface (``particles.kit.ParticleKit``): the domain and the
reservoir are LAMMPS instances of the scene's own model (``model``), the reservoir a fully
periodic box
(``LammpsSimulation(periodic_x=True)``) of the scene's FCC lattice at (ρ0, T0) under
LAMMPS's CSVR thermostat, so the inflow of an EAM copper scene is EAM copper. Its checkpoint
kind is ``io.checkpoint.LAMMPS_WINDOW_CHECKPOINT``. Everything is in LAMMPS's native units
(lj: σ, τ, ε; metal: Å, ps, eV, K).

Units metal: the window works natively; ``si.WindowSIView`` converts what crosses the seam.
"""

from __future__ import annotations

import os

import numpy as np
import xarray as xr

from ..failures import WindowError
from ..io.checkpoint import LAMMPS_WINDOW_CHECKPOINT, CheckpointKind
from ..particles.live_inflow import LiveReservoir
from .simulation import NATIVE_NAMES, LammpsSimulation
from .units import UNIT_SYSTEMS

#: The length the window set-up's fixed lengths are counted in (``particles.window``: MARGIN, the
#: seam's overlap distance, the walls' layer = 2, 0.8, 4 of these): lj 1 σ; metal 2 Å, so
#: the walls' layer is the backend's 8 Å (``backend.WALL_LAYER``) and the seam overlap
#: distance 1.6 Å (copper's nearest neighbours are 2.55 Å apart).
SCALE = {"lj": 1.0, "metal": 2.0}


class LammpsKit:
    """``particles.kit.ParticleKit`` for LAMMPS: ``model`` is the scene's validated ``model``
    block (None: only for loading a checkpoint, which carries its model)."""

    window_kind: CheckpointKind = LAMMPS_WINDOW_CHECKPOINT

    def __init__(self, model: dict | None, units: str = "lj") -> None:
        self.model = None if model is None else dict(model)
        self.usys = UNIT_SYSTEMS[units if model is None else self.model["units"]]
        self.units = NATIVE_NAMES[self.usys.name]
        self.scale = SCALE[self.usys.name]
        # K = ½ m mvv2e Σ v² [energy] (lj: 1)
        self.m_kin = 1.0 if model is None else float(self.model["mass"]) * self.usys.mvv2e

    def rc(self, sim: LammpsSimulation) -> float:
        """The model's cutoff [σ | Å]."""
        return sim.rc

    def rlist(self) -> float:
        """Cutoff plus the neighbour skin [σ | Å]."""
        from .scene_config import model_cutoff

        return model_cutoff(self.model) + float(self.model["skin"])

    def kT(self, T: float) -> float:
        """k_B T [ε | eV] of T [ε/k_B | K]."""
        return self.usys.k_B * T

    def reservoir(
        self, cells: tuple[int, int, int], rho0: float, T0: float, dt: float, seed: int,
        tau_bath: float,
    ) -> LammpsSimulation:  # fmt: skip
        """The scene's FCC lattice at ρ0 [σ⁻³ | Å⁻³], Maxwell velocities at T0 (variance
        k_B T0/(m mvv2e)), periodic in x, y, z, under ``fix temp/csvr`` at T0 [ε/k_B | K]."""
        from ..particles.fcc import fcc_positions, maxwell_velocities

        x, L = fcc_positions(cells, rho0)
        v = maxwell_velocities(x.shape[0], self.kT(T0) / self.m_kin, seed)
        return LammpsSimulation(
            x, v, np.arange(x.shape[0]), L, np.array([0.0, 0.0, L[0], 0.0]), self.model, dt,
            T_bath=T0, tau_bath=tau_bath, seed=seed, periodic_x=True,
        )  # fmt: skip

    def periodic(self, x: np.ndarray, v: np.ndarray, L: np.ndarray, dt: float) -> LammpsSimulation:
        """A fully periodic NVE box of these atoms."""
        return LammpsSimulation(x, v, np.arange(x.shape[0]), L, np.array([0.0, 0.0, L[0], 0.0]),
                                self.model, dt, periodic_x=True)  # fmt: skip

    def bulk_fields(self, run: LammpsSimulation, L: np.ndarray) -> tuple[float, float, float]:
        """(P_xx, (P_yy + P_zz)/2 [ε σ⁻³ | eV Å⁻³], T [ε/k_B | K]) of a periodic box of
        volume V: K_aa = m mvv2e (Σv_a² − c ū_a²), P_aa = (K_aa + ΣW_aa)/V, T = ΣK_aa/(3 (c
        − 1) k_B) (``particles.profiles`` with the mass and k_B)."""
        s = run.profile_sums(float(L[0]))[0]
        c = s[0]
        ubar = s[1:4] / c
        kin = self.m_kin * (s[4:7] - c * ubar * ubar)
        P = (kin + s[8:11]) / float(np.prod(L))
        return (
            float(P[0]),
            0.5 * float(P[1] + P[2]),
            float(kin.sum() / (3.0 * (c - 1.0) * self.usys.k_B)),
        )

    def domain(
        self, like: LammpsSimulation, x: np.ndarray, v: np.ndarray, ids: np.ndarray,
        L: np.ndarray, walls0: np.ndarray,
    ) -> LammpsSimulation:  # fmt: skip
        """The window's domain: a new LAMMPS instance of ``like``'s model, walls along x,
        ``like``'s clock and time step."""
        return LammpsSimulation(x, v, ids, L, walls0, like.model, like.dt, time=like.time,
                                step=like.step)  # fmt: skip

    def load(self, ds: xr.Dataset, source: str | os.PathLike | None) -> LammpsSimulation:
        return LammpsSimulation.from_dataset(ds, source)

    def skip_force_rows(self, sim: LammpsSimulation, n: int) -> None:
        """Nothing: LAMMPS computes the force on its frozen atoms (``fix nve/noforce`` ignores
        it); its neighbour lists are its own."""

    def live_reservoir(
        self, x: np.ndarray, v: np.ndarray, L: np.ndarray, dt: float, seam_work: str
    ) -> LiveReservoir:
        """The live inflow (``particles.live_inflow.LiveReservoir``): these atoms, positions
        [σ | Å] and velocities [σ/τ | Å/ps] in the reservoir's rest frame, as a periodic NVE
        LAMMPS box of side ``L`` stepped by ``dt`` [τ | ps] beside the window. The seam's
        work is kept (``seam_work`` "kept"): taking it back needs the pair forces between
        the copy and the window's atoms, which the numba MD computes and LAMMPS does not
        give (``WindowError`` "bad_config" for "returned")."""
        if seam_work != "kept":
            raise WindowError(
                "bad_config",
                f"a LAMMPS window's live inflow keeps the seam's work, not {seam_work!r}",
            )
        return LiveReservoir(self.periodic(x, v, L, dt), seam_work="kept")

    def load_live(self, ds: xr.Dataset, source: str | os.PathLike | None) -> LiveReservoir | None:
        """The live reservoir a window checkpoint holds, or None."""
        return LiveReservoir.from_dataset(ds, source, LammpsSimulation.from_dataset)
