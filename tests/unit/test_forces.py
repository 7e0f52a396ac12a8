"""LJ forces, per-atom energies and virials against a brute-force O(N²) minimum-image sum.

Reference: ``_reference`` (numpy, all pairs, textbook φ'). Tolerances: the kernels and the
reference add the same pair terms in different orders (and numba's fastmath may reassociate),
so they differ by round-off of order (number of terms) × ε × Σ_j |term_j|; with ≲ 100 terms
that is ≲ 2e-14 of Σ_j |F_ij|. The brief's 1e-10 relative to Σ_j |F_ij| is far above that and
far below any real error (a missing or doubled pair changes F_i by ~1e-2 of it or more).
"""

from __future__ import annotations

import numpy as np
import pytest

from hugomap.md.forces import energy_virial_full, forces_full, forces_half
from hugomap.md.neighbor import grid_shape, half_from_full
from hugomap.md.potential import LJParams
from hugomap.md.simulation import MDSimulation
from hugomap.md.state import MDState
from hugomap.particles.fcc import maxwell_velocities

from . import _reference as ref
from ._reference import EPS

REL = 1e-10


def _state(kind: str, seed: int = 3, T: float = 0.0) -> MDState:
    """Random displaced FCC (ρ = 0.8, offsets ±0.1 σ) in a periodic or walled-x box, or a
    slab of it filling half of a periodic box, centred on x = 0 (vacuum in the middle)."""
    if kind == "slab":
        x, L = ref.displaced_fcc((3, 3, 3), 0.8, 0.1, seed)
        L = L * np.array([2.0, 1.0, 1.0])
        x[:, 0] = np.mod(x[:, 0] - 0.25 * L[0], L[0])
        periodic = np.array([True, True, True])
    else:
        x, L = ref.displaced_fcc((3, 3, 3), 0.8, 0.1, seed)
        periodic = np.array([kind == "periodic", True, True])
    v = maxwell_velocities(len(x), T, seed) if T > 0 else np.zeros_like(x)
    return MDState(x=x, v=v, L=L, periodic=periodic, walls0=np.array([0.0, 0.0, L[0], 0.0]))


def _sim(kind: str, half: bool, T: float = 0.0, rc: float = 2.2) -> MDSimulation:
    sim = MDSimulation(_state(kind, T=T), LJParams(rc=rc), dt=0.005, use_half=half)
    assert sim.use_half is half
    return sim


def _assert_forces_match(f, x, L, periodic, rc):
    fref, scale = ref.forces(x, L, periodic, rc)
    err = np.linalg.norm(f - fref, axis=1)
    assert np.all(err <= REL * scale), f"max rel err {np.max(err / scale):.3e}"
    # Newton's third law: Σ_i F_i = 0 up to the round-off of the per-atom sums, bounded by
    # (terms per atom ~100) × ε × Σ_i Σ_j |F_ij| < 1e-12 Σ scale.
    assert np.all(np.abs(f.sum(axis=0)) <= 1e-12 * scale.sum())
    return fref


KINDS = ["periodic", "walled", "slab"]


@pytest.mark.parametrize("half", [False, True], ids=["full", "half"])
@pytest.mark.parametrize("kind", KINDS)
def test_simulation_forces_match_brute_force(kind, half):
    # "slab": a dense slab in a half-empty box. The rows are sized from the mean density,
    # and the first atoms in sorted order (cell 0, inside the slab) have every neighbour at
    # j > i, so their half-list rows are as long as their full rows.
    rc = 2.2
    sim = _sim(kind, half, T=1.5, rc=rc)
    s = sim.state
    fref = _assert_forces_match(s.f, s.x, s.L, s.periodic, rc)
    if kind == "walled":  # the walled box really differs from the periodic one
        fper, _ = ref.forces(s.x, s.L, np.array([True, True, True]), rc)
        assert np.max(np.abs(fper - fref)) > 1e-3
    if kind == "slab":
        # (Not advanced: its rows are sized tightly, so a step would soon need a longer list,
        # the GROW path, which test_integrate covers.)
        return
    # After steps (atoms moved, lists rebuilt and re-sorted) the forces still match.
    sim.advance(30 if ref.NO_JIT else 60)
    assert sim.list_builds > 1
    _assert_forces_match(s.f, s.x, s.L, s.periodic, rc)


