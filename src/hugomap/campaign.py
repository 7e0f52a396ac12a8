"""The validation campaign's dataset: its scenes' cost and error, one row per point.

The campaign block's variants of a few base scenes are expanded into scenes before the
config is validated (``hugomap.campaign_expand``, which this module re-exports for its
callers). After the run, ``campaign_dataset`` joins the scenes' aggregates
(``results/hugoniot/<scene>.nc``) into one flat dataset (dim ``point``) of dimensionless
figures, the cases having different units: the relative errors of D and P from the scene's
reference Hugoniot at the point's u_p, u_p/c0, the CPU cost [s], the status and its failure
class (``failures.FAILURES``); and the chart's markers (dim ``setting``: a case, scheme and
resolution over the piston velocities all its resolutions ran) with the Pareto fronts of
cost against each error. ``write_campaign`` (the CLI's ``campaign`` command) writes it.
"""

from __future__ import annotations

import json
import math
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np
import xarray as xr

from .analysis.causes import CLOSURES
from .analysis.replicas import replica_cases
from .campaign_expand import (  # noqa: F401 (re-exported: the campaign's public names)
    DEFAULT_NAME,
    SEP,
    CampaignError,
    Variant,
    as_number,
    campaign_name,
    expand_campaign,
    get_dotted,
    variants,
)
from .failures import MEASURED
from .io.dataset import jump_velocity
from .registry import backend, scene_schema, solver_of

USABLE = MEASURED  # the points that carry a value


def pareto_front(cost: np.ndarray, err: np.ndarray) -> np.ndarray:
    """Mask of the points no other point beats in both cost and |err| (ties: the cheaper).

    Sorted by cost, a point is on the front when its |err| is below that of every cheaper
    point. Points with a non-finite cost or error are never on it."""
    cost, err = np.asarray(cost, float), np.abs(np.asarray(err, float))
    ok = np.isfinite(cost) & np.isfinite(err)
    mask = np.zeros(cost.size, bool)
    best = math.inf
    for i in sorted(np.flatnonzero(ok), key=lambda j: (cost[j], err[j])):
        if err[i] < best:
            mask[i] = True
            best = err[i]
    return mask


def _base_on_axis(spec: Mapping, axis: str, base: Mapping) -> bool:
    """Whether the strength axis's points (the base variant) stand for the axis's default
    value: not if a further key is held at one value over the whole axis, away from the
    base's (e.g. a ``window.start_offset`` set with beta); keys that vary with the first
    one (the averaging times set together) keep the base on the axis."""
    for key, values in list(spec["stability"]["axes"][axis]["set"].items())[1:]:
        if len({json.dumps(v) for v in values}) == 1 and values[0] != get_dotted(base, key):
            return False
    return True


def _reference_curve(ds: xr.Dataset) -> tuple[np.ndarray, dict[str, np.ndarray]]:
    """The reference Hugoniot of an aggregate, sorted by u_p: (u_p, {D, P, D_err, P_err,
    u_p_err, P0_err}); missing errors are 0. ``P0_err`` is the error of the reference's own
    pole (its row at u_p = 0, where it has one): every point's P sits on that pole's
    Rayleigh line."""
    if not all(f"ref_{k}" in ds for k in ("u_p", "D", "P")):
        return np.empty(0), {}
    u = ds["ref_u_p"].values.astype(float)
    cols = {k: ds[f"ref_{k}"].values.astype(float) for k in ("D", "P")}
    for k in ("D", "P", "u_p"):
        e = f"ref_{k}_err"
        cols[k + "_err"] = ds[e].values.astype(float) if e in ds else np.zeros_like(u)
    ok = np.isfinite(u) & (u > 0) & np.isfinite(cols["D"]) & np.isfinite(cols["P"])
    order = np.argsort(u[ok])
    out = {k: v[ok][order] for k, v in cols.items()}
    at_pole = np.flatnonzero(u == 0.0)
    p0_err = float(cols["P_err"][at_pole[0]]) if at_pole.size else 0.0
    out["P0_err"] = np.full(int(ok.sum()), p0_err if np.isfinite(p0_err) else 0.0)
    return u[ok][order], out


