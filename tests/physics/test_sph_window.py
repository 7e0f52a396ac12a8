"""The shock methods run unchanged on the 1D CSPH window: AMW finds the copper shock speed.

Set-up: a copper piston run (no strength, u_p = 1000 m/s, 400 particles of 10 µm) until the
front is half-way; a window of 150 particles around the front in a frame moving 3 % slower
than the reference front speed (D_guess = 0.97 (c0 + s u_p)). AMW (``methods.control.amw``,
β = 0.5, ω from the particle count normalised by the upstream and Hugoniot densities,
averaging windows of L/Us, front-speed resolution 0.5 % of Us) shifts the frame until the
front stops. Reference: Us = c0 + s u_p = 5430 m/s (exact for the EOS). Tolerance 1 %, the
project's; measured: AMW D = 5399.7 m/s (−0.56 %) after 5 windows, against the piston's
front-tracked −0.39 % (the AMW stops once the slope is within its error, before the last
under-relaxed steps).
The window must also hold the shocked state behind the front: lab-frame velocity u_p within
0.1 % and −σ_xx within 1 % of the Hugoniot pressure ρ0 Us u_p.
"""

from __future__ import annotations

import numpy as np
import pytest

from hugomap.eos import copper
from hugomap.eos.mie_gruneisen import hugoniot_state
from hugomap.methods.control import OmegaSignal, amw
from hugomap.sph.simulation import CSPHSimulation
from hugomap.sph.state import SPHState
from hugomap.sph.window import SPHWindow

DX = 1e-5


@pytest.mark.slow
def test_amw_finds_copper_shock_speed():
    up, n, rho0 = 1000.0, 400, 8930.0
    eos = copper()
    h = hugoniot_state(up, eos.params)
    us = h["Us"]
    st = SPHState(x=(np.arange(n) + 0.5) * DX, v=np.zeros(n), m=rho0 * DX, rho=rho0, e=0.0)
    sim = CSPHSimulation(st, eos, walls=(0.0, up, None, 0.0))
    sim.run_until(0.5 * n * DX / us)
    xf = st.x[int(np.nonzero(st.v[:, 0] > 0.5 * up)[0].max()), 0]
    L = 150 * DX
    w = SPHWindow.from_piston(sim, xf, up, 0.97 * us, L)
    m0 = rho0 * DX
    signal = OmegaSignal("N", L * rho0 / m0, L * h["rho"] / m0, DX)
    res, hist = amw(
        w, signal, beta=0.5, window_time=L / us, calm_windows=2, max_windows=20, every=5,
        max_drift=0.005 * us,
    )  # fmt: skip
    assert res.converged, res
    D = -w.u_in
    assert abs(D / us - 1.0) < 0.01, (D, us)
    assert w.u_out - w.u_in == pytest.approx(up)
    s = w.sim.state
    sx = w.sim.stress_xx()
    mob = ~w.sim.frozen
    xfront = w.geom.x_lo + L * float(np.mean(hist.omega[-1:]))
    behind = mob & (s.x[:, 0] > w.geom.x_lo + 5 * DX) & (s.x[:, 0] < xfront - 20 * DX)
    assert behind.sum() >= 20
    assert abs((s.v[behind, 0] - w.u_in).mean() / up - 1.0) < 1e-3
    assert abs(-sx[behind].mean() / h["P"] - 1.0) < 0.01
