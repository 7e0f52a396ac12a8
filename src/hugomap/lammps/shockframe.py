"""Shock-frame Hugoniot schemes on LAMMPS (package SHOCK): ``nphug`` and ``msst``.

One homogeneous, fully periodic box of the scene's material stands for the shocked slab; a
LAMMPS fix holds it on the Hugoniot of the sample's measured pole (ρ0, P0, E0; a crystal's
box keeps its lattice and measures its own pole in NVE at T0, as the window's inflow of a
crystal: the sample's P_xx between walls need not be the periodic lattice's), so a point
costs a few thousand atoms and a few tens of τ instead of a whole piston run. Neither fix
is driven by u_p: both give the state of a given shock strength, so the scheme iterates on
that strength until the measured u_p is the scene's.

- ``nphug`` (Ravelo, Holian, Germann & Lomdahl, Phys. Rev. B 70, 014103 (2004); LAMMPS
  ``fix nphug``): a Nosé–Hoover barostat holds P_xx at a target P with x-only (uniaxial)
  compression, and a thermostat drives the temperature until the Hugoniot energy condition
  E − E0 = ½ (P + P0)(V0 − V) holds. From the relaxed state, per unit mass (V = 1/ρ, the
  Rayleigh line through the pole; ``rayleigh``):

      u_p = √((P_xx − P0)(V0 − V)),    D = V0 √((P_xx − P0)/(V0 − V)).

  The target P is found by a secant on u_p(P) (the first step, and any step whose secant
  slope is not positive, by the Rayleigh line with D ≈ D_k + s (u_p − u_k), s = 1.5).
- ``msst`` (Reed, Fried & Joannopoulos, Phys. Rev. Lett. 90, 235503 (2003); LAMMPS ``fix
  msst``): the cell's x length follows a Lagrangian that restrains the system to the Rayleigh
  line and the Hugoniot of a shock moving at the input speed Us; in the steady state
  u_p = Us (1 − V/V0) (mass conservation), D = Us (its error as a point of D(u_p):
  ``msst_D_error``). A secant on u_p(Us), the first step from D ≈ c0 + s u_p. MSST needs
  its cell mass ``q`` and viscosity ``mu`` tuned to the material: the momentum residual (the
  distance from the Rayleigh line) and the energy residual (from the Hugoniot) of the final
  state say whether it settled there.

The start: the backend's model sound speed c0 where it has one (units metal: the reference
fit's), else the adiabatic longitudinal sound speed of the equilibrated box, c0 =
√(ΔP_xx/(ρ0 ε)) after an affine x-compression ε (``STRAIN``) relaxed in NVE; D ≈ c0 + s u_p.

Each target is held for ``relax_time`` (discarded) and then ``average_time``: nphug continues
from the last state (its target is a state function), MSST starts each Us from the archived
pole state (its restraint conserves an energy from the start; the box starts at the pole's
energy exactly, velocities scaled, as the window's inflow reservoir); a target whose first
quarter of the average misses u_p by more than ``PROBE_MISS`` is not averaged further. The
averages are block averages of the samples (``analysis.stats.block_average``, 8 blocks); the
errors of u_p and D are those of their per-sample values, with the pole's errors added by
first-order propagation (``rayleigh_errors``). The jump residuals are
``analysis.jump.jump_residuals`` of the measured state against the pole, with
``jump_residual_errors``; the point is ``ok`` when
each closes (``analysis.causes.closes``: within ``shock.residual_tol`` and 3 of its error) and
the measured u_p is within the same of the scene's u_p; else ``not_converged``, the
diagnostic naming what did not close.

Only global quantities are read from LAMMPS (thermo keywords through ``get_thermo``: pxx,
pyy, pzz, vol, pe, ke, temp; ``get_natoms``), never per-atom arrays, so the box can run on
several MPI ranks. Units: what LAMMPS gives in its own units (lj: σ, τ, ε, m = 1; metal: Å,
ps, eV, bar, K) is converted here to the backend's (lj as it is; metal SI through
``units``: kg m⁻³, Pa, J kg⁻¹, m/s).
"""

from __future__ import annotations

import logging
import math
import time
from dataclasses import dataclass, field

import numpy as np