def _reference_name(ds: xr.Dataset) -> str:
    """The reference model's name, from the aggregate's ``ref_D`` long name."""
    text = str(ds["ref_D"].attrs.get("long_name", "")) if "ref_D" in ds else ""
    return text.split(":")[0] if text else "none"


def reference_at(u: float, ru: np.ndarray, ref: Mapping[str, np.ndarray]) -> dict[str, float]:
    """The reference Hugoniot at particle velocity ``u``: D, P, their errors at fixed u and
    their slopes dD/du, dP/du (NaN outside [ru[0], ru[-1]]; ``ru`` sorted, ``ref`` as
    ``_reference_curve`` returns it).

    D is linear in u between the bracketing points a, b (D(u) is nearly straight). P lies on
    the pole's Rayleigh line, P = P0 + rho0 D(u) u, with the pole from the same two points
    (P_i - P0 = rho0 D_i u_i at each: rho0 = (P_b - P_a)/(D_b u_b - D_a u_a)), so dP/du =
    rho0 (D + u dD/du). Interpolating P itself linearly would miss its curvature
    (P ~ rho0 (c0 + s u) u) by about rho0 s (u - u_a)(u_b - u): 0.25-0.4 % of P between the
    LJ reference points, 0.4 % at 100 m/s on an 83-m/s copper grid.

    Errors at fixed u: a reference point's u and D errors are one error (equilibrium MD
    derives both from its P at a fixed density, σ_u/u = σ_D/D: ``md.reference``), which
    moves the point along the curve, so at fixed u its D moves by σ_D − (dD/du) σ_u
    (for the LJ liquid 0.5-0.8 of σ_D; an EOS's D(u) has σ_u = 0 and keeps σ_D); the two
    bracketing points' errors are independent (separate runs) and weigh in as the
    interpolation weighs them, in quadrature; P moves by rho0 u times D's (the points stay
    on the pole's Rayleigh line) and with that pole's P0 (``P0_err``, where the reference
    has a pole: P = P0 + rho0 D u; D's own share of the pole's error is small, since a pole
    sampled hot moves the shocked state's P with P0). P's error as stated, at fixed density,
    was 3-4 times the seeds' scatter of window points' P about the reference at their u_p;
    without the P0 term, eight equilibrium references of the default liquid (seeds 1-8,
    each measuring its own pole) scattered at fixed u by 1.8 times the stated P error."""
    keys = ("D", "P", "D_err", "P_err", "D_slope", "P_slope")
    nan = dict.fromkeys(keys, math.nan)
    if ru.size < 2 or not (ru[0] <= u <= ru[-1]):
        return nan
    b = int(min(max(np.searchsorted(ru, u), 1), ru.size - 1))
    a = b - 1
    w = (u - ru[a]) / (ru[b] - ru[a])
    out = {k: float((1.0 - w) * ref[k][a] + w * ref[k][b]) for k in ("D", "P", "P_err")}
    slope = float((ref["D"][b] - ref["D"][a]) / (ru[b] - ru[a]))
    u_err = ref.get("u_p_err", np.zeros_like(ru))
    d_fixed = [abs(ref["D_err"][i] - slope * u_err[i]) for i in (a, b)]
    out["D_err"] = float(np.hypot((1.0 - w) * d_fixed[0], w * d_fixed[1]))
    out["D_slope"] = slope
    out["P_slope"] = float((ref["P"][b] - ref["P"][a]) / (ru[b] - ru[a]))
    flux_a, flux_b = ref["D"][a] * ru[a], ref["D"][b] * ru[b]
    if flux_b != flux_a:
        rho0 = (ref["P"][b] - ref["P"][a]) / (flux_b - flux_a)
        out["P"] = float(ref["P"][a] + rho0 * (out["D"] * u - flux_a))
        out["P_slope"] = float(rho0 * (out["D"] + u * slope))
        p0_err = float(ref["P0_err"][a]) if "P0_err" in ref else 0.0
        out["P_err"] = float(math.hypot(rho0 * u * out["D_err"], p0_err))
    return out


