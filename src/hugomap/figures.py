"""Hugoniot figures: P–V and D–u_p, points by scheme with error bars, reference as a line."""

from __future__ import annotations

import os
import re

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import xarray as xr  # noqa: E402
from matplotlib.ticker import FormatStrFormatter, LogLocator, NullFormatter  # noqa: E402

from .failures import MEASURED  # noqa: E402
from .io.dataset import NOT_RUN, jump_velocity  # noqa: E402


def _labels(ds: xr.Dataset, scene: str) -> dict:
    """The scene backend's figure text (``Backend.figure_labels``), from the resolved
    config in the aggregate."""
    import json

    from .registry import backend

    cfg = json.loads(ds.attrs.get("config_json", "{}"))
    sc = cfg.get("scenes", {}).get(scene, {})
    return backend(sc).figure_labels(sc)


SCHEME_COLORS = {"piston": "C0", "amw": "C1", "mw": "C2", "dichotomy": "C3"}


def _failed_text(u: np.ndarray, status: np.ndarray) -> str:
    """``u_p 0.5 (oscillating), 3 (too_few_samples)``: where a scheme failed, and why."""
    return "u_p " + ", ".join(f"{float(x):g} ({s})" for x, s in zip(u, status, strict=True))


def _reference(ax, ds: xr.Dataset, rx: str, ry: str, fx: float, fy: float, label: str) -> None:
    """The reference Hugoniot as a line, with a band of ±1 standard error where it has errors
    (``ref_<y>_err``; the equilibrium-MD reference does, a model's own Hugoniot does not) and
    x error bars where ``ref_<x>_err`` is non-zero."""
    x, y = ds[rx].values, ds[ry].values
    keep = np.isfinite(x) & np.isfinite(y)
    order = np.argsort(x[keep])
    x, y = x[keep][order] * fx, y[keep][order] * fy
    ye = ds[ry + "_err"].values[keep][order] * fy if ry + "_err" in ds else None
    band = ye is not None and np.isfinite(ye).any() and np.nanmax(ye) > 0
    ax.plot(x, y, "k-", lw=1.2, label=label + (" ± 1 s.e." if band else ""))
    if band:
        ax.fill_between(x, y - ye, y + ye, color="k", alpha=0.15, lw=0)
    if rx + "_err" in ds:
        xe = ds[rx + "_err"].values[keep][order] * fx
        if np.isfinite(xe).any() and np.nanmax(xe) > 0:
            ax.errorbar(x, y, xerr=xe, fmt="none", ecolor="k", elinewidth=0.6, capsize=0)


