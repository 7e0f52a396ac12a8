"""Velocity-Verlet time loop with reflecting walls, Verlet-list rebuilds and the CSVR thermostat.

One step (Verlet 1967; Swope et al., J. Chem. Phys. 76, 637 (1982)), m = 1:
    v ← v + ½Δt F;  x ← x + Δt v;  walls, wrap;  (rebuild list if needed);  F ← F(x);
    v ← v + ½Δt F;  (thermostat)

Walls: planes normal to x at x_L(t) = x_L + v_L t and x_R(t) = x_R + v_R t. An atom that
crossed one is reflected specularly in the wall's frame: x ← 2 x_w − x, v_x ← 2 v_w − v_x
(as LAMMPS ``fix wall/reflect``; a moving wall is the rigid piston). The momentum handed to
the atoms is accumulated, so the piston pressure is impulse / (area · time).

Thermostat (only to prepare samples and for the equilibrium reference): canonical
stochastic velocity rescaling, Bussi, Donadio & Parrinello, J. Chem. Phys. 126, 014101 (2007),
eq. (A7): with c = exp(−Δt/τ), K the kinetic energy, K_t = ½ N_f T,
    α² = c + (1 − c)(S + R₁²) K_t/(N_f K) + 2 R₁ √(c (1 − c) K_t/(N_f K)),
R₁ standard normal, S chi-squared with N_f − 1 degrees of freedom; v ← α v. The random
numbers are drawn in Python from a seeded generator and passed in, so runs are reproducible.

Status codes returned by ``run_steps``: 0 done, 1 neighbour list too short (grow and go on),
2 NaN or infinite coordinates, 3 step too long (an atom moved more than skin/2 in one step:
the list cannot be trusted, reduce Δt), 4 an atom left the box through a wall.
"""

from __future__ import annotations

import numpy as np

from ..numba_conf import njit
from .forces import forces_full, forces_half, forces_half_threads
from .neighbor import (
    build_full_list,
    build_half_list,
    cell_of,
    counting_sort,
    displacement2,
    half_from_full_rowless,
    half_stencil_ok,
    list_holds,
    rowless_atom,
)

OK, GROW, NAN, CFL, LOST = 0, 1, 2, 3, 4
STATUS_NAMES = {OK: "ok", GROW: "grow", NAN: "nan", CFL: "cfl", LOST: "atom_lost"}


@njit
def kick(v: np.ndarray, f: np.ndarray, ids: np.ndarray, h: float) -> None:
    """v ← v + h F (m = 1) for every mobile atom; frozen atoms (ids < 0) keep their velocity.

    Frozen atoms are the rigid boundary layers of the moving window (``particles.window``):
    they move at their own constant velocity and act on the mobile atoms through the pair
    forces."""
    # Serial: waking numba's waiting threads (OMP_WAIT_POLICY=PASSIVE, ``numba_conf``) for a
    # parallel loop costs more than this loop over tens of thousands of atoms.
    for i in range(v.shape[0]):
        if ids[i] >= 0:
            v[i, 0] += h * f[i, 0]
            v[i, 1] += h * f[i, 1]
            v[i, 2] += h * f[i, 2]


