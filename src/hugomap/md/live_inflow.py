"""The numba MD's live inflow reservoir (``MDLiveReservoir``): the live reservoir of
``particles.live_inflow`` with the copy's excess work at the seam taken back
(``seam_work = "returned"``), which needs the LJ pair forces.

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

Reduced LJ units."""

from __future__ import annotations

import numpy as np
import xarray as xr

from ..failures import SolverUnstable
from ..particles.live_inflow import LiveReservoir
from .forces import in_reach, pair_power
from .simulation import MDSimulation


class MDLiveReservoir(LiveReservoir):
    """``particles.live_inflow.LiveReservoir`` on an ``MDSimulation``, which can also take the
    copy's excess work back (``return_seam_work``)."""

    @property
    def rlist(self) -> float:
        """rc + skin [σ] of its potential (the window's): how far a copy atom reaches."""
        return self.sim.lj.rlist

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

    @classmethod
    def from_dataset(cls, ds: xr.Dataset, source=None) -> MDLiveReservoir | None:
        """The live reservoir stored in a window checkpoint (its ``MDSimulation``), or None if
        it has none."""
        return super().from_dataset(ds, source, MDSimulation.from_dataset)
