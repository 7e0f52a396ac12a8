"""The live inflow reservoir of the moving window (``particles.window.ParticleWindow``,
``inflow = "live"``), on any particle backend.

A frozen inflow copy is one snapshot carried rigidly at u_in: every pass feeds the window
the same instant of the snapshot's long acoustic modes, so each snapshot feeds a flow of its
own (the default liquid's 40-σ snapshots −0.06 to +0.06 σ/τ at 10.76 σ/τ, sd 0.03,
``particles.reservoir``). The live reservoir runs the snapshot on, a fully periodic NVE box stepped
with the window, and the copy behind ``x_hi`` follows it: the next image of reservoir atom
i sits at ``unwrap_i(t) + (image_i L_r + offset(t)) e_x`` (``offset`` carried at u_in),
on the reservoir's own trajectory, and is released, with the reservoir's position and
velocity + u_in, as it crosses ``x_hi``; its next image then waits L_r behind. Each pass
feeds a later instant of the same equilibrium fluid, so the acoustic modes average out:
on six snapshots (the default liquid's pole, 10.76 σ/τ, 12 τ averaged) the flow fed in was
−0.011 to +0.006 σ/τ (sd 0.007, errors 0.004–0.010) against −0.004 to +0.053 (sd 0.022)
frozen, ρ 0.7991–0.8010 against 0.8000–0.8031 (ρ0 = 0.80), T 1.975–1.997 against
1.986–2.011 (T0 = 2), at 1.6 times the CPU time of that small window.

A crystal's frozen copy also pushes: it does not vibrate, and the crystal released beside
it streams off faster than the inflow. Fed as a uniform flow, the LJ crystal (ρ 1.05, T
0.4, 12 σ/τ) moved 0.008–0.016 σ/τ ahead of u_in over the first 40 σ frozen, within ±0.0005
live; EAM copper (Cu_mishin1 at its 300-K zero-pressure lattice, 68 Å/ps) 8.7 m/s at the
seam, 6–8 m/s 50–100 Å on, frozen, and the material ahead of a window's front at 1500 and
2000 m/s was 0.23 GPa in tension, moving at −9 m/s.

``unwrap`` holds each atom's continuous position (its periodic jumps undone) and ``image``
its next image's index, both by the atom's id, so an atom that crosses the reservoir's
boundary keeps its place in the chain of images and none is fed twice or skipped.
In the simulation's units; the reservoir is the kit's periodic box (``ParticleKit.periodic``)."""

from __future__ import annotations

import json

import numpy as np
import xarray as xr

from .kit import ParticleSim

SEAM_WORK = ("returned", "kept")  # what becomes of the copy's excess work at the seam
LIVE_PREFIX = "live_"  # the reservoir's checkpoint variables inside a window checkpoint


