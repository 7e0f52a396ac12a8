"""The moving window's inflow reservoir: the snapshot whose copies
``particles.window.ParticleWindow`` feeds in (``make_reservoir``), chosen among candidates by
its energy and, for a fluid, by the flow it leaves in the material it feeds (``InflowScreen``, ``inflow_drift``: the seam
disturbance is each snapshot's own). Any particle backend, through its kit
(``particles.kit.ParticleKit``), in the simulation's units.
"""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass

import numpy as np

from ..analysis.stats import block_average
from ..failures import WindowError
from .fcc import lattice_constant
from .kit import ParticleKit, ParticleSim
from .window import ParticleWindow

log = logging.getLogger(__name__)


def make_reservoir(
    kit: ParticleKit, cells_yz: tuple[int, int], rho0: float, T0: float, dt: float,
    seed: int, equilibrate_time: float, tau_bath: float = 0.5, n_candidates: int = 40,
    every: int = 25, E0_target: float | None = None, pole_time: float = 2.0,
    min_length: float = 0.0, screen: InflowScreen | None = None,
) -> tuple[ParticleSim, dict[str, float]]:  # fmt: skip
    """The inflow's snapshot and the state of the material it feeds in.

    A fully periodic FCC box at (ρ0, T0), as many cells along x as make L_r ≥ 4 (rc + skin)
    and L_r ≥ ``min_length`` [length], thermostatted (CSVR) for ``equilibrate_time`` [τ].
    The material a snapshot feeds in is off the pole by a disturbance of its own: on the
    default liquid at u_p = 3 the material ahead of AMW's front moved at +0.064, +0.038,
    +0.023 σ/τ, its ρ 0.62, 0.27, 0.17 % above ρ0, with L_r = 11, 22, 45 σ
    (``window.reservoir_length``; below). One snapshot of a few hundred atoms
    carries the canonical fluctuations of its energy (several % per atom), and every copy
    repeats them, so the snapshot is chosen: of ``n_candidates`` taken every ``every`` steps,
    the one whose potential energy is closest to the target, its velocities then rescaled
    so that its energy per atom is ``E0_target`` exactly (the piston sample's measured E0:
    window and piston points then share their pole; a snapshot chosen only near the NVT mean
    was up to 0.06 ε per atom off, which moved P0 by 2 %, as much as a weak shock's
    P − P0 error budget) or, without a target, its temperature T0.

    The disturbance differs from snapshot to snapshot and shrinks as the snapshot grows:
    fed as a uniform flow at 10.76 σ/τ (``inflow_drift``, 20 τ averaged), the default
    liquid's snapshots flowed at −0.06 to +0.06 σ/τ (sd 0.030, 20 snapshots) with L_r =
    40 σ, sd 0.015 (8) with 120 σ and about 0.01 with 240 σ (−0.011 to +0.019, errors
    0.01; laid in 40-σ segments, ``ParticleWindow.from_piston(segment=)``; but on a 240-σ
    snapshot AMW oscillated), and AMW's P at u_p = 2 followed the flow fed in (about −1 %
    of P for +0.06 σ/τ). With ``screen`` (``InflowScreen``) the candidates closest to the target are
    tried in that order, each fed as a uniform flow through a window (``inflow_drift``),
    and the first whose flow is within ``screen.tolerance``·``screen.speed`` of the inflow's
    is kept (else the one closest to it; one that cannot reach E0 is passed over); the pole then carries the kept snapshot's flow ``inflow_du`` and its
    error, and how many were tried (``screened``).

    The returned pole is the inflow material's state, which the window points refer to:
    ρ0 exact, E0 the snapshot's energy per atom (conserved once released), and P0, Pyy0, T0
    measured on the released material itself, the snapshot run without thermostat for
    ``pole_time`` [τ] (block-average errors).

    ``kit`` (``ParticleKit``: ``md.kit.MDKit`` of the potential, ``lammps.window.LammpsKit``
    of the model) builds the boxes, so the same choice runs on any particle backend, in its
    own units: ρ0 [length⁻³], T0 its temperature
    (k_B T0 = ``kit.kT(T0)`` [energy]), E0 [energy per atom], P [energy/length³]."""
    a = lattice_constant(rho0)
    nx = max(2, math.ceil(max(4.0 * kit.rlist(), float(min_length)) / a))
    res = kit.reservoir((nx, *cells_yz), rho0, T0, dt, seed, tau_bath)
    res.advance(max(1, int(round(equilibrate_time / dt))))
    L = res.state.L.copy()
    n = res.state.n
    ke_T0 = 1.5 * (n - 1) * kit.kT(T0)  # kinetic energy at T0 with the momentum removed
    target_pe = None if E0_target is None else n * E0_target - ke_T0
    snaps = []
    for _ in range(n_candidates):
        res.advance(every)
        _, pe = res.energies()
        snaps.append((pe, res.state.x.copy(), res.state.v.copy(), res.state.ids.copy()))
    _close(res)
    pes = np.array([sn[0] for sn in snaps])
    goal = pes.mean() if target_pe is None else target_pe
    order = np.argsort(np.abs(pes - goal), kind="stable")
    if screen is None:
        snap = _snapshot(kit, snaps[order[0]], L, dt, ke_T0, E0_target)
    else:
        best, tried = None, 0
        for k in order[: max(1, min(screen.candidates, n_candidates))]:
            tried += 1
            try:
                cand = _snapshot(kit, snaps[k], L, dt, ke_T0, E0_target)
            except WindowError:
                if tried == 1:  # the nearest cannot reach E0: none can
                    raise
                continue
            d, d_err = inflow_drift(kit, cand, screen)
            log.info("inflow candidate %d: flow %+.4g ± %.2g", tried, d, d_err)
            if best is None or abs(d) < abs(best[1]):
                _close(best[0] if best is not None else None)
                best = (cand, d, d_err)
            else:
                _close(cand)
            if abs(d) <= screen.tolerance * screen.speed:
                break
        snap, du, du_err = best
    ke, pe = snap.energies()
    # The pole, measured on a copy of the snapshot released as it will be in the window.
    run = kit.periodic(snap.state.x.copy(), snap.state.v.copy(), L, dt)
    series: dict[str, list[float]] = {"Pxx": [], "Pyy": [], "T": []}
    for _ in range(max(16, int(round(pole_time / (every * dt))))):
        run.advance(every)
        pxx, pyy, T = kit.bulk_fields(run, L)
        series["Pxx"].append(pxx)
        series["Pyy"].append(pyy)
        series["T"].append(T)
    pole = {"rho0": n / float(np.prod(L)), "rho0_err": 0.0, "E0": (ke + pe) / n, "E0_err": 0.0}
    for key, name in (("Pxx", "P0"), ("Pyy", "Pyy0"), ("T", "T0")):
        pole[name], pole[name + "_err"] = block_average(np.asarray(series[key]))
    _close(run)
    if screen is not None:
        pole.update(du=float(du), du_err=float(du_err), screened=float(tried))
    return snap, pole


