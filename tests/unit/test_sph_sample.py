"""CSPH samples: lattices and the seeded random porous sample (hugomap.sph.sample).

References are exact counts and geometry: a lattice's mass per area must equal ρ0 exactly (up to
rounding of a sum, rtol 1e-12); the porous sample's distention is recomputed here from the
particle masses, independently of the packer's own count, and must meet the requested 0.5 %.
"""

from __future__ import annotations

import numpy as np
import pytest

from hugomap.sph.sample import (
    K_RESOLUTION,
    Sample,
    SampleError,
    lattice_1d,
    lattice_2d,
    porous_2d,
)

RHO = 8930.0  # copper [kg/m³]
DX = 2e-6  # [m]


def _mass_density(s: Sample, x_lo: float, x_hi: float) -> float:
    """Mean density [kg/m³] of the strip x_lo ≤ x < x_hi from the particle masses (kg per metre
    of depth) divided by the strip's area (m²)."""
    sel = (s.x[:, 0] >= x_lo) & (s.x[:, 0] < x_hi)
    return float(s.m[sel].sum() / ((x_hi - x_lo) * (s.y_hi - s.y_lo)))


def _porous(**kw) -> Sample:
    args = dict(pore_radius=(6e-6, 12e-6), seed=7)
    args.update(kw)
    return porous_2d(0.4e-3, 0.16e-3, DX, RHO, **args)


def test_lattice_1d_geometry_and_mass():
    s = lattice_1d(1e-3, DX, RHO)
    assert s.dim == 1 and s.x.shape == (500, 1)
    np.testing.assert_allclose(np.diff(s.x[:, 0]), DX, rtol=1e-9)
    assert s.x[0, 0] == pytest.approx(DX / 2) and s.x_hi == pytest.approx(1e-3)
    # Mass per unit cross-section [kg/m²] over the length gives ρ0 exactly.
    assert s.m.sum() / (s.x_hi - s.x_lo) == pytest.approx(RHO, rel=1e-12)
    assert s.distention == 1.0 and np.all(s.l == DX) and np.all(s.rho == RHO)
    with pytest.raises(AttributeError):
        s.x = None  # frozen dataclass


@pytest.mark.parametrize("kind", ["square", "hex"])
def test_lattice_2d_density_and_neighbours(kind):
    s = lattice_2d(60e-6, 40e-6, DX, RHO, kind=kind)
    assert s.dim == 2 and s.kind == kind
    inside = (s.x[:, 0] > s.x_lo) & (s.x[:, 0] < s.x_hi) & (s.x[:, 1] > s.y_lo)
    assert np.all(inside & (s.x[:, 1] < s.y_hi))
    assert s.m.sum() / ((s.x_hi - s.x_lo) * (s.y_hi - s.y_lo)) == pytest.approx(RHO, rel=1e-12)
    # Particle size l = (m/ρ)^(1/2), the solver's definition: dx on the square lattice.
    np.testing.assert_allclose(s.l, np.sqrt(s.m / s.rho), rtol=1e-15)
    if kind == "square":
        assert np.all(s.l == DX)
    # Nearest-neighbour distances with the y period: dx for every particle, and the coordination
    # number 4 (square) or 6 (hexagonal) away from the x ends: the lattice is periodic in y.
    d = s.x[:, None, :] - s.x[None, :, :]
    ly = s.y_hi - s.y_lo
    d[..., 1] -= ly * np.round(d[..., 1] / ly)
    r = np.sqrt((d**2).sum(-1))
    np.fill_diagonal(r, np.inf)
    np.testing.assert_allclose(r.min(axis=1), DX, rtol=1e-9)
    interior = (s.x[:, 0] > 3 * DX) & (s.x[:, 0] < s.x_hi - 3 * DX)
    coord = (r[interior] < DX * (1 + 1e-6)).sum(axis=1)
    assert np.all(coord == (4 if kind == "square" else 6))


def test_porous_reaches_target_distention_measured_from_masses():
    s = _porous()
    # Independent measure: particle mass per area in the porous core (and over the whole box).
    rho_core = _mass_density(s, s.core_x_lo, s.core_x_hi)
    assert RHO / rho_core == pytest.approx(s.distention_core, rel=1e-12)
    assert abs(RHO / rho_core / 1.35 - 1) <= 0.005
    rho_box = _mass_density(s, s.x_lo, s.x_hi)
    assert RHO / rho_box == pytest.approx(s.distention, rel=1e-12)
    assert s.rho_mean == pytest.approx(rho_box, rel=1e-12)
    # The box target (region="box") is the brief's ρ_solid·N_kept·dx²/(Lx·Ly).
    b = _porous(region="box")
    assert abs(b.distention / 1.35 - 1) <= 0.005
    assert b.distention == pytest.approx(
        (b.x_hi - b.x_lo) * (b.y_hi - b.y_lo) / (b.n * DX**2), rel=1e-12
    )