def reference_deviation(
    x: float, x_err: float, at: Mapping[str, float], q: str, u_err: float = 0.0,
    corr: float = 0.0,
) -> tuple[float, float]:  # fmt: skip
    """A point's relative deviation from the reference at its u_p, e = x/x_ref(u) − 1 for
    q = "D" or "P", and its standard error: the point's σ_x, the reference's at fixed u
    (``reference_at``) and the point's u_p error through the reference's slope, that one
    correlated with σ_x by ``corr`` (a window's slab: its u and P move together),
        s² = (σ_x/x_r)² + (x σ_r/x_r²)² + (x x_r' σ_u/x_r²)² − 2 corr (σ_x/x_r)(x x_r' σ_u/x_r²).
    NaN where the point or the reference has no value."""
    xr_, xre, slope = at.get(q, math.nan), at.get(q + "_err", math.nan), at.get(q + "_slope", 0.0)
    xre = xre if math.isfinite(xre) else 0.0
    du = x * slope * u_err / xr_**2 if math.isfinite(u_err) and u_err > 0 else 0.0
    c = corr if math.isfinite(corr) else 0.0
    a = x_err / xr_
    var = a * a + (x * xre / xr_**2) ** 2 + du * du - 2.0 * c * a * du
    return x / xr_ - 1.0, math.sqrt(max(var, 0.0))


def case_c0(ds: xr.Dataset, scene: Mapping) -> float:
    """The sound speed that scales u_p: the material model's c0 where the backend has one
    (CSPH: the EOS's, the solid's also for a porous sample), else the intercept of a
    straight-line fit D = c0 + s u_p to the reference Hugoniot (MD:
    ``stats.linear_hugoniot_fit``), in the scene's own units."""
    c0 = backend(scene).sound_speed(scene)
    if c0 is not None:
        return float(c0)
    from .analysis.stats import linear_hugoniot_fit

    u, ref = _reference_curve(ds)
    if u.size < 2:
        return math.nan
    return float(linear_hugoniot_fit(u, ref["D"], ref["D_err"])["c0"])


def _knobs(scene: Mapping, c0: float) -> dict[str, float]:
    """Dimensionless resolution of a scene: particles in the window at the upstream density
    and window length in particle spacings (``Backend.scale``), and the average time in
    sound crossings of the window (average_time c0 / L; NaN where average_time is null,
    derived per point)."""
    w = scene.get("window", {})
    sc = backend(scene).scale(scene)
    L = float(w.get("length", math.nan))
    avg = w.get("average_time")  # null: derived per point (CSPH)
    avg = math.nan if avg is None else float(avg)
    return {
        "n_window": sc["n_window"],
        "window_spacings": sc["window_spacings"],
        "average_crossings": avg * c0 / L,
    }


def _axis_unit(scene: Mapping, dotted: str) -> str:
    """The unit of a scene key, from the ``[...]`` of its schema description ('1' if none)."""
    import re

    node: Any = scene_schema(solver_of(scene))
    for p in dotted.split("."):
        node = node.get("properties", {}).get(p) if isinstance(node, dict) else None
        if node is None:
            return "?"
    m = re.search(r"\[([^\]]+)\]", str(node.get("description", "")))
    return m.group(1) if m else "1"


