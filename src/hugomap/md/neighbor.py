"""Cell lists and Verlet neighbour lists (reduced units, lengths in σ).

The box is [0, L_x) × [0, L_y) × [0, L_z); each dimension is periodic or bounded (walls).
At every rebuild the atoms are counting-sorted by cell (cells of side ≥ (rc + skin)/2, a
5 × 5 × 5 stencil), so that atoms close in space are close in memory, and a *full* list (both
i→j and j→i) is built row by row: row i is written only by the thread that owns i's cell, and
its order depends only on the positions, so the build and the forces are deterministic for
any thread count (which the bit-exact checkpoint resume relies on). The list radius is rc + skin; it is
rebuilt when an atom has moved more than skin/2 since the last build (see ``integrate``).
"""

from __future__ import annotations

import numpy as np

from ..numba_conf import njit, pjit, prange


@njit
def grid_shape(L: np.ndarray, rlist: float) -> np.ndarray:
    """Cells per dimension: as many as fit with a side of at least ``rlist``/2 [σ].

    Half-width bins: the stencil is 5 × 5 × 5 cells of side ≥ rlist/2 (a volume of about
    (2.5 rlist)³ searched, against (3 rlist)³ for 3 × 3 × 3 cells of side rlist).
    """
    nc = np.empty(3, dtype=np.int64)
    side = 0.5 * rlist * (1.0 + 1e-12)  # the margin keeps side ≥ rlist/2 after rounding
    for d in range(3):
        nc[d] = max(1, int(np.floor(L[d] / side)))
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


REACH = 2  # stencil half-width in cells (bins of side ≥ rlist/2)


