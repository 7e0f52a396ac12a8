"""CSPH against exact solutions of 1D Riemann problems.

1. Sod's shock tube (G. A. Sod, J. Comput. Phys. 27, 1 (1978); E. F. Toro, Riemann Solvers
   and Numerical Methods for Fluid Dynamics, 3rd ed., 2009, §4.3.3 test 1): ideal gas
   γ = 1.4, (ρ, u, P) = (1, 0, 1) | (0.125, 0, 0.1) at x = 0.5, t = 0.2 (units SI, the numbers
   are Toro's dimensionless ones). Exact solution: Toro's exact Riemann solver (§4.2–4.5),
   written out below. Particles: equal spacing 1/N on [0, 1] (masses ρ/N), fixed walls at
   0 and 1 (no wave reaches them by t = 0.2).
   Claim: the L1 density error over [0, 1] falls as the resolution rises. A first-order
   Godunov-type scheme converges at about order 1/2–1 on Sod (the contact and the shock are
   smeared over a fixed number of cells); we require the error to fall by at least 25 % per
   doubling (order ≥ 0.4) and the finest error to be below 1.5e-2. Measured: L1 = 0.0151,
   0.0109, 0.0076 at N = 200, 400, 800 (orders 0.48, 0.51) with the continuity density, 0.0157,
   0.0097, 0.0061 (orders 0.70, 0.66) with the 1D default kernel_ratio; total energy conserved
   to 1e-12.
2. Symmetric impact of two copper plates at ±u (no strength): the exact solution is u = 0
   between the two shocks and P = ρ0 (c0 + s u) u on the linear Hugoniot (the EOS is
   referenced to that Hugoniot, so this is exact for the model). Tolerance 1 %: the
   continuity density lags the real compression through a sharp front by < 1 % in copper at
   these speeds (measured in the piston test), which moves P by about as much. Measured:
   −0.05 % at u = 200 m/s, −0.59 % at 1000 m/s; |u| < 0.3 m/s between the shocks.
"""

from __future__ import annotations

import math

import numpy as np

from hugomap.eos import copper, ideal
from hugomap.sph.simulation import CSPHSimulation
from hugomap.sph.state import SPHState


# ----------------------------------------------------------------------------- exact solver
def _toro_f(p, rho, pr, c, g):
    """Toro's f_K(p) and its derivative (eqs. 4.6, 4.7, 4.37)."""
    if p > pr:
        a = 2.0 / ((g + 1.0) * rho)
        b = (g - 1.0) / (g + 1.0) * pr
        q = math.sqrt(a / (p + b))
        return (p - pr) * q, q * (1.0 - 0.5 * (p - pr) / (p + b))
    r = p / pr
    return (
        2.0 * c / (g - 1.0) * (r ** ((g - 1.0) / (2.0 * g)) - 1.0),
        1.0 / (rho * c) * r ** (-(g + 1.0) / (2.0 * g)),
    )


def toro_exact(x, t, x0, left, right, g):
    """Exact (ρ, u, P) at positions x and time t of the ideal-gas Riemann problem (Toro §4)."""
    rl, ul, pl = left
    rr, ur, pr = right
    cl = math.sqrt(g * pl / rl)
    cr = math.sqrt(g * pr / rr)
    p = 0.5 * (pl + pr)
    for _ in range(100):
        fl, dl = _toro_f(p, rl, pl, cl, g)
        fr, dr = _toro_f(p, rr, pr, cr, g)
        dp = (fl + fr + ur - ul) / (dl + dr)
        p = max(p - dp, 1e-12)
        if abs(dp) < 1e-14 * p:
            break
    fl, _ = _toro_f(p, rl, pl, cl, g)
    fr, _ = _toro_f(p, rr, pr, cr, g)
    u = 0.5 * (ul + ur) + 0.5 * (fr - fl)
    gm = (g - 1.0) / (g + 1.0)
    out = np.empty((len(x), 3))
    for k, xx in enumerate(x):
        s = (xx - x0) / t
        if s <= u:  # left of the contact
            if p > pl:
                rs = rl * (p / pl + gm) / (gm * p / pl + 1.0)
                sh = ul - cl * math.sqrt((g + 1) / (2 * g) * p / pl + (g - 1) / (2 * g))
                out[k] = (rl, ul, pl) if s < sh else (rs, u, p)
            else:
                rs = rl * (p / pl) ** (1.0 / g)
                cs = cl * (p / pl) ** ((g - 1) / (2 * g))
                if s < ul - cl:
                    out[k] = (rl, ul, pl)
                elif s > u - cs:
                    out[k] = (rs, u, p)
                else:
                    uf = 2 / (g + 1) * (cl + (g - 1) / 2 * ul + s)
                    cf = 2 / (g + 1) * (cl + (g - 1) / 2 * (ul - s))
                    out[k] = (
                        rl * (cf / cl) ** (2 / (g - 1)),
                        uf,
                        pl * (cf / cl) ** (2 * g / (g - 1)),
                    )
        else:
            if p > pr:
                rs = rr * (p / pr + gm) / (gm * p / pr + 1.0)
                sh = ur + cr * math.sqrt((g + 1) / (2 * g) * p / pr + (g - 1) / (2 * g))
                out[k] = (rs, u, p) if s < sh else (rr, ur, pr)
            else:
                rs = rr * (p / pr) ** (1.0 / g)
                cs = cr * (p / pr) ** ((g - 1) / (2 * g))
                if s > ur + cr:
                    out[k] = (rr, ur, pr)
                elif s < u + cs:
                    out[k] = (rs, u, p)
                else:
                    uf = 2 / (g + 1) * (-cr + (g - 1) / 2 * ur + s)
                    cf = 2 / (g + 1) * (cr - (g - 1) / 2 * (ur - s))
                    out[k] = (
                        rr * (cf / cr) ** (2 / (g - 1)),
                        uf,
                        pr * (cf / cr) ** (2 * g / (g - 1)),
                    )
    return out


