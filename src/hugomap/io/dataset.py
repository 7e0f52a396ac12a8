"""netCDF layout of Hugoniot points and per-scene aggregates (the only place that knows it).

A point file holds scalar variables (value and ``_err`` standard error) with ``units`` and
``long_name``, the point's ``status`` (and its code ``status_flag``) and ``diagnostic``, its
cost, and the front history. The aggregate ``results/hugoniot/<scene>.nc`` has dimensions
``scheme`` × ``u_p`` (the nominal piston velocity); the pole, the model and the resolved
config travel with it.

Every point file, aggregate and campaign dataset follows CF-1.11 (``cf_dataset``, applied by
``io.atomic.write_netcdf`` to any dataset whose ``Conventions`` attribute names CF): units
UDUNITS can read, LJ reduced quantities as ``units = "1"`` with their reduced unit in
``reduced_units``, flags on ``converged`` and ``status_flag``, no ``_FillValue`` on
coordinates, string labels stored as character arrays, and an index coordinate on every
dimension that has none so that files of different lengths combine (``open_scenes``,
``open_points``). docs/datasets.md describes the layout for users.
"""

from __future__ import annotations

import json
import logging
import math
import re
import subprocess
import time
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path

import netCDF4
import numpy as np
import xarray as xr

from .. import __version__
from ..failures import FAILURES, MEASURED
from ..keys import config_hash

log = logging.getLogger("hugomap")

P_UNIT = "epsilon sigma^-3"
POINT_VARS: dict[str, tuple[str, str]] = {
    "D": ("sigma tau^-1", "shock velocity relative to the upstream material"),
    "D_front": ("sigma tau^-1", "window points: D from the change-point front tracker (check)"),
    "omega_drift": ("sigma tau^-1", "window points: front drift L d(omega)/dt while averaged"),
    "u_p_measured": ("sigma tau^-1", "measured particle-velocity jump across the front"),
    "u_p_set": ("sigma tau^-1", "particle-velocity jump set by the window, u_out - u_in"),
    "u_p_jump": (
        "sigma tau^-1",
        "particle-velocity jump the jump conditions use: the piston's velocity (exact), a "
        "window's measured slab (u_p_measured)",
    ),
    "u_p_P_corr": ("1", "correlation of the errors of u_p_measured and P (one slab)"),
    "rho": ("sigma^-3", "number density behind the front"),
    "V": ("sigma^3", "specific volume behind the front (per atom, m = 1)"),
    "P": (P_UNIT, "longitudinal stress behind the front, P_xx = -sigma_xx"),
    "Pyy": (P_UNIT, "transverse stress behind the front, P_yy"),
    "Pzz": (P_UNIT, "transverse stress behind the front, P_zz"),
    "P_rh": (P_UNIT, "Rayleigh-line pressure P0 + rho0 D u_p_jump"),
    "T": ("epsilon k_B^-1", "temperature behind the front"),
    "E": ("epsilon", "specific internal energy behind the front (per atom)"),
    "E_minus_E0": ("epsilon", "specific internal energy jump E - E0"),
    "shear_stress": (P_UNIT, "(P_xx - (P_yy + P_zz)/2) / 2 behind the front"),
    # Across the tracked front, from the pole (1 = 0) or, when two_wave = 1, from the state
    # just ahead of it (1 = ahead_*).
    "residual_mass": ("1", "relative residual of rho1 (D - u1) = rho (D - u_p_jump)"),
    "residual_momentum": ("1", "relative residual of P - P1 = rho1 (D - u1)(u_p_jump - u1)"),
    "residual_energy": ("1", "relative residual of E - E1 = (P + P1)(V1 - V)/2"),
    "residual_flow": (
        "1",
        "the shocked slab's flow relative to the boundary behind it, (u_p_measured - u_p)/u_p "
        "(a closure for the piston, a diagnostic for a window)",
    ),
    "ahead_rho": ("sigma^-3", "number density just ahead of the tracked front"),
    "ahead_P": (P_UNIT, "P_xx just ahead of the tracked front (P0 unless a precursor runs)"),
    "ahead_E": ("epsilon", "specific internal energy just ahead of the tracked front"),
    "ahead_u": ("sigma tau^-1", "particle velocity just ahead of the tracked front"),
    "two_wave": ("1", "1 when an elastic precursor runs ahead of the tracked front"),
    "elastic_front": (
        "1",
        "1 when the slab behind the front holds a shear stress above 5 % of P - P0 (and 3 "
        "errors): a front that has not yielded, on the elastic branch",
    ),
    "relaxation_length": (
        "sigma",
        "window points: the relaxation zone, the distance behind the front over which the "
        "mean P_xx differs from the slab's by more than residual_tol of the jump",
    ),
    "precursor_D": (
        "sigma tau^-1",
        "two waves: the elastic precursor's speed relative to the upstream material (its "
        "state is ahead_*); NaN with one wave or once the precursor has left the measured region",
    ),
    "ahead_off_pole": (
        "1",
        "1 when the state ahead is off the pole beyond 3 errors and residual_tol of the jump "
        "(the point is then not ok)",
    ),
    "u_p_flow_err": (
        "sigma tau^-1",
        "uncertainty of the jump from the shocked slab's own flow "
        "(hypot(u_p_measured - u_p, its error))",
    ),
    "P_flow_err": (
        P_UNIT,
        "part of P_err from that flow beyond its noise: "
        "rho0 D sqrt(max(0, (u_p_measured - u_p)^2 - u_p_measured_err^2)); 0 for a window "
        "point (its jump is taken at the slab's velocity)",
    ),
    "P_closure_err": (
        P_UNIT,
        "part of P_err from the momentum closure beyond its noise: half of "
        "sqrt(max(0, (P - P_rh)^2 - its error^2)), P_rh the Rayleigh line's pressure",
    ),
    "D_rel_err": ("1", "relative standard error of D, D_err / D"),
    "P_rel_err": ("1", "relative standard error of the stress jump, P_err / |P - P0|"),
    "target_D": ("1", "the scene's target for D_rel_err (NaN: none asked)"),
    "target_P": ("1", "the scene's target for P_rel_err (NaN: none asked)"),
    "time_to_target": (
        "tau",
        "the averaging (window) or steady drive (piston) the point needed or would need to "
        "meet its target, from its error-vs-time law; NaN without a target",
    ),
    "sample_factor": (
        "1",
        "piston points: how many times the scene's sample the point was run on (more than 1: "
        "a first run missed the target, target.max_sample_factor)",
    ),
    "pilot_D_rel_err": ("1", "piston points run again: the first run's D_rel_err"),
    "pilot_P_rel_err": ("1", "piston points run again: the first run's P_rel_err"),
    "n_samples": ("1", "profile samples averaged"),
    "average_time": ("tau", "window points: how long the steady state was averaged"),
    "wall_s": ("s", "wall-clock time of the point (load + drive)"),
    "cpu_s": ("s", "CPU time of the point (load + drive), all threads"),
    "atom_steps": ("1", "atoms x time steps of the point (load + drive)"),
    "ranks": ("1", "MPI ranks of the point's last job (1: no MPI)"),
    "piston_velocity": ("sigma tau^-1", "nominal piston velocity"),
}
POLE_VARS: dict[str, tuple[str, str]] = {
    "rho0": ("sigma^-3", "pole: number density of the prepared sample"),
    "P0": (P_UNIT, "pole: longitudinal stress P_xx of the prepared sample"),
    "E0": ("epsilon", "pole: specific internal energy of the prepared sample"),
    "T0": ("epsilon k_B^-1", "pole: temperature of the prepared sample"),
    "Pyy0": (P_UNIT, "pole: transverse stress P_yy of the prepared sample"),
}
ERR_SUFFIX = "_err"
# Every point file carries these with their standard errors (NaN for a failed point), so an
# aggregate has the same layout whichever points failed (a scene whose every point failed
# still has D_err).
ALWAYS_WITH_ERR = ("D", "u_p_measured", "u_p_jump", "rho", "V", "P", "E", "E_minus_E0",
                   "residual_mass", "residual_momentum", "residual_energy",
                   "residual_flow")  # fmt: skip