def hugoniot_figures(
    agg: str | os.PathLike, out_pv: str | os.PathLike, out_dup: str | os.PathLike
) -> None:
    """Draw P(V) and D(u_p) for one scene's aggregate, each scheme in its colour: converged
    points filled, not-converged points hollow (both with their error bars), failed points
    (no value) named with their status in the legend and, on D–u_p, marked × on the bottom
    edge at their u_p. A scheme with nothing to draw has no legend entry. D–u_p is drawn at
    the jump's u_p (``u_p_jump``: the piston's speed, a window's slab ± 1 s.e.; older files:
    the u_p coordinate or a window's u_out − u_in); where u_p was also measured behind a
    piston's front, a thin bar at the point's D spans that measurement ± 1 s.e."""
    from matplotlib.transforms import blended_transform_factory

    with xr.open_dataset(agg, engine="netcdf4") as ds:
        ds = ds.load()
    scene = ds.attrs.get("scene", "")
    text = _labels(ds, scene)
    axes = text["axes"]
    for out, (xv, yv) in ((out_pv, ("V", "P")), (out_dup, ("u_p_measured", "D"))):
        (xl, fx), (yl, fy) = axes[xv], axes[yv]
        fig, ax = plt.subplots(figsize=(5.5, 4.2), dpi=120)
        measured_bar = False
        for i, sch in enumerate(ds["scheme"].values):
            d = ds.sel(scheme=sch)
            color = SCHEME_COLORS.get(str(sch), f"C{4 + i}")
            status = d["status"].values.astype(str)
            x, y = d[xv].values, d[yv].values
            xe, ye = d[xv + "_err"].values, d[yv + "_err"].values
            if xv == "u_p_measured":
                # at the jump's u_p: the piston's speed (exact), a window's slab (measured)
                um, ume = x * fx, xe * fx
                x, xe, _ = jump_velocity(d)
                # the measured slab as a check only where the jump was not taken at it
                um = np.where(np.isclose(x * fx, um, rtol=1e-12, atol=0.0), np.nan, um)
            x, xe, y, ye = x * fx, xe * fx, y * fy, ye * fy
            drawn = np.isfinite(x) & np.isfinite(y)
            ok = drawn & (status == "ok")
            nc = drawn & (status == "not_converged")
            tnr = drawn & (status == "target_not_reached")
            failed = ~np.isin(status, (*MEASURED, NOT_RUN, "", "nan"))
            if ok.any():
                ax.errorbar(x[ok], y[ok], xerr=xe[ok], yerr=ye[ok], fmt="o", color=color,
                            label=f"{sch} ({text['tag']})")  # fmt: skip
            if nc.any():
                ax.errorbar(x[nc], y[nc], xerr=xe[nc], yerr=ye[nc], fmt="o", mfc="none",
                            color=color, label=f"{sch}, not converged")  # fmt: skip
            if tnr.any():  # closed and steady, its errors above the scene's target
                ax.errorbar(x[tnr], y[tnr], xerr=xe[tnr], yerr=ye[tnr], fmt="s", color=color,
                            label=f"{sch}, target not reached")  # fmt: skip
            if xv == "u_p_measured":
                m = (ok | nc | tnr) & np.isfinite(um) & np.isfinite(ume)
                if m.any():
                    ax.errorbar(um[m], y[m], xerr=ume[m], fmt="|", color=color, alpha=0.6,
                                elinewidth=0.8, ms=6)  # fmt: skip
                    measured_bar = True
            if failed.any():
                label = f"{sch} failed (no value): {_failed_text(d['u_p'].values[failed] * fx, status[failed])}"
                if xv == "u_p_measured":
                    tr = blended_transform_factory(ax.transData, ax.transAxes)
                    ax.plot(x[failed], np.full(failed.sum(), 0.03), "x", color=color, ms=7,
                            mew=1.5, transform=tr, clip_on=False, label=label)  # fmt: skip
                else:
                    ax.plot([], [], "x", color=color, ms=7, mew=1.5, label=label)
        if measured_bar:
            ax.errorbar([], [], xerr=[], fmt="|", color="grey", alpha=0.6,
                        label="u_p measured behind the front ± 1 s.e.")  # fmt: skip
        rx = {"V": "ref_V", "u_p_measured": "ref_u_p"}[xv]
        ry = {"P": "ref_P", "D": "ref_D"}[yv]
        if rx in ds and ry in ds:
            _reference(ax, ds, rx, ry, fx, fy, text["reference"])
            sx = {"V": "ref_snowplow_V", "u_p_measured": "ref_u_p"}[xv]
            sy = {"P": "ref_snowplow_P", "D": "ref_snowplow_D"}[yv]
            if sx in ds and sy in ds:
                order = np.argsort(ds[rx].values)
                ax.plot(ds[sx].values[order] * fx, ds[sy].values[order] * fy, "k--", lw=1.0,
                        label="snowplow limit")  # fmt: skip
        if xv == "V" and "rho0" in ds:
            ax.plot([fx / float(ds["rho0"])], [fy * float(ds["P0"])], "k*", ms=9, label="pole")
        ax.set_xlabel(xl)
        ax.set_ylabel(yl)
        ax.set_title(f"{scene}: {text['title']}")
        ax.legend(fontsize=7)
        fig.tight_layout()
        fig.savefig(out)
        plt.close(fig)


def _unit(ds: xr.Dataset, name: str, default: str) -> str:
    """A variable's unit for a label: its ``reduced_units`` (LJ: ``units`` is "1") or
    ``units``."""
    if name not in ds:
        return default
    attrs = ds[name].attrs
    return str(attrs.get("reduced_units", attrs.get("units", default)))


