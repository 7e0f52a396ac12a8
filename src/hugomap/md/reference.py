"""Reference Hugoniot of the Lennard-Jones system from equilibrium NVT molecular dynamics.

Independent of any shock simulation: every state is a fully periodic box at fixed density,
held at a fixed temperature by the CSVR thermostat (``md.simulation.MDSimulation``), and the
Hugoniot is found from the Rankine–Hugoniot energy condition alone.

Reduced LJ units throughout (σ = ε = m = 1, τ = σ√(m/ε), k_B = 1); every per-atom quantity
is also per unit mass (m = 1), so V = 1/ρ [σ³] is the specific volume and E [ε] the specific
internal energy.

One NVT state is measured by ``md.nvt.measure_state`` (its quantities are defined there).

Hugoniot (Rankine–Hugoniot energy condition). For the pole (ρ0, T0) with measured E0, P0 and
V0 = 1/ρ0, the shocked state at V = 1/ρ < V0 is the temperature T_H that solves

    H(T) = E(V, T) − E0 − ½ (P(V, T) + P0) (V0 − V) = 0          [ε].

H increases with T at fixed V (the slope dH/dT = c_V − ½ (V0 − V) (∂P/∂T)_V is positive
wherever the Hugoniot is single-valued), so T_H is found by Newton/secant iterations, each
iterate one fresh NVT run. Mass and momentum conservation across a steady shock then give the
particle velocity u_p and the shock velocity D (both [σ/τ], pole at rest):

    u_p = √((P − P0)(V0 − V)),        D = V0 √((P − P0) / (V0 − V)).

The potential defines the Hugoniot: every dataset records ``rc`` and ``shift``.
"""

from __future__ import annotations

import math
import time
import warnings
from collections.abc import Callable, Sequence
from typing import Any

import numpy as np
import xarray as xr

from .. import __version__
from .nvt import MSD_FLUID, block_average, measure_state
from .potential import LJParams

# Default liquid pole (a supercritical fluid that stays fluid under compression, see
# the liquid scene of config/config.yaml) and compressions ρ/ρ0.
LIQUID_POLE = (0.80, 2.0)
CRYSTAL_POLE = (1.05, 0.1)
DEFAULT_COMPRESSIONS = np.round(np.linspace(1.05, 1.45, 8), 4)

_UNITS = {
    "rho": "sigma^-3",
    "V": "sigma^3",
    "P": "epsilon sigma^-3",
    "Pxx": "epsilon sigma^-3",
    "E": "epsilon",
    "H": "epsilon",
    "T": "epsilon k_B^-1",
    "u_p": "sigma tau^-1",
    "D": "sigma tau^-1",
}


# -- seeds ------------------------------------------------------------------------------------
def _derived_seed(*keys: int) -> int:
    """A 31-bit seed from integer keys (independent streams per point and iteration)."""
    return int(np.random.SeedSequence([int(k) for k in keys]).generate_state(1)[0] >> 1)


# -- pole and Hugoniot points ------------------------------------------------------------------
def pole(rho0: float, T0: float, lj: LJParams, **kwargs: Any) -> dict[str, Any]:
    """The pole (initial, unshocked state) at density ``rho0`` [σ⁻³] and temperature ``T0``.

    One ``measure_state`` run (``kwargs`` go to it). Returns ``rho0``, ``V0`` = 1/ρ0 [σ³],
    ``T0`` (the target), ``T0_measured`` ± ``T0_measured_err``, ``E0`` ± ``E0_err`` [ε],
    ``P0`` ± ``P0_err`` [ε σ⁻³], ``Pxx0`` ± ``Pxx0_err``, ``diffusive``, the full
    measurement under ``state`` and the sampled ``series`` of E and P (the Hugoniot points
    take the pole's error from their combination: E0 and P0 fluctuate together).
    """
    m = measure_state(rho0, T0, lj, keep_series=True, **kwargs)
    series = m.pop("series")
    return {
        "rho0": float(rho0),
        "V0": 1.0 / float(rho0),
        "T0": float(T0),
        "T0_measured": m["T"],
        "T0_measured_err": m["T_err"],
        "E0": m["E"],
        "E0_err": m["E_err"],
        "P0": m["P"],
        "P0_err": m["P_err"],
        "Pxx0": m["Pxx"],
        "Pxx0_err": m["Pxx_err"],
        "diffusive": m["diffusive"],
        "state": m,
        "series": {k: series[k] for k in ("E", "P")},
    }