def _lists(x, L, periodic, nc, rlist):
    xs, _, nbr, nnb, need = ref.sorted_lists(x, L, periodic, nc, rlist)
    assert need <= nbr.shape[1]
    half = np.zeros_like(nbr)
    nhalf = np.zeros_like(nnb)
    half_from_full(nbr, nnb, half, nhalf)
    return xs, nbr, nnb, half, nhalf


CASES = {
    # (cells, periodic, rc, skin, nc): nc None = grid_shape
    "periodic-grid": ((4, 4, 4), (True, True, True), 1.8, 0.2, None),
    "periodic-2cells": ((4, 4, 4), (True, True, True), 2.5, 0.3, (2, 2, 2)),
    "walled-grid": ((4, 4, 4), (False, True, True), 2.5, 0.3, None),
    "walled-3x2x2": ((5, 4, 4), (False, True, True), 2.5, 0.3, (3, 2, 2)),
}


@pytest.mark.parametrize("case", list(CASES))
def test_kernels_full_and_half_match_brute_force(case):
    cells, periodic, rc, skin, nc = CASES[case]
    x, L = ref.displaced_fcc(cells, 0.8, 0.1, 7)
    periodic = np.array(periodic)
    rlist = rc + skin
    nc = grid_shape(L, rlist) if nc is None else np.array(nc)
    xs, nbr, nnb, half, nhalf = _lists(x, L, periodic, nc, rlist)
    f_full = np.full_like(xs, np.nan)
    forces_full(xs, L, periodic, nbr, nnb, rc * rc, f_full)
    f_half = np.full_like(xs, np.nan)
    forces_half(xs, L, periodic, half, nhalf, rc * rc, f_half)
    _assert_forces_match(f_full, xs, L, periodic, rc)
    _assert_forces_match(f_half, xs, L, periodic, rc)


def test_pairs_between_rc_and_rlist_give_no_force():
    # Two atoms 2.6 σ apart: inside the list radius 2.8, outside rc = 2.5.
    x = np.array([[1.0, 3.0, 3.0], [3.6, 3.0, 3.0]])
    L = np.array([8.0, 8.0, 8.0])
    periodic = np.array([True, True, True])
    xs, nbr, nnb, half, nhalf = _lists(x, L, periodic, grid_shape(L, 2.8), 2.8)
    assert list(nnb) == [1, 1] and list(nhalf) == [1, 0]
    f = np.ones_like(xs)
    forces_full(xs, L, periodic, nbr, nnb, 6.25, f)
    assert np.all(f == 0.0)
    f = np.ones_like(xs)
    forces_half(xs, L, periodic, half, nhalf, 6.25, f)
    assert np.all(f == 0.0)
    pe = np.ones(2)
    vir = np.ones((2, 6))
    energy_virial_full(xs, L, periodic, nbr, nnb, 6.25, LJParams().ushift, pe, vir)
    assert np.all(pe == 0.0) and np.all(vir == 0.0)


@pytest.mark.parametrize("kind", ["periodic", "walled"])
def test_energy_virial_match_brute_force(kind):
    sim = _sim(kind, half=False)
    s = sim.state
    pe, vir = sim.per_atom_energy_virial()
    pref, vref, su, sw = ref.energy_virial(s.x, s.L, s.periodic, sim.lj.rc, sim.lj.ushift)
    # Same round-off argument as the forces, with Σ_j |U_ij| and Σ_j r |F_ij| as scales.
    assert np.all(np.abs(pe - pref) <= REL * su)
    assert np.all(np.abs(vir - vref) <= REL * sw[:, None])
    ke, pe_tot = sim.energies()
    assert pe_tot == pytest.approx(pref.sum(), rel=0, abs=REL * su.sum())
    assert ke == 0.0
    # Trace of the virial (the pressure's pair part): each pair's r_ij·F_ij is split evenly
    # between its two atoms, so Σ_i (W_xx + W_yy + W_zz) = Σ_pairs r_ij·F_ij = −Σ_pairs r φ'(r).
    i, j, d, r = ref.pairs(s.x, s.L, s.periodic, sim.lj.rc)
    trace = vir[:, :3].sum()
    assert trace == pytest.approx(-np.sum(r * ref.dphi(r)), rel=0, abs=REL * sw.sum())


