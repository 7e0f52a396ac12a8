"""One equilibrium NVT state of the Lennard-Jones system (the reference Hugoniot's iterate).

A fully periodic box at fixed density, held at a fixed temperature by the CSVR thermostat
(``md.simulation.MDSimulation``). Reduced LJ units throughout (σ = ε = m = 1,
τ = σ√(m/ε), k_B = 1).

Measured quantities of one NVT state (``measure_state``), N atoms in a box of volume 𝒱:

    K = ½ Σ_i |v_i − v̄|²                          kinetic energy [ε]
    T = 2K / (3N − 3)                              temperature [ε/k_B] (3N − 3 degrees of freedom)
    E = (K + Σ_i u_i) / N                          internal energy per atom [ε]
    P = (2K + Σ_i (W_i^xx + W_i^yy + W_i^zz)) / (3𝒱)    scalar pressure [ε σ⁻³]
    P_xx = (Σ_i (v_i^x − v̄^x)² + Σ_i W_i^xx) / 𝒱         normal stress along x [ε σ⁻³]

with u_i the per-atom potential energy and W_i^ab = ½ Σ_j r_ij^a F_ij^b the per-atom virial
(``md.forces``). Means carry standard errors from block averaging (``block_average``).
"""

from __future__ import annotations

import time
import warnings
from collections.abc import Sequence
from typing import Any

import numpy as np

from ..analysis import stats
from ..failures import SolverUnstable
from ..particles.fcc import maxwell_velocities
from .potential import LJParams
from .sample import fcc_state
from .simulation import MDSimulation
from .state import MDState

#: Mean squared displacement [σ²] over the production run above which a state is called
#: diffusive (fluid). A crystal's vibrational MSD stays near the Lindemann value
#: (0.15 × 1.1 σ)² ≈ 0.03 σ² up to melting; a dense LJ fluid (self-diffusion ≳ 0.02 σ²/τ)
#: moves ≳ 1 σ² in the default 12 τ of production.
MSD_FLUID = 0.5


# -- statistics --------------------------------------------------------------------------------
def block_average(series: Sequence[float] | np.ndarray, n_blocks: int = 10) -> tuple[float, float]:
    """``stats.block_average`` (mean and standard error of a correlated series, in its
    units) with ``n_blocks`` blocks, refusing a run too short to fill them: the reference
    is set up by its config, so too few samples is a config error, not a NaN error bar."""
    x = np.asarray(series, dtype=float).ravel()
    if n_blocks < 2:
        raise ValueError(f"n_blocks = {n_blocks}: need at least 2 blocks")
    if x.size < n_blocks:
        raise ValueError(f"{x.size} samples cannot fill {n_blocks} blocks")
    return stats.block_average(x, n_blocks)


# -- one equilibrium state --------------------------------------------------------------------
def _run_nvt(
    rho: float,
    T: float,
    lj: LJParams,
    cells: tuple[int, int, int],
    dt: float,
    n_equil: int,
    n_prod: int,
    sample_every: int,
    seed: int,
    lattice_start: bool,
    start: MDState | None,
    tau_bath: float,
) -> tuple[MDSimulation, dict[str, np.ndarray]]:
    """Equilibrate, then sample every ``sample_every`` steps; return the simulation and series."""
    if lattice_start or start is None:
        state = fcc_state(cells, rho, T, seed, periodic_x=True)
    else:
        if not np.all(start.periodic):
            raise ValueError("measure_state needs a fully periodic start state")
        n = start.n
        scale = (n / rho / float(np.prod(start.L))) ** (1.0 / 3.0)
        state = MDState(
            x=start.x * scale,
            v=maxwell_velocities(n, T, seed),
            L=start.L * scale,
            periodic=np.ones(3, dtype=bool),
            walls0=np.array([0.0, 0.0, start.L[0] * scale, 0.0]),
        )
    sim = MDSimulation(state, lj, dt, T_bath=T, tau_bath=tau_bath, seed=seed)
    sim.advance(n_equil)
    st = sim.state
    n = st.n
    vol = float(np.prod(st.L))
    n_samples = n_prod // sample_every
    out = {k: np.empty(n_samples) for k in ("E", "P", "Pxx", "T", "U")}
    disp = np.zeros((n, 3))
    x_prev = np.empty((n, 3))
    x_prev[st.ids] = st.x  # by atom label: list rebuilds re-sort the atoms
    for k in range(n_samples):
        sim.advance(sample_every)
        pe, vir = sim.per_atom_energy_virial()
        v = st.v - st.v.mean(axis=0)
        two_k = float(np.sum(v * v))
        u = float(np.sum(pe))
        out["E"][k] = (0.5 * two_k + u) / n
        out["U"][k] = u / n
        out["T"][k] = two_k / (3 * n - 3)
        out["P"][k] = (two_k + float(np.sum(vir[:, :3]))) / (3.0 * vol)
        out["Pxx"][k] = (float(np.sum(v[:, 0] ** 2)) + float(np.sum(vir[:, 0]))) / vol
        # Unwrapped displacement by atom label: minimum image of the move between two
        # samples (≪ L/2).
        x_now = np.empty((n, 3))
        x_now[st.ids] = st.x
        d = x_now - x_prev
        d -= st.L * np.rint(d / st.L)
        disp += d
        x_prev = x_now
    out["msd"] = np.array([float(np.mean(np.sum(disp * disp, axis=1)))])
    return sim, out