POINT_COLUMNS: dict[str, tuple[str, str]] = {
    "u_p_over_c0": ("1", "nominal piston velocity over the case's c0 (attrs cases)"),
    "u_eval_over_c0": ("1", "u_p the error is taken at (u_p_jump: a window's slab) over c0"),
    "D_over_c0": ("1", "shock velocity over c0"),
    "err_D": ("1", "relative error of D from the reference Hugoniot at u_eval: D/D_ref - 1"),
    "err_D_err": ("1", "standard error of err_D (the point's and the reference's)"),
    "err_P": ("1", "relative error of P from the reference Hugoniot at u_eval: P/P_ref - 1"),
    "err_P_err": ("1", "standard error of err_P (the point's and the reference's)"),
    "err_D_own_err": ("1", "standard error of err_D from the point alone (no reference part)"),
    "err_P_own_err": ("1", "standard error of err_P from the point alone (no reference part)"),
    **{
        f"residual_{k}{e}": ("1", f"{w} of the point's {k} closure (0 for a steady shock)")
        for k in CLOSURES
        for e, w in (("", "residual"), ("_err", "standard error"))
    },
    "cpu_s": ("s", "CPU time of the point, every stage it needed (load, window, run), all threads"),
    "wall_s": ("s", "wall-clock time of the point, every stage it needed"),
    "n_window": ("1", "particles in the window at the upstream density (resolution)"),
    "window_spacings": ("1", "window length in particle spacings (MD rho0^(-1/3), CSPH dx)"),
    "average_crossings": ("1", "average time in sound crossings of the window, t c0 / L"),
    "axis_value": ("1", "stability axis coordinate (its unit: axis_unit); NaN off an axis"),
    "converged": ("1", "1 when the scheme reported a steady state within its tolerances"),
}
TEXT_COLUMNS = {
    "case": "base scene of the campaign",
    "study": "resolution (error and cost per setting) or stability (the map)",
    "variant": "the resolution's name, or the stability axis and value index",
    "scene": "the generated scene (results/<scene>/, results/hugoniot/<scene>.nc)",
    "scheme": "piston, amw, mw or dichotomy",
    "axis": "the stability axis ('' for resolutions and the strength axis)",
    "axis_unit": "unit of axis_value",
    "status": "ok, not_converged, or a failure status (hugomap.status.FAILURES)",
    "failure_class": "FAILURES class of a failed point ('' if usable): e.g. control, dichotomy",
    "cause": "FAILURES text of a failed point ('' if usable)",
    "diagnostic": "the point's diagnostic",
}