def jump_velocities(
    P: float, dP_err: float, V: float, pole: dict[str, Any]
) -> tuple[float, float, float, float]:
    """u_p, its error, D, its error [σ/τ] from the jump conditions (pole at rest).

        u_p = √((P − P0)(V0 − V)),   D = V0 √((P − P0)/(V0 − V)),
        σ_u/u_p = σ_D/D = ½ σ(P − P0) / (P − P0)   (V and V0 exact),

    with ``dP_err`` = σ(P − P0), the standard error of the jump in P (the pole's error
    included). NaN where P ≤ P0 or V ≥ V0 (no compressive shock).
    """
    dp = P - pole["P0"]
    dv = pole["V0"] - V
    if not (dp > 0 and dv > 0):
        return math.nan, math.nan, math.nan, math.nan
    u_p = math.sqrt(dp * dv)
    D = pole["V0"] * math.sqrt(dp / dv)
    rel = 0.5 * dP_err / dp
    return u_p, u_p * rel, D, D * rel


def hugoniot_point(
    rho: float,
    pole: dict[str, Any],
    lj: LJParams,
    *,
    T_guess: float | None = None,
    max_iter: int = 10,
    h_tol_sigma: float = 1.0,
    seed: int = 0,
    on_iteration: Callable[[dict[str, Any]], None] | None = None,
    **kwargs: Any,
) -> dict[str, Any]:
    """The Hugoniot state at density ``rho`` [σ⁻³] for ``pole`` (from ``pole()``).

    Solves H(T) = E(T) − E0 − ½ (P(T) + P0)(V0 − V) = 0 at V = 1/ρ (Rankine–Hugoniot energy
    condition, [ε]) by iterating on T, each iterate a fresh NVT run (``measure_state``,
    ``kwargs`` go to it: FCC start at ρ, melted at the target T during equilibration).
    H is averaged per sample, so its standard error σ_H carries the E–P correlation.
    Iterate 0 runs at ``T_guess`` (default T0 (ρ/ρ0)²); iterate 1 is a Newton step with the
    fluctuation slope dH/dT = N Cov(H, E)/T²; later ones are secant steps: the root of the
    weighted least-squares line H(T) through the last three iterates (the secant of the last
    two when there are two), falling back to the Newton step where that line's slope is not
    significant, and kept inside the bracket once iterates with H < 0 and H > 0 exist. Stops when
    |H| < ``h_tol_sigma``·σ_H or after ``max_iter`` runs (then the run of smallest |H|/σ_H
    is kept and ``converged`` is False, with a warning).

    Returns ``rho``, ``V``, and ``T``, ``E``, ``P``, ``Pxx`` with errors: the accepted run's
    state moved along its isochore to H = 0 (``_at_root``: each error the block error of
    the moved per-sample series, which keeps the correlation of E and P with H, and the
    pole's errors through H); ``H`` and ``H_err``: the accepted run's own residual (σ_H of
    the run and the pole's σ_E0, ½(V0 − V)σ_P0 in quadrature; the returned E, P satisfy the
    energy condition exactly); ``u_p``, ``D`` (jump conditions, see ``jump_velocities``)
    with errors, ``dHdT``, ``n_iter``, ``converged``, ``diffusive``, ``msd``, ``history``
    (T, H, σ_H per iterate), ``wall_s``.
    """
    t_wall = time.perf_counter()
    if not rho > pole["rho0"]:
        raise ValueError(f"rho = {rho} <= rho0 = {pole['rho0']}: a shock compresses (rho > rho0)")
    V = 1.0 / float(rho)
    V0, E0, P0 = pole["V0"], pole["E0"], pole["P0"]
    dV = V0 - V
    n_blocks = int(kwargs.get("n_blocks", 10))
    T = float(T_guess) if T_guess is not None else pole["T0"] * (rho / pole["rho0"]) ** 2
    runs: list[dict[str, Any]] = []
    for it in range(max_iter):
        m = measure_state(rho, T, lj, seed=_derived_seed(seed, it), keep_series=True, **kwargs)
        s = m["series"]
        m["h"] = h = s["E"] - E0 - 0.5 * (s["P"] + P0) * dV  # H per sample
        m["H"], m["H_sigma"] = block_average(h, n_blocks)
        hc = h - h.mean()
        m["dHdT_fluct"] = float(m["n_atoms"] * np.mean(hc * (s["E"] - s["E"].mean())) / m["T"] ** 2)
        runs.append(m)
        if on_iteration is not None:
            on_iteration(
                {"iter": it, "rho": rho, "T": m["T_target"], "H": m["H"], "H_err": m["H_sigma"]}
            )
        if abs(m["H"]) < h_tol_sigma * m["H_sigma"]:
            break
        T = _next_temperature(runs)
    best = runs[-1]
    converged = abs(best["H"]) < h_tol_sigma * best["H_sigma"]
    if not converged:
        best = min(runs, key=lambda r: abs(r["H"]) / r["H_sigma"])
        warnings.warn(
            f"Hugoniot point at rho = {rho}: |H| = {abs(best['H']):.3g} > {h_tol_sigma} sigma_H "
            f"= {h_tol_sigma * best['H_sigma']:.3g} after {len(runs)} runs",
            RuntimeWarning,
            stacklevel=2,
        )
    fit = _line_fit(runs)
    slope = fit[2] if fit is not None else _slope_fluct(runs)
    dEdT = float(np.mean([r["dEdT"] for r in runs]))
    dPdT = float(np.mean([r["dPdT"] for r in runs]))
    root = _at_root(best, dEdT, dPdT, dV, pole, n_blocks)
    u_p, u_p_err, D, D_err = jump_velocities(root["P"], root["dP_err"], V, pole)
    H_err = math.sqrt(best["H_sigma"] ** 2 + pole["E0_err"] ** 2 + (0.5 * dV * pole["P0_err"]) ** 2)
    return {
        "rho": float(rho),
        "V": V,
        **{k: root[k] for k in ("T", "T_err", "E", "E_err", "P", "P_err", "Pxx", "Pxx_err")},
        "H": best["H"],
        "H_err": H_err,
        "u_p": u_p,
        "u_p_err": u_p_err,
        "D": D,
        "D_err": D_err,
        "dHdT": slope,
        "n_iter": len(runs),
        "converged": bool(converged),
        "diffusive": best["diffusive"],
        "msd": best["msd"],
        "dt": best["dt"],
        "history": [(r["T_target"], r["H"], r["H_sigma"]) for r in runs],
        "wall_s": time.perf_counter() - t_wall,
    }


