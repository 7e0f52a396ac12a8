"""Cell lists and Verlet lists against brute force (``_reference.pair_set``: all pairs, minimum
image). Set comparisons are exact: a missing, extra or duplicated pair fails."""

from __future__ import annotations

from collections import Counter

import numpy as np
import pytest

from hugomap.md.neighbor import cell_of, counting_sort, grid_shape, half_from_full
from hugomap.md.potential import LJParams
from hugomap.md.sample import fcc_state
from hugomap.md.simulation import MDSimulation

from . import _reference as ref

RLIST = 2.8

# (box, periodic flags, nc): nc None = grid_shape(L, rlist). Every periodic length is at
# least 2 rlist (the minimum-image condition MDSimulation enforces), and a forced nc keeps
# cells at least rlist wide, which any stencil handles.
BOXES = {
    "periodic-cube-grid": ((6.0, 6.0, 6.0), (True, True, True), None),
    "periodic-cube-2cells": ((6.0, 6.0, 6.0), (True, True, True), (2, 2, 2)),
    "periodic-minimal-2cells": ((5.61, 5.61, 5.61), (True, True, True), (2, 2, 2)),
    "periodic-3cells": ((8.7, 8.7, 8.7), (True, True, True), (3, 3, 3)),
    "periodic-mixed-2x3x4": ((5.7, 8.6, 11.5), (True, True, True), (2, 3, 4)),
    "periodic-mixed-grid": ((5.7, 8.6, 11.5), (True, True, True), None),
    "walled-thin-1cell": ((2.0, 6.0, 6.0), (False, True, True), (1, 2, 2)),
    "walled-grid": ((9.0, 6.0, 6.0), (False, True, True), None),
    "walled-3x2x2": ((9.0, 6.0, 6.0), (False, True, True), (3, 2, 2)),
    "walled-x-and-z": ((7.0, 6.0, 7.0), (False, True, False), None),
}


def _gas(L, density=0.6, seed=1):
    rng = np.random.default_rng(seed)
    L = np.array(L)
    n = int(density * np.prod(L))
    return rng.uniform(0.0, 1.0, size=(n, 3)) * L, L


def _list_pairs(nbr, nnb):
    """Ordered pairs (i, j) in the rows, as a Counter (to catch duplicates)."""
    return Counter((i, int(j)) for i in range(len(nnb)) for j in nbr[i, : nnb[i]])


@pytest.mark.parametrize("box", list(BOXES))
def test_list_is_exactly_the_pairs_within_rlist(box):
    L, periodic, nc = BOXES[box]
    x, L = _gas(L)
    periodic = np.array(periodic)
    nc = grid_shape(L, RLIST) if nc is None else np.array(nc)
    xs, order, nbr, nnb, need = ref.sorted_lists(x, L, periodic, nc, RLIST)
    # The sort is a permutation of the atoms.
    assert np.array_equal(np.sort(order), np.arange(len(x)))
    ordered = _list_pairs(nbr, nnb)
    # No row lists an atom twice (a small periodic dimension must not visit a cell twice)
    # and no atom lists itself.
    assert max(ordered.values()) == 1
    assert all(i != j for i, j in ordered)
    # Symmetric: j in row i iff i in row j.
    assert set(ordered) == {(j, i) for i, j in ordered}
    # Exactly the brute-force pairs within rlist (minimum image), no more, no less.
    expected = ref.pair_set(xs, L, periodic, RLIST)
    assert {(i, j) for i, j in ordered if i < j} == expected
    degree = np.bincount(np.array(list(expected)).ravel(), minlength=len(x))
    assert np.array_equal(nnb, degree)
    assert need == degree.max()


def test_short_rows_are_cut_and_report_the_need():
    x, L = _gas((6.0, 6.0, 6.0))
    periodic = np.array([True, True, True])
    xs, _, nbr, nnb, need = ref.sorted_lists(x, L, periodic, grid_shape(L, RLIST), RLIST, maxnb=5)
    expected = ref.pair_set(xs, L, periodic, RLIST)
    degree = np.bincount(np.array(list(expected)).ravel(), minlength=len(x))
    assert need == degree.max() > 5
    assert np.array_equal(nnb, np.minimum(degree, 5))
    for i in range(len(x)):  # what was kept are true neighbours
        for j in nbr[i, : nnb[i]]:
            assert (min(i, j), max(i, j)) in expected


