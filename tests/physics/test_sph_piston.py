"""1D copper driven by a piston: shock speed against the linear Hugoniot, and the elastic
precursor at the Hugoniot elastic limit.

Set-up: uniaxial strain (1D), copper on a lattice of spacing 10 µm at rest, Mie–Grüneisen EOS
(ρ0 = 8930 kg/m³, c0 = 3940 m/s, s = 1.49, Γ0 = 2, LASL), a rigid piston (the left wall)
moving at u_p from t = 0, free far end.

Shock speed (no strength). Reference: Us = c0 + s u_p, exact for this EOS (it is referenced to
that Hugoniot). Measurement: front tracking — every 20 steps the Eulerian position where the
particle velocity crosses u_p/2 (linear interpolation between the two particles that bracket
it); Us is the least-squares slope of that position against time over the last 70 % of the
run (the first 30 % holds the start-up transient). Tolerance 1 % (the project's requirement). Measured
errors (θ = 0.6, C = 0.3, gradient correction on, the 1D default ``kernel_ratio`` density):
u_p = 100: +0.04 %, 500: +0.01 %, 1000: −0.0004 %, 2000: −0.0007 %. With the seed's
continuity density (``density="continuity"``): +0.03, −0.12, −0.39, −0.89 %, growing with u_p
because that density keeps a memory of the front (0.83 % of ρ below m/Δx at 2000 m/s, the
same at half the spacing; ``test_shocked_state_on_the_hugoniot``). Without the gradient
correction and with the continuity density (the seed's sums as printed): −1.9 % at every
u_p from 100 to 2000.

HEL (von Mises, Steinberg–Guinan G = 47.7 GPa, Y = 0.12 GPa). Reference: the elastic
precursor of uniaxial strain carries σ_HEL = Y (1 − ν)/(1 − 2ν) = Y (K + 4G/3)/(2G), with
K = ρ0 c0² and ν = (3K − 2G)/(2(3K + G)) = 0.346: σ_HEL = 0.2544 GPa. (The EOS is nonlinear:
at the HEL η ≈ 1.2e-3 and s η changes K by 0.4 %, inside the tolerance.) Measurement: when
the elastic front has run 80 % of the sample, the plastic front is the last particle with
−σ_xx above half its maximum, the elastic front the last above 1 % of it; the precursor is
the median of −σ_xx over the middle third between them. Tolerance 5 % (the project's requirement); measured
with the seed's strain rate −0.8 % (n = 2000; −0.4 % with n = 3000), with ``dev_mean``
(mean-velocity strain rate for dS/dt) −0.2 % (n = 2000; −0.004 % with n = 3000).
"""

from __future__ import annotations

import numpy as np
import pytest

from hugomap.eos import copper
from hugomap.sph.simulation import CSPHSimulation
from hugomap.sph.state import SPHState
from hugomap.strength import copper as copper_strength
from hugomap.strength.von_mises import hel

DX = 1e-5


def _bar(n: int) -> SPHState:
    rho0 = copper().params[0]
    x = (np.arange(n) + 0.5) * DX
    return SPHState(x=x, v=np.zeros(n), m=rho0 * DX, rho=rho0, e=0.0)


def _strip(n: int, rows: int) -> SPHState:
    """A 2D square-lattice strip n × rows (index i·rows + j: row j is x[j::rows])."""
    rho0 = copper().params[0]
    i, j = np.meshgrid(np.arange(n), np.arange(rows), indexing="ij")
    x = np.column_stack([(i.ravel() + 0.5) * DX, (j.ravel() + 0.5) * DX])
    return SPHState(x=x, v=np.zeros_like(x), m=rho0 * DX * DX, rho=rho0, e=0.0)


