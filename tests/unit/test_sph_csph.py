"""CSPH kernels in 2D plane strain: neighbour lists, rigid motions, uniform compression,
conservation, stress rotation and the blow-up diagnostics.

Copper (Mie–Grüneisen LASL + von Mises Steinberg–Guinan) on small square lattices (spacing
10 µm), small enough for NUMBA_DISABLE_JIT=1. Tolerances are round-off unless stated: rigid
motions and homogeneous compression are linear velocity fields, which the corrected velocity
gradient L·B reproduces exactly, and the pair sums are antisymmetric, so momentum and total
energy are conserved to round-off (relative 1e-12 of the sums of magnitudes).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from hugomap.eos import copper
from hugomap.failures import SPHUnstable
from hugomap.sph import csph
from hugomap.sph.neighbors import build_list, cell_grid, sort_by_cell
from hugomap.sph.simulation import CSPHSimulation, profile_fields
from hugomap.sph.state import SPHState
from hugomap.strength import copper as copper_strength

DX = 1e-5
RHO0 = 8930.0


def _block(nx: int, ny: int, x0: float = 0.0, y0: float = 0.0) -> np.ndarray:
    i, j = np.meshgrid(np.arange(nx), np.arange(ny), indexing="ij")
    return np.column_stack([x0 + (i.ravel() + 0.5) * DX, y0 + (j.ravel() + 0.5) * DX])


def _state(x: np.ndarray, v: np.ndarray, rho: float = RHO0, e: float = 0.0) -> SPHState:
    return SPHState(x=x, v=v, m=RHO0 * DX * DX, rho=rho, e=e)


def test_neighbor_list_matches_brute_force():
    rng = np.random.default_rng(4)
    n, Ly, rl = 90, 6e-5, 2.3e-5
    x = np.column_stack([rng.uniform(0, 1e-4, n), rng.uniform(0, Ly, n)])
    per = np.array([False, True])
    length = np.array([1.0, Ly])
    origin, sides, nc = cell_grid(x, rl, per, np.zeros(2), length)
    cell, order, start = sort_by_cell(x, origin, sides, nc)
    nbr = np.zeros((n, 64), dtype=np.int32)
    nnb = np.zeros(n, dtype=np.int32)
    need = build_list(x, n, per, length, nc, cell, order, start, rl * rl, nbr, nnb)
    assert need <= 64
    for i in range(n):
        d = x - x[i]
        d[:, 1] -= Ly * np.rint(d[:, 1] / Ly)
        ref = set(np.nonzero((np.sum(d * d, axis=1) < rl * rl) & (np.arange(n) != i))[0])
        assert set(nbr[i, : nnb[i]].tolist()) == ref


def test_rigid_translation_creates_no_stress():
    x = _block(7, 6)
    v = np.tile([300.0, -200.0], (len(x), 1))
    sim = CSPHSimulation(_state(x, v), copper(), copper_strength())
    sim.advance(15)
    st = sim.state
    assert np.max(np.abs(st.S)) < 1e-3  # Pa, against G·(strain) ~ 1e9 Pa for any real strain
    assert np.max(np.abs(st.rho / RHO0 - 1.0)) < 1e-12
    assert np.max(np.abs(st.e)) < 1e-6  # J/kg, against ½v² = 6.5e4
    assert np.allclose(st.v, v, rtol=0, atol=1e-9)


def _rotation_rates(correct: bool, dev_mean: bool = False) -> tuple[np.ndarray, float]:
    x = _block(8, 7)
    omega = 2e6  # 1/s: rim speed ~ 80 m/s
    c = x.mean(axis=0)
    v = omega * np.column_stack([-(x[:, 1] - c[1]), x[:, 0] - c[0]])
    sim = CSPHSimulation(
        _state(x, v), copper(), copper_strength(), grad_correction=correct, dev_mean=dev_mean
    )
    return sim.compute_rates().copy(), omega


@pytest.mark.parametrize("dev_mean", [False, True])
def test_rigid_rotation_creates_no_strain_rate(dev_mean):
    r, omega = _rotation_rates(True, dev_mean)
    lxx, lxy, lyx, lyy = r[:, csph.RLXX], r[:, csph.RLXY], r[:, csph.RLYX], r[:, csph.RLYY]
    assert np.max(np.abs(lxx)) < 1e-9 * omega and np.max(np.abs(lyy)) < 1e-9 * omega
    assert np.max(np.abs(lxy + lyx)) < 1e-9 * omega  # symmetric part: no strain rate
    assert np.allclose(0.5 * (lyx - lxy), omega, rtol=1e-9)  # rotation rate = ω everywhere
    assert np.max(np.abs(r[:, csph.RMU])) < 1e-9 * omega
    # the seed's uncorrected sums see a spurious strain rate at the free surface
    r0, _ = _rotation_rates(False)
    assert np.max(np.abs(r0[:, csph.RLXY] + r0[:, csph.RLYX])) > 1e-2 * omega


def test_stress_corotates_with_the_material():
    """S(t) = R(ωt) S0 R(ωt)ᵀ under a pure spin (round-off; the rotation is exact per step)."""
    n = 1
    x = np.zeros((n, 2))
    v = np.zeros((n, 2))
    S = np.array([[3e8, -1e8, -2e8, 0.5e8]])
    rates = np.zeros((n, csph.NRATE))
    omega, dt, steps = 1e5, 1e-7, 40
    rates[0, csph.RLXY] = -omega
    rates[0, csph.RLYX] = omega
    args = (np.ones(n), np.full(n, RHO0), np.zeros(n))
    for _ in range(steps):
        csph.update(
            x, v, args[0], args[1], args[2], S, np.zeros(n), np.ones(n), rates, dt, 1,
            np.array([47.7e9, 1e12]), np.array([False, False]), np.zeros(2), np.ones(2), 1e30,
        )  # fmt: skip
    a = omega * dt * steps
    R = np.array([[math.cos(a), -math.sin(a)], [math.sin(a), math.cos(a)]])
    s0 = np.array([[3e8, 0.5e8], [0.5e8, -1e8]])
    ref = R @ s0 @ R.T
    assert np.allclose([S[0, 0], S[0, 1], S[0, 3]], [ref[0, 0], ref[1, 1], ref[0, 1]], atol=1e-4)
    assert S[0, 2] == -2e8


@pytest.mark.parametrize("dev_mean", [False, True])
def test_uniform_compression_is_seen_exactly(dev_mean):
    """v = −α (r − r_c): μ̇ = ∇·v = −2α and no deviatoric strain rate at every particle."""
    x = _block(8, 7)
    alpha = 1e5
    v = -alpha * (x - x.mean(axis=0))
    sim = CSPHSimulation(_state(x, v), copper(), copper_strength(), dev_mean=dev_mean)
    r = sim.compute_rates()
    assert np.allclose(r[:, csph.RMU], -2 * alpha, rtol=1e-9)
    assert np.allclose(r[:, csph.RLXX] + r[:, csph.RLYY], -2 * alpha, rtol=1e-9)
    assert np.allclose(r[:, csph.RLXX], r[:, csph.RLYY], rtol=1e-9)
    assert np.max(np.abs(r[:, csph.RLXY] + r[:, csph.RLYX])) < 1e-9 * alpha


def test_uniformly_compressed_lattice_holds_the_eos_pressure():
    """A periodic lattice at ρ = 1.1 ρ0 on the Hugoniot energy stays at rest with σ = −P_EOS."""
    eos = copper()
    rho = 1.1 * RHO0
    eta = 1 - RHO0 / rho
    ph = RHO0 * 3940.0**2 * eta / (1 - 1.49 * eta) ** 2
    e = ph * eta / (2 * RHO0)
    p_ref, _ = eos.pressure_sound_speed(rho, e)
    dx = DX * (RHO0 / rho) ** 0.5
    nx, ny = 8, 6
    i, j = np.meshgrid(np.arange(nx), np.arange(ny), indexing="ij")
    x = np.column_stack([(i.ravel() + 0.5) * dx, (j.ravel() + 0.5) * dx])
    st = SPHState(x=x, v=np.zeros_like(x), m=RHO0 * DX * DX, rho=rho, e=e)
    sim = CSPHSimulation(
        st, eos, copper_strength(), periodic=(True, True), length=(nx * dx, ny * dx)
    )
    sim.advance(10)
    assert np.allclose(-sim.stress_xx(), p_ref, rtol=1e-9)
    assert abs(p_ref / ph - 1.0) < 1e-12
    assert np.max(np.abs(st.v)) < 1e-6  # m/s, against the state's sound speed ~4.5e3
    assert np.max(np.abs(st.S)) < 1e-2  # Pa
    f = profile_fields(sim.profile_sums(2 * dx, x0=0.0, nbins=nx // 2))
    assert np.allclose(f["rho"], rho, rtol=1e-12) and np.allclose(f["P"], p_ref, rtol=1e-9)
    assert np.allclose(f["sxx"], -p_ref, rtol=1e-9) and np.allclose(f["count"], 2 * ny)
    assert abs(f["mass"].sum() / st.m.sum() - 1.0) < 1e-14


def test_collision_conserves_momentum_and_energy():
    a = _block(5, 6)
    b = _block(4, 5, x0=5.2 * DX, y0=0.3 * DX)
    x = np.vstack([a, b])
    v = np.vstack([np.tile([400.0, 30.0], (len(a), 1)), np.tile([-300.0, 0.0], (len(b), 1))])
    st = _state(x, v)
    sim = CSPHSimulation(st, copper(), copper_strength())
    p0 = (st.m[:, None] * st.v).sum(axis=0)
    e0 = float(np.sum(st.m * (st.e + 0.5 * np.sum(st.v**2, axis=1))))
    pscale = float(np.sum(st.m * np.abs(st.v[:, 0])))
    sim.advance(12)
    p1 = (st.m[:, None] * st.v).sum(axis=0)
    e1 = float(np.sum(st.m * (st.e + 0.5 * np.sum(st.v**2, axis=1))))
    assert np.max(np.abs(st.S)) > 1e7  # the blocks did interact
    assert np.all(np.abs(p1 - p0) < 1e-12 * pscale)
    assert abs(e1 - e0) < 1e-12 * e0


def test_periodic_box_too_short_refused():
    x = _block(6, 4)
    with pytest.raises(ValueError, match="twice the neighbour-list radius"):
        CSPHSimulation(_state(x, np.zeros_like(x)), copper(), periodic=(False, True),
                       length=(1.0, 4 * DX))  # fmt: skip


def test_blowup_diagnostics():
    x = _block(4, 4)
    st = _state(x, np.zeros_like(x))
    st.e[3] = np.nan
    sim = CSPHSimulation(st, copper())
    with pytest.raises(SPHUnstable) as err:
        sim.step()
    assert err.value.status == "nan" and "non-finite" in err.value.diagnostic
    # a particle behind the piston face
    st = _state(_block(4, 4), np.zeros((16, 2)))
    sim = CSPHSimulation(st, copper(), walls=(0.0, 50.0, None, 0.0))
    sim.state.x[0, 0] = -1e-5
    with pytest.raises(SPHUnstable) as err:
        sim.step()
    assert err.value.status == "particle_lost"
    # a free end a piston has pushed for long is not lost: it may run ahead of its initial
    # extent by the escape distance plus twice the piston's travel (free-surface doubling),
    # no further (porous copper at 50 m/s: the free end 1 mm out after 21 us)
    for factor, lost in ((1.9, False), (2.1, True)):
        st = _state(_block(4, 4), np.zeros((16, 2)))
        sim = CSPHSimulation(st, copper(), walls=(0.0, 50.0, None, 0.0))
        sim.state.time = 2.0e-5
        sim.state.x[15, 0] = sim.extent[1] + sim.escape + factor * 50.0 * 2.0e-5
        if lost:
            with pytest.raises(SPHUnstable) as err:
                sim.step()
            assert err.value.status == "particle_lost"
        else:
            sim.step()
    # the time step collapsing (dt_floor at 0.999 of the first step: the impact shortens it)
    a, b = _block(3, 3), _block(3, 3, x0=6.0 * DX)  # 1.1 DX beyond the 2.4 DX support
    v = np.vstack([np.tile([500.0, 0.0], (9, 1)), np.tile([-500.0, 0.0], (9, 1))])
    sim = CSPHSimulation(_state(np.vstack([a, b]), v), copper(), dt_floor=0.999)
    with pytest.raises(SPHUnstable) as err:
        sim.advance(60)
    assert err.value.status == "dt_collapse"


@pytest.mark.parametrize(
    "m",
    [
        [[0.96, 0.0], [0.0, 0.96]],  # the bulk of a square lattice: M⁻¹ itself
        [[0.7, 0.2], [0.2, 0.5]],  # a pore's surface, both eigenvalues above the floor
        [[0.65, 0.02], [0.02, 0.0026]],  # a one-particle chain: one eigenvalue 0.002
        [[0.3, 0.3], [0.3, 0.3]],  # rank one, off the axes
        [[0.05, 0.0], [0.0, 0.01]],  # almost no neighbours: B = I
    ],
)
def test_floored_inverse_bounds_the_gradient_correction(m):
    """B = Q diag(1/max(λ, floor)) Qᵀ against numpy's eigendecomposition: M⁻¹ exactly where
    M is well conditioned, never more than 1/floor where it is not (``csph.floored_inverse``)."""
    m = np.asarray(m)
    bxx, bxy, byy = csph.floored_inverse(m[0, 0], m[0, 1], m[1, 1])
    b = np.array([[bxx, bxy], [bxy, byy]])
    lam, q = np.linalg.eigh(m)
    if lam.max() < csph.EIG_FLOOR:
        ref = np.eye(2)
    else:
        ref = q @ np.diag(1.0 / np.maximum(lam, csph.EIG_FLOOR)) @ q.T
    assert np.allclose(b, ref, rtol=1e-12, atol=1e-12)
    assert np.max(np.abs(np.linalg.eigvalsh(b))) <= 1.0 / csph.EIG_FLOOR * (1 + 1e-12)
    if lam.min() >= csph.EIG_FLOOR:
        assert np.allclose(b @ m, np.eye(2), atol=1e-12)


def test_a_one_particle_chain_keeps_a_bounded_correction():
    """A chain of particles one wide (a ligament between two pores), zigzagging by 0.1 dx:
    M's eigenvalue across it is about 0.005, so M⁻¹ would amplify the velocity gradient
    across the chain 190-fold (the det M > 1e-3 guard let it); every B stays ≤ 1/floor."""
    x = np.column_stack([5e-5 + 0.1 * DX * (np.arange(9) % 2), (np.arange(9) + 0.5) * DX])
    sim = CSPHSimulation(_state(x, np.zeros_like(x)), copper(), copper_strength())
    sim.compute_rates()
    pk = sim._pk
    for i in range(len(x)):
        b = np.array([[pk[i, csph.PBXX], pk[i, csph.PBXY]], [pk[i, csph.PBXY], pk[i, csph.PBYY]]])
        assert np.all(np.isfinite(b))
        assert np.max(np.abs(np.linalg.eigvalsh(b))) <= 1.0 / csph.EIG_FLOOR * (1 + 1e-12)