def _snapshot(kit, cand: tuple, L: np.ndarray, dt: float, ke_T0: float,
              E0_target: float | None):  # fmt: skip
    """A candidate (pe, x, v, ids) as a periodic NVE box: its momentum removed, its
    velocities rescaled to the energy per atom ``E0_target`` (or to T0's kinetic energy
    ``ke_T0``), its atoms in id order."""
    pe, x, v, ids = cand
    n = x.shape[0]
    v = v - v.mean(axis=0)
    ke = ke_T0 if E0_target is None else n * E0_target - pe
    if not ke > 0.5 * ke_T0:
        raise WindowError(
            "reservoir_energy",
            f"the inflow snapshot cannot reach E0 = {E0_target:.4g}: its potential energy "
            f"{pe / n:.4g} per atom leaves a temperature below T0/2",
        )
    v *= math.sqrt(2.0 * ke / (kit.m_kin * float(np.sum(v * v))))
    order = np.argsort(ids)
    return kit.periodic(x[order], v[order], L, dt)


def _close(sim) -> None:
    """Free a simulation that holds an outside instance (LAMMPS); nothing for the numba MD."""
    close = getattr(sim, "close", None)
    if close is not None:
        close()


@dataclass(frozen=True)
class InflowScreen:
    """How ``make_reservoir`` screens its candidate snapshots (``inflow_drift``): a uniform
    flow of ``speed`` [velocity; the window's expected D] sampled where the window measures
    the state ahead of its front, from ``near`` to ``far`` [length] upstream of the inflow
    seam x_hi (``window_ahead``), through a window ``far`` + 5 ``kit.scale`` long
    (``ghost_width``, ``cut_every``, ``sync_steps``, the inflow ``segment`` as the window's),
    flushed for one transit of window and inflow copy, then averaged for ``average_time`` [time]; ``candidates``
    tried at most; ``tolerance`` [-]: a snapshot is kept when its material flows within
    ``tolerance``·``speed`` of the inflow (the density it then arrives at is off ρ0 by about
    that fraction: mass flux ρ (V − δu) = ρ0 V)."""

    speed: float
    near: float
    far: float
    ghost_width: float
    cut_every: float
    sync_steps: int
    average_time: float
    candidates: int
    tolerance: float
    segment: float = 0.0
    inflow: str = "frozen"


