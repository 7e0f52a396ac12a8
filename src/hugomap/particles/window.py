"""The moving observation window of molecular dynamics, over either particle backend.

Frame: the window's. Fresh material enters at the upstream edge ``x_hi`` moving at
``u_in`` < 0; shocked material leaves at the downstream edge ``x_lo`` moving at ``u_out``.
With the lab frame's upstream material at rest and the window moving at W (SEED-en.md, reading
notes): u_in = −W, u_out = u_p − W, so u_p = u_out − u_in, and a front at rest in the window
has D = −u_in. Units below: reduced LJ units (σ, τ, ε; m = 1), or the simulation's own.

Inflow (no gap or overlap at the seam). Fresh material comes from a reservoir: a snapshot
of a fully periodic box (length L_r, the domain's transverse size) equilibrated at the
scene's initial state. Beyond ``x_hi`` one copy of the snapshot, or of a segment of it,
moves rigidly at u_in (frozen, like the outflow layer): a piston that pushes fresh material
in. When its face reaches ``x_hi``, the copy is released (its atoms become mobile with the
snapshot's thermal velocities + u_in) and the next one is laid right behind it: the next
segment, and after the last the first again. Consecutive segments are neighbours in the
snapshot, and the last and the first are the snapshot's periodic image, so the seam between
two copies is never a cut: no gap, no overlap. The flow a snapshot feeds in is off u_in by
a disturbance of its own that shrinks as the snapshot grows (``particles.reservoir``); segments
let a long snapshot feed the window at the cost of a short one. That is the frozen inflow
(``inflow = "frozen"``). The live one (``inflow = "live"``, ``particles.live_inflow``) runs the
snapshot on beside the window: the copy behind ``x_hi`` follows the reservoir's trajectories
(``_drive_copy``, every step) and each atom is released, with the reservoir's state, at the
boundary update after it crosses ``x_hi``, its next image laid L_r behind; it feeds no flow
of its own, so it is not screened and not laid in segments. It needs the supersonic inflow
every shock window has (D > c0): the flow test (``tests/physics/test_window_flow.py``) at
9 σ/τ keeps ρ within 0.04 % and T within 0.8 %, but at 6 σ/τ, below c0 ≈ 7 σ/τ, the seam
heats it by 12 % (an earlier design of this kind heated it by 30 %).

Outflow (holds the shocked state). The material behind ``x_lo`` is a rigid piston made of the
shocked material itself: the atoms within ``ghost_width`` (≥ rc) behind the face are frozen
and move at ``u_out``, so the mobile atoms see a snapshot of their own state on the far side,
and a reflecting wall at the face, moving with it, keeps every mobile atom in front of it
(without the wall, atoms squeezed through the frozen snapshot: the shocked material then
streamed 0.14 σ/τ faster than u_out at u_p = 2 and its pressure fell 8 %). The boundary is
the piston of the piston method, in the window frame, at the flow speed. When the face has
moved ``cut_every`` behind ``x_lo``, the layer is cut again: frozen atoms farther than
``ghost_width`` behind ``x_lo`` are removed, the mobile atoms behind ``x_lo`` are frozen
(their thermal velocities dropped), and the face and the wall return to ``x_lo``.

Absorbing outflow (``outflow = "absorbing"``, ``set_absorbing``). The rigid layer reflects
every wave that reaches it; the shocked region between the front and the outflow then rings,
and at weak shocks it adjusts only over the transit time of sound running upstream against
the outflow, ~s u_p (1 − u_p/D) σ/τ in the window frame. The absorbing layer moves at
    u_face = u_out − (P_fast − P_slow)/Z,
the velocity a left-running (outgoing) simple wave of pressure jump P_fast − P_slow carries
(δP = −Z δu), so such a wave leaves without reflection (the characteristic, "non-reflecting"
boundary condition of hydrocodes). P is the pressure the mobile atoms exert on the boundary:
the x-force on the layer's atoms plus the wall's impulse rate, over the area, sampled every
``sync_steps``; P_fast and P_slow are its exponential averages over ``tau_fast`` (noise) and
``tau_slow`` (the steady level: over longer times the layer moves at u_out on average).
Z = ρ0 D (the Rayleigh-line impedance (P1 − P0)/u_p) stands for the shocked material's
ρ1 c1 ≈ ρ0 (D + s u_p); the mismatch reflects (Z1 − Z)/(Z1 + Z), ~10 % at u_p = 1.

Frozen atoms carry negative ids (inflow copy −1 − j, outflow layer ≤ −1 − N_res) and are
skipped by the kicks, the walls and every observable (``md.integrate``, ``MDSimulation``).

One window for every particle backend. ``ParticleWindow`` drives any simulation that offers
what it reads (``particles.kit.ParticleKit`` names it): a ``state`` view with x, v, f, ids
(negative: frozen, moving rigidly at its own velocity, exerting forces, in no observable),
impulse, L, walls0, time, step, ref_velocity; ``advance``, ``place_walls``,
``replace_atoms``, ``galilean_shift``, ``profile_sums``, ``mean_velocity``,
``wall_positions``, ``dt``, ``to_dataset``. What differs between backends, building a simulation (the domain, the
reservoir, the live one), loading one, its cutoff, units and checkpoint kind, comes from a
``ParticleKit``: ``md.kit.MDKit`` (numba MD, reduced LJ units; ``md.window.MDWindow`` is this
window with that kit by default), ``lammps.window.LammpsKit`` for LAMMPS. All lengths, times
and velocities are the simulation's own units; the fixed lengths of the set-up (``MARGIN``,
the seam's overlap distance, the walls' layer) are multiples of the kit's ``scale`` (MD:
1 σ). The live reservoir is the kit's (``kit.live_reservoir``); only the numba MD's takes the
seam's excess work back (``md.live_inflow.MDLiveReservoir``).
"""