from ..analysis.causes import (
    CLOSE_SIGMAS,
    closes,
    elastic_front,
    elastic_text,
    residual_text,
    shear_stress,
)
from ..analysis.jump import jump_residual_errors, jump_residuals
from ..analysis.linear_hugoniot import shock_velocity
from ..analysis.stats import block_average
from ..failures import SolverUnstable, StageFailed
from ..particles.fcc import lattice_constant
from ..states import Pole
from .units import BAR_PA, UnitSystem, number_density_factor, specific_energy_factor, unit_system

log = logging.getLogger("hugomap")

SCHEMES = ("nphug", "msst")
SLOPE = 1.5  # s of D ≈ c0 + s u_p for the start and the Rayleigh-line steps (most solids 1-2)
STRAIN = 0.01  # affine x-compression that measures c0 when the model has none
N_BLOCKS = 8
PROBE_MISS = 0.05  # an iteration whose probe misses u_p by more (relative) is not averaged on
THERMO = ("pxx", "pyy", "pzz", "vol", "pe", "ke", "temp")


@dataclass(frozen=True)
class Native:
    """Conversions between LAMMPS's units and the backend's (lj: all 1; metal: SI), for
    atoms of ``mass`` [m | g/mol]: pressure [ε σ⁻³ | bar → Pa], number density [σ⁻³ | Å⁻³
    → kg m⁻³], energy per atom [ε | eV → J kg⁻¹], velocity [σ/τ | Å/ps → m/s]."""

    usys: UnitSystem
    mass: float

    @property
    def pressure(self) -> float:
        return BAR_PA if self.usys.si else 1.0  # thermo pressure: bar in units metal

    @property
    def density(self) -> float:
        return number_density_factor(self.mass, self.usys) if self.usys.si else 1.0

    @property
    def energy(self) -> float:
        return specific_energy_factor(self.mass, self.usys) if self.usys.si else 1.0

    @property
    def velocity(self) -> float:
        return self.usys.velocity_m_s if self.usys.si else 1.0


@dataclass
class Params:
    """The resolved ``shock_frame`` block and the scene's time step (module docstring; times
    [τ | ps], ``nphug.pdamp``, ``tdamp``, ``relax_time`` [τ | ps], ``msst.q`` [mass²
    length⁻⁴], ``msst.mu`` [mass length⁻¹ time⁻¹], ``msst.tscale`` [-], ``msst.relax_time``
    [τ | ps])."""

    cells: tuple[int, int, int]
    dt: float
    equilibrate_time: float
    average_time: float
    sample_every: int
    max_iterations: int
    up_tolerance: float
    nphug: dict = field(default_factory=dict)
    msst: dict = field(default_factory=dict)

    @classmethod
    def from_scene(cls, scene: dict) -> Params:
        f = scene["shock_frame"]
        return cls(tuple(f["cells"]), float(scene["shock"]["dt"]), f["equilibrate_time"],
                   f["average_time"], int(f["sample_every"]),
                   int(f["max_iterations"]), float(f["up_tolerance"]), dict(f["nphug"]),
                   dict(f["msst"]))  # fmt: skip


def rayleigh(P: float, V: float, P0: float, V0: float) -> tuple[float, float]:
    """(u_p, D) of a state (P_xx, V) on the Rayleigh line through the pole (P0, V0), per unit
    mass (V specific volume): u_p = √((P − P0)(V0 − V)), D = V0 √((P − P0)/(V0 − V)) (mass and
    momentum jump conditions, ``analysis.jump``'s module docstring); NaN for a state that is
    not compressed by a positive stress jump."""
    dP, dV = P - P0, V0 - V
    if not (dP > 0 and dV > 0):
        return math.nan, math.nan
    return math.sqrt(dP * dV), V0 * math.sqrt(dP / dV)


def rayleigh_errors(
    P: float, V: float, P0: float, V0: float, errors: dict[str, float], rel_step: float = 1e-6
) -> tuple[float, float]:
    """Standard errors of ``rayleigh``'s (u_p, D) from independent errors of P, V, P0, V0
    (first-order propagation by central differences, as ``jump_residual_errors``)."""
    base = {"P": P, "V": V, "P0": P0, "V0": V0}
    var = [0.0, 0.0]
    for name, sx in errors.items():
        if not (sx and sx > 0):
            continue
        h = rel_step * max(abs(base[name]), 1e-300)
        up = rayleigh(**{**base, name: base[name] + h})
        dn = rayleigh(**{**base, name: base[name] - h})
        for i in range(2):
            var[i] += ((up[i] - dn[i]) / (2 * h) * sx) ** 2
    return math.sqrt(var[0]), math.sqrt(var[1])