def shock_speed(up: float, n: int = 400, grad_correction: bool = True, rows: int = 0) -> float:
    """Front-tracked Us [m/s] of a piston at u_p [m/s] into n particles (module docstring);
    ``rows`` > 0: a 2D plane-strain strip of that many rows, periodic in y (front tracked in
    every row, positions averaged)."""
    eos = copper()
    c0, s = eos.params[1], eos.params[2]
    if rows:
        st = _strip(n, rows)
        extra = {"periodic": (False, True), "length": (1.0, rows * DX)}
    else:
        st, extra, rows = _bar(n), {}, 1
    sim = CSPHSimulation(
        st, eos, walls=(0.0, up, None, 0.0), grad_correction=grad_correction, **extra
    )
    t_end = 0.8 * n * DX / (c0 + s * up)
    ts, xf = [], []
    while sim.time < t_end:
        sim.advance(20)
        pos = []
        for j in range(rows):
            v = st.v[j::rows, 0]
            xr = st.x[j::rows, 0]
            k = int(np.nonzero(v > 0.5 * up)[0].max())
            pos.append(xr[k] + (0.5 * up - v[k]) / (v[k + 1] - v[k]) * (xr[k + 1] - xr[k]))
        xf.append(np.mean(pos))
        ts.append(sim.time)
    ts, xf = np.array(ts), np.array(xf)
    late = ts > 0.3 * t_end
    return float(np.polyfit(ts[late], xf[late], 1)[0])


@pytest.mark.slow
@pytest.mark.parametrize("up", [100.0, 500.0, 1000.0, 2000.0])
def test_shock_speed_on_linear_hugoniot(up):
    eos = copper()
    ref = eos.params[1] + eos.params[2] * up
    us = shock_speed(up)
    assert abs(us / ref - 1.0) < 0.01, f"Us={us:.1f} m/s, c0+s*up={ref:.1f} m/s"


@pytest.mark.slow
def test_same_shock_in_1d_and_2d():
    """The project's "model no more than the scene needs": a plane-strain strip (8 rows,
    periodic in y: the period must be at least twice the neighbour-list radius) gives the 1D
    shock speed within 1 % (measured −0.42 %: the strip runs the 2D default continuity
    density, whose memory of the front the 1D default removes; with the continuity density
    in both, 0.014 %; with ``kernel_ratio`` in both, +0.17 %)."""
    us1 = shock_speed(1000.0, n=300)
    us2 = shock_speed(1000.0, n=300, rows=8)
    assert abs(us2 / us1 - 1.0) < 0.01, (us1, us2)