@njit
def drift_walls_wrap(
    x: np.ndarray,
    v: np.ndarray,
    ids: np.ndarray,
    x_ref: np.ndarray,
    dt: float,
    L: np.ndarray,
    periodic: np.ndarray,
    walls: np.ndarray,
    impulse: np.ndarray,
    shift_x: float,
) -> tuple[float, float, int]:
    """x ← x + Δt v, reflect mobile atoms (ids ≥ 0) at the walls, wrap periodic dimensions.

    ``walls`` = [x_L, v_L, x_R, v_R] at the end of the step; ``impulse`` (2,) accumulates the
    x-momentum given to atoms by the left and right wall. Returns the largest squared
    displacement since the last list build (less a uniform ``shift_x`` along x: see
    ``run_steps``), the largest squared one-step move, and 1 if an
    atom is NaN or outside the box.
    """
    n = x.shape[0]
    xl, vl, xr, vr = walls[0], walls[1], walls[2], walls[3]
    bad = 0
    max_d2 = 0.0
    max_step2 = 0.0
    for i in range(n):
        s2 = 0.0
        for d in range(3):
            dxd = dt * v[i, d]
            s2 += dxd * dxd
            x[i, d] += dxd
        if s2 > max_step2 or s2 != s2:
            max_step2 = s2 if s2 == s2 else np.inf
        if not periodic[0] and ids[i] >= 0:
            if x[i, 0] < xl:
                impulse[0] += 2.0 * (vl - v[i, 0])
                x[i, 0] = 2.0 * xl - x[i, 0]
                v[i, 0] = 2.0 * vl - v[i, 0]
            elif x[i, 0] > xr:
                impulse[1] += 2.0 * (vr - v[i, 0])
                x[i, 0] = 2.0 * xr - x[i, 0]
                v[i, 0] = 2.0 * vr - v[i, 0]
        for d in range(3):
            # an atom crosses at most one periodic face a step (its move is below skin/2, the
            # step is refused otherwise), so a branch wraps it: no division on every atom
            if periodic[d]:
                if x[i, d] >= L[d]:
                    x[i, d] -= L[d]
                elif x[i, d] < 0.0:
                    x[i, d] += L[d]
            if not (x[i, d] >= 0.0 and x[i, d] <= L[d]):
                bad = 1
        d2 = displacement2(x, x_ref, i, L, periodic, shift_x)
        if d2 > max_d2:
            max_d2 = d2
    return max_d2, max_step2, bad


@njit
def sort_by_cell(
    x: np.ndarray, v: np.ndarray, f: np.ndarray, ids: np.ndarray, L: np.ndarray, nc: np.ndarray
) -> np.ndarray:
    """Reorder atoms by cell (stable counting sort) in place; return the cell offsets."""
    cell = cell_of(x, L, nc)
    order, start = counting_sort(cell, nc[0] * nc[1] * nc[2])
    # Plain loops, not x[:] = x[order]: the fancy index's shape checks took numba seconds
    # to compile, at the first run of every fresh install.
    tmp = np.empty(x.shape[0])
    _permute_rows(x, order, tmp)
    _permute_rows(v, order, tmp)
    _permute_rows(f, order, tmp)
    ids_old = ids.copy()
    for i in range(ids.shape[0]):
        ids[i] = ids_old[order[i]]
    return start


@njit
def _permute_rows(a: np.ndarray, order: np.ndarray, tmp: np.ndarray) -> None:
    """a[i] ← a[order[i]] in place for an (n, 3) array, one column at a time through
    ``tmp`` (n,)."""
    for d in range(3):
        for i in range(a.shape[0]):
            tmp[i] = a[order[i], d]
        for i in range(a.shape[0]):
            a[i, d] = tmp[i]


@njit
def build_lists(
    x: np.ndarray,
    ids: np.ndarray,
    L: np.ndarray,
    periodic: np.ndarray,
    nc: np.ndarray,
    start: np.ndarray,
    rlist2: float,
    nbr: np.ndarray,
    nnb: np.ndarray,
    use_half: bool,
    half: np.ndarray,
    nhalf: np.ndarray,
    rowless: int,
) -> int:
    """Build the list the forces use from positions sorted by cell; return the row need
    (rows were cut if it exceeds the list width, ``list_width``).

    Half list: straight from the half stencil (``build_half_list``) where the grid allows
    it, else from the full list (``half_from_full_rowless``; a periodic dimension of fewer
    than 5 cells). Full list: ``build_full_list``, the rows of the window's inflow copy
    emptied (``drop_rows``). In both the full rows of that copy end empty."""
    if use_half and half_stencil_ok(nc, periodic):
        return build_half_list(x, ids, L, periodic, nc, start, rlist2, rowless, half, nhalf)
    need = build_full_list(x, L, periodic, nc, start, rlist2, nbr, nnb)
    if need <= nbr.shape[1]:
        if use_half:
            half_from_full_rowless(nbr, nnb, ids, rowless, half, nhalf)
        drop_rows(ids, nnb, rowless)
    return need


@njit
def list_width(nbr: np.ndarray, half: np.ndarray) -> int:
    """The row width of the list in use (the unused one is a 1 × 1 placeholder)."""
    return max(nbr.shape[1], half.shape[1])