class FrameBox:
    """A fully periodic LAMMPS box of the scene's model (``simulation.model_commands``): FCC
    (``particles.fcc.fcc_positions``) at the number density ``rho_n`` [σ⁻³ | Å⁻³], velocities
    at T0 [ε/k_B | K] (LAMMPS ``velocity create``, zero total momentum), time step ``dt``."""

    def __init__(self, model: dict, cells: tuple[int, int, int], rho_n: float, T0: float,
                 dt: float, seed: int) -> None:  # fmt: skip
        from ..particles.fcc import fcc_positions
        from .simulation import lammps_class, model_commands

        x, L = fcc_positions(tuple(int(c) for c in cells), rho_n)
        self.lmp = lammps_class()(cmdargs=["-log", "none", "-screen", "none", "-nocite"])
        self.lmp.commands_list([
            f"units {model['units']}", "atom_style atomic", "atom_modify map array",
            "boundary p p p",
            "region box block 0 {!r} 0 {!r} 0 {!r} units box".format(*map(float, L)),
            "create_box 2 box",
        ])  # fmt: skip
        n = x.shape[0]
        made = self.lmp.create_atoms(n, list(range(1, n + 1)), [1] * n, x.ravel().tolist(),
                                     [0.0] * (3 * n))  # fmt: skip
        if made != n:
            raise ValueError(f"LAMMPS created {made} of {n} atoms")
        self.lmp.commands_list([
            *model_commands(model), f"timestep {float(dt)!r}", "thermo 0",
            "thermo_modify norm no",  # extensive thermo keywords (units lj normalises)
            f"velocity all create {float(T0)!r} {int(seed)} dist gaussian mom yes rot no",
        ])  # fmt: skip
        self.n = int(self.lmp.get_natoms())
        self.dt = float(dt)
        self._setup = True
        self.steps = 0

    def commands(self, cmds: list[str]) -> None:
        """Issue commands (fixes): the next run sets up again."""
        self.lmp.commands_list(cmds)
        self._setup = True

    def run(self, steps: int) -> None:
        if steps <= 0:
            return
        self.lmp.command(f"run {int(steps)} pre {'yes' if self._setup else 'no'} post no")
        self._setup = False
        self.steps += int(steps)

    def sample(self, n_samples: int, every: int) -> dict[str, np.ndarray]:
        """Global thermo values (``THERMO``, LAMMPS units, extensive) every ``every`` steps."""
        rows = []
        for _ in range(n_samples):
            self.run(every)
            rows.append([self.lmp.get_thermo(k) for k in THERMO])
        a = np.asarray(rows, dtype=float).reshape(-1, len(THERMO))
        return {k: a[:, i] for i, k in enumerate(THERMO)}

    def set_energy(self, e_total: float) -> None:
        """Scale the velocities (``velocity all scale``) so the total energy pe + ke is
        ``e_total`` [energy] at the current positions (``make_reservoir``'s rule for the
        inflow: the box starts at the pole's energy exactly)."""
        self.run_zero()
        pe, ke, T = (self.lmp.get_thermo(k) for k in ("pe", "ke", "temp"))
        if not (ke > 0 and e_total - pe > 0):
            raise ValueError(f"the box cannot reach energy {e_total:.6g}: pe {pe:.6g}")
        self.commands([f"velocity all scale {T * (e_total - pe) / ke!r}"])
        self.run_zero()

    def run_zero(self) -> None:
        """``run 0``: thermo values current (set-up included)."""
        self.lmp.command("run 0 post no")
        self._setup = False

    def archive(self) -> None:
        """Keep the current state inside LAMMPS (``fix store/state 0``: positions,
        velocities, migrating with the atoms across ranks) and the box, for ``restore``."""
        lo, hi = self.lmp.extract_box()[:2]
        self._box = [(float(a), float(b)) for a, b in zip(lo, hi, strict=True)]
        self.commands(["fix hm_pole all store/state 0 x y z vx vy vz"] + [
            f"variable hm_{k} atom f_hm_pole[{i + 1}]"
            for i, k in enumerate(("x", "y", "z", "vx", "vy", "vz"))
        ])  # fmt: skip

    def restore(self) -> None:
        """The archived state again: ``change_box`` back to the archived box (first: with
        the stored positions set in a smaller box its wrap would move them), ``set`` from
        the stored values, and ``change_box`` to the same box again, which migrates every
        atom to the rank that owns its restored position (``set`` does not)."""
        extents = " ".join(
            f"{d} final {lo!r} {hi!r}" for d, (lo, hi) in zip("xyz", self._box, strict=True)
        )
        self.commands([
            f"change_box all {extents} units box",
            "set group all x v_hm_x y v_hm_y z v_hm_z vx v_hm_vx vy v_hm_vy vz v_hm_vz "
            "image 0 0 0",
            f"change_box all {extents} units box",
        ])  # fmt: skip

    def close(self) -> None:
        self.lmp.close()