class LiveReservoir:
    """A periodic NVE box (``sim``, the kit's ``periodic``) run one step at a time beside the
    window, with each atom's unwrapped position ``unwrap`` (N, 3) [length] indexed by its id
    (module docstring). ``seam_work``: "kept", or "returned" where a subclass takes the
    copy's excess work back (``md.live_inflow.MDLiveReservoir``); the twins of released atoms
    are kept here for it."""

    def __init__(
        self,
        sim: ParticleSim,
        unwrap: np.ndarray | None = None,
        image: np.ndarray | None = None,
        seam_work: str = "kept",
        returned: float = 0.0,
        twins: np.ndarray | None = None,
    ) -> None:
        if seam_work not in SEAM_WORK:
            raise ValueError(f"seam_work = {seam_work!r}: one of {SEAM_WORK}")
        self.sim = sim
        self.seam_work = seam_work
        self.returned = float(returned)  # the work returned so far [energy] (``return_seam_work``)
        # released atoms still by the seam, one row each: window id, reservoir id, the image
        # it was released from (``record_release``)
        tw = np.zeros((0, 3)) if twins is None else np.asarray(twins)
        self.twins = tw.astype(np.int64).reshape(-1, 3)
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
        """One velocity-Verlet step of ``dt`` [time]; the unwrapped positions follow."""
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
        """x [length] of each atom's next image in the window, by id: ``unwrap_x + image L_r +
        offset`` (``offset``: where the reservoir's x = 0 is carried, moving at u_in)."""
        return self.unwrap[:, 0] + self.image * self.L[0] + offset

    def images(self, sel: np.ndarray, offset: float) -> np.ndarray:
        """Positions (len(sel), 3) [length] of the next images of atoms ``sel`` (ids)."""
        X = self.unwrap[sel].copy()
        X[:, 0] += self.image[sel] * self.L[0] + offset
        return X

    def velocities(self) -> np.ndarray:
        """Velocities (N, 3) [velocity] in the reservoir's rest frame, by id."""
        s = self.sim.state
        v = np.empty_like(s.v)
        v[s.ids] = s.v
        return v

    def record_release(self, window_ids: np.ndarray, reservoir_ids: np.ndarray,
                       images: np.ndarray) -> None:  # fmt: skip
        """Note that reservoir atoms ``reservoir_ids``, released from their images ``images``,
        are now the window's atoms ``window_ids`` (their twins, ``return_seam_work``)."""
        rows = np.column_stack([window_ids, reservoir_ids, images]).astype(np.int64)
        self.twins = np.concatenate([self.twins, rows])

    def keep_twins(self, window_ids: np.ndarray) -> None:
        """Forget the twins of every released atom but ``window_ids`` (those still by the
        seam)."""
        self.twins = self.twins[np.isin(self.twins[:, 0], window_ids)]

    def twin_positions(self, rows: np.ndarray, offset: float) -> np.ndarray:
        """Positions (len(rows), 3) [length] in the window of the reservoir twins of released atoms
        (``twins`` rows): the images they were released from, carried on with the reservoir."""
        X = self.unwrap[rows[:, 1]].copy()
        X[:, 0] += rows[:, 2] * self.L[0] + offset
        return X

    def to_dataset(self) -> xr.Dataset:
        """The reservoir's checkpoint (its simulation's ``to_dataset``: the numba MD's
        bit-exact) and its unwrapped positions, every name prefixed ``live_``, its seal in
        ``live_attrs``."""
        ds = self.sim.to_dataset()
        length = ds["x"].attrs.get("units", "sigma")
        out = ds.rename({k: LIVE_PREFIX + k for k in {*ds.variables, *ds.dims}})
        out[LIVE_PREFIX + "unwrap"] = ((LIVE_PREFIX + "atom", LIVE_PREFIX + "xyz"),
                                       self.unwrap.copy(), {"units": length,
                                       "long_name": "live reservoir unwrapped positions, by id"})  # fmt: skip
        out[LIVE_PREFIX + "image"] = ((LIVE_PREFIX + "atom",), self.image.copy(),
                                      {"units": "1", "long_name": "next image index, by id"})  # fmt: skip
        out[LIVE_PREFIX + "twins"] = ((LIVE_PREFIX + "twin", LIVE_PREFIX + "twin_field"),
                                      self.twins.copy(), {"units": "1", "long_name":
                                      "released atoms by the seam: window id, reservoir id, "
                                      "image released from"})  # fmt: skip
        out.attrs = {LIVE_PREFIX + "attrs": json.dumps(ds.attrs),
                     LIVE_PREFIX + "seam": json.dumps({"seam_work": self.seam_work,
                                                      "returned": self.returned})}  # fmt: skip
        return out

    @classmethod
    def from_dataset(cls, ds: xr.Dataset, source, load) -> LiveReservoir | None:
        """The live reservoir stored in a window checkpoint, or None if it has none; ``load``
        (ds, source) → the reservoir's simulation (the kit's ``load``)."""
        key = LIVE_PREFIX + "attrs"
        if key not in ds.attrs:
            return None
        own = (LIVE_PREFIX + "unwrap", LIVE_PREFIX + "image", LIVE_PREFIX + "twins")
        names = [k for k in ds.data_vars if k.startswith(LIVE_PREFIX) and k not in own]
        sub = ds[names]
        sub = sub.rename({k: k[len(LIVE_PREFIX) :] for k in {*sub.variables, *sub.dims}})
        sub.attrs = json.loads(ds.attrs[key])
        sim = load(sub, source)
        # checkpoints written before the seam's work was returned kept it
        seam = json.loads(ds.attrs.get(LIVE_PREFIX + "seam", '{"seam_work": "kept"}'))
        twins = ds[own[2]].values if own[2] in ds else None
        return cls(sim, ds[own[0]].values.copy(), ds[own[1]].values, seam["seam_work"],
                   seam.get("returned", 0.0), twins)  # fmt: skip
