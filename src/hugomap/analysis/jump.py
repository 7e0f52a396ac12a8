"""The Rankine–Hugoniot jump conditions, their residuals and the residuals' errors.

Jump conditions across a steady front moving at D into material at rest (Zel'dovich &
Raizer, ch. I §17), with u_p the particle-velocity jump and V = 1/ρ:
    mass:      ρ0 D = ρ (D − u_p)
    momentum:  P − P0 = ρ0 D u_p          (P: longitudinal component P_xx)
    energy:    E − E0 = ½ (P + P0)(V0 − V)
``jump_residuals`` returns each as a relative residual (0 when it holds exactly), from a
state ahead that may itself move (an elastic precursor's). Units are the caller's, as long
as they are consistent (reduced LJ units, or SI for copper).
"""

from __future__ import annotations

import numpy as np


def rayleigh_jump(rho1: float, D: float, u: float, u1: float = 0.0) -> float:
    """The momentum jump ρ1 (D − u1)(u − u1) [pressure]: P − P1 on the Rayleigh line of a
    front at D from the state ahead (ρ1, moving at u1) to material moving at u."""
    return rho1 * (D - u1) * (u - u1)


def jump_residuals(
    rho1: float,
    P1: float,
    E1: float,
    D: float,
    u: float,
    rho: float,
    P: float,
    E: float,
    u1: float = 0.0,
) -> dict[str, float]:
    """Relative residuals of the three jump conditions (module docstring).

    The state ahead of the front is (ρ1, P1, E1) moving at u1 (the pole at rest by default;
    the elastic precursor's state when a plastic wave follows one), the state behind it
    (ρ, P, E) moving at u, the front at D (all velocities in the frame of the pole material):
    mass = ρ(D − u)/(ρ1(D − u1)) − 1;  momentum = (P − P1)/(ρ1 (D − u1)(u − u1)) − 1;
    energy = (E − E1)/(½(P + P1)(V1 − V)) − 1.
    """
    V1, V = 1.0 / rho1, 1.0 / rho
    with np.errstate(divide="ignore", invalid="ignore"):
        return {
            "mass": float(rho * (D - u) / (rho1 * (D - u1)) - 1.0),
            "momentum": float((P - P1) / rayleigh_jump(rho1, D, u, u1) - 1.0),
            "energy": float((E - E1) / (0.5 * (P + P1) * (V1 - V)) - 1.0),
        }


_JUMP_ARGS = ("rho1", "P1", "E1", "D", "u", "rho", "P", "E", "u1")


def jump_residual_errors(
    values: dict[str, float],
    errors: dict[str, float],
    rel_step: float = 1e-6,
    cov: dict[tuple[str, str], float] | None = None,
) -> dict[str, float]:
    """Standard errors of ``jump_residuals`` by first-order propagation.

    ``values``/``errors`` are keyed by the arguments of ``jump_residuals`` (rho1, P1, E1, D,
    u, rho, P, E, u1; missing errors count as 0); ``cov`` holds the covariances of pairs
    of them that are measured together (the slab's u and P: ``measure_point``), the rest
    independent: σ_r² = Σ (∂r/∂x σ_x)² + 2 Σ_pairs ∂r/∂x ∂r/∂y cov(x, y), the derivatives
    taken by central differences.
    """
    base = {k: float(values.get(k, 0.0)) for k in _JUMP_ARGS}
    keys = ("mass", "momentum", "energy")
    cov = cov or {}
    wanted = {n for pair in cov for n in pair}
    var = {k: 0.0 for k in keys}
    grad: dict[str, dict[str, float]] = {}
    for name in _JUMP_ARGS:
        sx = float(errors.get(name, 0.0) or 0.0)
        if not (sx > 0 or name in wanted):
            continue
        h = rel_step * max(abs(base[name]), 1.0)
        up = jump_residuals(**{**base, name: base[name] + h})
        dn = jump_residuals(**{**base, name: base[name] - h})
        grad[name] = {k: (up[k] - dn[k]) / (2 * h) for k in keys}
        for k in keys:
            var[k] += (grad[name][k] * (sx if sx > 0 else 0.0)) ** 2
    for (a, b), c in cov.items():
        if a != b and np.isfinite(c) and a in grad and b in grad:
            for k in keys:
                var[k] += 2.0 * grad[a][k] * grad[b][k] * c
    return {k: float(np.sqrt(max(v, 0.0))) for k, v in var.items()}