def measure_state(
    rho: float,
    T: float,
    lj: LJParams,
    cells: tuple[int, int, int] = (6, 6, 6),
    dt: float = 0.004,
    n_equil: int = 500,
    n_prod: int = 3000,
    sample_every: int = 20,
    seed: int = 0,
    lattice_start: bool = True,
    *,
    start: MDState | None = None,
    tau_bath: float = 0.1,
    n_blocks: int = 10,
    keep_series: bool = False,
) -> dict[str, Any]:
    """Equilibrium NVT state of the LJ system at density ``rho`` [σ⁻³] and temperature ``T``.

    A fully periodic cubic box of 4·cx·cy·cz atoms, started from an FCC lattice at ``rho``
    with Maxwell velocities at ``T`` (``lattice_start``; a fluid state melts during the
    ``n_equil`` equilibration steps at the target T), or, when ``lattice_start`` is False
    and a ``start`` state is given, from its positions rescaled to ``rho``. The CSVR thermostat (time constant ``tau_bath`` [τ])
    holds T; after ``n_equil`` steps of ``dt`` [τ], ``n_prod`` production steps are sampled
    every ``sample_every`` steps and averaged in ``n_blocks`` (≥ 8) blocks. If a run raises
    ``SolverUnstable`` it is repeated once with dt/2 (and twice the steps: same times).

    Returns a dict: ``rho``, ``V`` = 1/ρ [σ³], ``T_target``, and mean ± standard error
    (keys ``X`` and ``X_err``) of ``T`` [ε/k_B], ``E`` (kinetic + potential per atom, the
    specific internal energy [ε]), ``U`` (potential energy per atom [ε]), ``P`` (scalar
    pressure (2K + Σ_i tr W_i)/(3𝒱) [ε σ⁻³]) and ``Pxx`` [ε σ⁻³]; the fluctuation estimates
    ``dEdT`` = N Var(E)/T² (c_V per atom [k_B]) and ``dPdT`` = N Cov(P, E)/T² ([k_B σ⁻³],
    canonical-ensemble identities, rough: for step sizes, not for results); ``msd`` [σ²] over
    the production run and ``diffusive`` (msd > MSD_FLUID: the state flowed, i.e. is fluid);
    ``n_atoms``, ``dt`` (the step actually used), ``n_samples``, ``seed``, ``wall_s``; the
    final ``state`` (MDState); with ``keep_series`` the sampled series under ``series``.
    """
    if n_blocks < 8:
        raise ValueError(f"n_blocks = {n_blocks}: use at least 8 blocks")
    if not (rho > 0 and T > 0):
        raise ValueError(f"rho = {rho}, T = {T}: both must be > 0")
    if n_prod // sample_every < n_blocks:
        raise ValueError(f"n_prod / sample_every = {n_prod // sample_every} < {n_blocks} blocks")
    t_wall = time.perf_counter()
    args = (rho, T, lj, cells, dt, n_equil, n_prod, sample_every, seed, lattice_start, start)
    try:
        sim, s = _run_nvt(*args, tau_bath)
        dt_used = dt
    except SolverUnstable as exc:
        warnings.warn(
            f"NVT run at rho = {rho}, T = {T} unstable with dt = {dt} ({exc}); retrying with "
            f"dt = {dt / 2}",
            RuntimeWarning,
            stacklevel=2,
        )
        dt_used = 0.5 * dt
        sim, s = _run_nvt(
            rho, T, lj, cells, dt_used, 2 * n_equil, 2 * n_prod, 2 * sample_every, seed,
            lattice_start, start, tau_bath,
        )  # fmt: skip
    n = sim.state.n
    res: dict[str, Any] = {"rho": float(rho), "V": 1.0 / float(rho), "T_target": float(T)}
    for key in ("T", "E", "U", "P", "Pxx"):
        res[key], res[key + "_err"] = block_average(s[key], n_blocks)
    tm = res["T"]
    e_c = s["E"] - s["E"].mean()
    res["dEdT"] = float(n * np.mean(e_c * e_c) / tm**2)
    res["dPdT"] = float(n * np.mean((s["P"] - s["P"].mean()) * e_c) / tm**2)
    res["msd"] = float(s["msd"][0])
    res["diffusive"] = bool(res["msd"] > MSD_FLUID)
    res.update(
        n_atoms=n, dt=dt_used, n_samples=int(s["E"].size), seed=int(seed),
        wall_s=time.perf_counter() - t_wall, state=sim.state,
    )  # fmt: skip
    if keep_series:
        res["series"] = {k: v for k, v in s.items() if k != "msd"}
    return res
