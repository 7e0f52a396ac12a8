"""Cell lists and Verlet neighbour lists (reduced units, lengths in σ).

The box is [0, L_x) × [0, L_y) × [0, L_z); each dimension is periodic or bounded (walls).
At every rebuild the atoms are counting-sorted by cell (cells of side ≥ (rc + skin)/2, a
5 × 5 × 5 stencil), so that atoms close in space are close in memory, and a *full* list (both
i→j and j→i) is built row by row: row i is written only by the thread that owns i's cell, and
its order depends only on the positions, so the build and the forces are deterministic for
any thread count (which the bit-exact checkpoint resume relies on). The list radius is
rc + skin; once an atom has moved more than skin/2 since the last build (Verlet's rule),
``list_holds`` tests the list pair by pair, and it is rebuilt when a pair may have come
within rc unlisted (see ``integrate``).
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
def cell_coord(xd: float, Ld: float, ncd: int) -> int:
    """The cell (0 … ncd − 1) of coordinate ``xd`` [σ] along a dimension of length ``Ld``."""
    return min(max(int(xd / Ld * ncd), 0), ncd - 1)


@njit
def cell_of(x: np.ndarray, L: np.ndarray, nc: np.ndarray) -> np.ndarray:
    """Linear cell index (x fastest) of every atom; positions are assumed inside the box."""
    n = x.shape[0]
    cell = np.empty(n, dtype=np.int64)
    for i in range(n):
        c = 0
        stride = 1
        for d in range(3):
            c += cell_coord(x[i, d], L[d], nc[d]) * stride
            stride *= nc[d]
        cell[i] = c
    return cell


@njit
def rowless_atom(idv: int, rowless: int) -> bool:
    """Whether an atom of id ``idv`` is one of the frozen ids −1 … −``rowless`` (the window's
    inflow copy), which keep no force row (``integrate.drop_rows``)."""
    return -rowless <= idv < 0


@njit
def nearest_image(dd: float, Ld: float) -> float:
    """The separation ``dd`` [σ] of two coordinates in [0, Ld] along a periodic dimension,
    taken to its nearest image: one shift at most, so a branch rather than dd − Ld
    rint(dd/Ld), whose division was most of the cost of a step's displacement pass."""
    if dd > 0.5 * Ld:
        return dd - Ld
    if dd < -0.5 * Ld:
        return dd + Ld
    return dd


@njit
def _cell_along(k: int, n: int, periodic: bool) -> int:
    """Cell k of a dimension of n cells, wrapped where it is periodic; −1 past a wall."""
    if periodic:
        return k % n
    return k if 0 <= k < n else -1


@njit
def displacement2(
    x: np.ndarray, x_ref: np.ndarray, i: int, L: np.ndarray, periodic: np.ndarray, shift_x: float
) -> float:
    """|Δ_i|² [σ²]: atom i's displacement since the list was built at ``x_ref``, the minimum
    image in periodic dimensions, less a uniform ``shift_x`` along a bounded x (a uniform
    drift changes no pair distance: ``integrate.run_steps``)."""
    d2 = 0.0
    for d in range(3):
        if periodic[d]:
            dd = nearest_image(x[i, d] - x_ref[i, d], L[d])
        else:
            dd = x[i, d] - x_ref[i, d] - (shift_x if d == 0 else 0.0)
        d2 += dd * dd
    return d2