def campaign_dataset(cfg: Mapping, aggregates: Mapping[str, str | Path]) -> xr.Dataset:
    """One flat dataset (dim ``point``) from the aggregates of the campaign's scenes.

    ``cfg``: the validated config (campaign expanded); ``aggregates``: scene → path of its
    ``results/hugoniot/<scene>.nc``. Errors are relative to the reference Hugoniot stored in
    the aggregate (``ref_*``: LJ the equilibrium-MD Hugoniot, solid copper D = c0 + s u_p,
    porous copper McQueen's full compaction), taken at the u_p the point's jump was taken at
    (``u_p_jump``: the piston's velocity, a window's slab; older files: the nominal u_p, MW's
    ``u_p_set``) by ``reference_at`` (D linear, P on the Rayleigh line), NaN outside the
    reference's range, with errors from ``reference_deviation``.
    A failed point keeps its status, failure class and cause, and no value.
    """
    from .failures import FAILURES

    rows: list[dict[str, Any]] = []
    cases: dict[str, dict] = {}
    axes: dict[str, dict] = {}
    for v in variants(cfg["campaign"]):
        scene = cfg["scenes"][v.scene]
        with xr.open_dataset(aggregates[v.scene], engine="netcdf4") as ds:
            ds = ds.load()
        c0 = case_c0(ds, scene)
        ru, ref = _reference_curve(ds)
        cases.setdefault(v.case, {
            "c0": c0, "units": backend(scene).units.system,
            "velocity_unit": str(ds["u_p"].attrs.get("reduced_units",
                                                     ds["u_p"].attrs.get("units", ""))),
            "reference": _reference_name(ds),
        })  # fmt: skip
        # one c0 per case (its first variant's): a variant with its own reference (another
        # seed, another pole) must not move the case's u_p/c0 axis
        c0 = cases[v.case]["c0"]
        st = cfg["campaign"]["cases"][v.case].get("stability")
        if st:
            cases[v.case]["stability_variant"] = st["resolution"]
        if v.axis:
            base = cfg["scenes"][f"{v.case}{SEP}{st['resolution']}"]
            axes.setdefault(v.case, {})[v.axis] = {
                "keys": list(v.keys), "unit": _axis_unit(scene, v.keys[0]),
                "base": as_number(get_dotted(base, v.keys[0])),
                "base_row": int(_base_on_axis(cfg["campaign"]["cases"][v.case], v.axis, base)),
            }  # fmt: skip
        knobs = _knobs(scene, c0)
        for scheme in ds["scheme"].values:
            p = ds.sel({"scheme": scheme})
            jump = jump_velocity(p)  # the u_p each jump was taken at (a window's slab)
            for i, u in enumerate(p["u_p"].values.astype(float)):
                status = str(p["status"].values[i])

                def val(k: str, _p=p, _i=i) -> float:
                    return float(_p[k].values[_i]) if k in _p else math.nan

                u_eval, u_err, corr = (float(c[i]) for c in jump)
                row: dict[str, Any] = {
                    "case": v.case, "study": v.study, "variant": v.label, "scene": v.scene,
                    "scheme": str(scheme), "axis": v.axis,
                    "axis_unit": axes.get(v.case, {}).get(v.axis, {}).get("unit", ""),
                    "axis_value": v.value, "status": status,
                    "diagnostic": str(p["diagnostic"].values[i]),
                    "u_p_over_c0": u / c0, "u_eval_over_c0": u_eval / c0,
                    "cpu_s": val("cpu_s"), "wall_s": val("wall_s"),
                    "converged": val("converged"), **knobs,
                }  # fmt: skip
                usable = status in USABLE
                cls, cause = ("", "") if usable else FAILURES.get(status, ("?", "unregistered"))
                row.update(failure_class=cls, cause=cause)
                at = reference_at(u_eval, ru, ref) if ref else {}
                for q in ("D", "P"):
                    x, xe = (val(q), val(q + "_err")) if usable else (math.nan, math.nan)
                    c = corr if q == "P" else 0.0
                    row[f"err_{q}"], row[f"err_{q}_err"] = reference_deviation(
                        x, xe, at, q, u_err, c
                    )
                    # the reference's error left out: points on one reference compare so
                    own = reference_deviation(x, xe, {**at, f"{q}_err": 0.0}, q, u_err, c)
                    row[f"err_{q}_own_err"] = own[1]
                row["D_over_c0"] = (val("D") if usable else math.nan) / c0
                for k in CLOSURES:
                    for e in ("", "_err"):
                        row[f"residual_{k}{e}"] = val(f"residual_{k}{e}") if usable else math.nan
                rows.append(row)
    if not rows:
        raise ValueError("the campaign's aggregates hold no points")
    n = len(rows)
    data = {}
    for k, (unit, long_name) in POINT_COLUMNS.items():
        arr = np.array([r[k] for r in rows], dtype=float)
        data[k] = ("point", arr, {"units": unit, "long_name": long_name})
    for k, long_name in TEXT_COLUMNS.items():
        data[k] = ("point", np.array([str(r[k]) for r in rows], dtype=object),
                   {"long_name": long_name})  # fmt: skip
    out = xr.Dataset(data, coords={"point": np.arange(n)})
    out = out.set_coords(["case", "study", "variant", "scheme", "scene"])
    out = out.merge(settings(out))
    reps = replica_statistics(out, replica_cases(cfg["campaign"]))
    if reps:
        out.attrs["replicas"] = json.dumps(reps, sort_keys=True)
    out.attrs.update(
        Conventions="CF-1.11",  # written through io.dataset.cf_dataset
        title=f"hugomap validation campaign {campaign_name(cfg)}",
        campaign=campaign_name(cfg),
        cases=json.dumps(cases, sort_keys=True),
        axes=json.dumps(axes, sort_keys=True),
        campaign_config=json.dumps(cfg["campaign"], sort_keys=True),
    )
    return out


