"""Cell lists and Verlet neighbour lists (reduced units, lengths in σ).

The box is [0, L_x) × [0, L_y) × [0, L_z); each dimension is periodic or bounded (walls).
At every rebuild the atoms are counting-sorted by cell, so that atoms close in space are
close in memory, and a *full* list (both i→j and j→i) is built row by row: row i is written
only by the thread that owns i, so the build and the forces are deterministic for any thread
count (which the bit-exact checkpoint resume relies on). The list radius is rc + skin; it is
rebuilt when an atom has moved more than skin/2 since the last build (see ``integrate``).
"""

from __future__ import annotations

import numpy as np

from ..numba_conf import njit, pjit, prange


@njit
def grid_shape(L: np.ndarray, rlist: float) -> np.ndarray:
    """Cells per dimension: as many as fit with a side of at least ``rlist`` [σ]."""
    nc = np.empty(3, dtype=np.int64)
    for d in range(3):
        nc[d] = max(1, int(np.floor(L[d] / rlist)))
    return nc


@njit
def cell_of(x: np.ndarray, L: np.ndarray, nc: np.ndarray) -> np.ndarray:
    """Linear cell index (x fastest) of every atom; positions are assumed inside the box."""
    n = x.shape[0]
    cell = np.empty(n, dtype=np.int64)
    for i in range(n):
        c = 0
        stride = 1
        for d in range(3):
            k = int(x[i, d] / L[d] * nc[d])
            k = min(max(k, 0), nc[d] - 1)
            c += k * stride
            stride *= nc[d]
        cell[i] = c
    return cell


@njit
def counting_sort(cell: np.ndarray, ncells: int) -> tuple[np.ndarray, np.ndarray]:
    """Stable counting sort: the permutation ``order`` and ``start`` (ncells + 1 offsets)."""
    n = cell.shape[0]
    start = np.zeros(ncells + 1, dtype=np.int64)
    for i in range(n):
        start[cell[i] + 1] += 1
    for c in range(ncells):
        start[c + 1] += start[c]
    fill = start[:-1].copy()
    order = np.empty(n, dtype=np.int64)
    for i in range(n):
        c = cell[i]
        order[fill[c]] = i
        fill[c] += 1
    return order, start


@njit
def _offsets(n: int, periodic: bool) -> np.ndarray:
    # Neighbour-cell offsets along one dimension, without visiting a cell twice when the
    # periodic dimension has fewer than three cells.
    if periodic:
        if n == 1:
            return np.array([0], dtype=np.int64)
        if n == 2:
            return np.array([0, 1], dtype=np.int64)
    return np.array([-1, 0, 1], dtype=np.int64)


@pjit
def build_full_list(
    x: np.ndarray,
    L: np.ndarray,
    periodic: np.ndarray,
    nc: np.ndarray,
    start: np.ndarray,
    rlist2: float,
    nbr: np.ndarray,
    nnb: np.ndarray,
) -> int:
    """Fill ``nbr[i, :nnb[i]]`` with every j ≠ i closer than √rlist2, atoms sorted by cell.

    Returns the largest row length needed; if it exceeds ``nbr.shape[1]`` the rows were cut
    and the caller must grow ``nbr`` and build again.
    """
    n = x.shape[0]
    maxnb = nbr.shape[1]
    Lp = np.empty(3)
    for d in range(3):
        Lp[d] = L[d] if periodic[d] else 0.0
    ox = _offsets(nc[0], periodic[0])
    oy = _offsets(nc[1], periodic[1])
    oz = _offsets(nc[2], periodic[2])
    need = 0
    for i in prange(n):
        cx = min(max(int(x[i, 0] / L[0] * nc[0]), 0), nc[0] - 1)
        cy = min(max(int(x[i, 1] / L[1] * nc[1]), 0), nc[1] - 1)
        cz = min(max(int(x[i, 2] / L[2] * nc[2]), 0), nc[2] - 1)
        count = 0
        for a in oz:
            kz = cz + a
            if periodic[2]:
                kz %= nc[2]
            elif kz < 0 or kz >= nc[2]:
                continue
            for b in oy:
                ky = cy + b
                if periodic[1]:
                    ky %= nc[1]
                elif ky < 0 or ky >= nc[1]:
                    continue
                for c in ox:
                    kx = cx + c
                    if periodic[0]:
                        kx %= nc[0]
                    elif kx < 0 or kx >= nc[0]:
                        continue
                    cell = kx + nc[0] * (ky + nc[1] * kz)
                    for j in range(start[cell], start[cell + 1]):
                        if j == i:
                            continue
                        dx = x[i, 0] - x[j, 0]
                        dy = x[i, 1] - x[j, 1]
                        dz = x[i, 2] - x[j, 2]
                        dx -= Lp[0] * np.rint(dx / L[0])
                        dy -= Lp[1] * np.rint(dy / L[1])
                        dz -= Lp[2] * np.rint(dz / L[2])
                        if dx * dx + dy * dy + dz * dz < rlist2:
                            if count < maxnb:
                                nbr[i, count] = j
                            count += 1
        nnb[i] = min(count, maxnb)
        need = max(need, count)
    return need


@njit
def half_from_full(nbr: np.ndarray, nnb: np.ndarray, half: np.ndarray, nhalf: np.ndarray) -> None:
    """Keep the entries j > i of the full list (each pair once, for Newton's third law)."""
    n = nbr.shape[0]
    for i in range(n):
        k = 0
        for m in range(nnb[i]):
            j = nbr[i, m]
            if j > i:
                half[i, k] = j
                k += 1
        nhalf[i] = k
