"""Velocity Verlet, reflecting and moving walls, and the CSVR thermostat.

Energy-conservation bounds here are derived, not fitted; the model behind them:

1. Velocity Verlet conserves a modified ("shadow") Hamiltonian H̃ = H + Δt² C(x, v) + O(Δt⁴)
   for smooth forces, so H itself shows bounded O(Δt²) fluctuations and no drift
   (``_reference.verlet_shadow_correction`` evaluates C).
2. The shifted-energy LJ potential has a force jump |φ'(rc)| at rc. A pair crossing rc at a
   uniformly distributed fraction u of a step receives the impulse ½Δt(F_before + F_after)
   instead of uΔt F: an energy error |φ'(rc)| w_r Δt (½ − u) per crossing, of zero mean.
   The errors add up as a random walk of diffusion D = R ⟨δ²⟩, with the crossing rate
   R = (N/2) ρ g(rc) 4π rc² ⟨|w_r|⟩, ⟨|w_r|⟩ = √(4T/π) (relative radial speed, g(rc) ≈ 1),
   and ⟨δ²⟩ = (φ'(rc) Δt)² ⟨w_r²⟩_flux / 12 = (φ'(rc) Δt)² T / 3. Checked against 40 τ runs
   of this liquid (N = 256, ρ = 0.8, T ≈ 1.5): measured/model D = 1.13 and 0.61 at
   Δt = 0.005 (two seeds), 0.86 at Δt = 0.0025 (drift ∝ Δt, as the model says).
3. A reflection at a wall flips v_x after the half kick: the end velocity is off by
   F_x Δt (1 − 2u), an energy error v_x F_x Δt (1 − 2u) of zero mean and variance
   v_x² F_x² Δt² / 3; with ⟨v_x²⟩ = 2T over the flux of reflecting atoms, another random
   walk (measured on 108-atom liquids: 2–3 times below this estimate, which is kept).
For a random walk of diffusion D the least-squares slope b over a run of length t has
var(b t) = 1.2 D t (6D/5t per unit time², for a Brownian path sampled densely). The tests
bound the fitted drift of H̃ by 5 standard deviations of that, and the drift of H by the
same plus 3 max |Δt² (C − C̄)| (a sequence bounded by M has |b t| ≤ 3 M).
"""

from __future__ import annotations

import numpy as np
import pytest

from hugomap.md import integrate as ig
from hugomap.md.potential import LJParams
from hugomap.md.sample import fcc_state
from hugomap.md.simulation import MDSimulation
from hugomap.md.state import MDState

from . import _reference as ref
from ._reference import EPS, NO_JIT

DT = 0.005
EVERY = 10 if NO_JIT else 20  # steps between samples

pytestmark = pytest.mark.usefixtures("serial_numba")