SETTING_COLUMNS: dict[str, tuple[str, str]] = {
    "setting_n_points": ("1", "points of the setting: its case's common piston velocities"),
    "setting_n_usable": ("1", "of them ok or not_converged"),
    "setting_cpu_s": ("s", "mean CPU time per point (failed points included)"),
    "setting_err_D": ("1", "RMS relative error of D over the points; NaN if one failed"),
    "setting_err_P": ("1", "RMS relative error of P over the points; NaN if one failed"),
    "setting_err_D_err": ("1", "standard error of setting_err_D (the points' err_D_err)"),
    "setting_err_P_err": ("1", "standard error of setting_err_P (the points' err_P_err)"),
    "setting_n_window": ("1", "particles in the window at the upstream density"),
    "setting_average_crossings": ("1", "average time in sound crossings of the window"),
    "setting_pareto_D": ("1", "1 on the case's Pareto front of setting_cpu_s, setting_err_D"),
    "setting_pareto_P": ("1", "1 on the case's Pareto front of setting_cpu_s, setting_err_P"),
}


def settings(points: xr.Dataset) -> xr.Dataset:
    """The chart's markers (dim ``setting``): one per case, scheme and resolution, over the
    piston velocities every resolution of the case ran (so that settings compare on the same
    shocks): mean CPU per point, RMS relative errors, and the Pareto fronts per case.

    The RMS counts every point: a setting with a failed point (or one outside the reference)
    has no error and is not on a front."""
    res = points.isel(point=np.flatnonzero(points["study"].values == "resolution"))
    rows = []
    for case in dict.fromkeys(res["case"].values):
        c = res.isel(point=np.flatnonzero(res["case"].values == case))
        by_variant = {
            v: {round(float(u), 9) for u in c["u_p_over_c0"].values[c["variant"].values == v]}
            for v in dict.fromkeys(c["variant"].values)
        }
        common = set.intersection(*by_variant.values())
        for scheme in dict.fromkeys(c["scheme"].values):
            for variant in by_variant:
                sel = (c["scheme"].values == scheme) & (c["variant"].values == variant)
                sel &= np.isin(np.round(c["u_p_over_c0"].values.astype(float), 9), list(common))
                if not sel.any():
                    continue
                usable = np.isin(c["status"].values[sel], USABLE)
                row = {"setting_case": case, "setting_scheme": scheme,
                       "setting_variant": variant, "setting_n_points": float(sel.sum()),
                       "setting_n_usable": float(usable.sum()),
                       "setting_cpu_s": float(np.mean(c["cpu_s"].values[sel])),
                       "setting_n_window": float(c["n_window"].values[sel][0]),
                       "setting_average_crossings": float(
                           c["average_crossings"].values[sel][0])}  # fmt: skip
                for q in ("D", "P"):
                    e = c[f"err_{q}"].values[sel].astype(float)
                    se = c[f"err_{q}_err"].values[sel].astype(float)
                    rms = float(np.sqrt(np.mean(e**2)))  # NaN if any NaN
                    row[f"setting_err_{q}"] = rms
                    row[f"setting_err_{q}_err"] = _rms_error(e, se, rms)
                rows.append(row)
    n = len(rows)
    for q in ("D", "P"):
        flags = np.zeros(n, np.int8)
        for case in {r["setting_case"] for r in rows}:
            idx = np.array([j for j, r in enumerate(rows) if r["setting_case"] == case], int)
            m = pareto_front(np.array([rows[j]["setting_cpu_s"] for j in idx]),
                             np.array([rows[j][f"setting_err_{q}"] for j in idx]))  # fmt: skip
            flags[idx[m]] = 1
        for j in range(n):
            rows[j][f"setting_pareto_{q}"] = flags[j]
    data = {
        k: ("setting", np.array([r[k] for r in rows], dtype=np.int8 if "pareto" in k else float),
            {"units": unit, "long_name": long_name})
        for k, (unit, long_name) in SETTING_COLUMNS.items()
    }  # fmt: skip
    for k in ("setting_case", "setting_scheme", "setting_variant"):
        data[k] = ("setting", np.array([r[k] for r in rows], dtype=object),
                   {"long_name": k.split("_", 1)[1] + " of the setting"})  # fmt: skip
    return xr.Dataset(data).set_coords(["setting_case", "setting_scheme", "setting_variant"])