# -- unit tables ---------------------------------------------------------------------------
# The tables above are in Lennard-Jones reduced units (written to files as units = "1" with
# the reduced unit in ``reduced_units``: ``cf_units``); a backend in SI translates every unit
# (written the UDUNITS way) and reads "number density"/"per atom" as mass density/per unit
# mass, and adds the variables only it has. A backend hands its table to the functions below.
SI_UNITS = {
    "sigma tau^-1": "m s-1", "sigma^-3": "kg m-3", "sigma^3": "m3 kg-1", P_UNIT: "Pa",
    "epsilon k_B^-1": "K", "epsilon": "J kg-1", "tau": "s", "sigma": "m", "tau^-1": "s-1",
}  # fmt: skip
_SI_TEXT = (
    ("number density", "mass density"), ("(per atom, m = 1)", "(per unit mass)"),
    ("(per atom)", "(per unit mass)"), ("atoms x time steps", "particles x time steps"),
)  # fmt: skip
PROFILE_VARS: dict[str, tuple[str, str]] = {
    "x": ("sigma", "bin centre (window frame)"),
    "rho": ("sigma^-3", "steady profile: number density"),
    "u": ("sigma tau^-1", "steady profile: mean x velocity (window frame)"),
    "P": (P_UNIT, "steady profile: longitudinal stress P_xx"),
    "T": ("epsilon k_B^-1", "steady profile: temperature"),
}


@dataclass(frozen=True)
class UnitTable:
    """Names, units and long names of a backend's dataset variables: ``point`` (a Hugoniot
    point's scalars), ``pole``, ``profile`` (the steady window profile) and the ``axes``
    units of ``velocity``, ``time``, ``length``; ``system`` names the unit system."""

    point: dict[str, tuple[str, str]]
    pole: dict[str, tuple[str, str]]
    profile: dict[str, tuple[str, str]]
    axes: dict[str, str]
    system: str