def _at_root(
    run: dict[str, Any], dEdT: float, dPdT: float, dV: float, pole: dict[str, Any], n_blocks: int
) -> dict[str, float]:
    """The accepted run's state (its ``series`` and H per sample ``h``) moved along its
    isochore to the root of H, with errors.

    The run sits at |H| < h_tol_sigma σ_H, not at H = 0. Along the isochore T, E, P, P_xx
    move with T by (1, dE/dT, dP/dT) and H by g = dE/dT − ½(V0 − V) dP/dT, so the state at
    H = 0 is X* = X − (dX/dT / g) H (the runs' fluctuation slopes; the step is below σ_H/g,
    so their roughness is second order). Its error is the block error of the per-sample
    series X_i − (dX/dT / g) h_i, which keeps the correlation of X with H (a sample run hot
    has high E, P and H). The pole enters through H: X* moves by k_X (δE0 + ½(V0 − V) δP0),
    the jump P* − P0 (``dP_err``) by k_P δE0 − (1 − ½(V0 − V) k_P) δP0, each error the block
    error of that combination of the pole's samples (a pole sampled hot moves P* with P0),
    or, without the pole's series, of E0 and P0 taken as independent. Measured against
    seeds in docs/window-methods.md, "The reference's own errors"."""
    s, h = run["series"], run["h"]
    g = dEdT - 0.5 * dV * dPdT
    if not g > 0:
        raise ValueError(f"dH/dT = {g:.4g} along the isochore: not positive, no root to move to")
    ps = pole.get("series")

    def pole_err(c_E: float, c_P: float) -> float:
        if ps is None:
            return math.hypot(c_E * pole["E0_err"], c_P * pole["P0_err"])
        return float(block_average(c_E * ps["E"] + c_P * ps["P"], n_blocks)[1])

    out: dict[str, float] = {}
    for key, slope in (("T", 1.0), ("E", dEdT), ("P", dPdT), ("Pxx", dPdT)):
        k = slope / g
        out[key], err = block_average(s[key] - k * h, n_blocks)
        out[key + "_err"] = math.hypot(err, pole_err(k, 0.5 * dV * k))
        if key == "P":
            out["dP_err"] = math.hypot(err, pole_err(k, 0.5 * dV * k - 1.0))
    return out