def inflow_screen(window: dict, gap: float, speed: float) -> InflowScreen | None:
    """The screen of a scene's ``window`` block (``reservoir_screen``; its geometry the
    window's) at ``speed`` [velocity], sampling the state ahead's slab of a front at
    ``front_fraction`` with ``shock.gap`` = ``gap`` [length] (``analysis.shock``: from
    x_f + gap to x_hi − gap), or None where it tries no candidate."""
    rs = window["reservoir_screen"]
    if rs["candidates"] < 1:
        return None
    far = (1.0 - float(window["front_fraction"])) * float(window["length"]) - float(gap)
    return InflowScreen(
        float(speed), float(gap), max(far, float(gap) + 1.0), float(window["ghost_width"]),
        float(window["cut_every"]), int(window["sync_steps"]), float(rs["average_time"]),
        int(rs["candidates"]), float(rs["tolerance"]), float(window["reservoir_segment"]),
    )  # fmt: skip


def inflow_drift(kit, snap, screen: InflowScreen) -> tuple[float, float]:
    """The mean x velocity δu [velocity], relative to the inflow's u_in, of the material a
    snapshot feeds into a window, and its block-average error.

    The window (``ParticleWindow.from_piston`` with u_p = 0, D_guess = ``screen.speed``) is cut
    from copies of the snapshot itself laid end to end (periodic images: nothing to relax),
    so u_in = u_out = −V and only the inflow's seams act; after one transit it samples the
    mobile atoms from ``near`` to ``far`` upstream of the inflow seam every ``sync_steps``.
    The inflow is supersonic (V > c0), so nothing downstream reaches that slab: it sees what
    a shock window's material ahead of the front sees. What the seam leaves changes with V
    and along the flow as the disturbed material relaxes (one snapshot, 40-σ window: +0.006,
    −0.025, +0.056 σ/τ at V = 6, 8, 10), hence the speed and the slab of the window's own
    measurement."""
    s = snap.state
    Lr = float(s.L[0])
    sc = kit.scale
    wall = 4.0 * sc  # from_piston's default wall layer
    length = screen.far + 5.0 * sc
    need = length + screen.ghost_width + 2.0 * wall + 2.0 * sc
    copies = max(2, math.ceil(need / Lr))
    x0 = s.x.copy()
    x0[:, 0] %= Lr  # the copies tile [0, copies L_r) exactly, as from_piston lays them
    x = np.concatenate([x0 + np.array([i * Lr, 0.0, 0.0]) for i in range(copies)])
    v = np.tile(s.v - s.v.mean(axis=0), (copies, 1))
    L = np.array([copies * Lr, s.L[1], s.L[2]])
    ids = np.arange(x.shape[0], dtype=np.int64)
    flow = kit.domain(snap, x, v, ids, L, np.array([-sc, 0.0, L[0] + sc, 0.0]))
    front = wall + screen.ghost_width + sc + 0.5 * length
    win = ParticleWindow.from_piston(
        flow, snap, front, 0.0, screen.speed, length, 0.5, screen.ghost_width,
        screen.cut_every, screen.sync_steps, kit=kit, segment=screen.segment,
        inflow=screen.inflow,
    )  # fmt: skip
    _close(flow)
    flush = (length + win.geom.segment) / screen.speed
    win.advance(int(round(flush / win.dt)))
    g = win.geom
    series = []
    for _ in range(max(16, int(round(screen.average_time / (screen.sync_steps * win.dt))))):
        win.advance(screen.sync_steps)
        st = win.sim.state
        xs = st.x[:, 0]
        m = (st.ids >= 0) & (xs >= g.x_hi - screen.far) & (xs < g.x_hi - screen.near)
        series.append(float(st.v[m, 0].mean()) - win.u_in)
    _close(win.sim)
    return block_average(np.asarray(series))