@njit
def rebuild(
    x: np.ndarray,
    v: np.ndarray,
    f: np.ndarray,
    ids: np.ndarray,
    x_ref: np.ndarray,
    L: np.ndarray,
    periodic: np.ndarray,
    nc: np.ndarray,
    rlist2: float,
    nbr: np.ndarray,
    nnb: np.ndarray,
    use_half: bool,
    half: np.ndarray,
    nhalf: np.ndarray,
    rowless: int,
    start: np.ndarray,
) -> int:
    """Sort atoms by cell, build the list (``build_lists``), remember x_ref and the cell
    offsets (``start``, for ``list_holds``); return the row need. ``rowless``: frozen atoms
    with ids −1 … −rowless keep no row (``drop_rows``). (No literal flag among the
    arguments: called with a constant True from jitted code and with a bool from Python,
    numba compiled and cached two overloads, and a process that loaded the second from the
    cache called a null pointer.)"""
    fresh = sort_by_cell(x, v, f, ids, L, nc)
    for c in range(start.shape[0]):  # loops, not slice assignment: faster to compile
        start[c] = fresh[c]
    need = build_lists(
        x, ids, L, periodic, nc, start, rlist2, nbr, nnb, use_half, half, nhalf, rowless
    )
    for i in range(x.shape[0]):
        for d in range(3):
            x_ref[i, d] = x[i, d]
    return need


@njit
def drop_rows(ids: np.ndarray, nnb: np.ndarray, rowless: int) -> None:
    """Empty the full-list rows of the frozen atoms with ids −1 … −``rowless`` (the window's
    inflow copy): nothing reads the force on them (frozen atoms are not kicked), while every
    mobile row still lists them, so the mobile atoms' forces are unchanged bit for bit. (The
    half list leaves out the pairs of two such atoms instead: ``build_lists``.)"""
    if rowless <= 0:
        return
    for i in range(ids.shape[0]):
        if rowless_atom(ids[i], rowless):
            nnb[i] = 0


@njit
def compute_forces(
    x: np.ndarray,
    L: np.ndarray,
    periodic: np.ndarray,
    nbr: np.ndarray,
    nnb: np.ndarray,
    use_half: bool,
    half: np.ndarray,
    nhalf: np.ndarray,
    rc2: float,
    f: np.ndarray,
    fbuf: np.ndarray,
    ids: np.ndarray,
    rowless: int,
) -> None:
    """Forces from the half list (Newton's third law; on ``fbuf.shape[0] + 1`` threads) or
    the full list (``prange`` rows). The window's inflow copy (ids −1 … −``rowless``) gets
    zero force: nothing reads it, and the half list leaves out its inner pairs."""
    if use_half:
        if fbuf.shape[0] == 0:
            forces_half(x, L, periodic, half, nhalf, rc2, f)
        else:
            forces_half_threads(x, L, periodic, half, nhalf, rc2, f, fbuf)
        if rowless > 0:
            for i in range(ids.shape[0]):
                if rowless_atom(ids[i], rowless):
                    f[i, 0] = 0.0
                    f[i, 1] = 0.0
                    f[i, 2] = 0.0
    else:
        forces_full(x, L, periodic, nbr, nnb, rc2, f)


@njit
def csvr_factor(kin: float, target: float, nf: int, c: float, r1: float, s: float) -> float:
    """Bussi–Donadio–Parrinello velocity scale α (eq. A7) for kinetic energy ``kin``."""
    if kin <= 0.0:
        return 1.0
    ratio = target / (nf * kin)
    a2 = c + (1.0 - c) * (s + r1 * r1) * ratio + 2.0 * r1 * np.sqrt(c * (1.0 - c) * ratio)
    sign = 1.0 if r1 + np.sqrt(c / ((1.0 - c) * ratio)) >= 0.0 else -1.0
    return sign * np.sqrt(max(a2, 0.0))