def _si(table: dict[str, tuple[str, str]]) -> dict[str, tuple[str, str]]:
    out = {}
    for k, (u, ln) in table.items():
        for a, b in _SI_TEXT:
            ln = ln.replace(a, b)
        out[k] = (SI_UNITS.get(u, u), ln)
    return out


def lj_units() -> UnitTable:
    """Lennard-Jones reduced units (σ, ε, m, τ = σ√(m/ε), k_B = 1)."""
    axes = {"velocity": "sigma tau^-1", "time": "tau", "length": "sigma"}
    return UnitTable(POINT_VARS, POLE_VARS, PROFILE_VARS, axes, "LJ reduced")


def si_units(extra: dict[str, tuple[str, str]] | None = None) -> UnitTable:
    """SI units (m, s, kg, Pa, J/kg, K), with a backend's ``extra`` point variables."""
    axes = {"velocity": "m s-1", "time": "s", "length": "m"}
    return UnitTable({**_si(POINT_VARS), **(extra or {})}, _si(POLE_VARS), _si(PROFILE_VARS),
                     axes, "SI (m, s, kg)")  # fmt: skip


POINT_TEXT = {
    "status": "ok, target_not_reached (ok but its errors above the scene's target), "
    "not_converged, or why the run stopped",
    "diagnostic": "what happened, for a failed or unconverged point",
}


def git_commit(path: str | Path = ".") -> str:
    """The git commit of the working tree at ``path`` (``unknown`` outside git)."""
    try:
        out = subprocess.run(
            ["git", "rev-parse", "HEAD"], cwd=path, capture_output=True, text=True, timeout=10
        )
        return out.stdout.strip() or "unknown"
    except (OSError, subprocess.SubprocessError):
        return "unknown"


def scalar_vars(values: dict, table: dict[str, tuple[str, str]]) -> dict[str, xr.Variable]:
    """Scalar variables (and ``_err`` companions) for every key of ``table`` in ``values``."""
    out = {}
    for name, (units, long_name) in table.items():
        if name in values:
            out[name] = xr.Variable(
                (), float(values[name]), {"units": units, "long_name": long_name}
            )
        if name + ERR_SUFFIX in values:
            out[name + ERR_SUFFIX] = xr.Variable(
                (),
                float(values[name + ERR_SUFFIX]),
                {"units": units, "long_name": f"standard error of {name} (block averages)"},
            )
    return out


def provenance_attrs(config: dict | None) -> dict[str, str]:
    """Resolved config (JSON), its hash, the package version and the git commit."""
    cfg = config or {}
    return {
        "config_json": json.dumps(cfg, sort_keys=True),
        "config_hash": config_hash(cfg),
        "hugomap_version": __version__,
        "git_commit": git_commit(Path(__file__).parent),
    }


# -- CF-1.11 -------------------------------------------------------------------------------
CONVENTIONS = "CF-1.11"
REDUCED_ATTR = "reduced_units"
LJ_SYMBOLS = frozenset({"sigma", "epsilon", "tau", "k_B"})
UNITS_CONVENTION = (
    "units are UDUNITS strings; a Lennard-Jones reduced quantity has units = '1' and names "
    "its reduced unit in the attribute reduced_units (sigma, epsilon, m, "
    "tau = sigma sqrt(m/epsilon), k_B = 1; per-atom V and E, number density rho)"
)
REFERENCES = (
    "Murzov, Dyachkov, Vyskvarko, Galtsov and Levashov, Voprosy Atomnoi Nauki i Tekhniki "
    "(VANT), ser. Mathematical modelling of physical processes, 2025, no. 1 (the moving-window "
    "method and its control schemes)"
)
#: The status of an aggregate's (scheme, u_p) that has no point: not run there
#: (``schemes: [auto]`` chose another scheme at that u_p).
NOT_RUN = "not_run"
#: ``status_flag`` codes: index into this tuple (a status not listed is ``unregistered``).
STATUS_FLAGS: tuple[str, ...] = (*MEASURED, *FAILURES, NOT_RUN, "unregistered")
CONVERGED_FLAGS = {"flag_values": np.array([0, 1], np.int8),
                   "flag_meanings": "not_converged converged"}  # fmt: skip


def cf_units(units: str) -> tuple[str, str | None]:
    """(UDUNITS units, reduced unit or None) of a table's ``units`` string: an LJ reduced
    unit (one naming sigma, epsilon, tau or k_B, e.g. ``"sigma tau^-1"``) becomes ``"1"``
    and is returned as the reduced unit; any other is written the UDUNITS way
    (``"m s^-1"`` → ``"m s-1"``)."""
    text = str(units)
    if any(re.sub(r"\^?-?\d+$", "", t) in LJ_SYMBOLS for t in text.split()):
        return "1", text
    return re.sub(r"\^(-?\d+)", r"\1", text), None