@pytest.mark.parametrize("kind", ["periodic", "walled"])
def test_force_is_minus_gradient_of_total_energy(kind):
    """F_i = −∂U/∂x_i, U = Σ_i pe_i from energy_virial_full, by central differences."""
    sim = _sim(kind, half=False)
    s = sim.state
    rc = sim.lj.rc
    rc2 = rc * rc
    ushift = sim.lj.ushift
    pe = np.empty(s.n)
    vir = np.empty((s.n, 6))

    def pe_atoms(x):
        energy_virial_full(x, s.L, s.periodic, sim.nbr, sim.nnb, rc2, ushift, pe, vir)
        return pe.copy()

    h = 1e-5
    rng = np.random.default_rng(0)
    atoms = rng.choice(s.n, size=5, replace=False)
    if kind == "walled":  # include the atom nearest a wall
        atoms = np.append(atoms, np.argmin(np.minimum(s.x[:, 0], s.L[0] - s.x[:, 0])))
    _, _, su, _ = ref.energy_virial(s.x, s.L, s.periodic, rc, ushift)
    for i in atoms:
        # Pairs of atom i (all neighbours within rc + h of it, minimum image).
        d = s.x[i] - s.x
        d -= np.where(s.periodic, s.L, 0.0) * np.rint(d / s.L)
        r = np.linalg.norm(d, axis=1)
        r = r[(r > 0) & (r < rc + 2 * h)]
        # The cut at rc (a kink of the shifted U) must not fall inside the stencil.
        assert np.all(np.abs(r - rc) > 2 * h)
        r = r[r < rc]
        # Truncation h²/6 · |∂³U/∂x³|; for one pair, along a unit direction e with c = e·r̂,
        # ∂³φ(|r|) = φ''' c³ + 3 c (1 − c²)(φ''/r − φ'/r²), and |c (1 − c²)| ≤ 2/(3√3), so
        # |∂³| ≤ |φ'''| + 1.16 (|φ''|/r + |φ'|/r²); summed over the pairs of i.
        d3 = np.sum(
            np.abs(ref.d3phi(r)) + 1.16 * (np.abs(ref.d2phi(r)) / r + np.abs(ref.dphi(r)) / r**2)
        )
        trunc = h * h / 6.0 * d3 * 1.01
        for a in range(3):
            xp = s.x.copy()
            xp[i, a] += h
            xm = s.x.copy()
            xm[i, a] -= h
            # Only the pe_j that involve i change; summing the differences avoids the
            # round-off of the ~1e3 ε total. Each pe_j is off by ≲ 10 ε Σ_k |U_jk|.
            dU = np.sum(pe_atoms(xp) - pe_atoms(xm))
            round_off = 2 * 10 * EPS * np.sum(su) / (2 * h)
            fd = -dU / (2 * h)
            assert abs(s.f[i, a] - fd) <= trunc + round_off, (i, a, s.f[i, a], fd)
        # The bound is small against the force scale: the check has teeth.
        assert trunc + round_off < 1e-4 * max(np.linalg.norm(s.f[i]), 1.0)