def _rms_error(e: np.ndarray, se: np.ndarray, rms: float) -> float:
    """Standard error of r = sqrt(mean e_i^2) from independent errors s_i of the e_i:
    dr = sqrt(sum (e_i s_i)^2) / (n r); at r = 0, the RMS of the s_i (the first-order
    propagation vanishes there)."""
    if not math.isfinite(rms):
        return math.nan
    if rms == 0.0:
        return float(np.sqrt(np.mean(se**2)))
    return float(np.sqrt(np.sum((e * se) ** 2)) / (e.size * rms))


def replica_statistics(ds: xr.Dataset, cases: Sequence[str]) -> dict:
    """``analysis.replicas.replica_summary`` of each replica case's points, grouped by
    scheme and u_p, for D and P (their relative errors against the reference, with the
    combined errors) and for each closure's residual ``residual_<k>`` (whose reference is 0,
    with the point's own error: do the residuals' errors hold too?): over the usable points
    (ok or not_converged) and over the ok ones. ``vs_piston``: each window point's D and P
    against the piston point of the same seed and u_p (``analysis.replicas.against_base``,
    the points' own errors), grouped by scheme and u_p: do the methods agree?"""
    from .analysis.replicas import against_base, replica_summary

    # quantity -> its column (and <column>_err): D, P against the reference, residuals against 0
    cols = {"D": "err_D", "P": "err_P"} | {f"residual_{k}": f"residual_{k}" for k in CLOSURES}
    out = {}
    for case in cases:
        sel = ds["case"].values == case
        for which, keep in (("usable", np.isin(ds["status"].values, USABLE)),
                            ("ok", ds["status"].values == "ok")):  # fmt: skip
            m = sel & keep
            groups = [(str(a), round(float(b), 6)) for a, b in
                      zip(ds["scheme"].values[m], ds["u_p_over_c0"].values[m], strict=True)]  # fmt: skip
            vals = {q: (ds[c].values[m], ds[c + "_err"].values[m]) for q, c in cols.items()}
            out.setdefault(case, {})[which] = replica_summary(groups, vals)
            # a window point and its seed's piston point: one scene (seed), one u_p
            pairs = [(str(a), g[1]) for a, g in zip(ds["scene"].values[m], groups, strict=True)]
            schemes = [g[0] for g in groups]
            paired = {q: against_base(pairs, schemes, ds[f"err_{q}"].values[m],
                                      ds[f"err_{q}_own_err"].values[m]) for q in ("D", "P")}  # fmt: skip
            idx = paired["D"][0]  # the pairing does not depend on the values
            if idx:
                diffs = {q: (d, sd) for q, (_, d, sd) in paired.items()}
                vs = replica_summary([groups[i] for i in idx], diffs)
                out[case].setdefault("vs_piston", {})[which] = vs
        out[case]["n_points"] = int(sel.sum())
        out[case]["n_ok"] = int((sel & (ds["status"].values == "ok")).sum())
    return out


def write_campaign(cfg: Mapping, aggregates: Sequence[str | Path], out: str | Path) -> Path:
    """Build the campaign dataset from aggregate files (named ``<scene>.nc``) and write it."""
    from .io.atomic import write_netcdf
    from .io.dataset import provenance_attrs

    by_scene = {Path(a).stem: a for a in aggregates}
    missing = [v.scene for v in variants(cfg["campaign"]) if v.scene not in by_scene]
    if missing:
        raise ValueError(f"campaign: no aggregate for scene(s) {', '.join(missing)}")
    ds = campaign_dataset(cfg, by_scene)
    ds.attrs.update(provenance_attrs(dict(cfg)))
    return write_netcdf(ds, out)
