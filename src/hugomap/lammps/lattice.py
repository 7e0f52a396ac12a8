"""A crystal at the lattice constant of a requested pressure at T0 (``sample.lattice_pressure``)
and the check that a pole is at that pressure.

Why. A crystal built at a nominal lattice constant (``sample.rho0`` or
``sample.lattice_constant``; for copper the room-temperature experiment's or a potential's
0 K one) is, at T0, under whatever pressure the potential gives that lattice at T0: its
thermal pressure, about α K_T T0 for a lattice at its 0 K constant. The Hugoniot then starts
from that pole, and two schemes that hold the crystal differently (the walled sample, a
periodic box) start from different ones.

The search (``lattice_search.search_lattice``). With ``sample.lattice_pressure`` p the
crystal is built at the lattice constant a at which a fully periodic box of the scene's FCC
lattice and model at T0 is at the hydrostatic pressure p: an isothermal–isobaric run (LAMMPS ``fix npt``, Nosé–Hoover
(Shinoda, Shiga & Mikami, Phys. Rev. B 69, 134103 (2004)), ``iso``: the three box lengths
scaled together against (P_xx + P_yy + P_zz)/3, which keeps a cubic crystal cubic; thermostat
time ``sample.thermostat_tau``, barostat time ``sample.lattice_search.pdamp``, time step
``sample.dt``) of ``sample.lattice_search.cells`` FCC cells from the nominal lattice for
``run_time``, its velocities drawn at 2 T0 (atoms on their sites share their kinetic energy
with the potential within a vibration period, so the box is near T0 at once), the box
volume V sampled over its second half:

    a_i = (V_i / (n_x n_y n_z))^(1/3),   a = ⟨a_i⟩,   ρ0 = 4/a³   [σ, σ⁻³ | Å, Å⁻³]

(4 atoms a cubic FCC cell), the standard error of a from 8 block averages
(``analysis.stats.block_average``). Units: p [ε σ⁻³ | GPa] (the scene's; LAMMPS's pressure is
bar in units metal: 1 GPa = 10⁴ bar, ``units``).

One value for every stage. ``LammpsBackend.prepare`` runs the search once per scene and records
it in the sample file's backend info (``info["lattice"]``, ``search_lattice``'s keys), which
every checkpoint made from the sample carries (loading, the window); the stages that hand the
backend that info build their crystal from it (``lattice_density``: the window's inflow
reservoir and its seam). The stages that hand it only the sample's pole (the shock-frame
box, an lj reference) take the lattice from the pole's ρ0: the prepared sample measures a
crystal's ρ0 by counting its atoms in whole bins of the found lattice constant (``bin_width``),
i.e. in whole (100) planes, which is 4/a³ while the planes stay on their sites.

Bins. The profile bins (``shock.bin_width``) of a searched crystal scale with its lattice,
width × a/a_nominal (``bin_width``), so bins that held whole planes of the nominal lattice
(units metal's default: one lattice constant) hold whole planes of the found one.

The check (``pole_pressure_problem``). A pole is at the requested pressure p when its P_xx and
its mean stress (P_xx + 2 P_yy)/3 (P_zz = P_yy by the symmetry of a cubic crystal along
[100]) are each within ``sample.pressure_tolerance`` of p. The prepared sample
(``LammpsBackend.prepare``) and the shock-frame box (``shockframe.shock_frame_point``) are
checked; either one off ends its stage with status ``pole_off_pressure``.

Walls. The sample stands between a reflecting wall at x = 0 and a harmonic one at L_x with its
outer (100) planes a/4 inside them (``particles.fcc.fcc_positions``), so its faces along x are
free: a crystal under a positive pressure at its lattice expands uniaxially into that gap
until it presses on both walls, which relieves P_xx by C11 ΔL/L_x and P_yy by C12 ΔL/L_x (the
strain ΔL/L_x, C11 and C12 the elastic constants); at its zero-pressure lattice it touches
neither, and its P_xx is then 0 by the balance of forces on the slab (averaged over time).
Only a pressure near 0 is one that the walled sample's P_xx can hold. Its length breathes:
the slab's fundamental longitudinal mode, period 2 L_x/c_L, keeps the thermal energy k_B T
that the thermostats leave it, and the NVE pole run keeps its amplitude, so the slab-averaged
P_xx oscillates by about √(k_B T C11/V) (V the slab's volume) with that period; a
``sample.pole_time`` shorter than 2 L_x/c_L averages one phase of it (``breathing_period``).
"""