def _sample_run(sim: MDSimulation, nsteps: int, every: int = EVERY, near_wall: float = 0.25):
    """Advance ``nsteps``, recording every ``every`` steps H, Δt² C, P, impulses, thermal T
    and F_x² of atoms within ``near_wall`` of a wall."""
    s = sim.state
    rec = {k: [] for k in ("t", "H", "dC", "P", "imp", "T", "Fx2")}
    for k in range(nsteps // every + 1):
        if k:
            sim.advance(every)
        ke, pe = sim.energies()
        rec["t"].append(s.time)
        rec["H"].append(ke + pe)
        rec["dC"].append(
            sim.dt**2 * ref.verlet_shadow_correction(s.x, s.v, s.L, s.periodic, sim.lj.rc)
        )
        rec["P"].append(s.v.sum(axis=0))
        rec["imp"].append(s.impulse.copy())
        vc = s.v - s.v.mean(axis=0)
        rec["T"].append(np.sum(vc * vc) / (3 * s.n - 3))
        if not s.periodic[0]:
            xl, xr = sim.wall_positions()
            near = (s.x[:, 0] - xl < near_wall) | (xr - s.x[:, 0] < near_wall)
            rec["Fx2"].extend(s.f[near, 0] ** 2)
    return {k: np.array(v) for k, v in rec.items()}


def _fit_drift(t, y):
    """Least-squares slope × run length, and the residual standard deviation."""
    p = np.polyfit(t - t[0], y, 1)
    return p[0] * (t[-1] - t[0]), np.std(y - np.polyval(p, t - t[0]))


def _d_cutoff(n, volume, rc, T, dt):
    """Diffusion coefficient [ε²/τ] of the energy random walk from pairs crossing rc (2.)."""
    rate = 0.5 * n * (n / volume) * 4 * np.pi * rc**2 * np.sqrt(4 * T / np.pi)
    return rate * (ref.dphi(rc) * dt) ** 2 * T / 3.0


# -- NVE, periodic ------------------------------------------------------------------------

NVE_STEPS = 200 if NO_JIT else 2000
BOOST = np.array([0.5, -0.3, 0.2])


@pytest.fixture(scope="module")
def nve():
    # FCC at T0 = 2.6 melts into a liquid at T ≈ 1.5 (ρ = 0.8), rc = 2.5 shifted. A uniform
    # boost makes the total momentum (256 × BOOST) non-trivial.
    with ref.one_numba_thread():
        st = fcc_state((4, 4, 4), 0.8, 2.6, 11, periodic_x=True)
        st.v += BOOST
        sim = MDSimulation(st, LJParams(rc=2.5, shift=True, skin=0.3), dt=DT)
        return sim, _sample_run(sim, NVE_STEPS)


def test_nve_momentum_conserved(nve):
    sim, rec = nve
    n = sim.state.n
    P0 = n * BOOST
    vrms = np.sqrt(np.mean(np.sum(sim.state.v**2, axis=1)))
    # Each kick rounds every v_i by ~ε|v_i|; N atoms × 2 kicks × steps of independent errors
    # give ε v_rms √(2 N steps) ≈ 5e-13 here, and ΣF_i = 0 to ~1e-14 (test_forces). The
    # bound 1e-12 N v_rms (5e-10) leaves room for correlated round-off but would catch a
    # force or kick breaking Newton's third law by one part in 1e9.
    bound = 1e-12 * n * vrms
    assert np.all(np.abs(rec["P"] - P0) <= bound), np.max(np.abs(rec["P"] - P0))


def test_nve_energy_fluctuation_is_velocity_verlet(nve):
    """Adding Δt² C to H removes the O(Δt²) fluctuation (1.): what is left is the cutoff
    random walk (detrended rms √(D t / 15) ≈ 0.15 σ_H here) and O(Δt⁴) terms. A
    first-order or mis-ordered integrator leaves σ_H̃ ≈ σ_H."""
    _, rec = nve
    _, sd_h = _fit_drift(rec["t"], rec["H"])
    _, sd_shadow = _fit_drift(rec["t"], rec["H"] + rec["dC"])
    assert sd_shadow < 0.3 * sd_h, (sd_shadow, sd_h)


def test_nve_energy_drift(nve):
    sim, rec = nve
    s = sim.state
    t = rec["t"][-1] - rec["t"][0]
    T = float(np.mean(rec["T"]))
    assert 1.3 < T < 1.7  # the state point the model's numbers were checked at
    D = _d_cutoff(s.n, np.prod(s.L), sim.lj.rc, T, sim.dt)
    bound_shadow = 5.0 * np.sqrt(1.2 * D * t)
    drift_shadow, _ = _fit_drift(rec["t"], rec["H"] + rec["dC"])
    assert abs(drift_shadow) < bound_shadow, (drift_shadow, bound_shadow)
    drift_h, _ = _fit_drift(rec["t"], rec["H"])
    bound_h = bound_shadow + 3.0 * np.max(np.abs(rec["dC"] - rec["dC"].mean()))
    assert abs(drift_h) < bound_h, (drift_h, bound_h)
    # Per atom and τ at N = 256, 10 τ: bound_h ≈ 1.6e-4 ε/τ; measured |drift_h| ≈ 1e-6.


# -- walls ----------------------------------------------------------------------------------

WALL_STEPS = 300 if NO_JIT else 2000


def _walled(seed=1, T0=2.6):
    st = fcc_state((3, 3, 3), 0.8, T0, seed, periodic_x=False)
    return MDSimulation(st, LJParams(rc=2.2), dt=DT)


def _wall_bound(sim, rec, v_walls=(0.0, 0.0)):
    """5 σ of the drift of H̃ from the cutoff and wall random walks (2. and 3.)."""
    s = sim.state
    t = rec["t"][-1] - rec["t"][0]
    T = float(np.mean(rec["T"]))
    imp = np.abs(rec["imp"][-1] - rec["imp"][0]).sum()
    n_refl = 0.5 * imp / np.sqrt(np.pi * T / 2)  # impulse per reflection 2|v_x|, flux mean
    vw2 = max(v**2 for v in v_walls)
    sum_v2 = n_refl * 2 * (2 * T + vw2)  # ⟨(v_x)²⟩ ≤ 2 (⟨v_rel²⟩_flux + v_w²)
    Dt_wall = sum_v2 * np.mean(rec["Fx2"]) * sim.dt**2 / 3.0
    Dt_cut = _d_cutoff(s.n, np.prod(s.L), sim.lj.rc, T, sim.dt) * t
    return 5.0 * np.sqrt(1.2 * (Dt_cut + Dt_wall))


def test_static_walls_conserve_energy_and_impulse_is_momentum():
    sim = _walled()
    rec = _sample_run(sim, WALL_STEPS)
    s = sim.state
    imp = rec["imp"][-1]
    assert imp[0] > 0 > imp[1]  # the left wall pushes +x, the right one −x
    # Momentum: x changes by exactly what the walls gave (internal forces cancel), y and z
    # are conserved; round-off as in test_nve_momentum_conserved plus ~ε|v| per reflection.
    vrms = np.sqrt(np.mean(np.sum(s.v**2, axis=1)))
    bound = 1e-12 * s.n * vrms + 8 * EPS * np.abs(imp).sum()
    dP = rec["P"] - rec["P"][0]
    assert np.all(np.abs(dP[:, 0] - (rec["imp"][:, 0] + rec["imp"][:, 1])) <= bound)
    assert np.all(np.abs(dP[:, 1:]) <= bound)
    # Energy: static walls do no work.
    bound_e = _wall_bound(sim, rec)
    drift_shadow, _ = _fit_drift(rec["t"], rec["H"] + rec["dC"])
    assert abs(drift_shadow) < bound_e, (drift_shadow, bound_e)
    drift_h, _ = _fit_drift(rec["t"], rec["H"])
    assert abs(drift_h) < bound_e + 3 * np.ptp(rec["dC"]), (drift_h, bound_e)
    # The bound is small against what a lossy or energising wall would do: the kinetic
    # energy that crosses the walls in the run, Σ ½ v_x² over reflections.
    assert bound_e < 0.05 * 0.5 * np.abs(imp).sum() * np.sqrt(np.mean(rec["T"]))


def test_piston_transfers_momentum_equal_to_impulse():
    sim = _walled(seed=2, T0=2.0)
    v_piston = 0.25
    sim.set_walls(v_piston, 0.0)
    rec = _sample_run(sim, 200 if NO_JIT else 400)
    s = sim.state
    assert sim.wall_positions()[0] == pytest.approx(v_piston * s.time, abs=1e-12)
    imp = rec["imp"]
    vrms = np.sqrt(np.mean(np.sum(s.v**2, axis=1)))
    bound = 1e-12 * s.n * vrms + 8 * EPS * np.abs(imp[-1]).sum()
    dP = rec["P"] - rec["P"][0]
    assert np.all(np.abs(dP[:, 0] - imp.sum(axis=1)) <= bound)
    assert np.all(np.abs(dP[:, 1:]) <= bound)
    assert imp[-1, 0] > 0
    # Energy balance: a reflection off a wall moving at v_w changes ½v_x² by v_w × (impulse)
    # exactly, so H − v_L I_L − v_R I_R is conserved up to the random walks of 2. and 3.
    work = v_piston * imp[:, 0]
    bound_e = _wall_bound(sim, rec, v_walls=(v_piston, 0.0))
    drift, _ = _fit_drift(rec["t"], rec["H"] + rec["dC"] - work)
    assert abs(drift) < bound_e, (drift, bound_e)
    # and the piston's work is resolved: it exceeds the bound
    assert work[-1] > bound_e


def _one_atom(x, v, walls0):
    st = MDState(
        x=np.array([x], dtype=float),
        v=np.array([v], dtype=float),
        L=np.array([10.0, 6.0, 6.0]),
        periodic=np.array([False, True, True]),
        walls0=np.array(walls0, dtype=float),
    )
    return MDSimulation(st, LJParams(), dt=DT)


def test_single_reflection_static_wall_exact():
    sim = _one_atom([0.05, 3.0, 3.0], [-20.0, 1.0, 2.0], [0.0, 0.0, 10.0, 0.0])
    sim.advance(1)
    s = sim.state
    # x: 0.05 − 0.1 = −0.05 → mirrored at 0; v_x → −v_x; no force on a lone atom.
    assert s.x[0, 0] == pytest.approx(0.05, abs=4 * EPS)
    assert list(s.v[0]) == [20.0, 1.0, 2.0]
    assert list(s.impulse) == [40.0, 0.0]  # 2 |v_x|, exactly the momentum change


@pytest.mark.parametrize(("v_wall", "vx"), [(0.5, -2.0), (-3.0, -20.0), (1.0, 0.5)])
def test_single_reflection_moving_wall_exact(v_wall, vx):
    x0 = 5.0
    # Place the wall so that the atom crosses it during the first step.
    x_atom = x0 + DT * vx  # where the atom ends without the wall
    x_wall = x_atom + 0.3 * DT * abs(vx - v_wall) * np.sign(v_wall - vx)
    walls0 = [x_wall - v_wall * DT, v_wall, 10.0, 0.0]
    sim = _one_atom([x0, 3.0, 3.0], [vx, 0.0, 0.0], walls0)
    sim.advance(1)
    s = sim.state
    xw = walls0[0] + v_wall * DT
    assert s.x[0, 0] == pytest.approx(2 * xw - x_atom, abs=1e-13)
    assert s.v[0, 0] == pytest.approx(2 * v_wall - vx, abs=1e-13)
    assert s.impulse[0] == pytest.approx(2 * (v_wall - vx), abs=1e-13)  # = Δ(m v_x)
    # Work done by the wall: ½ v'² − ½ v² = v_w × impulse (algebraically exact).
    assert 0.5 * s.v[0, 0] ** 2 - 0.5 * vx**2 == pytest.approx(v_wall * s.impulse[0], abs=1e-12)


# -- neighbour-list growth ------------------------------------------------------------------


def test_list_growth_mid_run_is_transparent():
    """A run whose rows must grow mid-run (status GROW) is bit-for-bit the run that had
    long enough rows from the start (row contents do not depend on the row width)."""

    def make():
        st = fcc_state((3, 3, 3), 0.8, 1.5, 1, periodic_x=True)
        return MDSimulation(st, LJParams(rc=2.2), dt=DT)

    b = make()
    need0 = int(b.nnb.max())  # perfect FCC: every atom has the same count
    b._alloc_lists(need0)  # rows just long enough for the start
    b._build_list(sort=False)
    b.advance(100)
    assert b.nbr.shape[1] > need0  # it did grow
    a = make()
    width = a.nbr.shape[1]
    a.advance(100)
    assert a.nbr.shape[1] == width  # a never needed to grow
    for k in ("x", "v", "f", "ids"):
        assert np.array_equal(getattr(a.state, k), getattr(b.state, k))


# -- CSVR -------------------------------------------------------------------------------------


def test_csvr_factor_moments():
    """Bussi et al. (2007) eq. (A7): K' = α² K has mean c K + (1 − c) K_t and variance
    (1 − c)² (K_t/N_f)² 2 N_f + 4 c (1 − c) K K_t / N_f (S + R₁² ~ χ²_{N_f}, and R₁ is
    uncorrelated with R₁²). Tolerance: 5 standard errors of M samples."""
    rng = np.random.default_rng(42)
    nf, T, c, K = 30, 1.5, 0.3, 40.0
    Kt = 0.5 * nf * T
    M = 4000 if NO_JIT else 40000
    r1 = rng.standard_normal(M)
    chi = rng.chisquare(nf - 1, M)
    a = np.array([ig.csvr_factor(K, Kt, nf, c, r1[k], chi[k]) for k in range(M)])
    k_new = a * a * K
    mean = c * K + (1 - c) * Kt
    var = (1 - c) ** 2 * (Kt / nf) ** 2 * 2 * nf + 4 * c * (1 - c) * K * Kt / nf
    assert abs(k_new.mean() - mean) < 5 * np.sqrt(var / M)
    # Sample variance: standard error ≈ var √(2/M) for a near-Gaussian K' (N_f = 30).
    assert abs(k_new.var() - var) < 5 * var * np.sqrt(2 / M)
    # c = 0 (τ → 0): K' = K_t χ²_{N_f} / N_f, whatever K; and α = 1 at zero kinetic energy.
    a0 = np.array([ig.csvr_factor(K, Kt, nf, 0.0, r1[k], chi[k]) for k in range(100)])
    np.testing.assert_allclose(a0**2 * K, Kt * (chi[:100] + r1[:100] ** 2) / nf, rtol=1e-13)
    assert ig.csvr_factor(0.0, Kt, nf, c, 0.3, 20.0) == 1.0


def test_csvr_thermostat_reaches_target():
    """A 108-atom sample started at T = 0.5 is driven to T_bath = 1.5 (τ_bath = 0.1).

    Canonical kinetic temperature: mean T_bath, standard deviation σ_T = T_bath √(2/N_f).
    The time average over t has standard error σ_T √(2 τ_int / t); τ_int = 2 τ_bath is a
    conservative integrated autocorrelation time (measured: 0.08 τ for this system, and
    the energy relaxes in τ_bath C_V / C_kin ≈ 1.7 τ_bath). Tolerance: 4 standard errors.
    """
    T_bath, tau = 1.5, 0.1
    st = fcc_state((3, 3, 3), 0.8, 0.5, 2, periodic_x=True)
    sim = MDSimulation(st, LJParams(rc=2.2), dt=DT, T_bath=T_bath, tau_bath=tau, seed=3)
    nf = 3 * sim.state.n - 3
    sim.advance(200)  # 10 τ_bath: relaxed (measured: within σ_T after ~4 τ_bath)
    n_prod = 400 if NO_JIT else 1600
    temps = []
    for _ in range(n_prod // 5):
        sim.advance(5)
        temps.append(np.sum(sim.state.v**2) / nf)  # total momentum is zero (periodic)
    temps = np.array(temps)
    t_prod = n_prod * DT
    sigma_T = T_bath * np.sqrt(2.0 / nf)
    se = sigma_T * np.sqrt(2 * (2 * tau) / t_prod)
    assert abs(temps.mean() - T_bath) < 4 * se, (temps.mean(), se)
    # Fluctuations are canonical (a deterministic rescaling would squeeze them): the
    # relative standard error of a standard deviation is about √(τ_int / t).
    assert abs(temps.std() / sigma_T - 1) < 4 * np.sqrt(2 * tau / t_prod)
    assert abs(np.sum(sim.state.v, axis=0)).max() < 1e-10  # CSVR scales v: P stays 0


class _Slabs:
    """Two 10-σ slabs of mobile atoms between walls at 0 and 20 σ (duck-typed for
    ``particles.sizing.flatten_temperature``), the left at temperature 1, the right at 3, each
    with its own mean velocity."""

    def __init__(self) -> None:
        rng = np.random.default_rng(7)
        n = 400
        x = np.column_stack([np.r_[rng.uniform(0.5, 9.5, n), rng.uniform(10.5, 19.5, n)],
                             rng.uniform(0, 5, 2 * n), rng.uniform(0, 5, 2 * n)])  # fmt: skip
        v = rng.standard_normal((2 * n, 3))
        for sl, T, u in ((slice(0, n), 1.0, 0.3), (slice(n, 2 * n), 3.0, -0.2)):
            v[sl] -= v[sl].mean(axis=0)
            v[sl] *= np.sqrt(T * 3 * (n - 1) / np.sum(v[sl] ** 2))
            v[sl, 0] += u
        self.state = MDState(x=x, v=v, L=np.array([20.0, 5.0, 5.0]),
                             periodic=np.array([False, True, True]),
                             walls0=np.array([0.0, 0.0, 20.0, 0.0]))  # fmt: skip
        self.n = n
        self.tau_bath = 0.5

    def wall_positions(self) -> tuple[float, float]:
        return 0.0, 20.0


def _slab_T(v: np.ndarray) -> float:
    return float(np.sum((v - v.mean(axis=0)) ** 2) / (3 * (v.shape[0] - 1)))


def test_local_thermostat_moves_each_slab_towards_T0_and_keeps_its_momentum():
    """``flatten_temperature`` (Berendsen weak coupling per slab): with Δt/τ = 1 each slab
    lands on T0 exactly (λ² = T0/T_b); with Δt/τ = 0.1 the gap T_b − T0 shrinks to
    T0 + 0.9 (T_b − T0) (λ² T_b); every slab's momentum is unchanged (rounding)."""
    from hugomap.particles.sizing import flatten_temperature

    for frac, expect in ((1.0, (2.0, 2.0)), (0.1, (2.0 - 0.9, 2.0 + 0.9))):
        s = _Slabs()
        p0 = [s.state.v[:s.n].sum(axis=0), s.state.v[s.n:].sum(axis=0)]  # fmt: skip
        flatten_temperature(s, 2.0, frac * s.tau_bath, 10.0, 1.0)
        for k, sl in enumerate((slice(0, s.n), slice(s.n, 2 * s.n))):
            assert _slab_T(s.state.v[sl]) == pytest.approx(expect[k], rel=1e-12)
            np.testing.assert_allclose(s.state.v[sl].sum(axis=0), p0[k], atol=1e-10)