def window_history_figure(point: str | os.PathLike, out: str | os.PathLike) -> None:
    """History of one window point: ω(t), the slopes a_k, u_in/u_out and the D estimate
    −u_in + L a_k against time (AMW, MW); the trial sequence u_out → ⟨dω/dt⟩ (dichotomy)."""
    with xr.open_dataset(point, engine="netcdf4") as ds:
        ds = ds.load()
    title = f"{ds.attrs.get('scene', '')} {ds.attrs.get('scheme', '')}: {ds['status'].values}"
    # units from the file (MD: units "1" with reduced_units τ, σ/τ; CSPH: s, m/s)
    tu = {"tau": "τ", "s": "s"}.get(_unit(ds, "omega_t", "tau"), "τ")
    vu = {"sigma tau^-1": "σ/τ", "m s-1": "m/s", "m s^-1": "m/s"}.get(
        _unit(ds, "control_u_in", ""), "σ/τ"
    )
    fig, axes = plt.subplots(3, 1, figsize=(5.5, 7.5), dpi=110, sharex=False)
    if "omega_t" in ds:
        axes[0].plot(ds["omega_t"], ds["omega_value"], ".", ms=2)
        axes[0].set_ylabel("ω = (x_f − x_lo)/L")
        axes[0].set_xlabel(f"t [{tu}]")
    if "control_t" in ds:
        t = ds["control_t"].values
        axes[1].errorbar(t, ds["control_a"], yerr=ds["control_a_err"], fmt="o")
        axes[1].axhline(0.0, color="k", lw=0.8)
        axes[1].set_ylabel(f"a_k [1/{tu}]")
        L = float(ds.attrs.get("window_length", np.nan))
        axes[2].plot(t, -ds["control_u_in"], "o-", label="D estimate −u_in (frame)")
        axes[2].plot(t, -ds["control_u_in"] + L * ds["control_a"], "x", label="−u_in + L a_k")
        axes[2].plot(t, ds["control_u_out"] - ds["control_u_in"], "s-", label="u_p = u_out − u_in")
        axes[2].set_xlabel(f"t [{tu}]")
        axes[2].set_ylabel(f"velocity [{vu}]")
        axes[2].legend(fontsize=7)
    if "dichotomy_u_out" in ds:
        u, a = ds["dichotomy_u_out"].values, ds["dichotomy_slope"].values
        axes[1].plot(u, a, "o")
        for i, (ui, ai) in enumerate(zip(u, a, strict=True)):
            axes[1].annotate(str(i), (ui, ai), fontsize=7)
        axes[1].axhline(0.0, color="k", lw=0.8)
        axes[1].set_xlabel("trial u_out [σ/τ] (numbers: order)")
        axes[1].set_ylabel("⟨dω/dt⟩ [1/τ]")
        axes[2].plot(np.arange(u.size), u, "o-")
        axes[2].set_xlabel("trial")
        axes[2].set_ylabel("u_out [σ/τ]")
    axes[0].set_title(title)
    fig.tight_layout()
    fig.savefig(out)
    plt.close(fig)


_UNIT_SYMBOLS = {"sigma": "σ", "tau": "τ", "epsilon": "ε"}
_SUPERSCRIPTS = str.maketrans("-0123456789", "⁻⁰¹²³⁴⁵⁶⁷⁸⁹")


def unit_text(units: str) -> str:
    """A unit string of the datasets (``sigma tau^-1``, ``epsilon sigma^-3``, ``m s-1``) as the
    figures write it: σ, τ, ε for the LJ units, powers as superscripts, and a single factor
    to the power −1 after a slash (σ/τ, ε/k_B, ε σ⁻³, σ⁻³, m/s). A string that is not a
    product of powers is returned as it is."""
    factors = []
    for word in units.split():
        m = re.fullmatch(r"([A-Za-z_]*[A-Za-z])\^?(-?\d+)?", word)
        if m is None:
            return units
        factors.append((_UNIT_SYMBOLS.get(m[1], m[1]), int(m[2] or 1)))

    def power(name: str, n: int) -> str:
        return name if n == 1 else name + str(n).translate(_SUPERSCRIPTS)

    up = [(b, n) for b, n in factors if n > 0]
    down = [(b, n) for b, n in factors if n < 0]
    if up and len(down) == 1 and down[0][1] == -1:
        return " ".join(power(b, n) for b, n in up) + "/" + down[0][0]
    return " ".join(power(b, n) for b, n in factors) or units


