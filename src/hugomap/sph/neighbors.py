"""Cell lists and full neighbour lists for CSPH (2D positions; 1D runs have y = 0).

Particles (real ones and the wall ghosts after them) are counting-sorted by square cells of
side ≥ r_list; each real particle's row lists every other particle closer than r_list, found
in the 3 × 3 stencil of cells around its own. Rows are written only by the thread that owns
the row and their order depends only on the positions (stencil order, then sorted order), so
the list — and the pair sums — are the same for any thread count. Periodic dimensions use the
minimum image; a periodic dimension fewer than 3 cells long is one cell (every particle is a
candidate, none twice). The list radius is 2 h_max + skin; the solver rebuilds it when the
largest displacement since the build could bring a pair within 2 h from outside r_list.
"""

from __future__ import annotations

import numpy as np

from ..numba_conf import njit, pjit, prange


@njit
def image_lengths(periodic: np.ndarray, length: np.ndarray) -> tuple[float, float, float, float]:
    """(L_x, L_y, 1/L_x, 1/L_y) [m, 1/m] of the periodic dimensions, 0 along open ones, for
    ``min_image``."""
    Lx = length[0] if periodic[0] else 0.0
    Ly = length[1] if periodic[1] else 0.0
    iLx = 1.0 / length[0] if periodic[0] else 0.0
    iLy = 1.0 / length[1] if periodic[1] else 0.0
    return Lx, Ly, iLx, iLy


@njit
def min_image(d: float, L: float, iL: float) -> float:
    """The minimum image d − L·rint(d/L) of a separation d [m] along a dimension of period L
    (``image_lengths``: L = 1/L = 0 along an open one leaves d as it is)."""
    return d - L * np.rint(d * iL)


@njit
def cell_grid(
    x: np.ndarray, side: float, periodic: np.ndarray, lo: np.ndarray, length: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Cell origin, cell side per dimension and cells per dimension for positions x (n, 2).

    Periodic dimension d spans [lo_d, lo_d + length_d) with nc = ⌊length/side⌋ cells (1 if
    fewer than 3); a bounded one spans the particles' extent.
    """
    origin = np.empty(2)
    sides = np.empty(2)
    nc = np.empty(2, dtype=np.int64)
    for d in range(2):
        if periodic[d]:
            k = max(1, int(np.floor(length[d] / side)))
            if k < 3:
                k = 1
            origin[d] = lo[d]
            nc[d] = k
            sides[d] = length[d] / k
        else:
            a = x[0, d]
            b = x[0, d]
            for i in range(x.shape[0]):
                a = min(a, x[i, d])
                b = max(b, x[i, d])
            nc[d] = int((b - a) / side) + 1
            origin[d] = a
            sides[d] = side
    return origin, sides, nc


@njit
def sort_by_cell(
    x: np.ndarray, origin: np.ndarray, sides: np.ndarray, nc: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Cell of every particle (x fastest), the stable counting-sort permutation ``order`` and
    the offsets ``start`` (ncells + 1): the particles of cell c are order[start[c]:start[c+1]]."""
    n = x.shape[0]
    cell = np.empty(n, dtype=np.int64)
    for i in range(n):
        kx = min(max(int((x[i, 0] - origin[0]) / sides[0]), 0), nc[0] - 1)
        ky = min(max(int((x[i, 1] - origin[1]) / sides[1]), 0), nc[1] - 1)
        cell[i] = kx + nc[0] * ky
    ncell = nc[0] * nc[1]
    start = np.zeros(ncell + 1, dtype=np.int64)
    for i in range(n):
        start[cell[i] + 1] += 1
    for c in range(ncell):
        start[c + 1] += start[c]
    fill = start[:-1].copy()
    order = np.empty(n, dtype=np.int64)
    for i in range(n):
        c = cell[i]
        order[fill[c]] = i
        fill[c] += 1
    return cell, order, start


@pjit
def build_list(
    x: np.ndarray,
    n_rows: int,
    periodic: np.ndarray,
    length: np.ndarray,
    nc: np.ndarray,
    cell: np.ndarray,
    order: np.ndarray,
    start: np.ndarray,
    rlist2: float,
    nbr: np.ndarray,
    nnb: np.ndarray,
) -> int:
    """Fill ``nbr[i, :nnb[i]]`` (i < n_rows) with every j ≠ i (any of x's rows) closer than
    √rlist2 (minimum image along periodic dimensions). Returns the longest row needed; if it
    exceeds ``nbr.shape[1]`` the rows were cut and the caller must grow ``nbr`` and rebuild."""
    width = nbr.shape[1]
    nx = nc[0]
    ny = nc[1]
    Lx, Ly, iLx, iLy = image_lengths(periodic, length)
    need = 0
    for i in prange(n_rows):
        xi = x[i, 0]
        yi = x[i, 1]
        cx = cell[i] % nx
        cy = cell[i] // nx
        count = 0
        for b in range(-1, 2):
            ky = cy + b
            if periodic[1]:
                if ny == 1 and b != 0:
                    continue
                ky = ky % ny
            elif ky < 0 or ky >= ny:
                continue
            for a in range(-1, 2):
                kx = cx + a
                if periodic[0]:
                    if nx == 1 and a != 0:
                        continue
                    kx = kx % nx
                elif kx < 0 or kx >= nx:
                    continue
                c = kx + nx * ky
                for k in range(start[c], start[c + 1]):
                    j = order[k]
                    dx = x[j, 0] - xi
                    dy = x[j, 1] - yi
                    dx = min_image(dx, Lx, iLx)
                    dy = min_image(dy, Ly, iLy)
                    if dx * dx + dy * dy < rlist2 and j != i:
                        if count < width:
                            nbr[i, count] = j
                        count += 1
        nnb[i] = min(count, width)
        need = max(need, count)
    return need