def test_porous_pores_are_disjoint_resolved_and_empty():
    s = _porous()
    c, r = s.pore_centres, s.pore_radii
    ly = s.y_hi - s.y_lo
    gap = DX  # the default min_gap
    assert len(r) > 20
    # Radii: drawn in [r_min, r_max]; at most two final pores may be smaller, never below 3·dx.
    assert np.all(r <= 12e-6) and np.all(r >= K_RESOLUTION * DX * (1 - 1e-12))
    assert np.sum(r < 6e-6) <= 2
    # Pairwise separation ≥ r_i + r_j + min_gap with the y period.
    d = c[:, None, :] - c[None, :, :]
    d[..., 1] -= ly * np.round(d[..., 1] / ly)
    dist = np.sqrt((d**2).sum(-1))
    need = r[:, None] + r[None, :] + gap
    np.fill_diagonal(dist, np.inf)
    assert np.all(dist >= need * (1 - 1e-12))
    # Pores stay off the x ends: the first and last columns are solid (x_margin = 4·dx).
    assert np.all(c[:, 0] - r >= s.core_x_lo - 1e-15)
    assert np.all(c[:, 0] + r <= s.core_x_hi + 1e-15)
    full = lattice_2d(s.x_hi, s.y_hi, DX, RHO)
    end = (full.x[:, 0] < 4 * DX) | (full.x[:, 0] > s.x_hi - 4 * DX)
    kept = {tuple(p) for p in np.round(s.x / DX * 2).astype(int)}
    assert all(tuple(p) in kept for p in np.round(full.x[end] / DX * 2).astype(int))
    # Exactly the lattice sites strictly inside some pore were removed, no others.
    dd = full.x[:, None, :] - c[None, :, :]
    dd[..., 1] -= ly * np.round(dd[..., 1] / ly)
    in_pore = ((dd**2).sum(-1) < r[None, :] ** 2).any(axis=1)
    assert s.n == full.n - int(in_pore.sum())
    assert {tuple(p) for p in np.round(full.x[~in_pore] / DX * 2).astype(int)} == kept


def test_porous_is_reproducible_by_seed():
    a, b, c = _porous(seed=11), _porous(seed=11), _porous(seed=12)
    assert np.array_equal(a.x, b.x) and np.array_equal(a.pore_radii, b.pore_radii)
    assert not np.array_equal(a.pore_centres[:3], c.pore_centres[:3])


@pytest.mark.parametrize(
    "kw",
    [
        dict(pore_radius=8e-6),  # fixed radius: the last pores are resized
        dict(kind="hex"),
        dict(periodic_y=False),
        dict(distention=1.6, min_gap=0.0),
    ],
)
def test_porous_variants_meet_tolerance(kw):
    s = _porous(**kw)
    target = kw.get("distention", 1.35)
    assert abs(s.distention_core / target - 1) <= 0.005
    if kw.get("periodic_y") is False:  # pores kept min_gap = dx off the y walls
        c, r = s.pore_centres, s.pore_radii
        assert np.all(c[:, 1] - r >= DX * (1 - 1e-9))
        assert np.all(c[:, 1] + r <= s.y_hi - DX * (1 - 1e-9))


def test_distention_one_has_no_pores():
    s = _porous(distention=1.0)
    assert s.n == lattice_2d(0.4e-3, 0.16e-3, DX, RHO).n and len(s.pore_radii) == 0
    assert s.distention == 1.0


@pytest.mark.parametrize(
    ("kw", "words"),
    [
        (dict(distention=0.9), ["distention", "≥ 1"]),
        (dict(distention=2.5), ["distention", "≤ 2", "0.547"]),
        (dict(pore_radius=(5e-6, 12e-6)), ["pore_radius", "3·dx", "6e-06"]),
        (dict(pore_radius=(12e-6, 6e-6)), ["pore_radius", "r_min ≤ r_max"]),
        (dict(pore_radius=(6e-6, 90e-6)), ["pore_radius", "does not fit"]),
        (dict(min_gap=-1e-6), ["min_gap", "≥ 0"]),
        (dict(tolerance=0.0), ["tolerance"]),
        # 1e-5 of α is a fraction of one particle here: the last pore cannot hit it.
        (dict(tolerance=1e-5), ["tolerance = 1e-05", "misses the target"]),
    ],
)
def test_porous_bad_input_is_refused_with_clear_errors(kw, words):
    with pytest.raises(SampleError) as err:
        _porous(**kw)
    for w in words:
        assert w in str(err.value)


def test_bad_sizes_are_refused():
    with pytest.raises(SampleError, match="dx"):
        porous_2d(1e-3, 1e-3, 0.0, RHO, pore_radius=1e-5)
    with pytest.raises(SampleError, match="lx"):
        lattice_2d(-1e-3, 1e-3, DX, RHO)
    with pytest.raises(SampleError, match="length"):
        lattice_1d(-1e-3, DX, RHO)
    with pytest.raises(SampleError, match="dx"):
        lattice_1d(1e-3, -DX, RHO)
    with pytest.raises(SampleError, match="kind"):
        lattice_2d(1e-4, 1e-4, DX, RHO, kind="triangle")
    assert issubclass(SampleError, ValueError)


def test_unreachable_porosity_gives_up_instead_of_looping():
    # Porosity 0.47 (α = 1.9) is below the cap but unreachable for equal pores of radius 3·dx
    # with a 2·dx ligament: discs of effective radius 4·dx jam at ≈ 0.547·(3/4)² ≈ 0.31.
    with pytest.raises(SampleError, match="could not be packed"):
        _porous(distention=1.9, pore_radius=6e-6, min_gap=2 * DX, max_attempts=300)