@dataclass
class Iteration:
    """One target (P for nphug, Us for msst, native units) and what it measured (the
    backend's units): u_p, D with errors."""

    target: float
    u_p: float
    u_p_err: float
    D: float
    D_err: float
    state: dict = field(default_factory=dict)


def measure(series: dict[str, np.ndarray], n: int, conv: Native, pole: Pole,
            Us: float | None = None) -> dict[str, float]:  # fmt: skip
    """The state of the box over ``series`` in the backend's units: ρ, V = 1/ρ, P = P_xx,
    Pyy, Pzz, E (per unit mass | per atom), T, as block averages with standard errors, and
    (u_p, D): nphug (``Us`` None) from the Rayleigh line (``rayleigh``), msst u_p = Us (1 −
    V/V0), D = Us [velocity]; errors from the per-sample values' block averages and the
    pole's, propagated (``rayleigh_errors``)."""
    V0 = 1.0 / pole.rho0
    V0_err = pole.rho0_err / pole.rho0**2
    per = {
        "rho": n / series["vol"] * conv.density,
        "P": series["pxx"] * conv.pressure,
        "Pyy": series["pyy"] * conv.pressure,
        "Pzz": series["pzz"] * conv.pressure,
        "E": (series["pe"] + series["ke"]) / n * conv.energy,
        "T": series["temp"],
    }
    per["V"] = 1.0 / per["rho"]
    out: dict[str, float] = {}
    for k, y in per.items():
        out[k], out[k + "_err"] = block_average(y, N_BLOCKS)
    out["V"] = 1.0 / out["rho"]  # the mean state's volume, as the other schemes give it
    out["n_samples"] = float(series["pxx"].size)
    if Us is None:
        u, D = rayleigh(out["P"], out["V"], pole.P0, V0)
        per_u = np.array([rayleigh(p, v, pole.P0, V0) for p, v in zip(per["P"], per["V"],
                                                                     strict=True)])  # fmt: skip
        su = block_average(per_u[:, 0], N_BLOCKS)[1] if per_u.size else math.nan
        sD = block_average(per_u[:, 1], N_BLOCKS)[1] if per_u.size else math.nan
        pu, pD = rayleigh_errors(out["P"], out["V"], pole.P0, V0,
                                 {"P0": pole.P0_err, "V0": V0_err})  # fmt: skip
        out["u_p"], out["u_p_err"] = u, float(np.hypot(su, pu))
        out["D"], out["D_err"] = D, float(np.hypot(sD, pD))
    else:
        out["u_p"] = Us * (1.0 - out["V"] / V0)
        out["u_p_err"] = float(Us * np.hypot(out["V_err"] / V0, out["V"] * V0_err / V0**2))
        out["D"], out["D_err"] = float(Us), 0.0
    return out


def box_pole(series: dict[str, np.ndarray], n: int, conv: Native) -> Pole:
    """The pole of the box itself in the backend's units (block averages of ``series``, an
    NVE run at T0): ρ0, P0 = P_xx, Pyy0, E0 (per unit mass | per atom), T0."""
    st = {
        "rho0": n / series["vol"] * conv.density,
        "P0": series["pxx"] * conv.pressure,
        "Pyy0": series["pyy"] * conv.pressure,
        "E0": (series["pe"] + series["ke"]) / n * conv.energy,
        "T0": series["temp"],
    }
    out = {}
    for k, y in st.items():
        out[k], out[k + "_err"] = block_average(y, N_BLOCKS)
    return Pole.from_dict(out)