def test_skipped_force_rows_leave_the_mobile_atoms_exact():
    """The window's inflow copy (frozen, ids −1 … −n) leaves the force loop
    (``MDSimulation.skip_force_rows``): its atoms get no row and zero force, and every other
    atom's force, and after steps every mobile atom's position and velocity, are bit for bit
    those of the run that computed the copy's rows (the mobile rows still list the copy).
    The comparison is exact: the same rows are summed in the same order."""
    runs = []
    for skip in (False, True):
        st = _state("walled", T=1.5)
        copy = st.x[:, 0] > 0.6 * st.L[0]  # the far end plays the frozen inflow copy
        st.ids = np.where(copy, -1 - np.cumsum(copy) + 1, np.arange(st.n)).astype(np.int64)
        st.v[copy] = 0.0  # it streams uniformly (here at rest), as the copy at u_in
        sim = MDSimulation(st, LJParams(rc=2.2), dt=0.005)
        if skip:
            sim.skip_force_rows(int(copy.sum()))
            s = sim.state
            assert (s.f[s.ids < 0] == 0.0).all() and (sim.nnb[s.ids < 0] == 0).all()
        sim.advance(30 if ref.NO_JIT else 60)
        assert sim.list_builds > 1
        s = sim.state
        o = np.argsort(s.ids)
        runs.append((s.ids[o], s.x[o], s.v[o], s.f[o]))
    (ia, xa, va, fa), (ib, xb, vb, fb) = runs
    np.testing.assert_array_equal(ia, ib)
    mobile = ia >= 0
    np.testing.assert_array_equal(xa, xb)  # frozen atoms drift at their own velocity
    np.testing.assert_array_equal(va, vb)
    np.testing.assert_array_equal(fa[mobile], fb[mobile])
    assert (fb[~mobile] == 0.0).all() and (np.abs(fa[~mobile]) > 0).any()


def test_pair_power_is_the_work_moving_atoms_do_on_the_others() -> None:
    """``pair_power``: an atom b dragged at constant velocity past an atom a at rest changes
    a's energy (kinetic plus the pair's) by ∫ P dt. Reference: a's own equation of motion
    integrated by velocity Verlet at dt = 1e-5 τ over a 0.2-τ pass (r down to 0.85 σ, 50 ε
    exchanged), with P integrated by the trapezoid rule: measured 2.5e-9 apart, so 1e-6 is
    clear of the integrators' error and far below a sign or factor error. Atoms b at rest do
    no work however close."""
    from hugomap.md.forces import pair_power
    from hugomap.md.potential import lj_pair

    L = np.array([50.0, 50.0, 50.0])
    periodic = np.array([False, True, True])
    rc2 = 2.5**2
    xa = np.array([[20.0, 25.0, 25.0]])
    va = np.zeros((1, 3))
    xb = np.array([[18.0, 24.2, 25.0]])
    vb = np.array([[10.0, 0.5, 0.0]])
    dt, n = 1e-5, 20000

    def force(xa, xb):
        d = xa[0] - xb[0]
        u, fr = lj_pair(float(d @ d), rc2, 0.0)
        return u, fr * d

    def energy(xa, va, xb):
        return 0.5 * float(va[0] @ va[0]) + force(xa, xb)[0]

    e0 = energy(xa, va, xb)
    work = 0.0
    p0 = pair_power(xa, xb, vb, L, periodic, rc2)
    f = force(xa, xb)[1]
    for _ in range(n):
        va = va + 0.5 * dt * f
        xa = xa + dt * va
        xb = xb + dt * vb
        f = force(xa, xb)[1]
        va = va + 0.5 * dt * f
        p1 = pair_power(xa, xb, vb, L, periodic, rc2)
        work += 0.5 * dt * (p0 + p1)
        p0 = p1
    gained = energy(xa, va, xb) - e0
    assert abs(gained) > 1.0  # the pass exchanges a real amount of energy
    assert abs(work - gained) < 1e-6 * abs(gained), (work, gained)
    assert pair_power(xa, xb, np.zeros((1, 3)), L, periodic, rc2) == 0.0


def test_in_reach_marks_the_atoms_within_the_cutoff_of_any_other() -> None:
    """``in_reach``: the a atoms with a b atom closer than rc, the minimum image taken in the
    periodic dimensions only, as a brute-force NumPy count of the same pairs says (exact:
    the same comparisons)."""
    from hugomap.md.forces import in_reach

    rng = np.random.default_rng(3)
    L = np.array([10.0, 6.0, 6.0])
    periodic = np.array([False, True, True])
    xa = rng.uniform(0.0, 1.0, (40, 3)) * L
    xb = rng.uniform(0.0, 1.0, (30, 3)) * L
    rc2 = 1.5**2
    d = xa[:, None, :] - xb[None, :, :]
    d[..., 1:] -= L[1:] * np.rint(d[..., 1:] / L[1:])
    expect = ((d**2).sum(-1) < rc2).any(axis=1)
    got = in_reach(xa, xb, L, periodic, rc2)
    assert 0 < expect.sum() < expect.size
    np.testing.assert_array_equal(got, expect)
    # x is not periodic: an atom at the far x edge does not reach one at the near edge
    assert not in_reach(np.array([[0.2, 3.0, 3.0]]), np.array([[9.9, 3.0, 3.0]]), L, periodic, rc2)[
        0
    ]