@njit
def _offsets(n: int, periodic: bool) -> np.ndarray:
    # Neighbour-cell offsets along one dimension; a periodic dimension with fewer than
    # 2 REACH + 1 cells is walked once round (every cell once), never a cell twice.
    if periodic and n < 2 * REACH + 1:
        lo = -(n // 2)
        return np.arange(lo, lo + n).astype(np.int64)
    return np.arange(-REACH, REACH + 1).astype(np.int64)


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

    ``x`` must be sorted by the cells of ``nc`` (atoms of cell c are start[c]:start[c+1]).
    Cells are shared out among the threads in blocks; the rows of a cell's atoms are
    written only by the thread that owns the cell, and the order of every row depends only
    on the positions, never on the thread count.

    Per cell, the candidates of its stencil (±2 cells of side ≥ rlist/2) are gathered once
    into contiguous buffers: each run of consecutive cells along x is a contiguous range of
    atoms, copied with the periodic image shift of the run, so no minimum image is needed
    per pair (except along a periodic dimension too short for the stencil, walked once round
    with a per-pair minimum image instead). Then for each atom of the cell one long loop
    computes the squared distances (vectorisable) and one appends the row branch-free to a
    scratch row (j is always written and the length grows by the 0/1 test), which is then
    copied to ``nbr`` up to its width.

    Returns the largest row length needed; if it exceeds ``nbr.shape[1]`` the rows were cut
    and the caller must grow ``nbr`` and build again.
    """
    maxnb = nbr.shape[1]
    nx = nc[0]
    ny = nc[1]
    nz = nc[2]
    ncell = nx * ny * nz
    Lr = np.zeros(3)
    invL = np.empty(3)
    for d in range(3):
        invL[d] = 1.0 / L[d]
        if periodic[d] and nc[d] < 2 * REACH + 1:
            Lr[d] = L[d]
    wrap = Lr[0] + Lr[1] + Lr[2] > 0.0
    shift_x = periodic[0] and Lr[0] == 0.0
    shift_y = periodic[1] and Lr[1] == 0.0
    shift_z = periodic[2] and Lr[2] == 0.0
    oy = _offsets(ny, periodic[1])
    oz = _offsets(nz, periodic[2])
    ox = _offsets(nx, periodic[0])
    # Room for the candidates of any cell: stencil cells times the fullest cell.
    fullest = 1
    for c in range(ncell):
        fullest = max(fullest, start[c + 1] - start[c])
    cap = ox.size * oy.size * oz.size * fullest
    block = 32
    nblock = (ncell + block - 1) // block
    need = 0
    for blk in prange(nblock):
        bx = np.empty(cap)
        by = np.empty(cap)
        bz = np.empty(cap)
        bj = np.empty(cap, dtype=np.int32)
        r2 = np.empty(cap)
        rowbuf = np.empty(cap, dtype=np.int32)
        for c in range(blk * block, min(ncell, (blk + 1) * block)):
            if start[c + 1] == start[c]:
                continue
            cx = c % nx
            cy = (c // nx) % ny
            cz = c // (nx * ny)
            # The runs of cells along x: up to two (a periodic run that wraps is split).
            if periodic[0] and not shift_x:
                xlo0, xhi0, sx0 = 0, nx - 1, 0.0
                xlo1, xhi1, sx1 = 0, -1, 0.0
            elif periodic[0]:
                lo = cx - REACH
                hi = cx + REACH
                if lo < 0:
                    xlo0, xhi0, sx0 = lo + nx, nx - 1, -L[0]
                    xlo1, xhi1, sx1 = 0, hi, 0.0
                elif hi >= nx:
                    xlo0, xhi0, sx0 = lo, nx - 1, 0.0
                    xlo1, xhi1, sx1 = 0, hi - nx, L[0]
                else:
                    xlo0, xhi0, sx0 = lo, hi, 0.0
                    xlo1, xhi1, sx1 = 0, -1, 0.0
            else:
                xlo0, xhi0, sx0 = max(cx - REACH, 0), min(cx + REACH, nx - 1), 0.0
                xlo1, xhi1, sx1 = 0, -1, 0.0
            # Gather the candidates, each at the periodic image seen from this cell.
            ncand = 0
            self0 = -1
            for a in oz:
                kz = cz + a
                sz = 0.0
                if periodic[2]:
                    if kz < 0:
                        kz += nz
                        sz = -L[2] if shift_z else 0.0
                    elif kz >= nz:
                        kz -= nz
                        sz = L[2] if shift_z else 0.0
                elif kz < 0 or kz >= nz:
                    continue
                for b in oy:
                    ky = cy + b
                    sy = 0.0
                    if periodic[1]:
                        if ky < 0:
                            ky += ny
                            sy = -L[1] if shift_y else 0.0
                        elif ky >= ny:
                            ky -= ny
                            sy = L[1] if shift_y else 0.0
                    elif ky < 0 or ky >= ny:
                        continue
                    row = nx * (ky + ny * kz)
                    for seg in range(2):
                        if seg == 0:
                            j0 = start[row + xlo0]
                            j1 = start[row + xhi0 + 1]
                            sx = sx0
                        else:
                            if xhi1 < xlo1:
                                break
                            j0 = start[row + xlo1]
                            j1 = start[row + xhi1 + 1]
                            sx = sx1
                        if a == 0 and b == 0 and j0 <= start[c] < j1:
                            self0 = ncand + start[c] - j0
                        for j in range(j0, j1):
                            bx[ncand] = x[j, 0] + sx
                            by[ncand] = x[j, 1] + sy
                            bz[ncand] = x[j, 2] + sz
                            bj[ncand] = j
                            ncand += 1
            for i in range(start[c], start[c + 1]):
                xi = x[i, 0]
                yi = x[i, 1]
                zi = x[i, 2]
                if wrap:
                    for k in range(ncand):
                        dx = xi - bx[k]
                        dy = yi - by[k]
                        dz = zi - bz[k]
                        dx -= Lr[0] * np.rint(dx * invL[0])
                        dy -= Lr[1] * np.rint(dy * invL[1])
                        dz -= Lr[2] * np.rint(dz * invL[2])
                        r2[k] = dx * dx + dy * dy + dz * dz
                else:
                    for k in range(ncand):
                        dx = xi - bx[k]
                        dy = yi - by[k]
                        dz = zi - bz[k]
                        r2[k] = dx * dx + dy * dy + dz * dz
                r2[self0 + i - start[c]] = np.inf
                count = 0
                for k in range(ncand):
                    rowbuf[count] = bj[k]
                    count += r2[k] < rlist2
                m = min(count, maxnb)
                for k in range(m):
                    nbr[i, k] = rowbuf[k]
                nnb[i] = min(count, maxnb)
                need = max(need, count)
    return need


@njit
def half_from_full(nbr: np.ndarray, nnb: np.ndarray, half: np.ndarray, nhalf: np.ndarray) -> None:
    """Keep the entries j > i of the full list (each pair once, for Newton's third law).

    Branch-free: j is always written and the length grows by the 0/1 test, so ``half`` must
    be at least as wide as the longest full row (a half row can hold all of it: the atom
    sorted first in its neighbourhood has every neighbour j > i).
    """
    n = nbr.shape[0]
    w = half.shape[1]
    for i in range(n):
        if nnb[i] > w:
            raise ValueError("half list narrower than a full neighbour row")
        k = 0
        for m in range(nnb[i]):
            j = nbr[i, m]
            half[i, k] = j
            k += j > i
        nhalf[i] = k