def status_codes(status: np.ndarray) -> np.ndarray:
    """``status_flag`` of status strings: their index in ``STATUS_FLAGS`` (int8)."""
    index = {s: i for i, s in enumerate(STATUS_FLAGS)}
    other = len(STATUS_FLAGS) - 1
    arr = np.asarray(status, dtype=object)
    return np.vectorize(lambda s: index.get(str(s), other), otypes=[np.int8])(arr)


def cf_dataset(ds: xr.Dataset) -> xr.Dataset:
    """``ds`` made CF-1.11 conformant (a shallow copy; ``io.atomic.write_netcdf`` calls it for
    every dataset whose ``Conventions`` names CF, so variables added after ``point_dataset``
    are covered too).

    - ``units`` through ``cf_units``: LJ reduced → ``"1"`` plus ``reduced_units``.
    - ``converged`` gets ``flag_values``/``flag_meanings``; a string ``status`` gets its
      code ``status_flag`` (``STATUS_FLAGS``), the string kept for readers.
    - every dimension without a coordinate gets an integer index coordinate (0, 1, …), so
      files whose ``ref_point``/``sample``/``bin`` lengths differ combine by an outer join.
    - coordinates are written without ``_FillValue``; a string dimension coordinate
      (``scheme``) as a character array (CF labels; xarray reads it back as strings).
    - global ``Conventions``, ``title``, ``source``, ``references``, ``units_convention``,
      and a ``history`` line (UTC time, package version, title) appended.
    """
    ds = ds.copy(deep=False)
    for var in ds.variables.values():
        if "units" in var.attrs:
            cf, reduced = cf_units(var.attrs["units"])
            var.attrs["units"] = cf
            if reduced is not None:
                var.attrs.setdefault(REDUCED_ATTR, reduced)
    if "converged" in ds.variables:
        attrs = ds["converged"].attrs
        attrs.pop("units", None)
        attrs.update(CONVERGED_FLAGS)
        ds["converged"] = ds["converged"].astype(np.int8)
    if "status" in ds.variables and ds["status"].dtype.kind in "OUS":
        ds["status_flag"] = (ds["status"].dims, status_codes(ds["status"].values), {
            "long_name": "status as a flag (the status variable holds the same as text)",
            "flag_values": np.arange(len(STATUS_FLAGS), dtype=np.int8),
            "flag_meanings": " ".join(STATUS_FLAGS),
        })  # fmt: skip
    for dim, n in list(ds.sizes.items()):
        if dim not in ds.coords:
            ds = ds.assign_coords({dim: (dim, np.arange(n, dtype=np.int32),
                                         {"long_name": f"index along {dim}", "units": "1"})})  # fmt: skip
    for name in ds.coords:
        var = ds.variables[name]
        var.attrs.pop("_FillValue", None)
        if "long_name" not in var.attrs and "standard_name" not in var.attrs:
            var.attrs["long_name"] = f"index along {name}" if var.dtype.kind in "iu" else name
        if var.dtype.kind in "OUS":
            if var.dims == (name,):
                var.encoding["dtype"] = "S1"
        else:
            var.encoding["_FillValue"] = None
    title = str(ds.attrs.get("title") or "hugomap dataset")
    stamp = time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime())
    line = f"{stamp} hugomap {__version__}: {title}"
    old = str(ds.attrs.get("history", ""))
    ds.attrs.update(
        Conventions=CONVENTIONS,
        title=title,
        source=str(ds.attrs.get("source") or f"hugomap {__version__}"),
        references=str(ds.attrs.get("references") or REFERENCES),
        units_convention=UNITS_CONVENTION,
        history=f"{old}\n{line}" if old else line,
    )
    return ds