def _next_temperature(runs: list[dict[str, Any]]) -> float:
    """Next iterate: Newton step (fluctuation slope) after one run, then the root of the
    weighted least-squares line H(T) through the last three runs when its slope is
    significant, kept inside the bracket of the runs with H < 0 and H > 0."""
    last = runs[-1]
    fit = _line_fit(runs[-3:])
    if fit is not None:
        t_mean, h_mean, slope = fit
        T_new = t_mean - h_mean / slope
    else:
        best = min(runs, key=lambda r: abs(r["H"]) / r["H_sigma"])
        T_new = best["T_target"] - best["H"] / _slope_fluct(runs)
    T_new = float(np.clip(T_new, last["T_target"] / 3.0, 3.0 * last["T_target"]))
    below = [r["T_target"] for r in runs if r["H"] < 0]
    above = [r["T_target"] for r in runs if r["H"] > 0]
    if below and above and max(below) < min(above):
        lo, hi = max(below), min(above)
        if not lo < T_new < hi:
            T_new = 0.5 * (lo + hi)
    return T_new


def _slope_fluct(runs: list[dict[str, Any]]) -> float:
    """dH/dT from the fluctuation estimates of all runs, kept within physical bounds."""
    s = float(np.mean([r["dHdT_fluct"] for r in runs]))
    return float(np.clip(s, 0.3, 20.0)) if np.isfinite(s) else 1.5


def _line_fit(runs: list[dict[str, Any]]) -> tuple[float, float, float] | None:
    """Weighted least-squares line H = h_m + s (T − t_m) through ``runs``: (t_m, h_m, s), or
    None with fewer than two runs or a slope not positive by three of its standard errors."""
    if len(runs) < 2:
        return None
    t = np.array([r["T_target"] for r in runs])
    h = np.array([r["H"] for r in runs])
    w = 1.0 / np.array([r["H_sigma"] for r in runs]) ** 2
    tm = np.sum(w * t) / np.sum(w)
    sxx = np.sum(w * (t - tm) ** 2)
    if sxx <= 0:
        return None
    slope = float(np.sum(w * (t - tm) * h) / sxx)
    slope_err = 1.0 / math.sqrt(sxx)
    if not slope > 3.0 * slope_err:
        return None
    return float(tm), float(np.sum(w * h) / np.sum(w)), slope


