"""Brute-force references for the MD unit tests, in plain numpy (independent of the kernels).

Everything is O(N²) over all pairs with the minimum image in periodic dimensions, and uses
the textbook forms of the Lennard-Jones functions rather than the kernels' factorisations:
    φ(r)   = 4 (r⁻¹² − r⁻⁶),           φ'(r)  = −48 r⁻¹³ + 24 r⁻⁷,
    φ''(r) = 624 r⁻¹⁴ − 168 r⁻⁸,      φ'''(r) = −8736 r⁻¹⁵ + 1344 r⁻⁹.
"""

from __future__ import annotations

import contextlib

import numba
import numpy as np

from hugomap.particles.fcc import fcc_positions

#: True when the kernels run as plain Python (``NUMBA_DISABLE_JIT=1``): long runs are shortened.
NO_JIT = bool(numba.config.DISABLE_JIT)

EPS = np.finfo(float).eps


@contextlib.contextmanager
def one_numba_thread():
    """Run numba's parallel kernels on one thread inside the block, then restore.

    For the trajectory tests, which take thousands of short steps: on a shared 2-core
    machine every parallel region of a step waits on a descheduled worker (measured: 2000
    steps of 256 atoms take 44 s on 2 busy threads, 0.6 s on one). With one thread
    MDSimulation takes its one-thread path (half list); test_forces checks both paths.
    """
    before = numba.get_num_threads()
    numba.set_num_threads(1)
    try:
        yield
    finally:
        numba.set_num_threads(before)


def phi(r):
    return 4.0 * (r**-12 - r**-6)


def dphi(r):
    return -48.0 * r**-13 + 24.0 * r**-7


def d2phi(r):
    return 624.0 * r**-14 - 168.0 * r**-8


def d3phi(r):
    return -8736.0 * r**-15 + 1344.0 * r**-9


def pairs(x, L, periodic, rcut):
    """Pairs i < j closer than ``rcut``: (i, j, d = x_i − x_j minimum image, r)."""
    x = np.asarray(x, dtype=float)
    L = np.asarray(L, dtype=float)
    Lp = np.where(np.asarray(periodic, dtype=bool), L, 0.0)
    i, j = np.triu_indices(x.shape[0], 1)
    d = x[i] - x[j]
    d -= Lp * np.rint(d / L)
    r = np.sqrt(np.einsum("ij,ij->i", d, d))
    keep = r < rcut
    return i[keep], j[keep], d[keep], r[keep]


def pair_set(x, L, periodic, rcut):
    """The set of unordered pairs (i, j), i < j, closer than ``rcut``."""
    i, j, _, _ = pairs(x, L, periodic, rcut)
    return set(zip(i.tolist(), j.tolist(), strict=True))


def forces(x, L, periodic, rc):
    """Forces (n, 3) and, per atom, Σ_j |F_ij| (the scale of its summation round-off)."""
    n = len(x)
    i, j, d, r = pairs(x, L, periodic, rc)
    fij = (-dphi(r) / r)[:, None] * d  # force on i from j
    f = np.zeros((n, 3))
    np.add.at(f, i, fij)
    np.add.at(f, j, -fij)
    mag = np.abs(dphi(r))
    scale = np.zeros(n)
    np.add.at(scale, i, mag)
    np.add.at(scale, j, mag)
    return f, scale


def energy_virial(x, L, periodic, rc, ushift):
    """Per-atom energy ½ Σ_j U(r_ij) (n,), virial ½ Σ_j r_ij^a F_ij^b (n, 6), and the scales
    Σ_j |U(r_ij)| (n,) and Σ_j r |F(r)| (n,) of their round-off."""
    n = len(x)
    i, j, d, r = pairs(x, L, periodic, rc)
    u = phi(r) - ushift
    fr = -dphi(r) / r
    comps = [(0, 0), (1, 1), (2, 2), (0, 1), (0, 2), (1, 2)]
    w = np.stack([0.5 * fr * d[:, a] * d[:, b] for a, b in comps], axis=1)
    pe = np.zeros(n)
    np.add.at(pe, i, 0.5 * u)
    np.add.at(pe, j, 0.5 * u)
    vir = np.zeros((n, 6))
    np.add.at(vir, i, w)
    np.add.at(vir, j, w)
    su = np.zeros(n)
    np.add.at(su, i, np.abs(u) + abs(ushift))
    np.add.at(su, j, np.abs(u) + abs(ushift))
    sw = np.zeros(n)
    np.add.at(sw, i, np.abs(dphi(r)) * r)
    np.add.at(sw, j, np.abs(dphi(r)) * r)
    return pe, vir, su, sw