#: How a profile field is drawn: (axis label, SI scale, SI unit shown) for SI datasets.
PROFILE_SI = {"x": (1e10, "Å"), "rho": (1.0, "kg/m³"), "u": (1.0, "m/s"), "P": (1e-9, "GPa"),
              "T": (1.0, "K")}  # fmt: skip


def profile_figure(prof: dict, out: str | os.PathLike) -> None:
    """The front-frame profile of ``stages.profile.front_profile``: density, x velocity,
    P_xx with P_yy and P_zz (their gap: the shear stress a crystal holds, 2τ = P_xx −
    (P_yy + P_zz)/2), and temperature against the distance from the front (ahead > 0).
    Units as the other figures write them (``unit_text``: σ⁻³, σ/τ, ε σ⁻³, ε/k_B); each y
    label is the quantity over its unit, the four aligned."""
    si = prof["units"]["x"] == "m"
    units = prof["units"]

    def scaled(k: str) -> tuple[np.ndarray, str]:
        v = np.asarray(prof[k], dtype=float)
        if si:
            f, u = PROFILE_SI["P" if k in ("Pyy", "Pzz") else k]
            return v * f, u
        return v, unit_text(units[k])

    x, xu = scaled("x")
    fig, axes = plt.subplots(4, 1, figsize=(5.5, 8.0), dpi=110, sharex=True, layout="constrained")
    for ax, k, label in ((axes[0], "rho", "density ρ"), (axes[1], "u", "x velocity u"),
                         (axes[3], "T", "temperature T")):  # fmt: skip
        v, u = scaled(k)
        ax.plot(x, v, ".-", ms=3)
        ax.set_ylabel(f"{label}\n[{u}]")
    for k, style in (("P", ".-"), ("Pyy", "--"), ("Pzz", ":")):
        v, u = scaled(k)
        axes[2].plot(x, v, style, ms=3, label={"P": "P_xx"}.get(k, "P_" + k[1:]))
    axes[2].set_ylabel(f"stress\n[{u}]")
    axes[2].legend(fontsize=7)
    for ax in axes:
        ax.axvline(0.0, color="k", lw=0.6)
    axes[-1].set_xlabel(f"x − x_front [{xu}] (ahead of the front > 0)")
    axes[0].set_title(f"{prof['scene']}: {prof['samples']} samples in the front's frame, "
                      f"bins merged by {prof['merge']}", fontsize=9)  # fmt: skip
    fig.align_ylabels(axes)
    fig.savefig(out)
    plt.close(fig)


# -- the validation campaign (hugomap.campaign) ---------------------------------------------
SCHEME_MARKERS = {"piston": "s", "amw": "o", "mw": "^", "dichotomy": "D"}
OUTCOME_COLORS = {"ok": "tab:green", "not_converged": "goldenrod"}