# -- the whole reference curve -------------------------------------------------------------------
def reference_hugoniot(
    rho0: float = LIQUID_POLE[0],
    T0: float = LIQUID_POLE[1],
    lj: LJParams | None = None,
    compressions: Sequence[float] | np.ndarray = DEFAULT_COMPRESSIONS,
    cells: tuple[int, int, int] = (6, 6, 6),
    dt: float = 0.004,
    n_equil: int = 500,
    n_prod: int = 3000,
    seed: int = 0,
    *,
    sample_every: int = 20,
    tau_bath: float = 0.1,
    n_blocks: int = 10,
    max_iter: int = 10,
    h_tol_sigma: float = 1.0,
    pole_prod_factor: int = 4,
    progress: Callable[[str], None] | None = None,
) -> xr.Dataset:
    """Reference Hugoniot of the LJ potential ``lj`` (rc, shift) through the pole (ρ0, T0).

    Measures the pole (``pole``, with ``pole_prod_factor`` × ``n_prod`` production steps,
    since its errors enter every point), then ``hugoniot_point`` at ρ = ρ0·c for each compression
    c > 1 in ``compressions`` (sorted ascending); each point's first T is extrapolated from
    the points found so far (ln T quadratic in ln ρ through the last three, linear through two).
    The pole itself is the first row (c = 1; u_p = 0, D undefined = NaN).

    Returns an ``xarray.Dataset`` along dimension ``point`` (coordinate ``compression`` =
    ρ/ρ0), with variables (each with ``units`` and ``long_name``; ``X_err`` one standard
    error, see ``hugoniot_point`` for the error model): ``rho`` [σ⁻³] and ``V`` = 1/ρ [σ³]
    (exact: their errors are 0), ``P``, ``Pxx`` [ε σ⁻³], ``E`` [ε], ``T`` [ε/k_B], ``u_p``,
    ``D`` [σ/τ], the energy residual ``H`` [ε], ``n_iter``, ``converged``, ``diffusive`` and
    ``msd`` [σ²]; attributes ``rc``, ``shift`` (0/1), ``rho0``, ``T0``, ``E0``, ``E0_err``,
    ``P0``, ``P0_err`` and the run settings, ``method`` describing the procedure.
    """
    lj = LJParams() if lj is None else lj
    t_wall = time.perf_counter()
    comp = np.unique(np.asarray(compressions, dtype=float))
    if np.any(comp <= 1.0):
        raise ValueError(f"compressions {comp}: every rho/rho0 must be > 1 (the pole is added)")
    kw = dict(
        cells=cells, dt=dt, n_equil=n_equil, n_prod=n_prod, sample_every=sample_every,
        tau_bath=tau_bath, n_blocks=n_blocks,
    )  # fmt: skip
    say = progress or (lambda msg: None)
    # The pole enters every point (E0, P0 and their errors): sample it longer.
    p = pole(
        rho0, T0, lj, seed=_derived_seed(seed, 0), **{**kw, "n_prod": pole_prod_factor * n_prod}
    )
    say(
        f"pole rho0={rho0} T0={T0}: E0={p['E0']:.4f}±{p['E0_err']:.4f} P0={p['P0']:.4f}±{p['P0_err']:.4f}"
    )
    m0 = p["state"]

    def iter_msg(d: dict[str, Any]) -> None:
        say(
            f"  iter {d['iter']}: rho={d['rho']:.4f} T={d['T']:.4f} H={d['H']:+.4f}±{d['H_err']:.4f}"
        )

    rows: list[dict[str, Any]] = [
        {
            "rho": rho0, "V": 1.0 / rho0, "T": m0["T"], "T_err": m0["T_err"], "E": p["E0"],
            "E_err": p["E0_err"], "P": p["P0"], "P_err": p["P0_err"], "Pxx": p["Pxx0"],
            "Pxx_err": p["Pxx0_err"], "H": 0.0, "H_err": 0.0, "u_p": 0.0, "u_p_err": 0.0,
            "D": math.nan, "D_err": math.nan, "n_iter": 1, "converged": True,
            "diffusive": m0["diffusive"], "msd": m0["msd"],
        }
    ]  # fmt: skip
    for i, c in enumerate(comp, start=1):
        rho = rho0 * c
        known_rho = np.array([r["rho"] for r in rows[-3:]])
        known_T = np.array([r["T"] for r in rows[-3:]])
        if len(rows) == 1:
            T_guess = T0 * c**2
        else:
            coef = np.polyfit(np.log(known_rho), np.log(known_T), deg=min(2, len(rows) - 1))
            T_guess = float(np.exp(np.polyval(coef, np.log(rho))))
            T_guess = min(max(T_guess, rows[-1]["T"]), 3.0 * rows[-1]["T"])
        pt = hugoniot_point(
            rho, p, lj, T_guess=T_guess, max_iter=max_iter, h_tol_sigma=h_tol_sigma,
            seed=_derived_seed(seed, i), on_iteration=iter_msg, **kw,
        )  # fmt: skip
        say(
            f"rho={rho:.4f}: T={pt['T']:.4f} P={pt['P']:.4f}±{pt['P_err']:.4f} "
            f"u_p={pt['u_p']:.4f} D={pt['D']:.4f} H={pt['H']:.4f}±{pt['H_err']:.4f} "
            f"iters={pt['n_iter']} ({pt['wall_s']:.1f} s)"
        )
        rows.append(pt)
    wall = time.perf_counter() - t_wall
    return _to_dataset(
        rows, np.concatenate([[1.0], comp]), p, lj, kw, seed, max_iter, h_tol_sigma, wall
    )


