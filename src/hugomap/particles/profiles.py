"""Profiles along x: number density, velocity, pressure tensor, temperature, energy per atom,
for both particle backends: the fields made of the per-bin sums (``fields_from_sums``; the
sums themselves by the one binning kernel ``particles.bins.bin_sums``, which the numba MD
and LAMMPS's per-atom arrays both go through) and the profile reader the shock methods use
(``ParticleProfile``). No numba here: the aggregation and the reader load without it.

Atoms are binned by x into slabs of width w [σ] across the full transverse area A = L_y L_z.
For a slab with c atoms, volume V_b = A w (m = 1, k_B = 1):
    n      = c / V_b                                             [σ⁻³]
    ū_a    = Σ v_a / c                                           [σ/τ]
    K_aa   = Σ (v_a − ū_a)² = Σ v_a² − c ū_a²                     [ε]
    P_aa   = (K_aa + Σ W_aa) / V_b   (compression positive, −σ_aa) [ε σ⁻³]
    T      = (K_xx + K_yy + K_zz) / (3 (c − 1))   (3 d.o.f. lost to ū) [ε/k_B]
    e      = (½ Σ_a K_aa + Σ pe) / c   (specific internal energy)  [ε per atom]
"""

from __future__ import annotations

import numpy as np

from ..states import SlabState

# Columns of the raw per-bin sums.
SUM_FIELDS = ("count", "vx", "vy", "vz", "vxx", "vyy", "vzz", "pe", "wxx", "wyy", "wzz")


def fields_from_sums(sums: np.ndarray, bin_volume: float) -> dict[str, np.ndarray]:
    """Turn raw sums (..., nbins, 11) into the profile fields of the module docstring."""
    s = np.asarray(sums, dtype=float)
    c = s[..., 0]
    with np.errstate(invalid="ignore", divide="ignore"):
        u = s[..., 1:4] / c[..., None]
        kin = s[..., 4:7] - c[..., None] * u * u
        kin_tot = kin.sum(axis=-1)
        out = {
            "n": c / bin_volume,
            "ux": u[..., 0],
            "Pxx": (kin[..., 0] + s[..., 8]) / bin_volume,
            "Pyy": (kin[..., 1] + s[..., 9]) / bin_volume,
            "Pzz": (kin[..., 2] + s[..., 10]) / bin_volume,
            "T": np.where(c > 1, kin_tot / (3.0 * (c - 1.0)), np.nan),
            "e": (0.5 * kin_tot + s[..., 7]) / c,
        }
    return out


PROFILE_UNITS = {
    "n": ("sigma^-3", "number density"),
    "ux": ("sigma tau^-1", "mean x velocity"),
    "Pxx": ("epsilon sigma^-3", "longitudinal pressure-tensor component P_xx = -sigma_xx"),
    "Pyy": ("epsilon sigma^-3", "transverse pressure-tensor component P_yy = -sigma_yy"),
    "Pzz": ("epsilon sigma^-3", "transverse pressure-tensor component P_zz = -sigma_zz"),
    "T": ("epsilon k_B^-1", "temperature from velocities relative to the bin mean"),
    "e": ("epsilon", "specific internal energy per atom (thermal kinetic + potential)"),
}


class ParticleProfile:
    """Profile reader of a particle run in reduced LJ units (the numba MD's, LAMMPS units
    lj's; units metal: ``lammps.backend.MetalProfile``): bins of ``bin_width`` [σ] from
    x = 0 across the transverse ``area`` [σ²]; fields by ``fields_from_sums`` (n is also the
    mass density, m = 1)."""

    x0 = 0.0

    def __init__(self, area: float, bin_width: float):
        self.area = float(area)
        self.bin_width = float(bin_width)

    def sums(self, solver) -> np.ndarray:
        return solver.profile_sums(self.bin_width)

    def velocity(self, sums: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        c = sums[:, 0]
        with np.errstate(invalid="ignore", divide="ignore"):
            return sums[:, 1] / c, c

    def state(self, summed: np.ndarray, n_bins: int) -> SlabState:
        f = fields_from_sums(summed[None, :], self.area * self.bin_width * n_bins)
        return SlabState(rho=float(f["n"][0]), u=float(f["ux"][0]), P=float(f["Pxx"][0]),
                         Pyy=float(f["Pyy"][0]), Pzz=float(f["Pzz"][0]), E=float(f["e"][0]),
                         T=float(f["T"][0]))  # fmt: skip
