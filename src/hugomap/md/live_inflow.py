"""The live inflow reservoir of the moving window (``MDWindow``, ``inflow = "live"``).

A frozen inflow copy is one snapshot carried rigidly at u_in: every pass feeds the window
the same instant of the snapshot's long acoustic modes, so each snapshot feeds a flow of its
own (the default liquid's 40-σ snapshots −0.06 to +0.06 σ/τ at 10.76 σ/τ, sd 0.03,
``md.reservoir``). The live reservoir runs the snapshot on, a fully periodic NVE box stepped
with the window, and the copy behind ``x_hi`` follows it: the next image of reservoir atom
i sits at ``unwrap_i(t) + (image_i L_r + offset(t)) e_x`` (``offset`` carried at u_in),
on the reservoir's own trajectory, and is released, with the reservoir's position and
velocity + u_in, as it crosses ``x_hi``; its next image then waits L_r behind. Each pass
feeds a later instant of the same equilibrium fluid, so the acoustic modes average out:
on six snapshots (the default liquid's pole, 10.76 σ/τ, 12 τ averaged) the flow fed in was
−0.011 to +0.006 σ/τ (sd 0.007, errors 0.004–0.010) against −0.004 to +0.053 (sd 0.022)
frozen, ρ 0.7991–0.8010 against 0.8000–0.8031 (ρ0 = 0.80), T 1.975–1.997 against
1.986–2.011 (T0 = 2), at 1.6 times the CPU time of that small window.

The seam is not exact. The released atoms next to it are the previous images of the same
atoms, so at release they see the forces of the same periodic fluid, but chaos in a dense
liquid spreads upstream faster than the inflow streams in: 0.05 τ after release atoms are
already 1e-4–0.05 σ off their reservoir images (median 0.1 σ after 0.6 τ), and the force on
a newly released atom differs from the reservoir's by up to about half. The copy is then a
live equilibrium fluid beside, not inside, the window's material; what it feeds in is
measured, not assumed (``inflow_drift`` with ``InflowScreen.inflow = "live"``). The faster
the inflow, the less of that spread reaches the seam: a uniform flow at 9 σ/τ keeps ρ and T
within 0.04 % and 0.8 %, at 6 σ/τ (below c0 ≈ 7 σ/τ, which no shock window's inflow is)
the seam heats it by 12 % (``tests/physics/test_window_flow.py``).

``unwrap`` holds each atom's continuous position (its periodic jumps undone) and ``image``
its next image's index, both by the atom's id, so an atom that crosses the reservoir's
boundary keeps its place in the chain of images and none is fed twice or skipped.
Reduced LJ units."""

from __future__ import annotations

import json

import numpy as np
import xarray as xr

from .simulation import MDSimulation

LIVE_PREFIX = "live_"  # the reservoir's checkpoint variables inside a window checkpoint


class LiveReservoir:
    """A periodic NVE box (``sim``) run one step at a time beside the window, with each
    atom's unwrapped position ``unwrap`` (N, 3) [σ] indexed by its id (module docstring)."""

    def __init__(
        self, sim: MDSimulation, unwrap: np.ndarray | None = None, image: np.ndarray | None = None
    ) -> None:
        self.sim = sim
        s = sim.state
        n = s.n
        if unwrap is None:
            unwrap = np.empty((n, 3))
            unwrap[s.ids] = s.x
        self.unwrap = np.ascontiguousarray(unwrap, dtype=float)
        self.image = np.zeros(n, dtype=np.int64) if image is None else image.astype(np.int64)
        self._last = np.empty((n, 3))
        self._last[s.ids] = s.x
        self.L = s.L.copy()

    @property
    def n(self) -> int:
        return self.sim.state.n

    def step(self, dt: float) -> None:
        """One velocity-Verlet step of ``dt`` [τ]; the unwrapped positions follow."""
        if self.sim.dt != dt:
            self.sim.dt = dt
        self.sim.advance(1)
        s = self.sim.state
        now = np.empty_like(self._last)
        now[s.ids] = s.x
        d = now - self._last
        d -= self.L * np.rint(d / self.L)  # one step moves far less than half a box
        self.unwrap += d
        self._last = now

    def image_x(self, offset: float) -> np.ndarray:
        """x [σ] of each atom's next image in the window, by id: ``unwrap_x + image L_r +
        offset`` (``offset``: where the reservoir's x = 0 is carried, moving at u_in)."""
        return self.unwrap[:, 0] + self.image * self.L[0] + offset

    def images(self, sel: np.ndarray, offset: float) -> np.ndarray:
        """Positions (len(sel), 3) [σ] of the next images of atoms ``sel`` (ids)."""
        X = self.unwrap[sel].copy()
        X[:, 0] += self.image[sel] * self.L[0] + offset
        return X

    def velocities(self) -> np.ndarray:
        """Velocities (N, 3) [σ/τ] in the reservoir's rest frame, by id."""
        s = self.sim.state
        v = np.empty_like(s.v)
        v[s.ids] = s.v
        return v

    def to_dataset(self) -> xr.Dataset:
        """The reservoir's checkpoint (``MDSimulation.to_dataset``, bit-exact) and its
        unwrapped positions, every name prefixed ``live_``, its seal in ``live_attrs``."""
        ds = self.sim.to_dataset()
        out = ds.rename({k: LIVE_PREFIX + k for k in {*ds.variables, *ds.dims}})
        out[LIVE_PREFIX + "unwrap"] = ((LIVE_PREFIX + "atom", LIVE_PREFIX + "xyz"),
                                       self.unwrap.copy(), {"units": "sigma",
                                       "long_name": "live reservoir unwrapped positions, by id"})  # fmt: skip
        out[LIVE_PREFIX + "image"] = ((LIVE_PREFIX + "atom",), self.image.copy(),
                                      {"units": "1", "long_name": "next image index, by id"})  # fmt: skip
        out.attrs = {LIVE_PREFIX + "attrs": json.dumps(ds.attrs)}
        return out

    @classmethod
    def from_dataset(cls, ds: xr.Dataset, source=None) -> LiveReservoir | None:
        """The live reservoir stored in a window checkpoint, or None if it has none."""
        key = LIVE_PREFIX + "attrs"
        if key not in ds.attrs:
            return None
        own = (LIVE_PREFIX + "unwrap", LIVE_PREFIX + "image")
        names = [k for k in ds.data_vars if k.startswith(LIVE_PREFIX) and k not in own]
        sub = ds[names]
        sub = sub.rename({k: k[len(LIVE_PREFIX) :] for k in {*sub.variables, *sub.dims}})
        sub.attrs = json.loads(ds.attrs[key])
        sim = MDSimulation.from_dataset(sub, source)
        return cls(sim, ds[own[0]].values.copy(), ds[own[1]].values)
