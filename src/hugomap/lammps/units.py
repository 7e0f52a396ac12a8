"""LAMMPS unit systems and their conversion to SI: every conversion factor of the LAMMPS
backend is written here, once (light: numpy only).

A simulation keeps LAMMPS's native units (its positions, velocities, clock, walls and raw
profile sums); what crosses the backend seam in a ``units metal`` scene is SI (the
``SIView`` of a simulation, the ``MetalProfile`` reader), so the shared analysis measures a
point in one coherent system and the datasets are in m, s, kg, Pa, J/kg, K like the CSPH
backend's. ``units lj`` stays in reduced units (σ, τ, ε, m = 1, k_B = 1): no SI view.

units metal (LAMMPS ``units`` command doc): length Å, time ps, energy eV, mass g/mol,
velocity Å/ps, temperature K, pressure bar (the scene never sees pressure in bar: the
per-atom virial is read in eV, and ``stress/atom`` gives bar·Å³, converted by ``nktv2p``).
Exact constants (SI 2019; CODATA 2018 for the atomic mass constant):
    1 eV   = 1.602176634e-19 J          1 Å = 1e-10 m        1 ps = 1e-12 s
    1 bar  = 1e5 Pa                      1 Å/ps = 100 m/s
    1 g/mol per atom = 1 u = 1.66053906660e-27 kg
    k_B    = 8.617333262e-5 eV/K
Derived: ``mvv2e`` = u·(Å/ps)²/eV = 1.0364269e-4 (kinetic energy ½ mvv2e m v² [eV] for
m [g/mol], v [Å/ps]: LAMMPS's own ``force->mvv2e``, 1.0364269e-4); eV/Å³ = 1.602176634e11 Pa
= 1.602176634e6 bar (LAMMPS's ``nktv2p`` 1.6021765e6).
"""

from __future__ import annotations

from dataclasses import dataclass

EV_J = 1.602176634e-19  # J per eV (exact)
ANGSTROM_M = 1e-10  # m per Å
PS_S = 1e-12  # s per ps
BAR_PA = 1e5  # Pa per bar
GPA_PA = 1e9  # Pa per GPa (a units-metal scene's pressures, e.g. sample.lattice_pressure)
AMU_KG = 1.66053906660e-27  # kg per atomic mass unit (g/mol per atom)
KB_EV_K = 8.617333262e-5  # Boltzmann constant [eV/K] (exact to its digits: k_B/e)


@dataclass(frozen=True)
class UnitSystem:
    """One LAMMPS unit system: what one of its units is in SI (``length_m`` [m],
    ``time_s`` [s], ``energy_J`` [J], ``mass_kg`` [kg per mass unit]; NaN for units lj,
    which has no SI without a model's σ, ε, m), ``k_B`` [energy/temperature] and ``mvv2e``
    (mass·velocity² → energy), ``pv_energy`` (LAMMPS's pressure·volume, the unit of
    ``compute stress/atom``, → energy: metal bar·Å³ → eV, 1/nktv2p). Derived: ``velocity_m_s`` = length/time, ``pressure_Pa`` =
    energy/length³, ``bar`` in energy/length³ (metal: 1/nktv2p)."""

    name: str
    length_m: float
    time_s: float
    energy_J: float
    mass_kg: float
    k_B: float
    mvv2e: float
    pv_energy: float = 1.0

    @property
    def velocity_m_s(self) -> float:
        """m/s per velocity unit (metal: 1 Å/ps = 100 m/s)."""
        return self.length_m / self.time_s

    @property
    def pressure_Pa(self) -> float:
        """Pa per energy/length³ (metal: 1 eV/Å³ = 1.602176634e11 Pa)."""
        return self.energy_J / self.length_m**3

    @property
    def si(self) -> bool:
        """Whether this system converts to SI (metal) or stays reduced (lj)."""
        return self.length_m == self.length_m  # NaN for lj


METAL = UnitSystem(
    "metal", length_m=ANGSTROM_M, time_s=PS_S, energy_J=EV_J, mass_kg=AMU_KG, k_B=KB_EV_K,
    mvv2e=AMU_KG * (ANGSTROM_M / PS_S) ** 2 / EV_J, pv_energy=BAR_PA * ANGSTROM_M**3 / EV_J,
)  # fmt: skip
LJ = UnitSystem("lj", *(float("nan"),) * 4, k_B=1.0, mvv2e=1.0)
UNIT_SYSTEMS = {"lj": LJ, "metal": METAL}


def unit_system(model: dict) -> UnitSystem:
    """The unit system of a scene's ``model`` block (``model.units``, default lj)."""
    return UNIT_SYSTEMS[model.get("units", "lj")]


def number_density_factor(mass: float, units: UnitSystem = METAL) -> float:
    """kg m⁻³ per (atoms per length³) for atoms of ``mass`` [g/mol]: ρ = n m u_kg/length³
    (metal: n [Å⁻³] → ρ [kg/m³] = n · 63.546 · 1.66054e-27 / 1e-30 for copper)."""
    return mass * units.mass_kg / units.length_m**3


def specific_energy_factor(mass: float, units: UnitSystem = METAL) -> float:
    """J kg⁻¹ per energy unit per atom for atoms of ``mass`` [g/mol]: E = e · eV/(m u_kg)."""
    return units.energy_J / (mass * units.mass_kg)


def si_pole(pole: dict[str, float], mass: float, units: UnitSystem = METAL) -> dict[str, float]:
    """A pole measured in native units (ρ0 [length⁻³], P0, Pyy0 [energy/length³], E0
    [energy per atom], T0 [K]; each with ``_err``; an inflow's screened flow du [velocity]
    and its count ``screened``) in SI: ρ0 [kg/m³], P0, Pyy0 [Pa], E0 [J/kg], T0 [K], du
    [m/s] (``number_density_factor``, ``pressure_Pa``, ``specific_energy_factor``,
    ``velocity_m_s``)."""
    factor = {"rho0": number_density_factor(mass, units), "P0": units.pressure_Pa,
              "Pyy0": units.pressure_Pa, "E0": specific_energy_factor(mass, units), "T0": 1.0,
              "du": units.velocity_m_s, "screened": 1.0}  # fmt: skip
    out = {}
    for key, value in pole.items():
        out[key] = float(value) * factor[key.removesuffix("_err")]
    return out