from __future__ import annotations

import json
import math
import os
from dataclasses import asdict, dataclass
from pathlib import Path

import numpy as np
import xarray as xr

from ..failures import SolverUnstable, WindowError
from ..io.atomic import write_netcdf
from ..io.checkpoint import (
    read_checkpoint,
    seal_checkpoint,
    verify_checkpoint,
)
from .kit import ParticleKit, ParticleSim

MARGIN = 2.0  # σ (kit scales) of empty box beyond the frozen layers


@dataclass
class WindowGeometry:
    """x_lo, x_hi [σ]: window edges in the box; ghost_width [σ]: frozen outflow layer;
    cut_every [σ]: face travel between outflow cuts; sync_steps: steps between boundary
    updates; res_length [σ]: reservoir length (a whole number of lattice cells);
    seg_length [σ]: the length of the snapshot laid frozen behind ``x_hi`` at a time, a
    whole fraction of res_length (0: the whole snapshot)."""

    x_lo: float
    x_hi: float
    ghost_width: float
    cut_every: float
    sync_steps: int
    res_length: float
    seg_length: float = 0.0

    @property
    def segment(self) -> float:
        """The frozen copy's length [σ]."""
        return self.seg_length if self.seg_length > 0 else self.res_length

    @property
    def n_segments(self) -> int:
        return max(1, int(round(self.res_length / self.segment)))

    @property
    def length(self) -> float:
        return self.x_hi - self.x_lo


def _phase(x: np.ndarray, period: float) -> float:
    """Phase [0, period) of a set of coordinates against a lattice of planes of that period."""
    z = np.exp(2j * np.pi * x / period).mean()
    return float((np.angle(z) / (2 * np.pi)) % 1.0 * period)


