"""The live inflow reservoir of the moving window (``MDWindow``, ``inflow = "live"``).

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

The seam's work. The copy follows the reservoir and never recoils: once the window's atoms
by the seam have drifted off their reservoir images (0.1–0.2 σ within rc of the copy, at
8.1 σ/τ), the copy is a driven, unyielding boundary that does on them work it would not do
on its own fluid. The power it delivers to atoms a is P = Σ_a Σ_b F_ba · v_b over the
copy's atoms b (``forces.pair_power``), v_b their velocity in the copy's own frame, which
moves at u_in with the material it feeds; the same sum over the released atoms' reservoir
twins (atom r released from image k sits, in the reservoir, at ``unwrap_r + (k L_r +
offset) e_x``) is what the fluid itself passes across the seam. Their difference, the
seam's excess, heats the inflow: a uniform flow at 8.1 σ/τ (u_p = 1's D; 5 × 5 cells,
40 τ, seeds 5–7) arrives +0.047 to +0.078 ε per atom above the pole's E0 with it kept.
With ``seam_work = "returned"`` (``return_seam_work``; the scene default,
``MDWindow.from_piston``'s is "kept") it is taken back each step from the released atoms
within rc of the copy (their velocities about their mean scaled, momentum kept): −0.023 to
+0.018 ε, and the flow's speed is the inflow's as when kept (u + V −0.018 to +0.016 σ/τ,
kept −0.003 to +0.012). Summed in the window's frame instead (v_b + u_in, which adds the
copy's push on the flow: ``return_seam_work``), it left +0.036 to +0.045 ε and moved the
flow by +0.027 to +0.036 σ/τ. The twins are recorded only when the work is returned
(``record_release``).

``unwrap`` holds each atom's continuous position (its periodic jumps undone) and ``image``
its next image's index, both by the atom's id, so an atom that crosses the reservoir's
boundary keeps its place in the chain of images and none is fed twice or skipped.
Reduced LJ units."""

from __future__ import annotations

import json

import numpy as np
import xarray as xr

from ..failures import SolverUnstable
from .forces import in_reach, pair_power
from .simulation import MDSimulation

SEAM_WORK = ("returned", "kept")  # what becomes of the copy's excess work at the seam
LIVE_PREFIX = "live_"  # the reservoir's checkpoint variables inside a window checkpoint


