"""The equilibration of a particle sample between two walls, for both particle backends:
``size_bulk`` sizes the box so that the bulk is at ρ0 and ends at the canonical mean
energy of T0, under the simulation's global thermostat and a local one slab by slab
(``flatten_temperature``). It drives the simulation through its interface only (``state``,
``advance``, ``energies``, ``scale_x``, ``wall_positions``, ``tau_bath``): an
``MDSimulation`` in reduced LJ units, a ``LammpsSimulation`` in LAMMPS's (lengths [σ | Å],
energies [ε | eV], k_B T passed as an energy).
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:
    from .kit import ParticleSim

#: Fractions of the equilibration: melt and relax, first bulk-density measurement, relax
#: after the resize, final measurement (bulk density, kinetic and potential energy).
SCHEDULE = (0.3, 0.2, 0.1, 0.4)
#: Control-variate weight β [-] of the kinetic energy in the canonical-mean estimate of
#: ``size_bulk``: at fixed total energy the configurational and kinetic energies share a
#: slow fluctuation in the ratio of their heat capacities, (c_V − 3/2)/(3/2) ≈ 0.5 for the
#: dense LJ fluid (c_V ≈ 2.3 k_B; regression of 1–2 τ block means of the default liquid:
#: 0.53) and 1 for a harmonic crystal. Any fixed β leaves the estimate unbiased (⟨K⟩ − K0
#: has mean 0 exactly); 0.5 cut the scatter of the 1–4 τ means of U by 25–40 %.
BETA_KINETIC = 0.5


def bulk_density(sim: ParticleSim, layer: float) -> float:
    """Number density [σ⁻³] of the atoms further than ``layer`` [σ] from both walls:

        ρ_b = #{i : x_L + layer ≤ x_i < x_R − layer} / (A (x_R − x_L − 2 layer)),

    A = L_y L_z the transverse area."""
    xl, xr = sim.wall_positions()
    lo, hi = xl + layer, xr - layer
    x = sim.state.x[:, 0]
    n = np.count_nonzero((x >= lo) & (x < hi))
    return n / (float(sim.state.L[1] * sim.state.L[2]) * (hi - lo))


#: The local thermostat of the equilibration (``flatten_temperature``): its slabs are this
#: many wall layers wide (10 σ for the LJ scenes' 4-σ layer), its time constant the global
#: thermostat's, and it acts every ``LOCAL_EVERY`` steps.
LOCAL_SLAB_LAYERS = 2.5
LOCAL_EVERY = 25


def flatten_temperature(
    sim: ParticleSim, kT0: float, dt_since: float, width: float, kinetic: float
) -> None:
    """One step of a local weak-coupling thermostat along x: the mobile atoms are sorted into
    slabs ``width`` wide from the left wall, and in each slab b the velocities relative to
    the slab's mean u_b are scaled towards k_B T0 = ``kT0``,

        v_i ← u_b + λ_b (v_i − u_b),   λ_b² = 1 + (Δt/τ)(k_B T0/k_B T_b − 1),
        k_B T_b = c Σ_b (v_i − u_b)² / (3 (n_b − 1)),

    (Berendsen et al., J. Chem. Phys. 81, 3684 (1984), slab by slab), Δt = ``dt_since``
    since the last call, τ the simulation's thermostat time constant (``tau_bath``),
    c = ``kinetic`` the energy of a unit velocity squared, m·mvv2e (1 in LJ units); all in
    the simulation's own units. Each slab keeps its momentum. Why: the global CSVR
    thermostat holds the whole sample's kinetic energy only, and the atoms that gather into
    the walls' dense contact layers while the liquid melts and settles release energy
    there, which it removes from everywhere. Measured on the default liquid (410 σ between
    the walls, seed 1, 2 τ of NVE after the preparation): 2.03-2.15 within 24 σ of either
    wall, 1.94-1.98 at 40-100 σ, 2.00 in the middle, for T0 = 2; heat crosses 40 σ of the
    dense liquid in hundreds of τ, so the layers outlive the run, and the pole's average
    over them hid a bulk 1-3 % cooler than T0. With the local thermostat: 1.98-2.02 from
    4 σ on."""
    s = sim.state
    m = s.ids >= 0  # mobile atoms (frozen ones carry negative labels)
    xl, _ = sim.wall_positions()
    b = np.maximum(((s.x[m, 0] - xl) // width).astype(np.int64), 0)
    nb = int(b.max()) + 1 if b.size else 0
    n = np.bincount(b, minlength=nb).astype(float)
    v_all = np.array(s.v, dtype=float)  # a copy, assigned back (a LAMMPS state on ranks)
    v = v_all[m]
    u = np.stack([np.bincount(b, weights=v[:, d], minlength=nb) for d in range(3)], axis=1)
    u /= np.maximum(n, 1.0)[:, None]
    dv = v - u[b]
    kT = kinetic * np.bincount(b, weights=np.sum(dv * dv, axis=1), minlength=nb)
    kT /= np.maximum(3.0 * (n - 1.0), 1.0)
    ratio = kT0 / np.where(kT > 0.0, kT, kT0)
    lam2 = 1.0 + dt_since / float(sim.tau_bath) * (ratio - 1.0)
    v_all[m] = u[b] + np.sqrt(np.clip(lam2, 0.25, 4.0))[b][:, None] * dv
    s.v = v_all


def _kinetic_unit(sim: ParticleSim) -> float:
    """m·mvv2e: the kinetic energy of the mobile atoms over ½ Σ v² (1 in LJ units)."""
    v = np.asarray(sim.state.v)[np.asarray(sim.state.ids) >= 0]
    return 2.0 * sim.energies()[0] / float(np.sum(v * v))


def _advance_nvt(sim: ParticleSim, n_steps: int, kT0: float, width: float, kin: float) -> None:
    """``n_steps`` with the simulation's (global) thermostat and the local one
    (``flatten_temperature`` every ``LOCAL_EVERY`` steps; none when ``kin`` is 0)."""
    if not kin > 0.0:
        sim.advance(n_steps)  # in one go: a LAMMPS run per call costs a setup
        return
    done = 0
    while done < n_steps:
        k = min(LOCAL_EVERY, n_steps - done)
        sim.advance(k)
        done += k
        flatten_temperature(sim, kT0, k * sim.dt, width, kin)


def _measure_nvt(
    sim: ParticleSim, n_steps: int, every: int, layer: float, bath: tuple[float, float, float]
) -> np.ndarray:
    """Run ``n_steps`` (thermostats as ``_advance_nvt``, ``bath`` its k_B T0, width and c),
    sampling every ``every`` steps the bulk density ρ_b [σ⁻³], the kinetic and the potential
    energy K, U [ε]; returns the series as rows (ρ_b, K, U)."""
    rows = []
    done = 0
    while done < n_steps:
        k = min(every, n_steps - done)
        _advance_nvt(sim, k, *bath)
        done += k
        rows.append((bulk_density(sim, layer), *sim.energies()))
    return np.asarray(rows)


def size_bulk(
    sim: ParticleSim, rho0: float, T0: float, n_steps: int, layer: float, resize: bool,
    every: int = 25, local: bool = True,
) -> dict[str, float]:  # fmt: skip
    """Equilibrate a sample between two static walls for ``n_steps`` steps with its
    thermostats on (the simulation's global CSVR, and with ``local`` the slab-by-slab
    ``flatten_temperature``), sizing its box so that its bulk has density ``rho0`` [σ⁻³],
    and end at the canonical mean energy of ``T0`` [ε/k_B]. Returns what it did and
    measured.

    Box (``resize``, a fluid). A wall's contact layer is denser than the bulk (for a hard
    wall the contact density is P/k_BT, Henderson, Abraham & Barker, Mol. Phys. 31, 1291
    (1976)), so N atoms between walls L_x apart leave the bulk below N/(A L_x): with Γ the
    excess per wall [σ⁻²], N = A (ρ_b L_x + 2Γ). Γ depends on the bulk state, not on L_x, so
    each measurement of ρ_b (``bulk_density``, ``layer`` from the walls) at length L_x
    estimates the length of a bulk at ρ0, L* = (N/A − 2Γ)/ρ0 = L_x ρ_b/ρ0, and x is
    stretched affinely to it (the simulation's ``scale_x``; the bulk is at ρ0 at once and the
    layers re-form within a τ). Schedule (``SCHEDULE``, fractions of the run): melt and
    relax, measure, stretch to L*₁; relax, measure again, stretch to the mean of L*₁ and
    L*₂ weighted by their measuring times. A mean, not the last estimate alone: ρ_b carries
    the box's slow standing sound waves (its 2–10 τ means scatter by 0.03 % on the default
    liquid), and resizing on each new estimate would random-walk. A crystal (``resize``
    False) keeps its lattice: its bulk density is the lattice's (atoms do not leave their
    sites for the walls' layer), and an affine stretch would strain it uniaxially.

    Energy. The thermostat (CSVR) leaves the total energy wherever its last step put it,
    off the canonical mean by the canonical spread (√(2/3N) in temperature from the kinetic
    part alone), and the NVE run that follows keeps it. The velocities are scaled to the
    canonical mean energy of T0,

        E* = K0 + ⟨U⟩ + ΔU − β (⟨K⟩ − K0),    K0 = (n_f/2) k_B T0,
        v_i → λ v_i,  λ² = (E* − U)/K,

    ⟨U⟩, ⟨K⟩ the means of the last measurement, ΔU the instantaneous change of U in the
    last stretch (0.1 % or less; on the default liquid T0 came out −0.07 … −0.19 % off with
    it, −0.17 … −0.38 % without, seeds 1–4), n_f = 3N (walls: no momentum conservation) the
    thermostat's degrees of freedom, β (``BETA_KINETIC``) a control variate (⟨K⟩ − K0 has
    mean 0 exactly; it takes out the slow energy fluctuation U shares with K), U, K the
    energies now. The NVE temperature is then
    T0 on average (to O(1/N); Lebowitz, Percus & Verlet, Phys. Rev. 153, 250 (1967)), up to
    the error of the estimate over C_V."""
    f = [int(round(q * n_steps)) for q in SCHEDULE[:3]]
    f.append(n_steps - sum(f))
    f[1], f[3] = max(f[1], 1), max(f[3], 1)  # a short run still measures once
    info: dict[str, float] = {"length_x_nominal": float(sim.state.L[0])}
    dU = 0.0
    bath = (T0, LOCAL_SLAB_LAYERS * layer, _kinetic_unit(sim) if local else 0.0)
    if resize:
        _advance_nvt(sim, f[0], *bath)
        first = _measure_nvt(sim, f[1], every, layer, bath)
        L1 = float(sim.state.L[0]) * float(first[:, 0].mean()) / rho0
        sim.scale_x(L1 / float(sim.state.L[0]))
        _advance_nvt(sim, f[2], *bath)
        info["rho_bulk_first"] = float(first[:, 0].mean())
    else:
        _advance_nvt(sim, n_steps - f[3], *bath)
    last = _measure_nvt(sim, f[3], every, layer, bath)
    if resize:
        L2 = float(sim.state.L[0]) * float(last[:, 0].mean()) / rho0
        L_star = (f[1] * L1 + f[3] * L2) / (f[1] + f[3])
        U_before = sim.energies()[1]
        sim.scale_x(L_star / float(sim.state.L[0]))
        dU = sim.energies()[1] - U_before
    n = sim.state.n
    nf = 3 * n - (3 if sim.state.periodic.all() else 0)
    K0 = 0.5 * nf * T0
    K_mean, U_mean = float(last[:, 1].mean()), float(last[:, 2].mean())
    E_target = K0 + U_mean + dU - BETA_KINETIC * (K_mean - K0)
    K, U = sim.energies()
    if not E_target - U > 0.5 * K:
        raise ValueError(
            f"the sample cannot reach its canonical mean energy {E_target:.6g} epsilon: "
            f"its potential energy {U:.6g} leaves a kinetic energy below half of {K:.6g}"
        )
    sim.state.v *= math.sqrt((E_target - U) / K)
    info.update(
        length_x=float(sim.state.L[0]), rho_bulk=float(last[:, 0].mean()),
        T_nvt=2.0 * K_mean / nf, U_mean=U_mean / n, E_target=E_target / n,
    )  # fmt: skip
    return info