class ParticleWindow:
    """A moving window around a particle simulation (module docstring): any that ``kit``
    (``ParticleKit``) describes. A window made without a kit asks ``default_kit`` for one:
    none here; ``md.window.MDWindow`` gives the numba MD's.

    Implements the window protocol (``methods.protocol``) in the window frame: ``advance``,
    ``galilean_shift``, ``set_outflow``, ``count_in_window``, ``profile_sums``, checkpoints.
    ``res_x``/``res_v`` (N_res, 3): the reservoir snapshot (positions in [0, L_r) along x,
    thermal velocities in its rest frame); ``x_face_in``/``x_face``: the faces of the frozen
    inflow copy and of the frozen outflow layer [σ, or the simulation's length unit].
    """

    @staticmethod
    def default_kit(sim: ParticleSim | None = None) -> ParticleKit:
        """The kit of a window made without one (of ``sim``; None: loading a checkpoint):
        a backend's window class names its own; this one has none."""
        raise TypeError("a ParticleWindow needs its backend's kit (particles.kit.ParticleKit)")

    def __init__(
        self,
        sim: ParticleSim,
        res_x: np.ndarray,
        res_v: np.ndarray,
        geom: WindowGeometry,
        u_in: float,
        u_out: float,
        x_face_in: float,
        x_face: float,
        next_id: int,
        kit=None,
        seg_index: int = 0,
        live=None,
    ):
        self.kit = kit if kit is not None else self.default_kit(sim)
        self.live = live
        self.sim = sim
        self.res_x = np.asarray(res_x, dtype=float)
        self.res_v = np.asarray(res_v, dtype=float)
        self.geom = geom
        self.u_in = float(u_in)
        self.u_out = float(u_out)
        self.x_face_in = float(x_face_in)
        self.x_face = float(x_face)
        self.next_id = int(next_id)
        self.seg_index = int(seg_index)
        self.area = float(sim.state.L[1] * sim.state.L[2])
        self.n_res = int(self.res_x.shape[0])
        self.kit.skip_force_rows(sim, self.n_res)
        # the outflow: rigid (the layer moves at u_out) or absorbing (module docstring)
        self.outflow = "rigid"
        self.z_out = self.tau_fast = self.tau_slow = 0.0
        self.p_fast = self.p_slow = float("nan")
        self.u_face = self.u_out
        self.impulse_mark = float(sim.state.impulse[0])
        self._set_ref_velocity()

    def set_absorbing(
        self, impedance: float, tau_fast: float, tau_slow: float, p_start: float
    ) -> None:
        """Make the outflow absorbing (module docstring): ``impedance`` Z [m σ⁻² τ⁻¹],
        averaging times ``tau_fast`` < ``tau_slow`` [τ]; both averages start at ``p_start``
        [ε σ⁻³] (the jump condition's P0 + ρ0 D u_p: starting them from one noisy sample
        let the layer leak for tau_slow and the shocked P fell 3 %)."""
        if not (impedance > 0 and 0 < tau_fast < tau_slow):
            raise ValueError(
                f"absorbing outflow needs Z > 0 and 0 < tau_fast < tau_slow, got {impedance}, "
                f"{tau_fast}, {tau_slow}"
            )
        self.outflow = "absorbing"
        self.z_out, self.tau_fast, self.tau_slow = (
            float(impedance),
            float(tau_fast),
            float(tau_slow),
        )
        self.p_fast = self.p_slow = float(p_start)
        self.impulse_mark = float(self.sim.state.impulse[0])

    def face_pressure(self, interval: float) -> float:
        """P on the outflow boundary [ε σ⁻³]: −Σ f_x over the layer's atoms plus the wall's
        impulse since the last call over ``interval`` [τ], per area."""
        s = self.sim.state
        layer = s.ids < -self.n_res
        imp = float(s.impulse[0])
        p = (-float(np.sum(s.f[layer, 0])) + (imp - self.impulse_mark) / interval) / self.area
        self.impulse_mark = imp
        return p

    def _steer_outflow(self, interval: float) -> None:
        """Absorbing outflow: update P_fast, P_slow and move the layer and its wall at u_face."""
        p = self.face_pressure(interval)
        self.p_fast += (p - self.p_fast) * min(1.0, interval / self.tau_fast)
        self.p_slow += (p - self.p_slow) * min(1.0, interval / self.tau_slow)
        self._move_layer(self.u_out - (self.p_fast - self.p_slow) / self.z_out)

    def _move_layer(self, u_face: float) -> None:
        s = self.sim.state
        layer = s.ids < -self.n_res
        v = s.v
        v[layer, 0] = u_face
        v[layer, 1:] = 0.0
        s.v = v  # a copy (LAMMPS on several ranks) takes effect when assigned back
        xl, xr = self.sim.wall_positions()
        self.sim.place_walls(self.x_face, u_face, xr, s.walls0[3])
        self.u_face = float(u_face)

    def _set_ref_velocity(self) -> None:
        # The material streams at u_in upstream and u_out downstream: discounting their mean
        # from the list-rebuild test leaves displacements of about u_p/2 per unit time.
        self.sim.state.ref_velocity = 0.5 * (self.u_in + self.u_out)

    # -- set-up ------------------------------------------------------------------------------
    @classmethod
    def from_piston(
        cls,
        sim: ParticleSim,
        res: ParticleSim,
        x_front: float,
        u_p: float,
        D_guess: float,
        length: float,
        front_fraction: float,
        ghost_width: float,
        cut_every: float,
        sync_steps: int,
        wall_layer: float | None = None,
        crystal: bool = False,
        lattice: float | None = None,
        kit=None,
        segment: float = 0.0,
        inflow: str = "frozen",
        seam_work: str = "kept",
    ) -> ParticleWindow:
        """Cut a window out of a piston run (piston frame: piston at rest at the left wall,
        upstream material at −u_p) with the front at ``front_fraction`` of ``length`` from
        the outflow edge, and move to the frame in which a front of speed ``D_guess`` is at
        rest: every velocity gets u_p − D_guess, so u_in = −D_guess, u_out = u_p − D_guess.
        ``res`` is the reservoir snapshot (``make_reservoir``).

        For a crystal (``crystal``), the seam is placed so that the reservoir's lattice planes
        continue the sample's (period a/2 along each axis, ``lattice`` = a).

        ``kit`` (default ``default_kit(sim)``) builds the domain simulation; ``wall_layer``
        (default 4 of the kit's ``scale``) is kept clear of the piston run's walls. ``segment`` > 0
        lays the snapshot frozen behind ``x_hi`` a segment at a time, the longest whole
        fraction of L_r not above it (and at least one; module docstring). ``inflow``:
        "frozen" or "live"; a live one's ``seam_work`` (``md.live_inflow``): "returned" (the
        copy's excess work at the seam, over what it does on the released atoms' reservoir
        twins, is taken back each step; the scene default) or "kept" (this default)."""
        kit = kit if kit is not None else cls.default_kit(sim)
        unit = kit.units[0]
        wall_layer = 4.0 * kit.scale if wall_layer is None else wall_layer
        if ghost_width < kit.rc(sim):
            raise WindowError(
                "bad_config", f"ghost_width = {ghost_width} {unit} is less than rc = {kit.rc(sim)}"
            )
        s = sim.state
        xl, xr = sim.wall_positions()
        lo_s = x_front - front_fraction * length
        hi_s = x_front + (1.0 - front_fraction) * length
        if lo_s - ghost_width < xl + wall_layer or hi_s > xr - wall_layer:
            raise WindowError(
                "sample_too_short",
                f"a window of {length:.1f} {unit} around the front at {x_front:.1f} needs "
                f"[{lo_s - ghost_width:.1f}, {hi_s:.1f}] inside [{xl + wall_layer:.1f}, "
                f"{xr - wall_layer:.1f}]: shorten the window or lengthen the sample",
            )
        mobile = s.ids >= 0
        x, v = s.x[mobile].copy(), s.v[mobile].copy()
        r = res.state
        rx, rv = r.x.copy(), r.v - r.v.mean(axis=0)
        Lr = float(r.L[0])
        if crystal:
            if lattice is None:
                raise ValueError("crystal windows need the lattice constant")
            half = 0.5 * lattice
            up = (x[:, 0] > hi_s - 4 * lattice) & (x[:, 0] < hi_s)
            for d in (1, 2):  # transverse registry: shift the reservoir onto the sample
                shift = _phase(x[up, d], half) - _phase(rx[:, d], half)
                rx[:, d] = (rx[:, d] + shift) % r.L[d]
            # Reservoir planes at a/4 + m a/2; the seam x_hi goes a/4 past a sample plane, so
            # the first reservoir plane, at x_hi + a/4, continues the sample's lattice.
            rx[:, 0] = (rx[:, 0] + 0.25 * lattice - _phase(rx[:, 0], half)) % Lr
            target = (_phase(x[up, 0], half) + 0.25 * lattice) % half
            hi_s = hi_s - ((hi_s - target) % half)
        rx[:, 0] %= Lr
        margin = MARGIN * kit.scale
        x_lo = ghost_width + cut_every + margin
        shift = x_lo - (hi_s - length)
        x[:, 0] += shift
        x_hi = hi_s + shift
        keep = (x[:, 0] >= x_lo - ghost_width) & (x[:, 0] < x_hi)
        x, v = x[keep], v[keep]
        ids = np.arange(x.shape[0], dtype=np.int64)
        du = u_p - D_guess
        v[:, 0] += du
        u_in, u_out = -u_p + du, du
        n_res = r.n
        frozen = x[:, 0] < x_lo
        ids[frozen] = -1 - n_res - ids[frozen]
        v[frozen] = [u_out, 0.0, 0.0]
        # a live copy is the whole snapshot (its atoms cross x_hi one by one)
        seg = Lr / max(1, int(Lr // segment)) if segment > 0 and inflow != "live" else 0.0
        geom = WindowGeometry(x_lo, x_hi, ghost_width, cut_every, sync_steps, Lr, seg)
        # The first inflow copy (its first segment), right behind the sample's upstream end.
        xi, vi, idi = _inflow_copy(rx, geom, 0, x_hi, u_in)
        x = np.concatenate([x, xi])
        v = np.concatenate([v, vi])
        ids = np.concatenate([ids, idi])
        x, v, ids = _remove_seam_overlaps(x, v, ids, n_res, x_hi, s.L, 0.8 * kit.scale)
        Lx = x_hi + 2.0 * geom.segment + 2.0 * margin
        L = np.array([Lx, s.L[1], s.L[2]])
        wall_x = x_lo  # a reflecting wall at the face: no atom leaks into the layer
        # The window keeps the piston run's clock (and its dt).
        dom = kit.domain(sim, x, v, ids, L, np.array([wall_x, u_out, Lx, 0.0]))
        dom.place_walls(wall_x, u_out, Lx, 0.0)
        live = None
        if inflow == "live":
            # the copy laid above is the reservoir at t = 0: unwrap = rx, X = rx + x_hi e_x
            live = kit.live_reservoir(rx.copy(), rv.copy(), r.L.copy(), sim.dt, seam_work)
        elif inflow != "frozen":
            raise ValueError(f"inflow = {inflow!r}: 'frozen' or 'live'")
        return cls(dom, rx, rv, geom, u_in, u_out, x_face_in=x_hi, x_face=x_lo,
                   next_id=int(np.count_nonzero(ids >= 0)), kit=kit, live=live)  # fmt: skip

    # -- the time loop -------------------------------------------------------------------------
    @property
    def time(self) -> float:
        return self.sim.time

    @property
    def dt(self) -> float:
        return self.sim.dt

    @property
    def n_particles(self) -> int:
        return int(np.count_nonzero(self.sim.state.ids >= 0))

    @property
    def steps(self) -> int:
        """Time steps of the simulation inside."""
        return self.sim.steps

    def advance(self, n_steps: int) -> None:
        """Advance ``n_steps`` (rounded up to whole boundary updates of ``sync_steps``)."""
        k = self.geom.sync_steps
        for _ in range(max(1, math.ceil(n_steps / k))):
            if self.live is None:
                self.sim.advance(k)
                self.x_face_in += self.u_in * k * self.sim.dt
            else:
                for _ in range(k):
                    self._drive_copy()
                    self.sim.advance(1)
                    self.x_face_in += self.u_in * self.sim.dt
            self.x_face += self.u_face * k * self.sim.dt
            self._update_boundaries()
            if self.outflow == "absorbing":
                self._steer_outflow(k * self.sim.dt)

    def _drive_copy(self) -> None:
        """Live inflow: take back the copy's excess work of the coming step if it is returned
        (``md.live_inflow.MDLiveReservoir.return_seam_work``), step the reservoir and give each
        atom of the copy behind ``x_hi`` the velocity that carries it, in the coming step,
        onto its reservoir trajectory's image (``LiveReservoir.images``; module docstring of
        ``particles.live_inflow``)."""
        s, dt = self.sim.state, self.sim.dt
        copy = (s.ids < 0) & (s.ids >= -self.n_res)
        if self.live.seam_work == "returned":  # the window and the reservoir both at t
            self.live.return_seam_work(s, copy, self.geom.x_hi, self._lag(), self.x_face_in, dt)
        self.live.step(dt)
        X = self.live.images(-1 - s.ids[copy], self.x_face_in + self.u_in * dt)
        d = X - s.x[copy]
        d[:, 1:] -= s.L[1:] * np.rint(d[:, 1:] / s.L[1:])
        v = s.v
        v[copy] = d / dt
        s.v = v  # a LAMMPS state on several ranks holds copies: assigned back

    def _lag(self) -> float:
        """How far past x_hi an image travels between two releases [σ]."""
        return -self.u_in * self.geom.sync_steps * self.sim.dt

    def _update_boundaries(self) -> None:
        """Release the inflow copy that reached ``x_hi`` and lay the next one behind it (live:
        release each atom whose image crossed ``x_hi`` and lay its next image L_r behind);
        cut the outflow layer when its face has moved ``cut_every`` behind ``x_lo``."""
        g, s = self.geom, self.sim.state
        if not self.u_in < 0:
            raise WindowError(
                "no_inflow", f"u_in = {self.u_in:.4g} {self.kit.units[1]} must be < 0"
            )
        if self.x_face > g.x_lo + g.cut_every:
            raise WindowError(
                "outflow_reversed",
                f"the outflow face moved {self.x_face - g.x_lo:.2f} {self.kit.units[0]} into the "
                f"window (u_out = {self.u_out:.4g} {self.kit.units[1]} > 0 for too long)",
            )
        if self.live is None:
            step_travel = -self.u_in * g.sync_steps * self.sim.dt
            release = self.x_face_in < g.x_hi + step_travel
        else:  # atom by atom: each image that has crossed x_hi
            crossed = np.nonzero(self.live.image_x(self.x_face_in) < g.x_hi)[0]
            release = crossed.size > 0
        cut = self.x_face < g.x_lo - g.cut_every
        if not (release or cut):
            return
        x, v, ids = s.x.copy(), s.v.copy(), s.ids.copy()
        if release and self.live is not None:
            copy = (ids < 0) & (ids >= -self.n_res)
            gone = np.zeros(self.n_res, dtype=bool)
            gone[crossed] = True
            m = copy.copy()
            m[copy] = gone[-1 - ids[copy]]
            v[m] = self.live.velocities()[-1 - ids[m]] + np.array([self.u_in, 0.0, 0.0])
            r = -1 - ids[m]
            ids[m] = self.next_id + np.arange(int(m.sum()), dtype=np.int64)
            self.next_id += int(m.sum())
            if self.live.seam_work == "returned":  # twins of the released atoms
                self.live.record_release(ids[m], r, self.live.image[r])
                # ...while they are within reach of the copy, or will be before the next update
                self.live.keep_twins(ids[(ids >= 0) & (x[:, 0] > g.x_hi - 2 * self._lag()
                                                       - self.live.rlist)])  # fmt: skip
            # the same atoms' next images, L_r behind: the reservoir's trajectories go on
            self.live.image[crossed] += 1
            xi = self.live.images(crossed, self.x_face_in)
            xi[:, 1:] -= s.L[1:] * np.floor(xi[:, 1:] / s.L[1:])
            vi = np.zeros_like(xi)
            vi[:, 0] = self.u_in
            x = np.concatenate([x, xi])
            v = np.concatenate([v, vi])
            ids = np.concatenate([ids, -1 - crossed.astype(np.int64)])
        elif release:
            copy = (ids < 0) & (ids >= -self.n_res)
            j = -1 - ids[copy]
            v[copy] = self.res_v[j] + np.array([self.u_in, 0.0, 0.0])
            ids[copy] = self.next_id + np.arange(int(copy.sum()), dtype=np.int64)
            self.next_id += int(copy.sum())
            # The next copy: the snapshot's next segment (after the last, its first: the
            # snapshot's periodic image) one segment behind.
            face = self.x_face_in + g.segment
            self.seg_index = (self.seg_index + 1) % g.n_segments
            xi, vi, idi = _inflow_copy(self.res_x, g, self.seg_index, face, self.u_in)
            x = np.concatenate([x, xi])
            v = np.concatenate([v, vi])
            ids = np.concatenate([ids, idi])
            self.x_face_in = face
        if cut:
            behind = x[:, 0] < g.x_lo
            gone = x[:, 0] < g.x_lo - g.ghost_width
            freeze = behind & ~gone & (ids >= 0)
            ids[freeze] = -1 - self.n_res - ids[freeze]
            v[behind & ~gone] = [self.u_face, 0.0, 0.0]
            x, v, ids = x[~gone], v[~gone], ids[~gone]
            self.x_face = g.x_lo
            wall_x = g.x_lo
            self.sim.place_walls(wall_x, self.u_face, float(s.L[0]), 0.0)
        bad = (x[:, 0] < 0) | (x[:, 0] > s.L[0])
        if bad.any():
            raise SolverUnstable(
                "atom_lost", f"{int(bad.sum())} atoms outside the window box at t = {s.time:.3f}"
            )
        self.sim.replace_atoms(x, v, ids)

    # -- controls ------------------------------------------------------------------------------
    def galilean_shift(self, du: float) -> None:
        """Add ``du`` to every x velocity in the domain (mobile and frozen), to u_in, u_out and
        both walls (the snapshot's own velocities are thermal, in its rest frame)."""
        self.sim.galilean_shift(du)
        self.u_in += du
        self.u_out += du
        self.u_face += du
        self._set_ref_velocity()

    def set_outflow(self, u_out: float) -> None:
        """Set the outflow velocity [σ/τ]: the frozen layer and the wall behind it (an absorbing
        layer keeps its deviation u_face − u_out)."""
        self._move_layer(self.u_face + (u_out - self.u_out))
        self.u_out = float(u_out)
        self._set_ref_velocity()

    def wall_positions(self) -> tuple[float, float]:
        return self.geom.x_lo, self.geom.x_hi

    def profile_sums(self, width: float) -> np.ndarray:
        return self.sim.profile_sums(width)

    def mean_velocity(self) -> float:
        return self.sim.mean_velocity()

    def count_in_window(self) -> int:
        """Mobile atoms with x_lo ≤ x < x_hi."""
        s = self.sim.state
        xs = s.x[:, 0]
        return int(np.count_nonzero((s.ids >= 0) & (xs >= self.geom.x_lo) & (xs < self.geom.x_hi)))

    # -- checkpoints ---------------------------------------------------------------------------
    def to_dataset(self, extra: xr.Dataset | None = None, attrs: dict | None = None) -> xr.Dataset:
        """The complete window state: the domain, the reservoir snapshot, the boundaries;
        sealed with the format version and a checksum over all of it (``seal_checkpoint``)."""
        ds = self.sim.to_dataset(extra, attrs)
        if self.live is not None:  # the reservoir's own checkpoint, under ``live_`` names
            live = self.live.to_dataset()
            ds = ds.merge(live)
            ds.attrs.update(live.attrs)
        ln, vel = self.kit.units
        ds["res_x"] = (("res_atom", "xyz"), self.res_x.copy(), {"units": ln,
                       "long_name": "reservoir snapshot positions"})  # fmt: skip
        ds["res_v"] = (("res_atom", "xyz"), self.res_v.copy(), {"units": vel,
                       "long_name": "reservoir snapshot thermal velocities"})  # fmt: skip
        ds.attrs.update(
            window_format=self.kit.window_kind.format,
            window_geometry=json.dumps(asdict(self.geom)),
            window_state=json.dumps(
                {
                    "u_in": self.u_in,
                    "u_out": self.u_out,
                    "x_face_in": self.x_face_in,
                    "x_face": self.x_face,
                    "next_id": self.next_id,
                    "seg_index": self.seg_index,
                    "outflow": self.outflow,
                    "z_out": self.z_out,
                    "tau_fast": self.tau_fast,
                    "tau_slow": self.tau_slow,
                    "p_fast": self.p_fast,
                    "p_slow": self.p_slow,
                    "u_face": self.u_face,
                    "impulse_mark": self.impulse_mark,
                }
            ),  # fmt: skip
        )
        return seal_checkpoint(ds, self.kit.window_kind)  # the checksum covers the window too

    def save(
        self, path: str | os.PathLike, extra: xr.Dataset | None = None, attrs: dict | None = None
    ) -> Path:
        """Save the window atomically (bit-exact on resume, at the same thread count)."""
        return write_netcdf(self.to_dataset(extra, attrs), path)

    @classmethod
    def from_dataset(
        cls, ds: xr.Dataset, source: str | os.PathLike | None = None, kit=None
    ) -> ParticleWindow:
        """Rebuild a window saved by ``save``; a foreign, outdated or altered checkpoint is
        refused with ``CheckpointError`` naming ``source`` (default: the file of ``ds``).
        ``kit`` (default ``default_kit()``) names the checkpoint kind and loads the simulation
        and its live reservoir, if it has one."""
        kit = kit if kit is not None else cls.default_kit()
        verify_checkpoint(ds, source, kit.window_kind)
        sim = kit.load(ds, source)
        geom = WindowGeometry(**json.loads(ds.attrs["window_geometry"]))
        st = json.loads(ds.attrs["window_state"])
        win = cls(
            sim, ds["res_x"].values.copy(), ds["res_v"].values.copy(), geom, st["u_in"],
            st["u_out"], st["x_face_in"], st["x_face"], st["next_id"], kit=kit,
            seg_index=int(st.get("seg_index", 0)), live=kit.load_live(ds, source),
        )  # fmt: skip
        # the outflow's state (absent from checkpoints written before the absorbing outflow)
        for key in ("outflow", "z_out", "tau_fast", "tau_slow", "p_fast", "p_slow", "u_face",
                    "impulse_mark"):  # fmt: skip
            if key in st:
                setattr(win, key, st[key] if key == "outflow" else float(st[key]))
        return win

    @classmethod
    def load_path(cls, path: str | os.PathLike, kit=None) -> ParticleWindow:
        """Load a window checkpoint written by ``save`` (refused with ``CheckpointError`` if
        it is unreadable, foreign, outdated or altered)."""
        return cls.from_dataset(read_checkpoint(path, verify=False), path, kit)


def _inflow_copy(
    res_x: np.ndarray, geom: WindowGeometry, j: int, face: float, u_in: float
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:  # fmt: skip
    """The frozen inflow copy of segment ``j`` of the snapshot (its atoms with j s ≤ x <
    (j + 1) s, s = ``geom.segment``), its downstream face at ``face``: positions, velocities
    (rigid, u_in along x) and ids (−1 − the snapshot index)."""
    s = geom.segment
    k = np.minimum((res_x[:, 0] // s).astype(np.int64), geom.n_segments - 1)
    sel = np.nonzero(k == j)[0]
    xi = res_x[sel].copy()
    xi[:, 0] += face - j * s
    vi = np.zeros_like(xi)
    vi[:, 0] = u_in
    return xi, vi, -1 - sel.astype(np.int64)


def _remove_seam_overlaps(
    x: np.ndarray, v: np.ndarray, ids: np.ndarray, n_res: int, x_hi: float, L: np.ndarray,
    r_min: float = 0.8,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:  # fmt: skip
    """At set-up only: drop mobile atoms closer than ``r_min`` σ to the first inflow copy (that
    seam joins the piston sample to the reservoir; later seams are periodic images)."""
    near = np.nonzero((ids >= 0) & (x[:, 0] > x_hi - r_min))[0]
    copy = np.nonzero((ids < 0) & (ids >= -n_res) & (x[:, 0] < x_hi + r_min))[0]
    drop = np.zeros(x.shape[0], dtype=bool)
    for i in near:
        dd = x[copy] - x[i]
        for dim in (1, 2):
            dd[:, dim] -= L[dim] * np.rint(dd[:, dim] / L[dim])
        if copy.size and np.min(np.einsum("ij,ij->i", dd, dd)) < r_min**2:
            drop[i] = True
    return x[~drop], v[~drop], ids[~drop]