@pytest.mark.slow
def test_plane_strain_with_strength_matches_uniaxial():
    """With strength, the 2D strip behind the plastic wave matches the 1D run: σ_xx within
    1 % (measured 0.003 %), and with ``dev_mean`` the deviator keeps the uniaxial-strain form
    S_yy = S_zz = −S_xx/2 to round-off. (With the seed's contact-velocity strain rate the
    angled pairs' U* carries the longitudinal stress jump into L_yy inside the front, and
    the plastic flow there leaves S_yy ≠ S_zz by ~6 % of Y: measured 42.3 vs 37.4 MPa.)"""
    eos, strength, up, n, rows = copper(), copper_strength(), 300.0, 300, 8
    t_end = 0.7 * n * DX / 4759.0
    one = CSPHSimulation(_bar(n), eos, strength, walls=(0.0, up, None, 0.0), dev_mean=True)
    one.run_until(t_end)
    two = CSPHSimulation(
        _strip(n, rows), eos, strength, walls=(0.0, up, None, 0.0), dev_mean=True,
        periodic=(False, True), length=(1.0, rows * DX),
    )  # fmt: skip
    two.run_until(t_end)
    s1 = one.stress_xx()
    s2 = two.stress_xx().reshape(n, rows)
    mid = slice(n // 8, n // 3)  # behind the plastic wave, clear of the piston's start-up
    assert np.allclose(s2[mid].mean(axis=1), s1[mid], rtol=0.01)
    S = two.state.S.reshape(n, rows, 4)[mid]
    Y = strength.Y
    assert np.max(np.abs(S[..., 1] - S[..., 2])) < 1e-6 * Y
    assert np.max(np.abs(S[..., 1] + 0.5 * S[..., 0])) < 1e-6 * Y


@pytest.mark.slow
@pytest.mark.parametrize("dev_mean", [False, True])
def test_elastic_precursor_at_hel(dev_mean):
    eos = copper()
    strength = copper_strength()
    rho0, c0 = eos.params[0], eos.params[1]
    K = rho0 * c0**2
    G, Y = strength.G, strength.Y
    ref = hel(G, Y, K)
    n = 2000
    st = _bar(n)
    sim = CSPHSimulation(st, eos, strength, walls=(0.0, 300.0, None, 0.0), dev_mean=dev_mean)
    cl = np.sqrt((K + 4.0 * G / 3.0) / rho0)
    sim.run_until(0.8 * n * DX / cl)
    sx = -sim.stress_xx()
    smax = sx.max()
    i_e = int(np.nonzero(sx > 0.01 * smax)[0].max())
    i_p = int(np.nonzero(sx > 0.5 * smax)[0].max())
    a, b = i_p + (i_e - i_p) // 3, i_p + 2 * (i_e - i_p) // 3
    assert b - a >= 20, "the precursor plateau is not resolved"
    plateau = float(np.median(sx[a:b]))
    assert abs(plateau / ref - 1.0) < 0.05, f"precursor {plateau:.4g} Pa, HEL {ref:.4g} Pa"
    # nowhere outside the yield surface; behind the plastic wave every particle has yielded
    # (reverberations later unload some slightly inside the surface: down to 0.92 Y here)
    seq = np.sqrt(1.5 * np.sum(st.S[:, :3] ** 2, axis=1) + 3.0 * st.S[:, 3] ** 2)
    assert np.all(seq <= Y * (1.0 + 1e-12))
    behind = slice(5, i_p - 20)
    assert np.all(st.eps_p[behind] > 0.0)


@pytest.mark.slow
def test_plastic_wave_offset_from_the_hydrodynamic_line():
    """With strength the plastic wave is not on D = c0 + s u_p: it runs into the precursor's
    state (u_HEL = 6 m/s, σ_HEL = 0.254 GPa) and carries σ_x = P + 2Y/3 behind it.
    Reference: the two-wave jump conditions (``analysis.elastic_plastic.two_wave_state``):
    at 100 m/s D_p = 4098.3 m/s, +9.3 m/s (+0.23 %) above the hydrodynamic 4089.0 m/s.
    Measurement: the plastic front, where the particle velocity crosses (u_HEL + u_p)/2,
    tracked as in ``shock_speed`` over the last 70 % of the run (1000 particles, dev_mean).
    Tolerances: D_p within 0.1 % of the theory (the same tracking's error without strength at
    100 m/s is +0.03 %, 1.2 m/s), and the offset D_p − (c0 + s u_p) within 25 % of the
    theory's 9.3 m/s (that 1.2 m/s bias is 13 % of it): a solver without strength, or one
    whose stress lacked the deviator, would put the plastic wave on the line (offset 0).
    Measured: D_p = 4097.3 m/s (−0.02 %), offset 8.3 m/s."""
    from hugomap.analysis.elastic_plastic import two_wave_state

    eos, strength, up, n = copper(), copper_strength(), 100.0, 1000
    ref = two_wave_state(up, eos, strength)
    st = _bar(n)
    sim = CSPHSimulation(st, eos, strength, walls=(0.0, up, None, 0.0), dev_mean=True)
    t_end = 0.75 * n * DX / ref["D_hydro"]
    mid = 0.5 * (ref["u_HEL"] + up)
    ts, xf = [], []
    while sim.time < t_end:
        sim.advance(20)
        v, x = st.v[:, 0], st.x[:, 0]
        k = int(np.nonzero(v > mid)[0].max())
        xf.append(x[k] + (mid - v[k]) / (v[k + 1] - v[k]) * (x[k + 1] - x[k]))
        ts.append(sim.time)
    ts, xf = np.array(ts), np.array(xf)
    late = ts > 0.3 * t_end
    d_p = float(np.polyfit(ts[late], xf[late], 1)[0])
    assert abs(d_p / ref["D_plastic"] - 1.0) < 0.001, (d_p, ref["D_plastic"])
    offset, want = d_p - ref["D_hydro"], ref["D_plastic"] - ref["D_hydro"]
    assert abs(offset / want - 1.0) < 0.25, (offset, want)


@pytest.mark.slow
@pytest.mark.parametrize("up", [2000.0, 4000.0])
def test_shocked_state_on_the_hugoniot(up):
    """Behind a strong 1D copper shock the state obeys the jump conditions with the EOS's
    own density. Reference: the Rankine–Hugoniot relations, exact for any conservative
    scheme once the front is steady — mass ρ_geo = ρ0 D/(D − u_p) with ρ_geo = m/Δx the
    particle spacing's density (Δx = ½(x_{i+1} − x_{i−1})), and D = c0 + s u_p with
    E = ½ P (V0 − V) for this EOS (referenced to that Hugoniot). Measurement: the front
    tracked as in ``shock_speed`` (400 particles of 10 µm, the last 70 % of a run of 80 % of
    the sample); the state averaged over the particles between 35 % and 75 % of the way from
    the piston to the front (clear of the piston's start-up and of the front).
    Tolerances: ρ/ρ_geo − 1 within 0.1 % (measured −0.001 % at 2000, −0.011 % at 4000 m/s;
    the continuity density's memory of the front, −0.83 % and −2.7 %, is what it catches),
    D within 0.1 % of c0 + s u_p (measured −0.001 %, −0.003 %; the continuity density gave
    −0.89 %, −1.7 %), the energy jump E / (½ P (V0 − V)) − 1 within 0.5 % (measured
    +0.002 %, +0.024 %; continuity +2.9 %, +7.0 %), and total energy (kinetic + internal)
    equal to the piston's work u_p × (momentum) to 1e-9 (the scheme's pairwise
    conservation; 1e-12 measured)."""
    eos = copper()
    rho0, c0, s = eos.params[0], eos.params[1], eos.params[2]
    n = 400
    st = _bar(n)
    sim = CSPHSimulation(st, eos, walls=(0.0, up, None, 0.0))
    t_end = 0.8 * n * DX / (c0 + s * up)
    ts, xf = [], []
    while sim.time < t_end:
        sim.advance(20)
        v, x = st.v[:, 0], st.x[:, 0]
        k = int(np.nonzero(v > 0.5 * up)[0].max())
        xf.append(x[k] + (0.5 * up - v[k]) / (v[k + 1] - v[k]) * (x[k + 1] - x[k]))
        ts.append(sim.time)
    ts, xf = np.array(ts), np.array(xf)
    late = ts > 0.3 * t_end
    D = float(np.polyfit(ts[late], xf[late], 1)[0])
    x, v = st.x[:, 0], st.v[:, 0]
    kf = int(np.nonzero(v > 0.5 * up)[0].max())
    sl = slice(int(0.35 * kf), int(0.75 * kf))
    rho_geo = st.m[1:-1] / (0.5 * (x[2:] - x[:-2]))
    rho, rg = st.rho[sl].mean(), rho_geo[sl.start - 1 : sl.stop - 1].mean()
    P = -sim.stress_xx()[sl].mean()
    energy = float(np.sum(st.m * (st.e + 0.5 * v**2)))
    work = up * float(np.sum(st.m * v))
    assert abs(rho / rg - 1.0) < 1e-3, (rho, rg)
    assert abs(D / (c0 + s * up) - 1.0) < 1e-3, (D, c0 + s * up)
    jump = st.e[sl].mean() / (0.5 * P * (1.0 / rho0 - 1.0 / rho))
    assert abs(jump - 1.0) < 5e-3, jump
    assert abs(energy / work - 1.0) < 1e-9, (energy, work)