def verlet_shadow_correction(x, v, L, periodic, rc):
    """C(x, v) with H̃ = H + Δt² C + O(Δt⁴) the modified Hamiltonian that velocity Verlet
    (kick–drift–kick, m = 1) conserves: C = vᵀ∇²U v / 12 − |∇U|² / 24 (Hairer, Lubich &
    Wanner, Geometric Numerical Integration, ch. IX; the signs are those for which the
    harmonic oscillator's exact invariant p² + (1 − Δt²/4) q² is recovered). For a pair
    potential vᵀ∇²U v = Σ_pairs φ'' (w·r̂)² + (φ'/r)(|w|² − (w·r̂)²), w = v_i − v_j.
    (Dense N × N arrays: faster than the pair lists above for a few hundred atoms.)
    """
    L = np.asarray(L, dtype=float)
    d = []
    w = []
    for a in range(3):  # per component: (N, N) arrays, i − j
        da = x[:, a, None] - x[None, :, a]
        if periodic[a]:
            da -= L[a] * np.rint(da / L[a])
        d.append(da)
        w.append(v[:, a, None] - v[None, :, a])
    r2 = d[0] * d[0] + d[1] * d[1] + d[2] * d[2]
    np.fill_diagonal(r2, np.inf)
    inside = r2 < rc * rc
    r2 = np.where(inside, r2, 1.0)
    inv2 = 1.0 / r2
    inv6 = inv2 * inv2 * inv2
    p1 = np.where(inside, inv2 * inv6 * (24.0 - 48.0 * inv6), 0.0)  # φ'/r
    p2 = np.where(inside, inv2 * inv6 * (624.0 * inv6 - 168.0), 0.0)  # φ''
    wd = w[0] * d[0] + w[1] * d[1] + w[2] * d[2]
    ww = w[0] * w[0] + w[1] * w[1] + w[2] * w[2]
    wr2 = wd * wd * inv2
    quad = 0.5 * np.sum(p2 * wr2 + p1 * (ww - wr2))  # each pair twice in the N × N sum
    f2 = sum(np.sum(np.sum(p1 * d[a], axis=1) ** 2) for a in range(3))  # |∇U|²
    return quad / 12.0 - f2 / 24.0


def displaced_fcc(cells, rho, amp, seed):
    """FCC positions at density ``rho`` moved by uniform random offsets in [−amp, amp]³, and
    the box; with the lattice's a/4 offset every atom stays inside [0, L) if amp < a/4."""
    x, L = fcc_positions(cells, rho)
    rng = np.random.default_rng(seed)
    return x + rng.uniform(-amp, amp, size=x.shape), L


def sorted_lists(x, L, periodic, nc, rlist, maxnb=None):
    """Sort atoms by cell and build the full Verlet list with the package's kernels.

    Returns (x sorted, order, nbr, nnb, need).
    """
    from hugomap.md.neighbor import build_full_list, cell_of, counting_sort

    L = np.asarray(L, dtype=float)
    periodic = np.asarray(periodic, dtype=np.bool_)
    nc = np.asarray(nc, dtype=np.int64)
    cell = cell_of(np.ascontiguousarray(x), L, nc)
    order, _ = counting_sort(cell, int(np.prod(nc)))
    xs = np.ascontiguousarray(x[order])
    start = counting_sort(cell_of(xs, L, nc), int(np.prod(nc)))[1]
    n = len(x)
    if maxnb is None:
        maxnb = n
    nbr = np.zeros((n, maxnb), dtype=np.int32)
    nnb = np.zeros(n, dtype=np.int32)
    need = build_full_list(xs, L, periodic, nc, start, rlist * rlist, nbr, nnb)
    return xs, order, nbr, nnb, int(need)
