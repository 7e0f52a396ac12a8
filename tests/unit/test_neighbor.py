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
    """Verlet's guarantee: with rebuilds when an atom has moved skin/2, the list built at
    x_ref holds every pair now closer than rc (checked after every few steps)."""
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