def test_counting_sort_is_a_stable_permutation():
    rng = np.random.default_rng(5)
    ncells = 12
    cell = rng.integers(0, 9, size=300)  # cells 9..11 empty, duplicates everywhere
    order, start = counting_sort(cell, ncells)
    # Stable: equal to numpy's stable argsort (ties keep their input order).
    assert np.array_equal(order, np.argsort(cell, kind="stable"))
    assert np.array_equal(np.sort(order), np.arange(cell.size))
    counts = np.bincount(cell, minlength=ncells)
    assert np.array_equal(start, np.concatenate([[0], np.cumsum(counts)]))
    for c in range(ncells):  # each block holds exactly its cell's atoms, in input order
        block = order[start[c] : start[c + 1]]
        assert np.all(cell[block] == c) and np.all(np.diff(block) > 0)


def test_cell_of_places_atoms_in_their_cell():
    L = np.array([9.0, 6.0, 7.5])
    nc = np.array([3, 2, 5])
    rng = np.random.default_rng(2)
    x = rng.uniform(0, 1, size=(200, 3)) * L
    x[0] = [0.0, 0.0, 0.0]
    x[1] = L  # on the far faces (walls sit there): clamped into the last cells
    x[2] = L * (1 - 1e-16)
    cell = cell_of(x, L, nc)
    k = np.stack([cell % nc[0], (cell // nc[0]) % nc[1], cell // (nc[0] * nc[1])], axis=1)
    side = L / nc
    inside = (k * side <= x * (1 + 1e-12)) & (x <= (k + 1) * side * (1 + 1e-12))
    assert np.all(inside)
    assert cell[0] == 0 and cell[1] == np.prod(nc) - 1
    assert np.all((cell >= 0) & (cell < np.prod(nc)))


def test_half_list_keeps_each_pair_once():
    x, L = _gas((6.0, 6.0, 6.0))
    periodic = np.array([True, True, True])
    xs, _, nbr, nnb, _ = ref.sorted_lists(x, L, periodic, grid_shape(L, RLIST), RLIST)
    half = np.full_like(nbr, -1)
    nhalf = np.zeros_like(nnb)
    half_from_full(nbr, nnb, half, nhalf)
    for i in range(len(x)):
        row = nbr[i, : nnb[i]]
        assert list(half[i, : nhalf[i]]) == [j for j in row if j > i]  # order kept
    pairs = [(i, int(j)) for i in range(len(x)) for j in half[i, : nhalf[i]]]
    assert len(pairs) == len(set(pairs)) == len(ref.pair_set(xs, L, periodic, RLIST))


@pytest.mark.usefixtures("serial_numba")
@pytest.mark.parametrize("periodic_x", [True, False])
def test_simulation_list_always_covers_rc(periodic_x):
    """Verlet's guarantee, kept by the pair-by-pair test (``list_holds``) that replaces
    Verlet's rebuild at skin/2: the list built at x_ref holds every pair now closer than rc
    (checked after every few steps)."""
    st = fcc_state((3, 3, 3), 0.8, 2.0, 4, periodic_x=periodic_x)
    sim = MDSimulation(st, LJParams(rc=2.2, skin=0.3), dt=0.005)
    s = sim.state
    for _ in range(6 if ref.NO_JIT else 20):
        sim.advance(5)
        listed = {
            (min(i, int(j)), max(i, int(j))) for i in range(s.n) for j in sim.nbr[i, : sim.nnb[i]]
        }
        assert ref.pair_set(s.x, s.L, s.periodic, sim.lj.rc) <= listed
        # and the list is the exact rlist list at the positions where it was built
        assert ref.pair_set(s.x_ref, s.L, s.periodic, sim.lj.rlist) == listed
    assert sim.list_builds > 2


# Boxes whose periodic dimensions have ≥ 5 cells: the half list comes straight from the half
# stencil (``build_half_list``); bounded dimensions may have any number of cells.
HALF_BOXES = {
    "periodic-5x6x6": ((7.1, 8.5, 9.0), (True, True, True)),
    "periodic-8x5x7": ((11.5, 7.2, 10.0), (True, True, True)),
    "walled-x-2cells": ((4.0, 8.5, 9.0), (False, True, True)),
    "walled-x-and-z": ((9.0, 7.5, 3.0), (False, True, False)),
    "walled-all": ((5.0, 4.0, 8.0), (False, False, False)),
}


def _half_direct(xs, L, periodic, ids=None, rowless=0, maxnb=None):
    from hugomap.md.neighbor import build_half_list

    nc = grid_shape(L, RLIST)
    start = counting_sort(cell_of(xs, L, nc), int(np.prod(nc)))[1]
    n = len(xs)
    half = np.full((n, n if maxnb is None else maxnb), -1, dtype=np.int32)
    nhalf = np.zeros(n, dtype=np.int32)
    ids = np.arange(n, dtype=np.int64) if ids is None else ids
    need = build_half_list(xs, ids, L, periodic, nc, start, RLIST**2, rowless, half, nhalf)
    return half, nhalf, int(need)


@pytest.mark.parametrize("box", list(HALF_BOXES))
def test_half_stencil_list_is_each_pair_within_rlist_once(box):
    from hugomap.md.neighbor import half_stencil_ok

    L, periodic = HALF_BOXES[box]
    x, L = _gas(L)
    periodic = np.array(periodic)
    nc = grid_shape(L, RLIST)
    assert half_stencil_ok(nc, periodic)
    xs, _, _, _, _ = ref.sorted_lists(x, L, periodic, nc, RLIST)
    half, nhalf, need = _half_direct(xs, L, periodic)
    unordered = Counter(
        (min(i, int(j)), max(i, int(j))) for i in range(len(xs)) for j in half[i, : nhalf[i]]
    )
    assert all(i != j for i, j in unordered)
    assert max(unordered.values()) == 1  # each pair once: never from both ends
    assert set(unordered) == ref.pair_set(xs, L, periodic, RLIST)
    assert need == nhalf.max()


def test_half_stencil_refuses_short_periodic_dimensions():
    from hugomap.md.neighbor import half_stencil_ok

    assert not half_stencil_ok(np.array([4, 6, 6]), np.array([True, True, True]))
    assert half_stencil_ok(np.array([4, 6, 6]), np.array([False, True, True]))
    assert half_stencil_ok(np.array([1, 1, 1]), np.array([False, False, False]))


def test_half_stencil_short_rows_are_cut_and_report_the_need():
    L, periodic = HALF_BOXES["periodic-5x6x6"]
    x, L = _gas(L)
    periodic = np.array(periodic)
    xs, _, _, _, _ = ref.sorted_lists(x, L, periodic, grid_shape(L, RLIST), RLIST)
    full, nfull, need = _half_direct(xs, L, periodic)
    cut, ncut, need_cut = _half_direct(xs, L, periodic, maxnb=5)
    assert need_cut == need > 5
    assert np.array_equal(ncut, np.minimum(nfull, 5))
    for i in range(len(xs)):  # the rows are cut, not changed
        assert np.array_equal(cut[i, : ncut[i]], full[i, : ncut[i]])


@pytest.mark.parametrize("direct", [True, False], ids=["half-stencil", "from-full"])
def test_half_list_leaves_out_only_the_pairs_inside_the_inflow_copy(direct):
    """With ``rowless`` the pairs of two copy atoms (ids −1 … −rowless) are dropped, and
    nothing else: every row keeps its other entries in their order (the mobile atoms'
    forces are then summed in the same order, bit for bit)."""
    from hugomap.md.neighbor import half_from_full_rowless

    L, periodic = HALF_BOXES["periodic-5x6x6"] if direct else ((6.0, 6.0, 6.0), (True,) * 3)
    x, L = _gas(L)
    periodic = np.array(periodic)
    xs, _, nbr, nnb, _ = ref.sorted_lists(x, L, periodic, grid_shape(L, RLIST), RLIST)
    n = len(xs)
    copy = xs[:, 0] > 0.5 * L[0]
    ids = np.where(copy, -1 - np.cumsum(copy) + 1, np.arange(n)).astype(np.int64)
    ids[copy & (xs[:, 1] > 0.8 * L[1])] = -n - 5  # frozen, but not of the copy: kept
    rowless = int(copy.sum())
    if direct:
        h0, n0, _ = _half_direct(xs, L, periodic)
        h1, n1, _ = _half_direct(xs, L, periodic, ids, rowless)
    else:
        h0, h1 = np.zeros((n, n), np.int32), np.zeros((n, n), np.int32)
        n0, n1 = np.zeros(n, np.int32), np.zeros(n, np.int32)
        half_from_full_rowless(nbr, nnb, ids, 0, h0, n0)
        half_from_full_rowless(nbr, nnb, ids, rowless, h1, n1)
    in_copy = (ids < 0) & (ids >= -rowless)
    assert in_copy.sum() > 10 and (ids < -rowless).any()
    dropped = 0
    for i in range(n):
        kept = [int(j) for j in h0[i, : n0[i]] if not (in_copy[i] and in_copy[j])]
        dropped += n0[i] - len(kept)
        assert list(h1[i, : n1[i]]) == kept
    assert dropped > 0


# (box, periodic flags, shift along x): the shift is a uniform drift of every atom along a
# bounded x (the window frame's reference drift), which changes no pair distance.
HOLD_BOXES = {
    "periodic": ((8.7, 9.0, 11.5), (True, True, True), 0.0),
    "walled-x": ((9.0, 8.5, 8.7), (False, True, True), 0.0),
    "walled-x-drifting": ((9.0, 8.5, 8.7), (False, True, True), 0.37),
    "walled-x-and-z": ((9.0, 8.5, 7.0), (False, True, False), 0.0),
}


@pytest.mark.parametrize("box", list(HOLD_BOXES))
def test_list_holds_only_while_no_unlisted_pair_is_within_rc(box):
    """``list_holds`` against brute force: whenever it keeps the list, every pair now closer
    than rc was closer than rlist at the build (exact sets, all pairs, minimum image). The
    displacements are drawn so that Verlet's rule (rebuild once an atom has moved skin/2)
    would rebuild in every trial; the test also asks that the pair bound keeps the list in
    some of them and that the brute force finds a pair come within rc in some others (so
    that both answers are exercised)."""
    from hugomap.md.neighbor import list_holds

    rc, skin = 2.5, 0.3
    rlist = rc + skin
    L, periodic, shift = HOLD_BOXES[box]
    x0, L = _gas(L, density=0.5, seed=7)
    periodic = np.array(periodic)
    nc = grid_shape(L, rlist)
    start = counting_sort(cell_of(x0, L, nc), int(np.prod(nc)))[1]
    x_ref = np.ascontiguousarray(x0[np.argsort(cell_of(x0, L, nc), kind="stable")])
    listed = ref.pair_set(x_ref, L, periodic, rlist)
    rng = np.random.default_rng(11)
    kept = broken = 0
    for trial in range(200):  # as many without the JIT: fewer trials may break none
        # Most atoms move a little; a few move between skin/2 and skin.
        u = rng.normal(size=x_ref.shape)
        u /= np.linalg.norm(u, axis=1)[:, None]
        mag = rng.uniform(0.0, 0.1, len(x_ref))
        fast = rng.choice(len(x_ref), size=1 + trial % 6, replace=False)
        mag[fast] = rng.uniform(0.5 * skin * 1.01, skin, fast.size)
        x = x_ref + mag[:, None] * u
        x[:, 0] += shift
        for d in range(3):
            if periodic[d]:
                x[:, d] %= L[d]
        holds = list_holds(x, x_ref, shift, L, periodic, nc, start, rc, rlist)
        now = ref.pair_set(x, L, periodic, rc)
        if holds:
            kept += 1
            assert now <= listed, f"trial {trial}: a pair within rc is not in the list"
        broken += not now <= listed
    assert kept > 0 and broken > 0, (kept, broken)


def test_list_holds_refuses_moves_of_skin_and_more():
    """An atom that has moved a whole skin, however alone, sends the list to a rebuild (the
    search stencil is sized for moves below skin)."""
    from hugomap.md.neighbor import list_holds

    rc, rlist = 2.5, 2.8
    L = np.array([9.0, 9.0, 9.0])
    periodic = np.array([True, True, True])
    x_ref = np.array([[1.0, 1.0, 1.0], [6.0, 6.0, 6.0]])
    nc = grid_shape(L, rlist)
    order = np.argsort(cell_of(x_ref, L, nc), kind="stable")
    x_ref = np.ascontiguousarray(x_ref[order])
    start = counting_sort(cell_of(x_ref, L, nc), int(np.prod(nc)))[1]
    x = x_ref.copy()
    x[0, 0] += 0.29
    assert list_holds(x, x_ref, 0.0, L, periodic, nc, start, rc, rlist)
    x[0, 0] += 0.02
    assert not list_holds(x, x_ref, 0.0, L, periodic, nc, start, rc, rlist)