def speed_accuracy_figure(ds: xr.Dataset, out: str | os.PathLike) -> None:
    """CPU per point against the RMS relative error of P and of D, one marker per scheme
    and resolution (``campaign.settings``), a row per case; the Pareto front as a staircase;
    bars: one standard error of the RMS (statistics of the points and of the reference).
    A setting with a failed point has no error: it is drawn as a cross on the top edge."""
    cases = list(dict.fromkeys(ds["setting_case"].values))
    fig, axes = plt.subplots(len(cases), 2, figsize=(10, 3.6 * len(cases)), squeeze=False)
    variants = list(dict.fromkeys(ds["setting_variant"].values))
    colors = {v: plt.cm.viridis(i / max(len(variants) - 1, 1)) for i, v in enumerate(variants)}
    for r, case in enumerate(cases):
        sel = ds["setting_case"].values == case
        cpu = ds["setting_cpu_s"].values[sel]
        for c, q in enumerate(("P", "D")):
            ax = axes[r, c]
            err = np.abs(ds[f"setting_err_{q}"].values[sel])
            name = f"setting_err_{q}_err"
            se = ds[name].values[sel] if name in ds else np.full(err.shape, np.nan)
            ok = np.isfinite(err)
            top = 2.0 * np.nanmax(err) if ok.any() else 1.0
            for i in range(sel.sum()):
                scheme = str(ds["setting_scheme"].values[sel][i])
                variant = str(ds["setting_variant"].values[sel][i])
                y = max(err[i], 1e-5) if ok[i] else top
                if ok[i] and np.isfinite(se[i]) and se[i] > 0:
                    # one standard error; the lower bar stops above zero on the log axis
                    lo = min(se[i], 0.9 * y)
                    ax.errorbar(cpu[i], y, yerr=[[lo], [se[i]]], color=colors[variant],
                                lw=0.8, capsize=2, zorder=2)  # fmt: skip
                ax.scatter(cpu[i], y, marker=SCHEME_MARKERS.get(scheme, "x") if ok[i] else "x",
                           color=colors[variant], s=55, zorder=3,
                           edgecolors="k" if ok[i] else None, linewidths=0.5)  # fmt: skip
            front = ds[f"setting_pareto_{q}"].values[sel].astype(bool)
            o = np.argsort(cpu[front])
            if front.any():
                fx, fy = cpu[front][o], np.maximum(err[front][o], 1e-5)
                ax.step(np.r_[fx, fx[-1] * 3], np.r_[fy, fy[-1]], where="post", color="k",
                        lw=1, ls="--", zorder=2, label="Pareto front")  # fmt: skip
            ax.set_xscale("log")
            ax.set_yscale("log")
            ax.set_xlabel("CPU per point [s]")
            ax.set_ylabel(f"RMS |{q}/{q}_ref − 1|")
            ax.set_title(f"{case}: {q}", fontsize=10)
            ax.grid(True, which="both", alpha=0.25)
    handles = [plt.Line2D([], [], marker=m, ls="", color="grey", markeredgecolor="k", label=s)
               for s, m in SCHEME_MARKERS.items()]  # fmt: skip
    handles += [plt.Line2D([], [], marker="o", ls="", color=colors[v], label=v) for v in variants]
    handles += [plt.Line2D([], [], marker="x", ls="", color="grey", label="a point failed"),
                plt.Line2D([], [], ls="--", color="k", label="Pareto front")]  # fmt: skip
    fig.legend(handles=handles, loc="upper center", ncol=min(len(handles), 6), fontsize=8)
    fig.tight_layout(rect=(0, 0, 1, 1 - 0.5 / (3.6 * len(cases))))
    fig.savefig(out, dpi=120)
    plt.close(fig)