@njit
def list_holds(
    x: np.ndarray,
    x_ref: np.ndarray,
    shift_x: float,
    L: np.ndarray,
    periodic: np.ndarray,
    nc: np.ndarray,
    start: np.ndarray,
    rc: float,
    rlist: float,
) -> bool:
    """Whether the list built at ``x_ref`` still holds every pair closer than rc at ``x``.

    Verlet's rule (rebuild once an atom has moved skin/2, skin = rlist − rc) is a bound
    for the worst pair, two atoms that both moved that far towards each other. This is the
    bound pair by pair: a pair left out of the list had r₀ ≥ rlist at the build, and at
    ``x`` it is at least r₀ − |Δ_i| − |Δ_j| apart (``displacement2``), so the list holds
    while r₀ − |Δ_i| − |Δ_j| ≥ rc for every such pair. Only a pair with |Δ_i| + |Δ_j| >
    skin can fail, so one of its atoms has moved more than skin/2: the test runs over those
    atoms and the atoms that were within rc + |Δ_i| + max|Δ| of them at the build, found
    in the build's cells (``x_ref`` sorted by cell, atoms of cell c at start[c]:start[c+1]).
    Exact up to rounding, which it resolves towards a rebuild. Returns False (rebuild) once
    an atom has moved skin, or the search would reach half a periodic box or cost more than
    ``SEARCH_BUDGET`` allows.
    """
    n = x.shape[0]
    skin = rlist - rc
    disp = np.empty(n)
    dmax = 0.0
    moved = 0
    for i in range(n):
        disp[i] = np.sqrt(displacement2(x, x_ref, i, L, periodic, shift_x))
        dmax = max(dmax, disp[i])
        moved += disp[i] > 0.5 * skin
    if not dmax < skin:  # also NaN
        return False
    reach_r = rc + 2.0 * dmax
    for d in range(3):
        if periodic[d] and not reach_r < 0.5 * L[d]:
            return False
    nx = nc[0]
    ny = nc[1]
    nz = nc[2]
    ox = _offsets(nx, periodic[0], int(reach_r / (L[0] / nx)) + 1)
    oy = _offsets(ny, periodic[1], int(reach_r / (L[1] / ny)) + 1)
    oz = _offsets(nz, periodic[2], int(reach_r / (L[2] / nz)) + 1)
    # The share of the atoms searched around each moved atom.
    share = min(1.0, ox.size / nx) * min(1.0, oy.size / ny) * min(1.0, oz.size / nz)
    # A dear search is not worth it (``SEARCH_BUDGET``): a region moving as a whole (a
    # piston's shocked slab in the lab frame) has every atom past skin/2 at once, and a
    # build finds its pairs again faster.
    if moved * share > SEARCH_BUDGET:
        return False
    # Pairs closer than this at the build are in the list (the margin sends a pair at the
    # edge, where the build's rounding may have differed, to the test).
    in_list2 = rlist * rlist * (1.0 - 1e-10)
    for i in range(n):
        if disp[i] <= 0.5 * skin:
            continue
        ix = cell_coord(x_ref[i, 0], L[0], nx)
        iy = cell_coord(x_ref[i, 1], L[1], ny)
        iz = cell_coord(x_ref[i, 2], L[2], nz)
        for a in oz:
            cz = _cell_along(iz + a, nz, periodic[2])
            if cz < 0:
                continue
            for b in oy:
                cy = _cell_along(iy + b, ny, periodic[1])
                if cy < 0:
                    continue
                for e in ox:
                    cx = _cell_along(ix + e, nx, periodic[0])
                    if cx < 0:
                        continue
                    c = cx + nx * (cy + ny * cz)
                    for j in range(start[c], start[c + 1]):
                        if disp[i] + disp[j] <= skin:
                            continue
                        r2 = 0.0
                        for d in range(3):
                            dd = x_ref[j, d] - x_ref[i, d]
                            if periodic[d]:
                                dd = nearest_image(dd, L[d])
                            r2 += dd * dd
                        if r2 < in_list2:
                            continue
                        if np.sqrt(r2) - disp[i] - disp[j] < rc:
                            return False
    return True


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
# Unsigned counters and indices in the hot loops: numba gives a signed index a test for
# negative values (Python's wraparound) at every access, which an unsigned one skips.
ZERO = np.uint64(0)
ONE = np.uint64(1)
# ``list_holds`` runs at every step from the first atom past skin/2 until it fails, so its
# search around the moved atoms is held to this many atom visits per atom of the system (a
# force evaluation visits ~38 list pairs an atom on bench/in.lj, a build ~150 candidates);
# past it, a rebuild.
SEARCH_BUDGET = 8.0
# The builds share cells out among the threads in blocks of this many (x fastest), each
# block's rows built by one call (``_full_block``, ``_half_block``; a call per block costs
# nothing beside its cells' work), so that the parallel functions stay small.
BLOCK = 32