def test_toro_solver_star_state():
    """Toro's Table 4.2 (test 1): p* = 0.30313, u* = 0.92745."""
    w = toro_exact([0.5 + 1e-9], 0.2, 0.5, (1.0, 0.0, 1.0), (0.125, 0.0, 0.1), 1.4)
    assert abs(w[0, 2] - 0.30313) < 1e-5 and abs(w[0, 1] - 0.92745) < 1e-5


def _sod(n: int) -> tuple[float, CSPHSimulation]:
    g = 1.4
    dx = 1.0 / n
    x = (np.arange(n) + 0.5) * dx
    left = x < 0.5
    rho = np.where(left, 1.0, 0.125)
    p = np.where(left, 1.0, 0.1)
    st = SPHState(x=x, v=np.zeros(n), m=rho * dx, rho=rho, e=p / ((g - 1.0) * rho))
    sim = CSPHSimulation(st, ideal(g), walls=(0.0, 0.0, 1.0, 0.0))
    e_tot0 = float(np.sum(st.m * st.e))
    sim.run_until(0.2)
    ex = toro_exact(st.x[:, 0], sim.time, 0.5, (1.0, 0.0, 1.0), (0.125, 0.0, 0.1), g)
    # L1 norm ∫|ρ − ρ_exact| dx with each particle standing for its volume m/ρ
    l1 = float(np.sum(np.abs(st.rho - ex[:, 0]) * st.m / st.rho))
    e_tot = float(np.sum(st.m * (st.e + 0.5 * st.v[:, 0] ** 2)))
    assert abs(e_tot - e_tot0) < 1e-12 * e_tot0, "fixed walls: total energy must be conserved"
    return l1, sim


def test_sod_converges():
    errs = [_sod(n)[0] for n in (200, 400, 800)]
    orders = [math.log2(errs[k] / errs[k + 1]) for k in range(2)]
    msg = f"L1 density errors {errs}, orders {orders}"
    assert all(o > 0.4 for o in orders), msg
    assert errs[-1] < 1.5e-2, msg


def test_copper_plate_impact():
    """Two copper plates (1.2 mm each, 150 particles) meet at x = 0 at ±u; measured when the
    shocks have crossed 80 % of the plates, in the particles between 30 % and 80 % of the way
    from the impact plane to the shocks (the first layers carry the impact's start-up
    heating: lower density, higher energy, a known artefact of first-order schemes, also at
    the piston face)."""
    eos = copper()
    rho0, c0, s = eos.params[:3]
    n, dx = 300, 8e-6
    x = (np.arange(n) + 0.5) * dx - 0.5 * n * dx
    for u in (200.0, 1000.0):
        st = SPHState(x=x, v=np.where(x < 0, u, -u), m=rho0 * dx, rho=rho0, e=0.0)
        sim = CSPHSimulation(st, eos)
        us = c0 + s * u
        sim.run_until(0.8 * 0.5 * n * dx / us)
        sxx = sim.stress_xx()
        xs = (us - u) * sim.time  # the shocks' distance from the impact plane (lab frame)
        sel = (np.abs(st.x[:, 0]) > 0.3 * xs) & (np.abs(st.x[:, 0]) < 0.8 * xs)
        p_ref = rho0 * us * u
        assert sel.sum() >= 40
        assert np.max(np.abs(st.v[sel, 0])) < 0.01 * u
        assert abs(-sxx[sel].mean() / p_ref - 1.0) < 0.01, (u, -sxx[sel].mean(), p_ref)