def stability_map_figure(ds: xr.Dataset, out: str | os.PathLike) -> None:
    """Where each scheme converged or failed: u_p/c0 across, a panel per case and axis.

    The strength panel holds the stability resolution's points (a row per scheme); each
    axis panel a row per axis value and scheme, the default value taken from the strength
    panel's points. Colour: the outcome (ok, not_converged, or the failure status, whose
    class from ``failures.FAILURES`` is in the legend); marker: the scheme."""
    import json

    from .failures import FAILURES

    cases = json.loads(ds.attrs.get("cases", "{}"))
    axes_meta = json.loads(ds.attrs.get("axes", "{}"))
    panels = []  # (case, axis or "")
    for case, meta in cases.items():
        if "stability_variant" in meta:
            panels.append((case, ""))
            panels += [(case, a) for a in axes_meta.get(case, {})]
    if not panels:
        fig, ax = plt.subplots(figsize=(4, 2))
        ax.text(0.5, 0.5, "no stability map in this campaign", ha="center", va="center")
        ax.axis("off")
        fig.savefig(out, dpi=100)
        plt.close(fig)
        return
    statuses = list(dict.fromkeys(["ok", "not_converged", *sorted(set(ds["status"].values))]))
    failed = [s for s in statuses if s not in OUTCOME_COLORS]
    palette = ["tab:red", "tab:purple", "tab:brown", "tab:pink", "tab:blue", "tab:cyan",
               "tab:olive", "tab:gray", "black", "tab:orange"]  # fmt: skip
    color = {**OUTCOME_COLORS, **{s: palette[i % len(palette)] for i, s in enumerate(failed)}}
    ncol = min(3, len(panels))
    nrow = -(-len(panels) // ncol)
    fig, grid = plt.subplots(nrow, ncol, figsize=(5.2 * ncol, 3.4 * nrow), squeeze=False)
    case_v, variant_v = ds["case"].values, ds["variant"].values
    axis_v, scheme_v = ds["axis"].values, ds["scheme"].values
    x_all = ds["u_p_over_c0"].values
    for k, (case, axis) in enumerate(panels):
        ax = grid[k // ncol, k % ncol]
        base = (case_v == case) & (variant_v == cases[case]["stability_variant"])
        rows: list[tuple[str, np.ndarray]] = []  # (label, mask) bottom to top
        if not axis:
            for s in dict.fromkeys(scheme_v[base]):
                rows.append((s, base & (scheme_v == s)))
            title = f"{case}: shock strength ({cases[case]['stability_variant']} resolution)"
        else:
            meta = axes_meta[case][axis]
            on = (case_v == case) & (axis_v == axis)
            schemes = list(dict.fromkeys(scheme_v[on]))
            own = set(ds["axis_value"].values[on].astype(float))
            # the default value's row: the axis's own points if it ran it, else the strength
            # panel's (when the axis's other keys are at the base's values: base_row)
            with_base = meta["base"] not in own and meta.get("base_row", 1)
            values = sorted(own | ({meta["base"]} if with_base else set()))
            for val in values:
                for s in schemes:
                    if val in own:
                        m = on & (scheme_v == s) & np.isclose(ds["axis_value"].values, val)
                    else:
                        m = base & (scheme_v == s)
                    tag = f"{val:.3g}" + (" (default)" if val == meta["base"] else "")
                    rows.append((f"{s} {tag}", m))
            unit = meta["unit"]
            more = len(meta["keys"]) - 1
            title = (f"{case}: {axis} = {meta['keys'][0]}" + (f" [{unit}]" if unit != "1" else "")
                     + (f" (+{more} key{'s' * (more > 1)})" if more else ""))  # fmt: skip
        for y, (_, m) in enumerate(rows):
            for i in np.flatnonzero(m):
                st = str(ds["status"].values[i])
                ax.scatter(x_all[i], y, marker=SCHEME_MARKERS.get(str(scheme_v[i]), "x"),
                           color=color.get(st, "k"), s=60, edgecolors="k", linewidths=0.4)  # fmt: skip
        ax.set_yticks(range(len(rows)), [r[0] for r in rows], fontsize=7)
        ax.set_ylim(-0.7, len(rows) - 0.3)
        ax.set_xscale("log")
        # labels at 1, 2, 5 per decade (every minor tick's label overlapped on a narrow
        # range), at every digit where the panel spans less than a decade
        xs = x_all[np.any([m for _, m in rows], axis=0)] if rows else np.empty(0)
        xs = xs[np.isfinite(xs) & (xs > 0)]
        narrow = xs.size and xs.max() < 10 * xs.min()
        subs = tuple(range(1, 10)) if narrow else (1.0, 2.0, 5.0)
        ax.xaxis.set_major_locator(LogLocator(base=10.0, subs=subs))
        ax.xaxis.set_major_formatter(FormatStrFormatter("%g"))
        ax.xaxis.set_minor_formatter(NullFormatter())
        ax.set_xlabel("u_p / c0")
        ax.set_title(title if len(title) < 70 else title[:67] + "...", fontsize=9)
        ax.grid(True, axis="x", alpha=0.3)
    for k in range(len(panels), nrow * ncol):
        grid[k // ncol, k % ncol].axis("off")
    handles = [
        plt.Line2D([], [], marker="o", ls="", color=color[s], markeredgecolor="k",
                   label=s if s in OUTCOME_COLORS else f"{s} ({FAILURES.get(s, ('?',))[0]})")
        for s in statuses if s in set(ds["status"].values) or s in OUTCOME_COLORS
    ]  # fmt: skip
    handles += [plt.Line2D([], [], marker=m, ls="", color="w", markeredgecolor="k", label=s)
                for s, m in SCHEME_MARKERS.items()]  # fmt: skip
    fig.legend(handles=handles, loc="upper center", ncol=min(len(handles), 6), fontsize=8)
    fig.tight_layout(rect=(0, 0, 1, 1 - 0.9 / (3.4 * nrow)))
    fig.savefig(out, dpi=120)
    plt.close(fig)


def pulls_figure(ds: xr.Dataset, out: str | os.PathLike) -> None:
    """Every usable point's pull against its reference, z = (X/X_ref − 1)/σ (σ the combined
    error ``err_X_err``), for D and for P, a row per case: x the point's u_p/c0 (schemes set
    side by side), filled markers ok, open not_converged; bands at |z| ≤ 1 and 2. The
    title gives the RMS pull and, for a replica study (the ``replicas`` attribute:
    ``analysis.replicas``), the pooled reduced χ² of the replicas about their means."""
    import json

    reps = json.loads(ds.attrs.get("replicas", "{}"))
    cases = list(dict.fromkeys(ds["case"].values))
    fig, axes = plt.subplots(len(cases), 2, figsize=(10, 3.4 * len(cases)), squeeze=False)
    schemes = list(SCHEME_MARKERS)
    for r, case in enumerate(cases):
        sel = ds["case"].values == case
        status = ds["status"].values[sel]
        x0 = ds["u_p_over_c0"].values[sel].astype(float)
        span = np.ptp(x0) if x0.size > 1 and np.ptp(x0) > 0 else 1.0
        for c, q in enumerate(("D", "P")):
            ax = axes[r, c]
            z = ds[f"err_{q}"].values[sel] / ds[f"err_{q}_err"].values[sel]
            ax.axhspan(-2, 2, color="0.92", zorder=0)
            ax.axhspan(-1, 1, color="0.82", zorder=0)
            ax.axhline(0, color="k", lw=0.6)
            for k, scheme in enumerate(schemes):
                m = ds["scheme"].values[sel] == scheme
                x = x0[m] + (k - 1.5) * 0.012 * span
                for okm, face in (
                    (status[m] == "ok", None),
                    (status[m] == "not_converged", "none"),
                ):
                    ax.scatter(x[okm], z[m][okm], marker=SCHEME_MARKERS[scheme], s=40,
                               facecolors=face, edgecolors="k" if face is None else "C0",
                               color="C0", linewidths=0.8, zorder=3)  # fmt: skip
            fin = np.isfinite(z)
            rms = float(np.sqrt(np.mean(z[fin] ** 2))) if fin.any() else float("nan")
            title = f"{case}: {q}, RMS pull {rms:.2f}"
            u = reps.get(case, {}).get("usable", {})
            if f"{q}_chi2_red" in u:
                title += f", replicas' pooled χ²/ν {u[f'{q}_chi2_red']:.2f}"
            ax.set_title(title, fontsize=9)
            ax.set_xlabel("u_p / c0")
            ax.set_ylabel(f"({q}/{q}_ref − 1) / σ")
            ax.grid(True, alpha=0.25)
    handles = [plt.Line2D([], [], marker=m, ls="", color="C0", markeredgecolor="k", label=s)
               for s, m in SCHEME_MARKERS.items()]  # fmt: skip
    handles.append(plt.Line2D([], [], marker="o", ls="", markerfacecolor="none",
                              markeredgecolor="C0", label="not_converged"))  # fmt: skip
    fig.legend(handles=handles, loc="upper center", ncol=len(handles), fontsize=8)
    fig.tight_layout(rect=(0, 0, 1, 1 - 0.5 / (3.4 * len(cases))))
    fig.savefig(out, dpi=120)
    plt.close(fig)