@njit
def _offsets(n: int, periodic: bool, reach: int) -> np.ndarray:
    # Neighbour-cell offsets along one dimension, −reach … reach; a periodic dimension with
    # fewer than 2 reach + 1 cells is walked once round (every cell once), never a cell twice.
    if periodic and n < 2 * reach + 1:
        lo = -(n // 2)
        return np.arange(lo, lo + n).astype(np.int64)
    return np.arange(-reach, reach + 1).astype(np.int64)


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
    scratch row (the candidate's place k is always written and the length grows by the 0/1
    test; k rather than j, so that the loop reads one buffer less), whose entries are then
    mapped to atoms (j = bj[k]) into ``nbr`` up to its width.

    Returns the largest row length needed; if it exceeds ``nbr.shape[1]`` the rows were cut
    and the caller must grow ``nbr`` and build again.
    """
    # Everything but the prange loop is in serial helpers: numba turns array allocations
    # and reductions in a parallel function into parallel loops of their own, each about a
    # second to compile on every fresh install.
    Lr, invL, oy, oz, cap, nblock = _full_plan(L, periodic, nc, start)
    needs = np.empty(nblock, dtype=np.int64)
    for blk in prange(nblock):
        needs[blk] = _full_block(blk, cap, x, L, periodic, nc, start, rlist2, nbr, nnb, Lr, invL,
                                 oy, oz)  # fmt: skip
    return _largest(needs)


@njit
def _largest(needs: np.ndarray) -> int:
    """The largest of the blocks' row needs (0 for no block)."""
    need = 0
    for b in range(needs.shape[0]):
        need = max(need, needs[b])
    return need


@njit
def _fullest(start: np.ndarray) -> int:
    """The most atoms in one cell (at least 1), from the cell offsets ``start``."""
    fullest = 1
    for c in range(start.shape[0] - 1):
        fullest = max(fullest, start[c + 1] - start[c])
    return fullest


@njit
def _full_plan(
    L: np.ndarray, periodic: np.ndarray, nc: np.ndarray, start: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, int, int]:
    """``build_full_list``'s set-up: ``Lr`` (L_d along a periodic dimension too short for
    the stencil, else 0), 1/L, the y and z cell offsets, the candidate buffers' size and the
    number of blocks of cells."""
    Lr = np.zeros(3)
    invL = np.empty(3)
    for d in range(3):
        invL[d] = 1.0 / L[d]
        if periodic[d] and nc[d] < 2 * REACH + 1:
            Lr[d] = L[d]
    oy = _offsets(nc[1], periodic[1], REACH)
    oz = _offsets(nc[2], periodic[2], REACH)
    ox = _offsets(nc[0], periodic[0], REACH)
    # Room for the candidates of any cell: stencil cells times the fullest cell.
    cap = ox.size * oy.size * oz.size * _fullest(start)
    return Lr, invL, oy, oz, cap, _blocks(nc)


@njit
def _blocks(nc: np.ndarray) -> int:
    """How many blocks of ``BLOCK`` cells the builds share out among the threads."""
    return (nc[0] * nc[1] * nc[2] + BLOCK - 1) // BLOCK


@njit
def _full_block(
    blk: int,
    cap: int,
    x: np.ndarray,
    L: np.ndarray,
    periodic: np.ndarray,
    nc: np.ndarray,
    start: np.ndarray,
    rlist2: float,
    nbr: np.ndarray,
    nnb: np.ndarray,
    Lr: np.ndarray,
    invL: np.ndarray,
    oy: np.ndarray,
    oz: np.ndarray,
) -> int:
    """``build_full_list``'s rows of the cells of block ``blk`` (``BLOCK`` cells), with
    candidate buffers of ``cap`` entries; ``Lr`` holds L_d along the periodic dimensions too
    short for the stencil (a per-pair minimum image there, with ``invL`` = 1/L), ``oy`` and
    ``oz`` the cell offsets (``_offsets``). Returns the block's largest row need."""
    maxnb = nbr.shape[1]
    nx = nc[0]
    ny = nc[1]
    nz = nc[2]
    ncell = nx * ny * nz
    wrap = Lr[0] + Lr[1] + Lr[2] > 0.0
    shift_x = periodic[0] and Lr[0] == 0.0
    shift_y = periodic[1] and Lr[1] == 0.0
    shift_z = periodic[2] and Lr[2] == 0.0
    need = 0
    bx = np.empty(cap)
    by = np.empty(cap)
    bz = np.empty(cap)
    bj = np.empty(cap, dtype=np.int32)
    r2 = np.empty(cap)
    rowbuf = np.empty(cap, dtype=np.int32)
    for c in range(blk * BLOCK, min(ncell, (blk + 1) * BLOCK)):
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
        ncand = ZERO
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
                        self0 = int(ncand) + start[c] - j0
                    for j in range(np.uint64(j0), np.uint64(j1)):
                        bx[ncand] = x[j, 0] + sx
                        by[ncand] = x[j, 1] + sy
                        bz[ncand] = x[j, 2] + sz
                        bj[ncand] = j
                        ncand += ONE
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
            count = ZERO
            for k in range(ncand):
                rowbuf[count] = k
                count += np.uint64(r2[k] < rlist2)
            m = min(int(count), maxnb)
            for k in range(m):
                nbr[i, k] = bj[np.uint64(rowbuf[k])]
            nnb[i] = m
            need = max(need, int(count))
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


@njit
def half_from_full_rowless(
    nbr: np.ndarray,
    nnb: np.ndarray,
    ids: np.ndarray,
    rowless: int,
    half: np.ndarray,
    nhalf: np.ndarray,
) -> None:
    """``half_from_full`` without the pairs of two frozen atoms with ids −1 … −``rowless``
    (the window's inflow copy): the rows are those of ``half_from_full`` less those pairs,
    so every other atom's force is unchanged bit for bit."""
    n = nbr.shape[0]
    w = half.shape[1]
    for i in range(n):
        if nnb[i] > w:
            raise ValueError("half list narrower than a full neighbour row")
        fi = rowless_atom(ids[i], rowless)
        k = 0
        for m in range(nnb[i]):
            j = nbr[i, m]
            half[i, k] = j
            k += (j > i) & (not (fi and rowless_atom(ids[j], rowless)))
        nhalf[i] = k


@njit
def half_stencil_ok(nc: np.ndarray, periodic: np.ndarray) -> bool:
    """Whether ``build_half_list`` applies: every periodic dimension has at least
    2 REACH + 1 cells, so that no two stencil cells are the same cell (no pair is met twice)."""
    for d in range(3):
        if periodic[d] and nc[d] < 2 * REACH + 1:
            return False
    return True


@pjit
def build_half_list(
    x: np.ndarray,
    ids: np.ndarray,
    L: np.ndarray,
    periodic: np.ndarray,
    nc: np.ndarray,
    start: np.ndarray,
    rlist2: float,
    rowless: int,
    half: np.ndarray,
    nhalf: np.ndarray,
) -> int:
    """Fill ``half[i, :nhalf[i]]`` with each pair closer than √rlist2 once (Newton's third law),
    from a half stencil of cells; atoms sorted by cell as for ``build_full_list``.

    Cell c = (cx, cy, cz) pairs its atoms with the cells "after" it: dz ∈ {1, 2} (any dy, dx),
    dz = 0 with dy ∈ {1, 2} (any dx), and along its own row of cells cx … cx + 2 the atoms
    sorted after i (j > i in its own cell). Every unordered pair of cells within ±2 appears
    exactly once that way, so each pair is listed once and no j ≤ i test is needed across
    cells: about half the candidates of the full stencil. The own row goes first in the
    candidate buffers, so that atom i's candidates are one contiguous tail of them. Needs
    ``half_stencil_ok`` (periodic dimensions of ≥ 5 cells).

    Pairs of two frozen atoms with ids −1 … −``rowless`` are left out (nothing reads the
    force on them, ``integrate.drop_rows``); the rows of the other atoms are the same as
    with ``rowless`` = 0, so the mobile atoms' forces are unchanged bit for bit.

    Deterministic as ``build_full_list``: a cell's rows are written only by the thread that
    owns the cell and their order depends only on the positions. Returns the largest row
    length needed (> ``half.shape[1]``: rows were cut, grow and build again).
    """
    frozen = _rowless_mask(ids, rowless)  # serial helpers: see build_full_list
    # 12 runs of 5 cells (dz > 0, or dz = 0 and dy > 0) and the own run of 3 cells.
    cap = (12 * (2 * REACH + 1) + REACH + 1) * _fullest(start)
    nblock = _blocks(nc)
    needs = np.empty(nblock, dtype=np.int64)
    for blk in prange(nblock):
        needs[blk] = _half_block(blk, cap, x, frozen, L, periodic, nc, start, rlist2, half, nhalf)
    return _largest(needs)


@njit
def _rowless_mask(ids: np.ndarray, rowless: int) -> np.ndarray:
    """True for the frozen atoms with ids −1 … −``rowless`` (the window's inflow copy)."""
    frozen = np.empty(ids.shape[0], dtype=np.bool_)
    for i in range(ids.shape[0]):
        frozen[i] = rowless_atom(ids[i], rowless)
    return frozen


@njit
def _half_block(
    blk: int,
    cap: int,
    x: np.ndarray,
    frozen: np.ndarray,
    L: np.ndarray,
    periodic: np.ndarray,
    nc: np.ndarray,
    start: np.ndarray,
    rlist2: float,
    half: np.ndarray,
    nhalf: np.ndarray,
) -> int:
    """``build_half_list``'s rows of the cells of block ``blk`` (``BLOCK`` cells), with
    candidate buffers of ``cap`` entries; returns the block's largest row need."""
    maxnb = half.shape[1]
    nx = nc[0]
    ny = nc[1]
    nz = nc[2]
    ncell = nx * ny * nz
    px = periodic[0]
    need = 0
    bx = np.empty(cap)
    by = np.empty(cap)
    bz = np.empty(cap)
    bj = np.empty(cap, dtype=np.int32)
    bf = np.empty(cap, dtype=np.bool_)
    r2 = np.empty(cap)
    rowbuf = np.empty(cap, dtype=np.int32)
    for c in range(blk * BLOCK, min(ncell, (blk + 1) * BLOCK)):
        if start[c + 1] == start[c]:
            continue
        cx = c % nx
        cy = (c // nx) % ny
        cz = c // (nx * ny)
        # Gather the candidates run by run (written out here: as a function called per
        # run, with its arrays' reference counting, the gather took twice as long).
        ncand = ZERO
        for run in range(13):
            if run == 0:  # own row first: cells cx … cx + 2, from cell c's own atoms
                a, b, lo, hi = 0, 0, cx, cx + REACH
            elif run <= REACH:  # dz = 0, dy = 1, 2
                a, b, lo, hi = 0, run, cx - REACH, cx + REACH
            else:  # dz = 1, 2, dy = −2 … 2
                q = run - REACH - 1
                a = 1 + q // (2 * REACH + 1)
                b = q % (2 * REACH + 1) - REACH
                lo, hi = cx - REACH, cx + REACH
            kz = cz + a
            sz = 0.0
            if kz >= nz:
                if not periodic[2]:
                    continue
                kz -= nz
                sz = L[2]
            ky = cy + b
            sy = 0.0
            if ky < 0 or ky >= ny:
                if not periodic[1]:
                    continue
                sy = -L[1] if ky < 0 else L[1]
                ky += ny if ky < 0 else -ny
            row = nx * (ky + ny * kz)
            # The run's cells along x: one range of atoms, or two split at the periodic
            # seam (the far one shifted by ±L_x); clipped at walls.
            j0b, j1b, sxa, sxb = 0, 0, 0.0, 0.0
            if px and lo < 0:
                j0a, j1a, sxa = start[row + lo + nx], start[row + nx], -L[0]
                j0b, j1b = start[row], start[row + hi + 1]
            elif px and hi >= nx:
                j0a, j1a = start[row + lo], start[row + nx]
                j0b, j1b, sxb = start[row], start[row + hi - nx + 1], L[0]
            else:
                j0a, j1a = start[row + max(lo, 0)], start[row + min(hi, nx - 1) + 1]
            for seg in range(2):
                j0 = j0a if seg == 0 else j0b
                j1 = j1a if seg == 0 else j1b
                sx = sxa if seg == 0 else sxb
                for j in range(np.uint64(j0), np.uint64(j1)):
                    bx[ncand] = x[j, 0] + sx
                    by[ncand] = x[j, 1] + sy
                    bz[ncand] = x[j, 2] + sz
                    bj[ncand] = j
                    bf[ncand] = frozen[j]
                    ncand += ONE
        for i in range(start[c], start[c + 1]):
            xi = x[i, 0]
            yi = x[i, 1]
            zi = x[i, 2]
            k0 = i - start[c] + 1  # the candidates after i
            # All candidates, k < k0 too: a loop from 0 is vectorised better (measured).
            for k in range(ncand):
                dx = xi - bx[k]
                dy = yi - by[k]
                dz = zi - bz[k]
                r2[k] = dx * dx + dy * dy + dz * dz
            count = ZERO
            if frozen[i]:
                for k in range(np.uint64(k0), ncand):
                    rowbuf[count] = k
                    count += np.uint64((r2[k] < rlist2) & (not bf[k]))
            else:
                for k in range(np.uint64(k0), ncand):
                    rowbuf[count] = k
                    count += np.uint64(r2[k] < rlist2)
            m = min(int(count), maxnb)
            for k in range(m):
                half[i, k] = bj[np.uint64(rowbuf[k])]
            nhalf[i] = m
            need = max(need, int(count))
    return need
