"""Slab profiles: ``bin_sums`` + ``fields_from_sums`` on configurations with known fields.

Synthetic ideal gas (no forces, so pe = W = 0 unless added): in each bin c = 8 atoms with
velocities u + (±a_x, ±a_y, ±a_z) (all eight sign combinations), and dyadic numbers so that
every sum is exact in floating point. Exactly:
    n = c / V_b,  ū = u,  K_aa = Σ (v_a − u_a)² = c a_a²,  P_aa = (K_aa + Σ W_aa) / V_b,
    T = Σ_a K_aa / (3 (c − 1)),  e = (½ Σ_a K_aa + Σ pe) / c,
so the ideal-gas law reads P = n T (c − 1)/c · 3 a_a² / Σ_b a_b² (isotropic: P = n T (c−1)/c).
"""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from hugomap.md.potential import LJParams
from hugomap.md.sample import fcc_state
from hugomap.md.simulation import MDSimulation
from hugomap.particles.bins import bin_sums
from hugomap.particles.profiles import SUM_FIELDS, fields_from_sums

from ._reference import EPS

WIDTH = 0.5
AREA = 4.0  # L_y L_z
V_B = AREA * WIDTH
SIGNS = np.array(list(itertools.product((-1.0, 1.0), repeat=3)))  # 8 × 3

# per bin: (u (3,), a (3,), pe per atom, W_xx per atom); bin 2 left empty
BINS = {
    0: ((0.0, 0.0, 0.0), (1.0, 1.0, 1.0), 0.0, 0.0),
    1: ((1.5, -0.25, 0.5), (0.5, 0.5, 0.5), -2.0, 0.0),
    3: ((-3.0, 0.125, 2.0), (2.0, 0.25, 1.0), 0.0, 0.75),  # anisotropic, with a virial
}
NBINS = 5


def _gas():
    xs, vs, pes, virs = [], [], [], []
    for b, (u, a, pe, wxx) in BINS.items():
        x = np.zeros((8, 3))
        x[:, 0] = (b + np.linspace(0.0625, 0.9375, 8)) * WIDTH  # inside bin b
        xs.append(x)
        vs.append(np.array(u) + SIGNS * np.array(a))
        pes.append(np.full(8, pe))
        vir = np.zeros((8, 6))
        vir[:, 0] = wxx
        virs.append(vir)
    return np.concatenate(xs), np.concatenate(vs), np.concatenate(pes), np.concatenate(virs)


def test_fields_of_a_synthetic_gas_are_exact():
    x, v, pe, vir = _gas()
    sums = np.zeros((NBINS, len(SUM_FIELDS)))
    bin_sums(x, v, pe, vir, WIDTH, sums)
    out = fields_from_sums(sums, V_B)
    for b, (u, a, pe_b, wxx) in BINS.items():
        c = 8
        a = np.array(a)
        K = c * a**2
        T = K.sum() / (3 * (c - 1))
        # Every input is dyadic, every sum exact; the divisions round once: 2 ulp.
        assert out["n"][b] == pytest.approx(c / V_B, rel=2 * EPS)
        assert out["ux"][b] == pytest.approx(u[0], rel=2 * EPS, abs=0)
        assert out["Pxx"][b] == pytest.approx((K[0] + c * wxx) / V_B, rel=2 * EPS)
        assert out["Pyy"][b] == pytest.approx(K[1] / V_B, rel=2 * EPS)
        assert out["Pzz"][b] == pytest.approx(K[2] / V_B, rel=2 * EPS)
        assert out["T"][b] == pytest.approx(T, rel=4 * EPS)
        assert out["e"][b] == pytest.approx((0.5 * K.sum() + c * pe_b) / c, rel=4 * EPS)
        if wxx == 0 and np.all(a == a[0]):  # ideal gas law, with the c − 1 of T
            assert out["Pxx"][b] == pytest.approx(out["n"][b] * T * (c - 1) / c, rel=8 * EPS)
    # The empty bin: zero density, no temperature.
    assert out["n"][2] == 0.0 and np.isnan(out["T"][2])
    assert out["n"][4] == 0.0