@njit
def run_steps(
    nsteps: int,
    x: np.ndarray,
    v: np.ndarray,
    f: np.ndarray,
    ids: np.ndarray,
    x_ref: np.ndarray,
    L: np.ndarray,
    periodic: np.ndarray,
    walls0: np.ndarray,
    t_epoch: float,
    k0: int,
    dt: float,
    rc2: float,
    rlist2: float,
    half_skin2: float,
    nc: np.ndarray,
    nbr: np.ndarray,
    nnb: np.ndarray,
    use_half: bool,
    half: np.ndarray,
    nhalf: np.ndarray,
    fbuf: np.ndarray,
    impulse: np.ndarray,
    thermo: np.ndarray,
    r1: np.ndarray,
    chi: np.ndarray,
    counters: np.ndarray,
    ref: np.ndarray,
    rowless: int,
    start: np.ndarray,
) -> tuple[int, int]:
    """Advance up to ``nsteps`` velocity-Verlet steps; return (steps completed, status).

    ``ref`` = [v_ref, shift]: displacements count relative to a uniform drift at v_ref along
    x (shift = v_ref × time since the last build). A uniform drift does not change any pair
    distance, so the list stays valid (Verlet's bound holds for displacements relative to
    any common shift) while, in a window frame where all the material streams at ~D, the
    list is not rebuilt every few steps. Once an atom has moved skin/2 (Verlet's rule) the
    list is tested pair by pair (``list_holds``, on the build's cell offsets ``start``) and
    rebuilt only when some pair could have come within rc unlisted.
    ``walls0`` = [x_L0, v_L, x_R0, v_R]: wall positions at t = 0 and their velocities, so the
    wall position at time t is x_w0 + v_w t, with t = t_epoch + k Δt at step k counted from the
    epoch (``k0`` steps done so far): the same floats however the run is split. ``thermo`` = [T, τ, N_f]
    (T ≤ 0: no thermostat) with ``r1``/``chi`` the per-step random numbers. ``counters``
    [0] counts list builds. On status GROW the step is half done: the caller grows the list,
    rebuilds, and calls ``finish_step``. ``rowless``: as ``rebuild``'s.
    """
    walls = np.empty(4)
    for s in range(nsteps):
        t = t_epoch + (k0 + s + 1) * dt
        walls[0] = walls0[0] + walls0[1] * t
        walls[1] = walls0[1]
        walls[2] = walls0[2] + walls0[3] * t
        walls[3] = walls0[3]
        kick(v, f, ids, 0.5 * dt)
        ref[1] += ref[0] * dt
        max_d2, max_step2, bad = drift_walls_wrap(
            x, v, ids, x_ref, dt, L, periodic, walls, impulse, ref[1]
        )
        if max_step2 != max_step2 or max_d2 != max_d2 or np.isinf(max_step2):
            return s, NAN
        if max_step2 > half_skin2:
            return s, CFL
        if bad:
            return s, LOST
        if max_d2 > half_skin2 and not list_holds(
            x, x_ref, ref[1], L, periodic, nc, start, np.sqrt(rc2), np.sqrt(rlist2)
        ):
            need = rebuild(
                x, v, f, ids, x_ref, L, periodic, nc, rlist2, nbr, nnb, use_half, half, nhalf,
                rowless, start,
            )  # fmt: skip
            counters[0] += 1
            ref[1] = 0.0
            if need > list_width(nbr, half):
                return s, GROW
        finish_step(
            x, v, f, ids, L, periodic, nbr, nnb, use_half, half, nhalf, fbuf, rc2, dt, thermo,
            r1[s], chi[s], rowless,
        )  # fmt: skip
    return nsteps, OK


@njit
def finish_step(
    x: np.ndarray,
    v: np.ndarray,
    f: np.ndarray,
    ids: np.ndarray,
    L: np.ndarray,
    periodic: np.ndarray,
    nbr: np.ndarray,
    nnb: np.ndarray,
    use_half: bool,
    half: np.ndarray,
    nhalf: np.ndarray,
    fbuf: np.ndarray,
    rc2: float,
    dt: float,
    thermo: np.ndarray,
    r1: float,
    chi: float,
    rowless: int,
) -> None:
    """Second half of a step: F(x), v ← v + ½Δt F, then the thermostat if one is set."""
    compute_forces(x, L, periodic, nbr, nnb, use_half, half, nhalf, rc2, f, fbuf, ids, rowless)
    kick(v, f, ids, 0.5 * dt)
    if thermo[0] > 0.0:
        kin = 0.5 * np.sum(v * v)
        nf = int(thermo[2])
        alpha = csvr_factor(kin, 0.5 * nf * thermo[0], nf, np.exp(-dt / thermo[1]), r1, chi)
        v *= alpha