# A box of 6 × 6 × 6 list cells in every dimension: MDSimulation builds the half list
# straight from the half stencil there (the 3 × 3 × 3-cell boxes above derive it from the
# full list).
def _big_sim(kind: str, half: bool, rc: float = 2.2) -> MDSimulation:
    x, L = ref.displaced_fcc((5, 5, 5), 0.8, 0.1, 11)
    periodic = np.array([kind == "periodic", True, True])
    st = MDState(
        x=x, v=maxwell_velocities(len(x), 1.5, 11), L=L, periodic=periodic,
        walls0=np.array([0.0, 0.0, L[0], 0.0]),
    )  # fmt: skip
    return MDSimulation(st, LJParams(rc=rc), dt=0.005, use_half=half)


@pytest.mark.parametrize("kind", ["periodic", "walled"])
def test_half_stencil_forces_energies_virials_match_brute_force(kind):
    rc = 2.2
    sim = _big_sim(kind, half=True, rc=rc)
    assert sim._direct  # the half-stencil list, not derived from the full one
    s = sim.state
    _assert_forces_match(s.f, s.x, s.L, s.periodic, rc)
    sim.advance(20 if ref.NO_JIT else 60)
    assert sim.list_builds > 1
    _assert_forces_match(s.f, s.x, s.L, s.periodic, rc)
    pe, vir = sim.per_atom_energy_virial()
    pref, vref, su, sw = ref.energy_virial(s.x, s.L, s.periodic, rc, sim.lj.ushift)
    assert np.all(np.abs(pe - pref) <= REL * su)
    assert np.all(np.abs(vir - vref) <= REL * sw[:, None])


@pytest.mark.parametrize("chunks", [2, 3])
def test_threaded_newton_forces_match_serial_and_brute_force(chunks):
    """``forces_half_threads``: rows cut in ``chunks`` pieces with their own force buffers
    (whatever the number of threads that run them) give the brute-force forces, and equal
    the serial half-list forces to round-off (the same pair terms, added in another order)."""
    from hugomap.md.forces import forces_half_threads

    sim = _big_sim("periodic", half=True)
    s = sim.state
    rc2 = sim.lj.rc**2
    f1 = np.full_like(s.x, np.nan)
    forces_half(s.x, s.L, s.periodic, sim.half, sim.nhalf, rc2, f1)
    ft = np.full_like(s.x, np.nan)
    fbuf = np.full((chunks - 1, s.n, 3), np.nan)
    forces_half_threads(s.x, s.L, s.periodic, sim.half, sim.nhalf, rc2, ft, fbuf)
    fref = _assert_forces_match(ft, s.x, s.L, s.periodic, sim.lj.rc)
    _, scale = ref.forces(s.x, s.L, s.periodic, sim.lj.rc)
    assert np.all(np.linalg.norm(ft - f1, axis=1) <= REL * scale)
    assert np.max(np.abs(fref)) > 1.0


def test_half_and_full_lists_give_the_same_trajectory_to_round_off():
    """The half list (default) and the full list run the same dynamics: after 40 steps
    (several rebuilds) positions agree to round-off amplified by the chaos of 40 steps."""
    a = _big_sim("periodic", half=True)
    b = _big_sim("periodic", half=False)
    np.testing.assert_allclose(a.state.f, b.state.f, rtol=0, atol=1e-11)
    a.advance(40)
    b.advance(40)
    assert a.list_builds > 2 and b.list_builds > 2
    np.testing.assert_array_equal(a.state.ids, b.state.ids)
    np.testing.assert_allclose(a.state.x, b.state.x, rtol=0, atol=1e-9)