def jump_velocity(points: xr.Dataset) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The particle velocity each point's jump was taken at, its error and its correlation
    with P, for one scheme's points along ``u_p`` (an aggregate's ``.sel(scheme=...)``):
    ``u_p_jump``, ``u_p_jump_err``, ``u_p_P_corr`` (the piston's speed, a window's slab);
    in files without them the window's ``u_p_set`` (MW's amplitude; AMW and the dichotomy
    hold the nominal one) or the ``u_p`` coordinate, error and correlation 0."""
    nan = np.full(points.sizes["u_p"], np.nan)

    def col(k: str) -> np.ndarray:
        return points[k].values.astype(float) if k in points else nan

    u_set = col("u_p_set")
    u = np.where(np.isfinite(u_set), u_set, points["u_p"].values.astype(float))
    jump = col("u_p_jump")
    has = np.isfinite(jump)
    err, corr = col("u_p_jump_err"), col("u_p_P_corr")
    return (np.where(has, jump, u), np.where(has & np.isfinite(err), err, 0.0),
            np.where(has & np.isfinite(corr), corr, 0.0))  # fmt: skip


# -- SI values of LJ quantities (a scene's ``units`` block) ---------------------------------
K_B = 1.380649e-23  # Boltzmann constant [J K-1], exact since the 2019 SI
#: Quantities that get an ``<name>_SI`` (and ``<name>_SI_err``) companion, also as ``ref_*``.
SI_QUANTITIES = ("u_p", "piston_velocity", "u_p_set", "u_p_measured", "u_p_jump", "D", "rho",
                 "V", "P", "P_rh", "T", "E", "E_minus_E0", "rho0", "P0", "E0", "T0")  # fmt: skip
SI_SUFFIX = "_SI"


def lj_si_factors(lj: Mapping[str, float]) -> dict[str, tuple[float, str]]:
    """Reduced unit → (SI value of one reduced unit, UDUNITS unit) for an LJ model with
    ``lj`` = {sigma [m], epsilon_over_kB [K], mass [kg]} (a scene's ``units`` block):
    ε = k_B (ε/k_B) [J], τ = σ √(m/ε) [s]; velocity σ/τ [m s-1], number density → mass
    density m/σ³ [kg m-3], volume per atom → per mass σ³/m [m3 kg-1], pressure ε/σ³ [Pa],
    temperature ε/k_B [K], energy per atom → per mass ε/m [J kg-1], time τ [s], length σ [m].
    """
    sigma, mass = float(lj["sigma"]), float(lj["mass"])
    eps = K_B * float(lj["epsilon_over_kB"])
    tau = sigma * math.sqrt(mass / eps)
    return {
        "sigma tau^-1": (sigma / tau, "m s-1"), "sigma^-3": (mass / sigma**3, "kg m-3"),
        "sigma^3": (sigma**3 / mass, "m3 kg-1"), P_UNIT: (eps / sigma**3, "Pa"),
        "epsilon k_B^-1": (float(lj["epsilon_over_kB"]), "K"), "epsilon": (eps / mass, "J kg-1"),
        "tau": (tau, "s"), "sigma": (sigma, "m"),
    }  # fmt: skip


def si_attrs(lj: Mapping[str, float]) -> dict[str, float]:
    """Global attributes that record the LJ model of the ``_SI`` variables."""
    eps = K_B * float(lj["epsilon_over_kB"])
    return {
        "lj_sigma_m": float(lj["sigma"]), "lj_epsilon_over_kB_K": float(lj["epsilon_over_kB"]),
        "lj_mass_kg": float(lj["mass"]), "lj_tau_s": float(lj["sigma"]) * math.sqrt(float(lj["mass"]) / eps),
    }  # fmt: skip


def si_companions(ds: xr.Dataset, lj: Mapping[str, float]) -> dict[str, xr.Variable]:
    """SI copies of the ``SI_QUANTITIES`` (and their ``_err``, and the reference's ``ref_*``)
    of a dataset in LJ reduced units: ``D`` → ``D_SI``, ``D_err`` → ``D_SI_err``,
    ``ref_P`` → ``ref_P_SI``, the ``u_p`` coordinate → ``u_p_SI``; values times
    ``lj_si_factors(lj)`` of the variable's reduced unit (``reduced_units``, else ``units``)."""
    factors = lj_si_factors(lj)
    out = {}
    for name, var in ds.variables.items():
        ref = name.startswith("ref_")
        base = name[4:] if ref else name
        err = base.endswith(ERR_SUFFIX)
        q = base[: -len(ERR_SUFFIX)] if err else base
        unit = var.attrs.get(REDUCED_ATTR, var.attrs.get("units"))
        if q not in SI_QUANTITIES or unit not in factors or var.dtype.kind != "f":
            continue
        f, si = factors[unit]
        new = ("ref_" if ref else "") + q + SI_SUFFIX + (ERR_SUFFIX if err else "")
        long_name = str(var.attrs.get("long_name", name))
        out[new] = xr.Variable(var.dims, np.asarray(var.values, dtype=float) * f,
                               {"units": si, "long_name": f"{long_name} (SI, from the units block)"})  # fmt: skip
    return out


def with_si(ds: xr.Dataset, scene: Mapping) -> xr.Dataset:
    """``ds`` with ``si_companions`` and ``si_attrs`` when the scene has a ``units`` block
    (MD); else ``ds`` unchanged."""
    lj = scene.get("units") if isinstance(scene, Mapping) else None
    if not lj:
        return ds
    ds = ds.assign(si_companions(ds, lj))
    ds.attrs.update(si_attrs(lj))
    return ds


def control_vars(history, units: UnitTable) -> dict:
    """The control loop's record (``methods.control.ControlHistory``) as dataset variables:
    per averaging window k ``control_{t, a, a_err, omega, u_in, u_out, du}`` and the raw ω
    samples ``omega_t``, ``omega_value``, in the backend's units."""
    time_unit, velocity_unit = units.axes["time"], units.axes["velocity"]
    a = history.arrays()
    names = {
        "t": (time_unit, "end of averaging window k"),
        "a": (f"{time_unit}^-1", "slope a_k of omega(t) = a_k t + b_k"),
        "a_err": (f"{time_unit}^-1", "standard error of a_k"),
        "omega": ("1", "mean omega over window k"),
        "u_in": (velocity_unit, "inflow velocity (window frame)"),
        "u_out": (velocity_unit, "outflow velocity (window frame)"),
        "du": (velocity_unit, "correction applied after window k"),
    }
    out = {f"control_{k}": ("window_k", a[k], {"units": u, "long_name": ln})
           for k, (u, ln) in names.items()}  # fmt: skip
    out["omega_t"] = ("omega_sample", a["samples_t"], {"units": time_unit, "long_name": "time"})
    out["omega_value"] = ("omega_sample", a["samples_omega"], {"units": "1", "long_name": "omega"})
    return out


def average_vars(h: dict[str, np.ndarray], units: UnitTable) -> dict:
    """A window point's steady average chunk by chunk (``methods.steady.steady_state``'s
    ``chunk_*``): its length, the relative errors of D and P it stated then, and the point's
    CPU so far (loading and window set-up counted), along ``chunk``: the point's error
    against its cost, the data of the CPU a target costs."""
    names = {
        "chunk_T": (units.axes["time"], "length of the steady average at the end of chunk k"),
        "chunk_D_rel_err": ("1", "D_err / D stated over the average up to chunk k"),
        "chunk_P_rel_err": ("1", "P_err / |P - P0| stated over the average up to chunk k"),
        "chunk_cpu_s": ("s", "CPU time of the point up to chunk k, its loading counted"),
    }
    return {k: ("chunk", np.asarray(h[k], dtype=float), {"units": u, "long_name": ln})
            for k, (u, ln) in names.items() if k in h}  # fmt: skip


def profile_vars(profile: dict[str, np.ndarray], units: UnitTable) -> dict:
    """The steady window profile (``methods.steady.mean_profile``) as ``profile_*`` variables
    along ``bin``; fields without a unit in the table are left out."""
    return {f"profile_{k}": ("bin", v, {"units": units.profile[k][0],
                                        "long_name": units.profile[k][1]})
            for k, v in profile.items() if k in units.profile}  # fmt: skip


def point_dataset(
    values: dict,
    pole: dict,
    history: dict[str, np.ndarray] | None,
    scheme: str,
    scene: str,
    status: str,
    diagnostic: str,
    scene_config: dict,
    units: UnitTable,
) -> xr.Dataset:
    """One Hugoniot point as a Dataset (NaN-filled where a failed run has no value), in the
    backend's ``units``; with SI companions (``with_si``) when the scene has a ``units``
    block. It declares CF-1.11: ``io.atomic.write_netcdf`` writes it through ``cf_dataset``."""
    point_vars, pole_vars, axes = units.point, units.pole, units.axes
    vals = {k: values.get(k, np.nan) for k in point_vars}
    vals.update(
        {
            k + ERR_SUFFIX: values.get(k + ERR_SUFFIX, np.nan)
            for k in point_vars
            if k + ERR_SUFFIX in values or k in ALWAYS_WITH_ERR
        }
    )
    data = scalar_vars(vals, point_vars)
    data.update(scalar_vars(pole, pole_vars))
    data["converged"] = xr.Variable(
        (),
        np.int8(bool(values.get("converged", False))),
        {"units": "1", "long_name": "1 if every jump residual is within tolerance"},
    )
    data["status"] = xr.Variable((), str(status), {"long_name": POINT_TEXT["status"]})
    data["diagnostic"] = xr.Variable((), str(diagnostic), {"long_name": POINT_TEXT["diagnostic"]})
    if history is not None and len(history.get("t", [])):
        data["history_t"] = xr.Variable(
            ("sample",), history["t"], {"units": axes["time"], "long_name": "sample time"}
        )
        data["history_front"] = xr.Variable(
            ("sample",),
            history["front"],
            {"units": axes["length"], "long_name": "front position (piston frame)"},
        )
        data["history_stage"] = xr.Variable(
            ("sample",), history["stage"], {"units": "1", "long_name": "0 load, 1 drive"}
        )
        if "omega" in history:  # a window's steady average: its ω samples, for error studies
            data["history_omega"] = xr.Variable(
                ("sample",), history["omega"], {"units": "1", "long_name": "omega (front fraction)"}
            )
        slab = {"u_slab": ("u_p_measured", "velocity of the slab behind, relative to the upstream"),
                "P_slab": ("P", "P_xx of the slab behind")}  # fmt: skip
        for k, (unit_of, text) in slab.items():  # the series a point's block errors come from
            if k in history:
                data["history_" + k] = xr.Variable(
                    ("sample",), history[k], {"units": point_vars[unit_of][0], "long_name": text}
                )
    ds = xr.Dataset(data)
    ds.attrs.update(
        Conventions=CONVENTIONS,
        title=f"Hugoniot point of scene {scene}, scheme {scheme}",
        scheme=scheme,
        scene=scene,
        unit_system=units.system,
        scene_config=json.dumps(scene_config, sort_keys=True),
    )
    return with_si(ds, scene_config)


def _read_scalars(path: str | Path, var_attrs: dict[str, dict]) -> tuple[dict, dict]:
    """The 0-d variables of a point file and its global attributes, read with the file open
    once (the front history is not read). Attributes of variables not yet in ``var_attrs``
    are added to it."""
    with netCDF4.Dataset(str(path)) as nc:
        nc.set_auto_mask(False)
        values = {}
        for name, var in nc.variables.items():
            if var.ndim:
                continue
            v = var.getValue()  # much cheaper than var[...] for a scalar
            values[name] = v if isinstance(v, str) else v.item()
            if name not in var_attrs:
                var_attrs[name] = {
                    a: var.getncattr(a) for a in var.ncattrs() if not a.startswith("_")
                }
        return values, {a: nc.getncattr(a) for a in nc.ncattrs()}


CHECKPOINT_FORMAT_ATTRS = ("window_format", "format", "sim_format")  # io.checkpoint's kinds


def _not_a_point(variables: Mapping, attrs: Mapping) -> str | None:
    """None where a file with these variables (name: dimensions) and global attributes is
    a point file; else what it is instead (see ``point_file_problem``)."""
    dims = variables.get("status")
    if dims is not None and len(dims) == 0:
        return None
    stage = f", stage {attrs['stage']}" if "stage" in attrs else ""
    for a in CHECKPOINT_FORMAT_ATTRS:
        if a in attrs:
            return f"a checkpoint ({a} {attrs[a]}{stage}), not a point file"
    if "stage" in attrs and "status" in attrs:
        return (f"a checkpoint stage's failure record (stage {attrs['stage']}, status "
                f"{attrs['status']}), not a point file")  # fmt: skip
    if dims is not None:
        return f"a dataset of many points (status along {', '.join(dims)}), not a point file"
    return "not a point file (no 0-d status variable)"


def point_file_problem(path: str | Path) -> str | None:
    """None where ``path`` is a point file; else what it is instead, e.g. "a checkpoint
    (format hugomap-md-checkpoint/2, stage loaded), not a point file".

    A point file is told by its 0-d ``status`` variable, which ``point_dataset`` writes in
    every point (ok or failed) and nothing else hugomap writes has: checkpoints (the
    sample, ``loaded.nc``, ``window.nc``, a running piston's ``.part.nc``) carry ``status``
    as an attribute, or not at all; a checkpoint stage's failure record has attributes
    only; an aggregate's ``status`` lies along ``scheme`` × ``u_p``; a reference has none.
    Only the file's header is read. A file netCDF cannot open raises (``OSError``)."""
    with netCDF4.Dataset(str(path)) as nc:
        variables = {k: v.dimensions for k, v in nc.variables.items()}
        attrs = {a: nc.getncattr(a) for a in nc.ncattrs()}
    return _not_a_point(variables, attrs)


def aggregate_points(
    paths: Sequence[str | Path],
    scheme: str,
    reference: xr.Dataset | None,
    config: dict,
    scene: str,
    units: UnitTable,
) -> xr.Dataset:
    """Join point files into one dataset with dims ``scheme`` × ``u_p``, in the backend's
    ``units``.

    Each file is opened once, its scalars read and the file closed, so memory is the
    aggregate itself (about 70 numbers per point) and one open file, for any number of
    points. (``open_mfdataset`` was used before: beyond xarray's 128 cached file handles it
    reopened a file for every variable of every point, 300 points took 8 minutes and
    430 MB; a netCDF file of 0-d variables gains nothing from dask chunks.) A variable
    missing from some files (``_err`` values of failed points, the pole of a point whose
    loading failed) is NaN there; the pole is taken from the first point that has it.
    Of the points' global attributes only ``scene_config`` is kept (a point's ``scheme`` or
    window attributes say nothing of the aggregate). The reference's points lie along
    ``ref_point``, which gets an index coordinate when written (``cf_dataset``), so scenes
    with references of different lengths combine (``open_scenes``). (The SI companions of a
    scene with a ``units`` block are added to the joined aggregate: ``stages.aggregation``.)

    A path that is not a point file (``point_file_problem``: a checkpoint, an aggregate)
    is refused with a ValueError naming it and what it is: every path given is meant to be
    a point of the aggregate, and one left out would be a point silently lost.
    """
    if not paths:
        raise ValueError(f"scene {scene}: no point files to aggregate")
    rows: list[dict] = []
    var_attrs: dict[str, dict] = {}
    first_attrs: dict = {}
    for i, p in enumerate(paths):
        values, gattrs = _read_scalars(p, var_attrs)
        if not isinstance(values.get("status"), str):  # a 0-d status variable: a point
            problem = point_file_problem(p)
            if problem is not None:
                raise ValueError(f"scene {scene}: cannot aggregate {p}: {problem}")
        rows.append(values)
        if i == 0:
            first_attrs = {k: v for k, v in gattrs.items() if k == "scene_config"}
    point_vars, pole_vars, axes = units.point, units.pole, units.axes
    keep = [
        k for k in (*point_vars, *(k + ERR_SUFFIX for k in point_vars)) if k != "piston_velocity"
    ]
    pole_names = [*pole_vars, *(k + ERR_SUFFIX for k in pole_vars)]
    present = {k for r in rows for k in r}

    def column(k: str, fill: object = np.nan) -> np.ndarray:
        return np.array([r.get(k, fill) for r in rows])

    up = column("piston_velocity").astype(float)
    pts = xr.Dataset(
        {k: ("u_p", column(k).astype(float), var_attrs[k]) for k in keep if k in present},
        attrs=first_attrs,
    )
    pts["converged"] = (
        "u_p",
        column("converged", 0).astype(np.int8),
        var_attrs.get("converged", {}),
    )
    # Strings as objects: a fixed-width array would truncate to the widest seen so far.
    for k in ("status", "diagnostic"):
        pts[k] = ("u_p", np.array([str(r.get(k, "")) for r in rows], dtype=object))
        pts[k].attrs = {"long_name": POINT_TEXT[k]}
    pole = {}
    for k in pole_names:
        found = [r[k] for r in rows if k in r and np.isfinite(r[k])]
        if k in present:
            pole[k] = xr.Variable((), found[0] if found else np.nan, var_attrs[k])
    pts = pts.assign_coords(
        u_p=("u_p", up, {"units": axes["velocity"], "long_name": "nominal piston velocity"})
    )
    out = pts.expand_dims(scheme=[scheme])
    for k, v in pole.items():
        out[k] = v
    if reference is not None:
        model = reference.attrs.get("reference_model", "equilibrium MD")
        for name, var in reference.data_vars.items():
            out["ref_" + name] = var.rename({d: "ref_point" for d in var.dims})
            out["ref_" + name].attrs = dict(
                var.attrs,
                long_name=f"reference Hugoniot ({model}): " + var.attrs.get("long_name", name),
            )
    out.attrs.update(provenance_attrs(config))
    out.attrs.update(Conventions=CONVENTIONS, scene=scene, title=f"Hugoniot of scene {scene}",
                     unit_system=units.system)  # fmt: skip
    return out


# -- many files as one dataset (dask) ------------------------------------------------------
def _open_many(paths: Sequence[str | Path], dim: str, label, **kwargs) -> xr.Dataset:
    def preprocess(ds: xr.Dataset) -> xr.Dataset:
        # non-index coordinates (the reference's compression) vary per file: variables
        return ds.reset_coords().expand_dims({dim: [label(ds)]})

    opts = {"engine": "netcdf4", "combine": "nested", "concat_dim": dim, "join": "outer",
            "data_vars": "all", "coords": "minimal", "compat": "no_conflicts",
            "combine_attrs": "drop_conflicts", "preprocess": preprocess}  # fmt: skip
    opts.update(kwargs)
    return xr.open_mfdataset([str(p) for p in paths], **opts)


def open_scenes(paths: Sequence[str | Path], **kwargs) -> xr.Dataset:
    """Aggregates (``results/hugoniot/<scene>.nc``) as one lazy, dask-backed dataset with a
    leading ``scene`` dimension labelled by each file's ``scene`` attribute: ``u_p``,
    ``scheme`` and ``ref_point`` are joined outer (NaN where a scene has no such point);
    global attributes that differ between scenes (config, history) are dropped (each
    file keeps its own). ``kwargs`` go to ``xarray.open_mfdataset`` (e.g. ``chunks``)."""
    return _open_many(paths, "scene", lambda ds: str(ds.attrs.get("scene", "")), **kwargs)


def open_points(paths: Sequence[str | Path], **kwargs) -> xr.Dataset:
    """Point files as one lazy, dask-backed dataset along a ``point`` dimension labelled by
    each file's path; the front history (``sample``), steady profile (``bin``), control
    record (``window_k``, ``omega_sample``) and trials (``trial``) are NaN-padded to the
    longest; a variable a point lacks (a failed point's values) is NaN there. For many
    points' scalars only, ``aggregate_points`` is much faster (it reads no arrays).

    Paths that are not point files (``point_file_problem``: the checkpoints ``loaded.nc``,
    ``window.nc``, ``sample.nc`` and ``*.part.nc`` share the folder and the ``.nc``
    extension, so a glob such as ``up*/*.nc`` finds them) are skipped, each with a logged
    warning naming it and what it is; a ValueError if no point file is left."""
    points = []
    for p in paths:
        problem = point_file_problem(p)
        if problem is None:
            points.append(p)
        else:
            log.warning("open_points: skipping %s: %s", p, problem)
    if not points:
        raise ValueError(f"open_points: no point file among {len(paths)} path(s)")
    return _open_many(points, "point", lambda ds: str(ds.encoding.get("source", "")), **kwargs)
