"""netCDF layout of Hugoniot points and per-scene aggregates (the only place that knows it).

A point file holds scalar variables (value and ``_err`` standard error) with ``units`` and
``long_name``, the point's ``status`` and ``diagnostic``, its cost, and the front history.
The aggregate ``results/hugoniot/<scene>.nc`` has dimensions ``scheme`` × ``u_p`` (the
nominal piston velocity); the pole, the model and the resolved config travel with it.
"""

from __future__ import annotations

import json
import subprocess
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import netCDF4
import numpy as np
import xarray as xr

from .. import __version__
from ..keys import config_hash

P_UNIT = "epsilon sigma^-3"
POINT_VARS: dict[str, tuple[str, str]] = {
    "D": ("sigma tau^-1", "shock velocity relative to the upstream material"),
    "D_front": ("sigma tau^-1", "window points: D from the change-point front tracker (check)"),
    "omega_drift": ("sigma tau^-1", "window points: front drift L d(omega)/dt while averaged"),
    "u_p_measured": ("sigma tau^-1", "measured particle-velocity jump across the front"),
    "u_p_set": ("sigma tau^-1", "particle-velocity jump set by the window, u_out - u_in"),
    "rho": ("sigma^-3", "number density behind the front"),
    "V": ("sigma^3", "specific volume behind the front (per atom, m = 1)"),
    "P": (P_UNIT, "longitudinal stress behind the front, P_xx = -sigma_xx"),
    "Pyy": (P_UNIT, "transverse stress behind the front, P_yy"),
    "Pzz": (P_UNIT, "transverse stress behind the front, P_zz"),
    "P_rh": (P_UNIT, "Rayleigh-line pressure P0 + rho0 D u_p"),
    "T": ("epsilon k_B^-1", "temperature behind the front"),
    "E": ("epsilon", "specific internal energy behind the front (per atom)"),
    "E_minus_E0": ("epsilon", "specific internal energy jump E - E0"),
    "shear_stress": (P_UNIT, "(P_xx - (P_yy + P_zz)/2) / 2 behind the front"),
    # Across the tracked front, from the pole (1 = 0) or, when two_wave = 1, from the state
    # just ahead of it (1 = ahead_*).
    "residual_mass": ("1", "relative residual of rho1 (D - u1) = rho (D - u_p)"),
    "residual_momentum": ("1", "relative residual of P - P1 = rho1 (D - u1)(u_p - u1)"),
    "residual_energy": ("1", "relative residual of E - E1 = (P + P1)(V1 - V)/2"),
    "ahead_rho": ("sigma^-3", "number density just ahead of the tracked front"),
    "ahead_P": (P_UNIT, "P_xx just ahead of the tracked front (P0 unless a precursor runs)"),
    "ahead_E": ("epsilon", "specific internal energy just ahead of the tracked front"),
    "ahead_u": ("sigma tau^-1", "particle velocity just ahead of the tracked front"),
    "two_wave": ("1", "1 when an elastic precursor runs ahead of the tracked front"),
    "n_samples": ("1", "profile samples averaged"),
    "wall_s": ("s", "wall-clock time of the point (load + drive)"),
    "cpu_s": ("s", "CPU time of the point (load + drive), all threads"),
    "atom_steps": ("1", "atoms x time steps of the point (load + drive)"),
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
ALWAYS_WITH_ERR = ("D", "u_p_measured", "rho", "V", "P", "E", "E_minus_E0",
                   "residual_mass", "residual_momentum", "residual_energy")  # fmt: skip

# -- unit tables ---------------------------------------------------------------------------
# The tables above are in Lennard-Jones reduced units; a backend in SI translates every unit
# and reads "number density"/"per atom" as mass density/per unit mass, and adds the
# variables only it has. A backend hands its table to the functions below.
SI_UNITS = {
    "sigma tau^-1": "m s^-1", "sigma^-3": "kg m^-3", "sigma^3": "m^3 kg^-1", P_UNIT: "Pa",
    "epsilon k_B^-1": "K", "epsilon": "J kg^-1", "tau": "s", "sigma": "m", "tau^-1": "s^-1",
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
    axes = {"velocity": "m s^-1", "time": "s", "length": "m"}
    return UnitTable({**_si(POINT_VARS), **(extra or {})}, _si(POLE_VARS), _si(PROFILE_VARS),
                     axes, "SI (m, s, kg)")  # fmt: skip


POINT_TEXT = {
    "status": "ok, not_converged, or why the run stopped",
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


def control_vars(history, units: UnitTable) -> dict:
    """The control loop's record (``window.methods.ControlHistory``) as dataset variables:
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


def profile_vars(profile: dict[str, np.ndarray], units: UnitTable) -> dict:
    """The steady window profile (``window.steady.mean_profile``) as ``profile_*`` variables
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
    backend's ``units``."""
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
    ds = xr.Dataset(data)
    ds.attrs.update(
        scheme=scheme, scene=scene, scene_config=json.dumps(scene_config, sort_keys=True)
    )
    return ds


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
    """
    if not paths:
        raise ValueError(f"scene {scene}: no point files to aggregate")
    rows: list[dict] = []
    var_attrs: dict[str, dict] = {}
    first_attrs: dict = {}
    for i, p in enumerate(paths):
        values, gattrs = _read_scalars(p, var_attrs)
        rows.append(values)
        if i == 0:
            first_attrs = gattrs
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
    out.attrs.update(scene=scene, title=f"Hugoniot of scene {scene}")
    return out