class LiveReservoir:
    """A periodic NVE box (``sim``) run one step at a time beside the window, with each
    atom's unwrapped position ``unwrap`` (N, 3) [σ] indexed by its id (module docstring)."""

    def __init__(
        self,
        sim: MDSimulation,
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
        self.returned = float(returned)  # the work returned so far [ε] (``return_seam_work``)
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

    @property
    def rlist(self) -> float:
        """rc + skin [σ] of its potential (the window's): how far a copy atom reaches."""
        return self.sim.lj.rlist

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
        """Positions (len(rows), 3) [σ] in the window of the reservoir twins of released atoms
        (``twins`` rows): the images they were released from, carried on with the reservoir."""
        X = self.unwrap[rows[:, 1]].copy()
        X[:, 0] += rows[:, 2] * self.L[0] + offset
        return X

    def return_seam_work(self, s, copy: np.ndarray, x_hi: float, lag: float, offset: float,
                         dt: float) -> float:  # fmt: skip
        """Take back from the window's atoms at the seam the copy's excess work in the coming
        step of ``dt`` [τ] (module docstring), and return it [ε].

        W = dt [Σ_a Σ_b F_ba(x_a) · v_b − Σ_a Σ_b F_ba(x̃_a) · v_b] (``forces.pair_power``)
        over the released atoms a with a twin (x̃_a, ``twin_positions`` at ``offset``) beyond
        x_hi − ``lag`` − rc (every copy atom lies beyond x_hi − ``lag``, the distance an image
        travels between releases) and the copy atoms b (``copy``, a mask of the window state
        ``s``) within rc of them, v_b the reservoir's velocity: the window and the reservoir
        are at the same instant, and the work is the one done in the copy's own frame, which
        moves at u_in with the material it feeds, so W is heat. (In the window's frame, v_b +
        u_in, it also holds u_in · ΔP, ΔP the excess impulse the copy gives: the push that
        keeps the released atoms off the copy, which belongs to their flow, not their heat.
        On the unit tests' window, a uniform flow at 8 σ/τ of 4 × 4 cells, that term made
        W's sd per step 0.78 ε against 0.15 ε without it, and its sum over 2 τ turned the
        heat returned from +25 to −5.5 ε.) The velocities of the a atoms within rc of a copy
        atom (``forces.in_reach``: those the work went to) about their own mean are scaled by
        √(1 − W/K), K their kinetic energy about that mean: momentum is kept and the energy
        changes by exactly −W. (Scaling every a atom, those just released included, cooled a
        uniform flow at 8.1 σ/τ 0.06–0.07 ε per atom below E0, the work then summed in the
        window's frame.)"""
        if not self.twins.size:
            return 0.0
        rc = self.sim.lj.rc
        x = s.x
        idx = np.flatnonzero((s.ids >= 0) & (x[:, 0] > x_hi - lag - rc))
        known = self.twins[:, 0]  # ascending: window ids are handed out in order
        pos = np.minimum(np.searchsorted(known, s.ids[idx]), known.size - 1)
        has = known[pos] == s.ids[idx]
        a = idx[has]
        if a.size < 2:
            return 0.0
        near = copy & (x[:, 0] < float(x[a, 0].max()) + rc)
        vb = self.velocities()[-1 - s.ids[near]]
        xb = x[near]
        xt = self.twin_positions(self.twins[pos[has]], offset)
        rc2 = rc * rc
        work = dt * (pair_power(x[a], xb, vb, s.L, s.periodic, rc2)
                     - pair_power(xt, xb, vb, s.L, s.periodic, rc2))  # fmt: skip
        # back from the atoms that took it: those within rc of the copy
        hit = a[in_reach(x[a], xb, s.L, s.periodic, rc2)]
        if hit.size < 2:
            return 0.0
        v = s.v[hit]
        mean = v.mean(axis=0)
        th = v - mean
        kin = 0.5 * float(np.sum(th * th))
        if not work < kin:
            raise SolverUnstable(
                "seam_work",
                f"the copy's excess work at the seam, {work:.4g} eps in one step, exceeds the "
                f"kinetic energy of the {hit.size} atoms there ({kin:.4g} eps)",
            )
        s.v[hit] = mean + np.sqrt(1.0 - work / kin) * th
        self.returned += work
        return work

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
        out[LIVE_PREFIX + "twins"] = ((LIVE_PREFIX + "twin", LIVE_PREFIX + "twin_field"),
                                      self.twins.copy(), {"units": "1", "long_name":
                                      "released atoms by the seam: window id, reservoir id, "
                                      "image released from"})  # fmt: skip
        out.attrs = {LIVE_PREFIX + "attrs": json.dumps(ds.attrs),
                     LIVE_PREFIX + "seam": json.dumps({"seam_work": self.seam_work,
                                                      "returned": self.returned})}  # fmt: skip
        return out

    @classmethod
    def from_dataset(cls, ds: xr.Dataset, source=None) -> LiveReservoir | None:
        """The live reservoir stored in a window checkpoint, or None if it has none."""
        key = LIVE_PREFIX + "attrs"
        if key not in ds.attrs:
            return None
        own = (LIVE_PREFIX + "unwrap", LIVE_PREFIX + "image", LIVE_PREFIX + "twins")
        names = [k for k in ds.data_vars if k.startswith(LIVE_PREFIX) and k not in own]
        sub = ds[names]
        sub = sub.rename({k: k[len(LIVE_PREFIX) :] for k in {*sub.variables, *sub.dims}})
        sub.attrs = json.loads(ds.attrs[key])
        sim = MDSimulation.from_dataset(sub, source)
        # checkpoints written before the seam's work was returned kept it
        seam = json.loads(ds.attrs.get(LIVE_PREFIX + "seam", '{"seam_work": "kept"}'))
        twins = ds[own[2]].values if own[2] in ds else None
        return cls(sim, ds[own[0]].values.copy(), ds[own[1]].values, seam["seam_work"],
                   seam.get("returned", 0.0), twins)  # fmt: skip
