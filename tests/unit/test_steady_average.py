"""The steady average of a window point goes on while its point is unresolved
(``methods.steady.steady_state``, ``unresolved``), on a held front with noisy slabs."""

from __future__ import annotations

import numpy as np

from hugomap.methods.control import OmegaSignal
from hugomap.methods.steady import steady_state, unresolved
from hugomap.states import Pole, SlabState

D, U_P = 3.0, 1.0
POLE = Pole(rho0=1.0, P0=1.0, E0=0.0, T0=1.0, Pyy0=1.0, rho0_err=0.0, P0_err=0.0, E0_err=0.0,
            T0_err=0.0, Pyy0_err=0.0)  # fmt: skip


class _Geom:
    x_lo, x_hi, length = 0.0, 100.0, 100.0


class _HeldFront:
    """A window holding a steady front at x = 50 (bins of width 1): material enters at
    u_in = −D, leaves shocked at u_out = u_in + u_p; each sample's bins carry (count, u, ρ,
    P, E) of the exact jump from the pole (ρ0 1, P0 1, E0 0), ρ, P and E with white noise
    of relative size ``noise``."""

    geom = _Geom()
    dt = 0.01
    u_in, u_out = -D, -D + U_P

    def __init__(self, noise: float, seed: int = 1) -> None:
        self.rng = np.random.default_rng(seed)
        self.noise = noise
        self.time = 0.0
        rho = (D - 0.0) / (D - U_P)
        P = 1.0 + D * U_P
        E = 0.5 * (P + 1.0) * (1.0 - 1.0 / rho)
        x = np.arange(100) + 0.5
        behind = (x < 50.0)[:, None]
        self.exact = np.where(behind, [30.0, self.u_out, rho, P, E],
                              [30.0, self.u_in, 1.0, 1.0, 0.0])  # fmt: skip

    def advance(self, n: int) -> None:
        self.time += n * self.dt

    def sums(self) -> np.ndarray:
        s = self.exact.copy()
        s[:, 2:] *= 1 + self.noise * self.rng.standard_normal((100, 3))
        return s

    def count_in_window(self) -> float:
        """ω of a held front (``_SIGNAL`` reads it as is): constant, its last digits noisy
        so that the slope has an error."""
        return 0.5 + 1e-6 * self.rng.standard_normal()


class _Profile:
    """The toy's bins: their sums are the fields themselves; a slab's state their mean."""

    x0, bin_width = 0.0, 1.0

    def sums(self, win: _HeldFront) -> np.ndarray:
        return win.sums()

    def velocity(self, sums: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        return sums[:, 1], sums[:, 0]

    def state(self, summed: np.ndarray, n_bins: int) -> SlabState:
        m = summed / n_bins
        return SlabState(rho=m[2], u=m[1], P=m[3], Pyy=m[3], Pzz=m[3], E=m[4])


_SIGNAL = OmegaSignal("N", q_up=0.0, q_sh=1.0, bin_width=1.0)


def _average(noise: float, max_duration: float | None) -> dict:
    win = _HeldFront(noise)
    r, h = steady_state(win, _Profile(), POLE, _SIGNAL, duration=0.16, every=1, gap=3.0,
                        avg_length=20.0, residual_tol=0.01, max_duration=max_duration)  # fmt: skip
    assert len(h["t"]) == round(r["average_time"] / (win.dt * 1))
    return r


def test_an_unresolved_point_averages_on_until_its_errors_resolve_the_tolerance():
    """With noise 0.1 per bin, 16 samples leave a residual error above 1 % (the energy's
    2.3 %): the average goes on, 16 samples at a time, and stops once every error is within
    1 % (long before the cap); without a cap it stops at its own time, and at the cap while
    still unresolved; a quiet slab never goes on."""
    short = _average(0.1, None)
    assert short["average_time"] == 0.16
    assert unresolved(short, 0.01)
    long = _average(0.1, 100.0)
    assert 0.16 < long["average_time"] < 2.0
    assert not unresolved(long, 0.01)
    assert round(long["average_time"] / 0.16, 9) % 1 == 0  # whole chunks of the average
    capped = _average(0.1, 0.32)
    assert capped["average_time"] == 0.32  # the cap holds even while still unresolved
    assert _average(0.01, 100.0)["average_time"] == 0.16


def test_the_rule_reads_errors_only():
    """Residuals far beyond the tolerance with small errors are resolved (a bias, which a
    longer average would not remove), small residuals with large errors are not, and an
    error that is not a number does not hold the average."""
    errs = {f"residual_{k}_err": 0.002 for k in ("mass", "momentum", "energy")}
    assert not unresolved({**errs, "residual_energy": 0.2}, 0.01)
    assert unresolved({**errs, "residual_energy": 0.0, "residual_energy_err": 0.03}, 0.01)
    assert not unresolved({**errs, "residual_mass_err": float("nan")}, 0.01)