from __future__ import annotations

from .units import BAR_PA, GPA_PA, UnitSystem, unit_system

STATUS = "pole_off_pressure"


def searched(scene: dict) -> bool:
    """Whether the scene's crystal is built at a searched lattice (a crystal that gives
    ``sample.lattice_pressure``)."""
    return scene.get("phase") == "crystal" and "lattice_pressure" in scene.get("sample", {})


def pressure_units(usys: UnitSystem) -> tuple[float, float, str]:
    """A scene pressure's unit as (the backend's units per it, LAMMPS's thermo pressure units
    per it, its name): units metal GPa (10⁹ Pa, 10⁴ bar), units lj ε σ⁻³ (1, 1)."""
    if usys.si:
        return GPA_PA, GPA_PA / BAR_PA, "GPa"
    return 1.0, 1.0, "epsilon sigma^-3"


def lattice_density(scene: dict, info: dict | None, pole_density: float | None = None) -> float:
    """The number density [σ⁻³ | Å⁻³] a crystal of the scene is built at: the searched
    lattice's 4/a³ recorded in the sample's ``info`` (``info["lattice"]``); for a searched
    scene whose stage has only the pole, ``pole_density`` (the sample's measured ρ0 in number
    density: its whole planes in bins of the found lattice, module docstring); otherwise the
    nominal ``sample.rho0``. ``ValueError`` for a searched scene with neither."""
    lat = (info or {}).get("lattice")
    if lat:
        return float(lat["number_density"])
    if not searched(scene):
        return float(scene["sample"]["rho0"])
    if pole_density is None or not (pole_density > 0):
        raise ValueError(
            "sample.lattice_pressure: the searched lattice is neither in the sample's info "
            "nor given by its pole's rho0"
        )
    return float(pole_density)


def bin_width(scene: dict, info: dict | None) -> float:
    """The profile bins' width [σ | Å]: ``shock.bin_width``, scaled by a/a_nominal for a
    crystal whose lattice was searched (its ``info["lattice"]``), so that bins that held
    whole lattice planes at the nominal lattice hold them at the found one."""
    width = float(scene["shock"]["bin_width"])
    lat = (info or {}).get("lattice")
    if not lat:
        return width
    return width * float(lat["lattice_constant"]) / float(lat["nominal_lattice_constant"])


def breathing_period(length: float, sound_speed: float) -> float:
    """Period 2 L_x/c_L of a slab's fundamental longitudinal mode between free faces
    [time of ``length``/``sound_speed``]."""
    return 2.0 * length / sound_speed


def pole_pressure_problem(
    P_xx: float, P_xx_err: float, P_yy: float | None, scene: dict, where: str
) -> str:
    """The check of the module docstring on a pole's P_xx (± its error) and P_yy [the
    backend's units: ε σ⁻³ | Pa]: '' when P_xx and the mean stress (P_xx + 2 P_yy)/3 are
    each within ``sample.pressure_tolerance`` of ``sample.lattice_pressure`` (P_yy None: P_xx
    alone), else a diagnostic naming ``where``, both values, the requested pressure and the
    keys (scene units: ε σ⁻³ | GPa)."""
    s = scene["sample"]
    to_backend, _, unit = pressure_units(unit_system(scene["model"]))
    p, tol = float(s["lattice_pressure"]), float(s["pressure_tolerance"])
    xx = P_xx / to_backend
    mean = xx if P_yy is None else (P_xx + 2.0 * P_yy) / 3.0 / to_backend
    off = [name for name, v in (("P_xx", xx), ("the mean stress", mean)) if not abs(v - p) <= tol]
    if not off:
        return ""
    return (
        f"{where}: P_xx = {xx:.4g} ± {P_xx_err / to_backend:.2g} {unit}, mean stress "
        f"(P_xx + 2 P_yy)/3 = {mean:.4g} {unit}, against sample.lattice_pressure = {p:g} "
        f"{unit}: {' and '.join(off)} off by more than sample.pressure_tolerance = {tol:g} "
        f"{unit}"
    )
