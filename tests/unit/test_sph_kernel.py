"""Wendland C2 kernel and the acoustic Riemann solver of CSPH.

Kernel: ∫ W dV = 1 (1D, 2D, 3D), checked by composite Simpson quadrature on 4001 points
(error ~1e-12 for this smooth integrand; tolerance 1e-9), and dW/dr against a centred finite
difference (δ = 1e-6 h; error O(δ²) + round-off ~1e-9 relative; tolerance 1e-6 of max |W'|).
Riemann: the contact state must satisfy both acoustic jump relations σ* − σ_i = Z_i (U* − u_i)
and σ* − σ_j = −Z_j (U* − u_j) (round-off), be symmetric under i ↔ j with the axis reversed,
and the wall solution must equal the pair solution with the mirror image.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from hugomap.sph.kernel import dwdr, pair_h, w
from hugomap.sph.riemann import contact, wall_contact


def _simpson(f, a, b, n=4000):
    x = np.linspace(a, b, n + 1)
    y = np.array([f(t) for t in x])
    return (b - a) / (3 * n) * (y[0] + y[-1] + 4 * y[1:-1:2].sum() + 2 * y[2:-1:2].sum())


@pytest.mark.parametrize("dim", [1, 2, 3])
def test_kernel_normalised(dim):
    h = 0.37
    shell = {1: lambda r: 2.0, 2: lambda r: 2 * math.pi * r, 3: lambda r: 4 * math.pi * r * r}
    total = _simpson(lambda r: shell[dim](r) * w(r, h, dim), 0.0, 2.0 * h)
    assert abs(total - 1.0) < 1e-9
    assert w(2.0 * h, h, dim) == 0.0 and w(3.0 * h, h, dim) == 0.0


@pytest.mark.parametrize("dim", [1, 2, 3])
def test_kernel_derivative(dim):
    h = 1.3
    d = 1e-6 * h
    scale = max(abs(dwdr(r, h, dim)) for r in np.linspace(0, 2 * h, 50))
    for r in np.linspace(0.05, 1.95, 20) * h:
        fd = (w(r + d, h, dim) - w(r - d, h, dim)) / (2 * d)
        assert abs(fd - dwdr(r, h, dim)) < 1e-6 * scale
    assert dwdr(2.5 * h, h, dim) == 0.0 and dwdr(0.0, h, dim) == 0.0


def test_pair_h():
    assert pair_h(1.0, 3.0, 0.6) == pytest.approx(2.4)


def test_contact_jump_relations_and_symmetry():
    rng = np.random.default_rng(0)
    for _ in range(100):
        ui, uj = rng.normal(size=2) * 300
        si, sj = rng.normal(size=2) * 1e9
        zi, zj = rng.uniform(1e7, 6e7, size=2)
        us, ss = contact(ui, si, zi, uj, sj, zj)
        assert abs((ss - si) - zi * (us - ui)) < 1e-6 * (abs(ss) + abs(si) + 1.0)
        assert abs((ss - sj) + zj * (us - uj)) < 1e-6 * (abs(ss) + abs(sj) + 1.0)
        # j | i seen along −e: velocities change sign, stresses do not
        us2, ss2 = contact(-uj, sj, zj, -ui, si, zi)
        assert abs(us2 + us) < 1e-9 * (abs(us) + 1) and abs(ss2 - ss) < 1e-6 * (abs(ss) + 1)


def test_contact_limits():
    # approaching equal particles compress the contact by Z Δu / 2 (acoustic impact)
    us, ss = contact(100.0, 0.0, 4e7, -100.0, 0.0, 4e7)
    assert us == 0.0 and ss == pytest.approx(-4e7 * 100.0)
    # no shear impedance: mean velocity, mean stress
    assert contact(1.0, 0.0, 0.0, 3.0, 0.0, 0.0) == (2.0, 0.0)


def test_wall_is_mirror_pair():
    rng = np.random.default_rng(2)
    for _ in range(20):
        u, s, z, uw = (
            rng.normal() * 500,
            rng.normal() * 1e9,
            rng.uniform(1e7, 5e7),
            rng.normal() * 300,
        )
        a = wall_contact(u, s, z, uw)
        b = contact(u, s, z, 2 * uw - u, s, z)
        assert abs(a[0] - b[0]) < 1e-9 * (abs(uw) + 1) and abs(a[1] - b[1]) < 1e-6 * (abs(a[1]) + 1)