def _to_dataset(
    rows: list[dict[str, Any]],
    comp: np.ndarray,
    p: dict[str, Any],
    lj: LJParams,
    kw: dict[str, Any],
    seed: int,
    max_iter: int,
    h_tol_sigma: float,
    wall: float,
) -> xr.Dataset:
    names = {
        "rho": "number density (= mass density, m = 1)",
        "V": "specific volume 1/rho",
        "P": "scalar pressure (2K + sum tr W)/(3 Vbox)",
        "Pxx": "normal stress xx (hydrostatic: equals P within errors)",
        "E": "specific internal energy (kinetic + potential per atom)",
        "T": "temperature 2K/(3N - 3)",
        "u_p": "particle velocity sqrt((P - P0)(V0 - V))",
        "D": "shock velocity V0 sqrt((P - P0)/(V0 - V))",
        "H": "Rankine-Hugoniot energy residual E - E0 - (P + P0)(V0 - V)/2 of the accepted run, before its state is moved along the isochore to H = 0",
    }
    data: dict[str, Any] = {}
    for key, long_name in names.items():
        vals = np.array([r[key] for r in rows], dtype=float)
        errs = (
            np.zeros_like(vals)
            if key in ("rho", "V")
            else np.array([r[key + "_err"] for r in rows], dtype=float)
        )
        u = _UNITS[key]
        data[key] = ("point", vals, {"units": u, "long_name": long_name})
        data[key + "_err"] = (
            "point",
            errs,
            {
                "units": u,
                "long_name": f"standard error of {key}"
                + (" (exact)" if key in ("rho", "V") else ""),
            },
        )
    data["n_iter"] = ("point", np.array([r["n_iter"] for r in rows], dtype=np.int32),
                      {"units": "1", "long_name": "NVT runs used to solve H(T) = 0"})  # fmt: skip
    data["converged"] = ("point", np.array([r["converged"] for r in rows], dtype=np.int8),
                         {"units": "1", "long_name": "1 if |H| < h_tol_sigma * sigma_H"})  # fmt: skip
    data["diffusive"] = ("point", np.array([r["diffusive"] for r in rows], dtype=np.int8),
                         {"units": "1", "long_name": f"1 if msd > {MSD_FLUID} sigma^2 (fluid)"})  # fmt: skip
    data["msd"] = ("point", np.array([r["msd"] for r in rows], dtype=float),
                   {"units": "sigma^2", "long_name": "mean squared displacement over production"})  # fmt: skip
    ds = xr.Dataset(
        data,
        coords={"compression": ("point", comp, {"units": "1", "long_name": "rho/rho0"})},
    )
    n_atoms = int(p["state"]["n_atoms"])
    ds.attrs.update(
        title="Reference Hugoniot of the Lennard-Jones system from equilibrium NVT MD",
        rc=float(lj.rc),
        shift=int(bool(lj.shift)),
        skin=float(lj.skin),
        rho0=float(p["rho0"]),
        T0=float(p["T0"]),
        E0=float(p["E0"]),
        E0_err=float(p["E0_err"]),
        P0=float(p["P0"]),
        P0_err=float(p["P0_err"]),
        units="reduced LJ units: sigma, epsilon, m, tau = sigma sqrt(m/epsilon), k_B = 1",
        method=(
            "Equilibrium NVT MD (velocity Verlet, CSVR thermostat) in a fully periodic cubic "
            "box started from an FCC lattice at each density. Pole measured at (rho0, T0); at "
            "each rho the temperature solving the Rankine-Hugoniot energy condition "
            "H = E - E0 - (P + P0)(V0 - V)/2 = 0 is found by Newton/secant iterations on T "
            "(one fresh NVT run per iterate) until |H| < h_tol_sigma * sigma_H, and the accepted "
            "run's state is moved along its isochore to H = 0 (fluctuation slopes dE/dT, "
            "dP/dT); u_p = sqrt((P - P0)(V0 - V)), D = V0 sqrt((P - P0)/(V0 - V)). Errors: "
            "block averages of the moved per-sample series, plus the pole's errors through H "
            "(hugomap.md.reference)."
        ),
        n_atoms=n_atoms,
        cells=np.asarray(kw["cells"], dtype=np.int32),
        dt=float(kw["dt"]),
        n_equil=int(kw["n_equil"]),
        n_prod=int(kw["n_prod"]),
        pole_n_prod=int(p["state"]["n_samples"] * kw["sample_every"]),
        sample_every=int(kw["sample_every"]),
        tau_bath=float(kw["tau_bath"]),
        n_blocks=int(kw["n_blocks"]),
        max_iter=int(max_iter),
        h_tol_sigma=float(h_tol_sigma),
        seed=int(seed),
        wall_time_s=float(wall),
        hugomap_version=__version__,
    )
    return ds