def residuals(state: dict[str, float], pole: Pole) -> tuple[dict[str, float], dict[str, float]]:
    """The three jump residuals of ``state`` (D, u_p, ρ, P, E) against the pole
    (``analysis.jump.jump_residuals``) and their errors (``jump_residual_errors``)."""
    vals = {"rho1": pole.rho0, "P1": pole.P0, "E1": pole.E0, "D": state["D"],
            "u": state["u_p"], "rho": state["rho"], "P": state["P"], "E": state["E"],
            "u1": 0.0}  # fmt: skip
    errs = {"rho1": pole.rho0_err, "P1": pole.P0_err, "E1": pole.E0_err, "D": state["D_err"],
            "u": state["u_p_err"], "rho": state["rho_err"], "P": state["P_err"],
            "E": state["E_err"]}  # fmt: skip
    return jump_residuals(**vals), jump_residual_errors(vals, errs)


def next_target(scheme: str, its: list[Iteration], u_t: float, pole: Pole, conv: Native) -> float:
    """The next P (nphug, native pressure) or Us (msst, native velocity) for the target u_t:
    a secant through the last two iterations where its slope is positive, else the Rayleigh
    line from the last one with D ≈ D_k + s (u_t − u_k), s = ``SLOPE``; within [½, 2] × the
    last target."""
    last = its[-1]
    return float(np.clip(_next(scheme, its, u_t, pole, conv), 0.5 * last.target,
                         2.0 * last.target))  # fmt: skip


def _next(scheme: str, its: list[Iteration], u_t: float, pole: Pole, conv: Native) -> float:
    """``next_target`` before its clamp to [½, 2] × the last target (a fix that did not
    respond, u_p ≈ 0, gives a secant slope that would throw the next target far off)."""
    last = its[-1]
    if len(its) >= 2:
        prev = its[-2]
        du = last.u_p - prev.u_p
        slope = (last.target - prev.target) / du if du != 0 else math.nan
        if math.isfinite(slope) and slope > 0:
            return last.target + slope * (u_t - last.u_p)
    D = (last.D if math.isfinite(last.D) else 0.0) + SLOPE * (u_t - last.u_p)
    if scheme == "msst":
        return max(D, u_t * 1.05) / conv.velocity
    return (pole.P0 + pole.rho0 * D * u_t) / conv.pressure


def msst_D_error(its: list[Iteration], conv: Native) -> float:
    """MSST's D is its input Us, exact; as a point of the Hugoniot D(u_p) its error is that of
    the Us whose steady u_p is the one measured: σ_D = |dUs/du_p| σ_u, the slope from the last
    two iterations (a secant) where it is positive, else ``SLOPE`` [velocity]."""
    last = its[-1]
    slope = SLOPE
    if len(its) >= 2 and its[-2].u_p != last.u_p:
        s = (last.target - its[-2].target) * conv.velocity / (last.u_p - its[-2].u_p)
        if math.isfinite(s) and s > 0:
            slope = s
    return float(slope * last.u_p_err)


def start_target(scheme: str, c0: float, u_t: float, pole: Pole, conv: Native) -> float:
    """The first P or Us (native) from D ≈ c0 + s u_t: Us = D, P = P0 + ρ0 D u_t."""
    D = shock_velocity(u_t, c0, SLOPE)
    if scheme == "msst":
        return D / conv.velocity
    return (pole.P0 + pole.rho0 * D * u_t) / conv.pressure