def test_galilean_invariance_of_thermal_fields():
    # Adding a flow velocity changes ū only: T and P are relative to the bin mean.
    x, v, pe, vir = _gas()
    base = np.zeros((NBINS, len(SUM_FIELDS)))
    bin_sums(x, v, pe, vir, WIDTH, base)
    moved = np.zeros_like(base)
    bin_sums(x, v + np.array([4.0, -2.0, 1.0]), pe, vir, WIDTH, moved)
    f0 = fields_from_sums(base, V_B)
    f1 = fields_from_sums(moved, V_B)
    occupied = list(BINS)
    # Σ v² − c ū² loses ~ε (|u| + 4)² per atom to cancellation: ≤ 1e-13 here.
    for k in ("Pxx", "Pyy", "Pzz", "T", "e"):
        np.testing.assert_allclose(f1[k][occupied], f0[k][occupied], rtol=0, atol=1e-13)
    np.testing.assert_allclose(f1["ux"][occupied], f0["ux"][occupied] + 4.0, rtol=0, atol=1e-14)


def test_bin_sums_accumulate_and_drop_atoms_outside():
    x, v, pe, vir = _gas()
    # (x = −0.6: bin −1.2 → −1. Note int() truncates, so −WIDTH < x < 0 would land in bin 0;
    # MD positions are never negative, see the report.)
    x = np.concatenate([x, [[-0.6, 0, 0], [NBINS * WIDTH + 0.01, 0, 0]]])
    v = np.concatenate([v, np.ones((2, 3))])
    pe = np.concatenate([pe, [5.0, 5.0]])
    vir = np.concatenate([vir, np.ones((2, 6))])
    sums = np.zeros((NBINS, len(SUM_FIELDS)))
    bin_sums(x, v, pe, vir, WIDTH, sums)
    bin_sums(x, v, pe, vir, WIDTH, sums)  # accumulates (+=)
    assert sums[:, 0].sum() == 2 * 8 * len(BINS)  # the two outside atoms are dropped
    # Stacked sums (time, bin, field) give the fields of each slice.
    stacked = np.stack([sums, 0.5 * sums])
    f = fields_from_sums(stacked, V_B)
    f_half = fields_from_sums(0.5 * sums, V_B)
    np.testing.assert_array_equal(f["T"][1], f_half["T"])
    assert f["n"].shape == (2, NBINS)


def test_simulation_profile_sums_add_up():
    """profile_sums on an MD sample: the bins hold every atom, the total potential energy
    and the total virial trace (checked against energies() and energy_virial_full)."""
    st = fcc_state((3, 3, 3), 0.8, 1.5, 1, periodic_x=False)
    sim = MDSimulation(st, LJParams(rc=2.2), dt=0.005)
    sim.advance(20)
    L = sim.state.L[0]
    width = L / 6  # six bins exactly covering the box
    sums = sim.profile_sums(width)
    assert sums.shape == (6, len(SUM_FIELDS))
    assert sums[:, 0].sum() == sim.state.n
    ke, pe = sim.energies()
    _, vir = sim.per_atom_energy_virial()
    # Same terms summed in another grouping: round-off ~1e-13 of the magnitudes.
    assert sums[:, 7].sum() == pytest.approx(pe, rel=1e-12)
    assert sums[:, 4:7].sum() == pytest.approx(2 * ke, rel=1e-12)
    assert sums[:, 8].sum() == pytest.approx(vir[:, 0].sum(), rel=1e-12, abs=1e-12)
    f = fields_from_sums(sums, width * sim.state.L[1] * sim.state.L[2])
    assert np.all(f["n"] > 0) and np.all(np.isfinite(f["T"]))