# -- interpolation -------------------------------------------------------------------------------
def interpolate_P(ref_ds: xr.Dataset, V: float | np.ndarray) -> float | np.ndarray:
    """Reference pressure [ε σ⁻³] at specific volume ``V`` [σ³] on the Hugoniot ``ref_ds``.

    Monotone piecewise-cubic Hermite interpolation in V (Fritsch & Carlson, SIAM J. Numer.
    Anal. 17, 238 (1980)): no overshoot between points, exact at the points. Raises
    ValueError for V outside [min V, max V] of the dataset (no extrapolation).
    """
    order = np.argsort(ref_ds["V"].values)
    x = np.asarray(ref_ds["V"].values, dtype=float)[order]
    y = np.asarray(ref_ds["P"].values, dtype=float)[order]
    v = np.asarray(V, dtype=float)
    tol = 1e-12 * max(1.0, abs(x[-1]))
    if np.any(~np.isfinite(v)) or np.any(v < x[0] - tol) or np.any(v > x[-1] + tol):
        raise ValueError(f"V = {V} outside the reference range [{x[0]:.6g}, {x[-1]:.6g}] sigma^3")
    if x.size < 2:
        raise ValueError("need at least two reference points to interpolate")
    h = np.diff(x)
    delta = np.diff(y) / h
    d = np.zeros_like(y)
    if x.size == 2:
        d[:] = delta[0]
    else:
        for k in range(1, x.size - 1):
            if delta[k - 1] * delta[k] > 0:
                w1 = 2 * h[k] + h[k - 1]
                w2 = h[k] + 2 * h[k - 1]
                d[k] = (w1 + w2) / (w1 / delta[k - 1] + w2 / delta[k])
        d[0] = _pchip_end(h[0], h[1], delta[0], delta[1])
        d[-1] = _pchip_end(h[-1], h[-2], delta[-1], delta[-2])
    vc = np.clip(v, x[0], x[-1])
    k = np.clip(np.searchsorted(x, vc, side="right") - 1, 0, x.size - 2)
    t = (vc - x[k]) / h[k]
    h00 = (1 + 2 * t) * (1 - t) ** 2
    h10 = t * (1 - t) ** 2
    h01 = t * t * (3 - 2 * t)
    h11 = t * t * (t - 1)
    out = h00 * y[k] + h10 * h[k] * d[k] + h01 * y[k + 1] + h11 * h[k] * d[k + 1]
    return float(out) if np.ndim(V) == 0 else out


def _pchip_end(h0: float, h1: float, m0: float, m1: float) -> float:
    """One-sided three-point end derivative, limited to keep the interpolant monotone."""
    d = ((2 * h0 + h1) * m0 - h0 * m1) / (h0 + h1)
    if np.sign(d) != np.sign(m0):
        return 0.0
    if np.sign(m0) != np.sign(m1) and abs(d) > abs(3 * m0):
        return 3 * m0
    return d