def box_sound_speed(box: FrameBox, params: Params, conv: Native, rho0: float) -> float:
    """The adiabatic longitudinal sound speed of the equilibrated box [velocity, backend's
    units]: c0 = √(ΔP_xx/(ρ0 ε)) after an affine x-compression by ε = ``STRAIN`` (``change_box
    x scale 1 − ε remap``), ΔP_xx the change of P_xx, each averaged over a quarter of
    ``average_time`` of NVE, the compressed one after half of that (a fluid's stress relaxes
    from the instantaneous modulus in a fraction of a τ); the box is put back afterwards. A
    start guess only."""
    steps = max(int(round(params.average_time / 4 / params.dt / params.sample_every)), 4)
    before = box.sample(steps, params.sample_every)["pxx"].mean()
    box.commands([f"change_box all x scale {1.0 - STRAIN!r} remap"])
    box.run(steps * params.sample_every // 2)
    after = box.sample(steps, params.sample_every)["pxx"].mean()
    box.commands([f"change_box all x scale {1.0 / (1.0 - STRAIN)!r} remap"])
    dP = (after - before) * conv.pressure
    return math.sqrt(dP / (rho0 * STRAIN)) if dP > 0 else math.nan


def check_box_pole(scene: dict, pole: Pole, rho_lattice: float) -> None:
    """A crystal box built at a searched lattice (``sample.lattice_pressure``): its pole must
    be at that pressure (``lattice.pole_pressure_problem``), else ``StageFailed`` with status
    ``pole_off_pressure`` and a diagnostic naming the box's lattice constant [σ | Å] and the
    keys to change. A scene without the key is not checked."""
    from .lattice import STATUS, pole_pressure_problem, searched

    if not searched(scene):
        return
    problem = pole_pressure_problem(pole.P0, pole.P0_err, pole.Pyy0, scene,
                                    "the shock-frame box's pole")  # fmt: skip
    if problem:
        a = lattice_constant(rho_lattice)
        raise StageFailed(STATUS, (
            f"{problem}; the periodic box was built at the sample's lattice constant {a:.6g} "
            "(the lattice search's, read from the sample). Lengthen "
            "sample.lattice_search.run_time, or change sample.lattice_pressure or "
            "sample.pressure_tolerance"))  # fmt: skip


def up_reached(miss: float, err: float, u_p: float, tol: float, up_tolerance: float) -> bool:
    """Whether a measured u_p that misses the scene's ``u_p`` by ``miss`` ± ``err`` (same
    velocity units) is at it: within ``up_tolerance`` of u_p (the scene's ``shock_frame``
    key), or within 2 of its error where that error is no larger than ``tol``
    (``shock.residual_tol``) of u_p, so that a fix still swinging is not hit by luck. The
    rule that ends the iteration and the one the status applies."""
    if not math.isfinite(miss):
        return False
    return abs(miss) <= max(min(2.0 * err, tol * abs(u_p)), up_tolerance * abs(u_p))


def shock_frame_point(
    scene: dict, scheme: str, u_p: float, pole: Pole, c0: float | None, rho_lattice: float | None
) -> tuple[dict[str, float], str, str, dict, dict[str, float]]:
    """One Hugoniot point of ``scheme`` (nphug or msst) at the particle velocity ``u_p`` of
    the frame [σ/τ | m/s] from the sample's ``pole`` (the backend's units), following the
    module docstring; ``c0``: the model's sound speed [velocity] or None (measured on the
    box); ``rho_lattice``: a crystal's FCC number density [σ⁻³ | Å⁻³] (None: a fluid, its
    box made at the pole's ρ0; a crystal's box measures its own pole in NVE at T0 and
    holds the Hugoniot from it, as the window's inflow of a crystal does: the sample's P0
    between walls need not be the periodic lattice's; a searched lattice's box pole is
    checked, ``check_box_pole``). Returns (values, status, diagnostic,
    attrs, the pole used as a dict): values as
    ``analysis.shock.measure_point`` names them (D, u_p_measured, ρ, V, P, Pyy, Pzz, T, E,
    E_minus_E0, P_rh, shear_stress, the residuals, each with ``_err``, n_samples,
    atom_steps), attrs the fix, its parameters and the iterations."""
    if scheme not in SCHEMES:
        raise ValueError(f"scheme {scheme!r}: not a shock-frame scheme ({', '.join(SCHEMES)})")
    model, s = scene["model"], scene["sample"]
    usys = unit_system(model)
    conv = Native(usys, float(model["mass"]))
    prm = Params.from_scene(scene)
    tol = float(scene["shock"]["residual_tol"])
    rho_n = rho_lattice if rho_lattice is not None else pole.rho0 / conv.density
    T0 = float(pole.T0 if pole.T0 is not None else s["T0"])
    box = FrameBox(model, prm.cells, rho_n, T0, prm.dt, int(s["seed"]) + 104729)
    t_wall = time.perf_counter()
    p = getattr(prm, scheme)
    try:
        n = box.n
        tau = float(s["thermostat_tau"])
        thermostat = f"fix hm_th all temp/csvr {T0!r} {T0!r} {tau!r} {int(s['seed']) + 1}"
        box.commands(["fix hm_eq all nve", thermostat])
        box.run(int(round(prm.equilibrate_time / prm.dt)))
        box.commands(["unfix hm_th"])
        c_start = c0 if c0 is not None else box_sound_speed(box, prm, conv, pole.rho0)
        if not (c_start and math.isfinite(c_start) and c_start > 0):
            c_start = 2.0 * u_p  # no measurable modulus: a strong-shock guess
        if rho_lattice is not None:  # a crystal: the box's own pole (module docstring)
            n_pole = max(int(round(prm.average_time / prm.dt / prm.sample_every)), 2 * N_BLOCKS)
            pole = box_pole(box.sample(n_pole, prm.sample_every), box.n, conv)
            log.info("shock-frame pole (the crystal box's): %s", pole.as_dict())
            check_box_pole(scene, pole, rho_lattice)
        # the pole in LAMMPS's units for the fixes: total volume and energy of n atoms
        V0_tot = n / (pole.rho0 / conv.density)
        E0_tot = n * pole.E0 / conv.energy
        P0_nat = pole.P0 / conv.pressure
        # start at the pole's energy exactly: MSST conserves its extended energy from the
        # start, so the Hugoniot it reaches is that of the box's own starting energy
        box.commands([thermostat])
        box.run(int(round(0.25 * prm.equilibrate_time / prm.dt)))
        box.commands(["unfix hm_th"])
        box.set_energy(E0_tot)
        box.commands(["unfix hm_eq"])
        box.archive()
        n_avg = max(int(round(prm.average_time / prm.dt / prm.sample_every)), 2 * N_BLOCKS)
        n_relax = int(round(p["relax_time"] / prm.dt))
        target = start_target(scheme, c_start, u_p, pole, conv)
        its: list[Iteration] = []
        for _ in range(prm.max_iterations):
            if scheme == "nphug":  # a state function: continue from the last state
                box.commands([
                    *(["unfix hm_sf"] if its else []),
                    f"fix hm_sf all nphug temp 1.0 1.0 {p['tdamp']!r} x {target!r} {target!r} "
                    f"{p['pdamp']!r}",
                    f"fix_modify hm_sf e0 {E0_tot!r} v0 {V0_tot!r} p0 {P0_nat!r}",
                ])  # fmt: skip
            else:  # MSST's restraint holds from the pole: each Us starts there again
                if its:
                    box.commands(["unfix hm_sf"])
                    box.restore()
                box.commands([
                    f"fix hm_sf all msst x {target!r} q {p['q']!r} mu {p['mu']!r} "
                    f"p0 {P0_nat!r} v0 {V0_tot!r} e0 {E0_tot!r} tscale {p['tscale']!r}",
                ])  # fmt: skip
            box.run(n_relax)
            Us = target * conv.velocity if scheme == "msst" else None
            # a probe of a quarter of the average first: a target far off (u_p more than
            # PROBE_MISS from the scene's) is not worth the rest
            n_probe = max(n_avg // 4, 2 * N_BLOCKS)
            series = box.sample(n_probe, prm.sample_every)
            st = measure(series, n, conv, pole, Us)
            if not abs(st["u_p"] - u_p) > PROBE_MISS * abs(u_p) and n_avg > n_probe:
                more = box.sample(n_avg - n_probe, prm.sample_every)
                series = {k: np.concatenate([series[k], more[k]]) for k in series}
                st = measure(series, n, conv, pole, Us)
            its.append(Iteration(target, st["u_p"], st["u_p_err"], st["D"], st["D_err"], st))
            log.info("%s iteration %d: target %.6g -> u_p %.6g +- %.2g, D %.6g +- %.2g, "
                     "P %.6g, V %.6g", scheme, len(its), target, st["u_p"], st["u_p_err"],
                     st["D"], st["D_err"], st["P"], st["V"])  # fmt: skip
            miss = st["u_p"] - u_p
            if not math.isfinite(miss):
                target = next_target(scheme, its, u_p, pole, conv) if math.isfinite(
                    st["D"]) else target * 1.2  # fmt: skip
                continue
            if up_reached(miss, st["u_p_err"], u_p, tol, prm.up_tolerance):
                break
            target = next_target(scheme, its, u_p, pole, conv)
        steps = box.steps
    except Exception as exc:  # the lammps module raises plain exceptions
        if "Lost atoms" in str(exc) or "Out of range atoms" in str(exc):
            raise SolverUnstable("atom_lost", f"{scheme}: LAMMPS stopped: {exc}") from None
        raise
    finally:
        box.close()
    st = its[-1].state
    values = {k: st[k] for k in ("rho", "rho_err", "V", "V_err", "P", "P_err", "Pyy", "Pyy_err",
                                 "Pzz", "Pzz_err", "T", "T_err", "E", "E_err", "D", "D_err")}  # fmt: skip
    values["V_err"] = st["rho_err"] / st["rho"] ** 2
    values["u_p_measured"], values["u_p_measured_err"] = st["u_p"], st["u_p_err"]
    if scheme == "msst":
        values["D_err"] = msst_D_error(its, conv)
    values["E_minus_E0"] = st["E"] - pole.E0
    values["E_minus_E0_err"] = float(np.hypot(st["E_err"], pole.E0_err))
    values["P_rh"] = pole.P0 + pole.rho0 * st["D"] * st["u_p"]
    values["P_rh_err"] = float(np.hypot(pole.rho0 * st["D"] * st["u_p_err"],
                                        pole.rho0 * st["u_p"] * st["D_err"]) + pole.P0_err)  # fmt: skip
    values["shear_stress"], values["shear_stress_err"] = shear_stress(values)
    values["elastic_front"] = float(elastic_front(values, pole))
    res, res_err = residuals(st, pole)
    values.update({f"residual_{k}": v for k, v in res.items()})
    values.update({f"residual_{k}_err": v for k, v in res_err.items()})
    values["n_samples"] = st["n_samples"]
    values["atom_steps"] = float(n * steps)
    miss = (st["u_p"] - u_p) / u_p
    closing = {k: closes(v, res_err[k], tol) for k, v in res.items()}
    # the rule that ended the iterations: a point the loop accepted is not refused for it
    closing["u_p"] = up_reached(st["u_p"] - u_p, st["u_p_err"], u_p, tol, prm.up_tolerance)
    finite = all(math.isfinite(st[k]) for k in ("D", "u_p", "rho", "P", "E"))
    ok = finite and all(closing.values())
    values["converged"] = ok
    status, diagnostic = ("ok", "") if ok else ("not_converged", "")
    if not ok:
        causes = []
        if not closing["u_p"]:
            causes.append(f"u_p not reached: measured {st['u_p']:.6g} ± {st['u_p_err']:.2g} "
                          f"against {u_p:.6g} ({miss:+.3%}) after {len(its)} of "
                          "shock_frame.max_iterations iterations")  # fmt: skip
        if not closing.get("momentum", True):
            causes.append("the state is off the Rayleigh line (momentum residual)")
        if values["elastic_front"]:
            causes.append(elastic_text(values, pole))
        if not closing.get("energy", True):
            causes.append("the state is off the Hugoniot (energy residual)")
        if not closing.get("mass", True):
            causes.append("mass residual")
        if scheme == "msst" and not (closing.get("momentum", True) and closing.get("energy", True)):
            causes.append("MSST has not settled on the Rayleigh line and the Hugoniot of its "
                          "shock speed: tune shock_frame.msst.q and mu, or a longer msst.relax_time")  # fmt: skip
        diagnostic = ("; ".join(causes) + f"; {residual_text(values)}; ok needs each within "
                      f"shock.residual_tol = {tol:.3g} and {CLOSE_SIGMAS:g} of its error")  # fmt: skip
    fix = "nphug" if scheme == "nphug" else "msst"
    attrs = {
        "shock_frame_fix": fix,
        "shock_frame_reference": (
            "Ravelo et al., Phys. Rev. B 70, 014103 (2004)" if fix == "nphug"
            else "Reed, Fried, Joannopoulos, Phys. Rev. Lett. 90, 235503 (2003)"),
        "shock_frame_params": repr({"cells": list(prm.cells), "dt": prm.dt,
                                    "equilibrate_time": prm.equilibrate_time,
                                    "average_time": prm.average_time,
                                    "sample_every": prm.sample_every,
                                    **{f"{fix}.{k}": v for k, v in getattr(prm, fix).items()}}),
        "shock_frame_iterations": len(its),
        "shock_frame_targets": [float(i.target) for i in its],
        "shock_frame_target_name": ("P_xx [LAMMPS pressure units]" if fix == "nphug"
                                    else "Us [LAMMPS velocity units]"),
        "shock_frame_u_p": [float(i.u_p) for i in its],
        "shock_frame_c0_start": float(c_start),
        "shock_frame_atoms": int(n),
        "lammps_units": str(model["units"]),
        "shock_frame_wall_s": time.perf_counter() - t_wall,
        "shock_frame_pole": ("the sample's" if rho_lattice is None else
                             "the periodic box's at the lattice's rho0 and T0 (a crystal)"),
    }  # fmt: skip
    return values, status, diagnostic, attrs, pole.as_dict()
