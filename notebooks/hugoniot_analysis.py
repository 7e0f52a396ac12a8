# ---
# jupyter:
#   jupytext:
#     formats: ipynb,py:percent
#     text_representation:
#       extension: .py
#       format_name: percent
#       format_version: '1.3'
#       jupytext_version: 1.19.6
#   kernelspec:
#     display_name: Python 3
#     language: python
#     name: python3
# ---

# %% [markdown]
# # Hugoniot analysis of a hugomap sweep
#
# Opens the aggregated datasets `results/hugoniot/<scene>.nc` (dims `scheme` × `u_p`) with
# xarray and dask, fits the linear Us–up Hugoniot D = c0 + s·u_p per scheme with its
# uncertainties, overlays each scene's reference (LJ: the equilibrium-MD Hugoniot;
# copper: the EOS or the porous model), and charts cost against error and where the
# methods failed. Units are each dataset's own: SI for CSPH scenes (`units` attributes);
# Lennard-Jones reduced units for MD scenes, which the files (CF-1.11) mark `units = "1"` with
# the reduced unit in `reduced_units` (docs/datasets.md; an MD scene with a `units:` block
# also carries SI copies `D_SI`, `P_SI`, ...).
#
# Run it after a sweep (`snakemake --cores 2 ...`) from the repository root; set
# `HUGOMAP_RESULTS` to read another results folder (the test suite points it at the tiny
# sweep's).

# %%
import os
from pathlib import Path

import matplotlib

matplotlib.use(os.environ.get("MPLBACKEND", "Agg"))
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pandas as pd  # noqa: E402
import xarray as xr  # noqa: E402

from hugomap.analysis.stats import linear_hugoniot_fit  # noqa: E402
from hugomap.campaign import reference_at  # noqa: E402
from hugomap.failures import FAILURES  # noqa: E402
from hugomap.figures import SCHEME_COLORS, SCHEME_MARKERS, unit_text  # noqa: E402
from hugomap.io.dataset import jump_velocity  # noqa: E402

RESULTS = Path(os.environ.get("HUGOMAP_RESULTS", "results"))
FIGURES = RESULTS / "figures" / "notebook"
FIGURES.mkdir(parents=True, exist_ok=True)
files = sorted((RESULTS / "hugoniot").glob("*.nc"))
print(f"{len(files)} scene(s) in {RESULTS / 'hugoniot'}:", [f.stem for f in files])

# %% [markdown]
# ## The datasets
# One file per scene, opened lazily (dask chunks); `status` says which points hold a
# steady state (`ok`), which missed a jump-condition tolerance (`not_converged`), and which
# failed (any other status: the cause is in `hugomap.failures.FAILURES`).

# %%
lazy = {f.stem: xr.open_dataset(f, chunks={}) for f in files}  # dask-backed
scenes = {name: ds.compute() for name, ds in lazy.items()}  # small: read each file once


def unit(var: xr.DataArray) -> str:
    """A variable's unit for a label: its reduced LJ unit (MD) or its SI unit, written as the
    package's figures write units (σ/τ, ε σ⁻³)."""
    return unit_text(str(var.attrs.get("reduced_units", var.attrs.get("units", ""))))


for name, ds in scenes.items():
    print(f"{name}: schemes {list(ds['scheme'].values)}, u_p {list(ds['u_p'].values)} "
          f"[{unit(ds['u_p'])}]")  # fmt: skip

USABLE = ("ok", "not_converged")


def points(ds: xr.Dataset) -> pd.DataFrame:
    """One row per (scheme, u_p): the state, its errors, the status and the cost."""
    cols = [c for c in ("D", "D_err", "u_p_measured", "P", "P_err", "rho", "status",
                        "cpu_s", "ref_P_at_V") if c in ds]  # fmt: skip
    return ds[cols].to_dataframe().reset_index()


tables = {name: points(ds) for name, ds in scenes.items()}
next(iter(tables.values())) if tables else None

# %% [markdown]
# ## Linear Us–up fits
# Weighted least squares on the usable points of each scheme (`ok` and `not_converged`),
# weights 1/D_err², covariance scaled by the reduced χ² where the points scatter more than
# their errors (`hugomap.analysis.stats.linear_hugoniot_fit`). Each point at the u_p its
# jump was taken at, `u_p_jump`: the piston's imposed one, a window's shocked slab (`u_p` of
# the dataset is the requested value; files without `u_p_jump`: MW's amplitude `u_p_set`).


# %%
fits = []
for name, ds in scenes.items():
    for scheme in ds["scheme"].values:
        p = ds.sel(scheme=scheme)
        use = np.isin(p["status"].values.astype(str), USABLE)
        u = jump_velocity(p)[0]
        f = linear_hugoniot_fit(u[use], p["D"].values[use], p["D_err"].values[use])
        fits.append({"scene": name, "scheme": str(scheme), **f})
    if "ref_u_p" in ds and "ref_D" in ds:
        ok = np.isfinite(ds["ref_u_p"].values) & np.isfinite(ds["ref_D"].values)
        ok &= ds["ref_u_p"].values > 0
        err = ds["ref_D_err"].values[ok] if "ref_D_err" in ds else None
        f = linear_hugoniot_fit(ds["ref_u_p"].values[ok], ds["ref_D"].values[ok], err)
        fits.append({"scene": name, "scheme": "reference", **f})
fit_table = pd.DataFrame(fits)
fit_table

# %% [markdown]
# ## D against u_p and P against V, every scheme with the reference
# Each scheme in the colour and marker of the package's figures (`hugomap.figures`): filled
# where the point is `ok`, hollow where it is `not_converged`.

# %%
MARK = {**SCHEME_MARKERS, "reference": "."}
for name, ds in scenes.items():
    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(10, 4))
    for scheme in ds["scheme"].values:
        p = ds.sel(scheme=scheme)
        status = p["status"].values.astype(str)
        use = np.isin(status, USABLE)
        if not use.any():
            continue  # nothing drawn: no legend entry
        u = jump_velocity(p)[0]
        m, c = MARK.get(str(scheme), "x"), SCHEME_COLORS.get(str(scheme), "C4")
        for which, face, tag in (("ok", c, ""), ("not_converged", "none", ", not converged")):
            sel = status == which
            if not sel.any():
                continue
            ax1.errorbar(u[sel], p["D"].values[sel], yerr=p["D_err"].values[sel], fmt=m,
                         color=c, mfc=face, label=f"{scheme}{tag}", capsize=2)  # fmt: skip
            ax2.errorbar(p["V"].values[sel], p["P"].values[sel], yerr=p["P_err"].values[sel],
                         fmt=m, color=c, mfc=face, label=f"{scheme}{tag}", capsize=2)  # fmt: skip
        row = fit_table[(fit_table.scene == name) & (fit_table.scheme == str(scheme))]
        if len(row) and np.isfinite(row["s"].iloc[0]):
            # over the u_p the fit was made on
            uu = np.linspace(float(np.nanmin(u[use])), float(np.nanmax(u[use])), 50)
            ax1.plot(uu, row["c0"].iloc[0] + row["s"].iloc[0] * uu, "--", color=c, lw=0.8,
                     label=f"{scheme}: D = c0 + s u_p")  # fmt: skip
    if "ref_V" in ds and "ref_P" in ds:
        o = np.argsort(ds["ref_V"].values)
        ax2.plot(ds["ref_V"].values[o], ds["ref_P"].values[o], "k-", lw=1, label="reference")
    if "ref_u_p" in ds and "ref_D" in ds:
        o = np.argsort(ds["ref_u_p"].values)
        ax1.plot(ds["ref_u_p"].values[o], ds["ref_D"].values[o], "k-", lw=1, label="reference")
    ax1.set_xlabel(f"u_p [{unit(ds['u_p'])}]")
    ax1.set_ylabel(f"D [{unit(ds['D'])}]")
    ax2.set_xlabel(f"V [{unit(ds['V'])}]")
    ax2.set_ylabel(f"P [{unit(ds['P'])}]")
    ax1.legend(fontsize=8)
    ax1.set_title(name)
    fig.tight_layout()
    fig.savefig(FIGURES / f"{name}_hugoniot.png", dpi=120)

# %% [markdown]
# ## Cost against error
# Per point: CPU seconds (all stages of the point: loading, window set-up, control or
# trials, averaging) against the relative error of P and of D from the scene's reference
# Hugoniot at the point's u_p (MW: the amplitude it reached). This is the sweep's version
# of the campaign chart, from whatever points this results folder holds.

# %%
rows = []
for name, ds in scenes.items():
    if not all(k in ds for k in ("ref_u_p", "ref_P", "ref_D")):
        continue
    o = np.argsort(ds["ref_u_p"].values)
    ru, rp, rd = (ds[k].values[o] for k in ("ref_u_p", "ref_P", "ref_D"))
    keep = np.isfinite(ru) & np.isfinite(rp) & np.isfinite(rd) & (ru > 0)
    ru, rp, rd = ru[keep], rp[keep], rd[keep]
    for scheme in ds["scheme"].values:
        p = ds.sel(scheme=scheme)
        u_all = p["u_p_set"].values if ("u_p_set" in p and scheme == "mw") else p["u_p"].values
        for i, u in enumerate(u_all):
            st = str(p["status"].values[i])
            if st not in USABLE or not (ru.size and ru.min() <= u <= ru.max()):
                continue
            # D linear in u_p, P on the pole's Rayleigh line (campaign.reference_at)
            at = reference_at(u, ru, {"D": rd, "P": rp, "D_err": 0 * ru, "P_err": 0 * ru})
            rows.append({
                "scene": name, "scheme": str(scheme), "u_p": float(u), "status": st,
                "cpu_s": float(p["cpu_s"].values[i]),
                "P_rel_err": abs(float(p["P"].values[i]) / at["P"] - 1.0),
                "D_rel_err": abs(float(p["D"].values[i]) / at["D"] - 1.0),
            })  # fmt: skip
cost = pd.DataFrame(rows, columns=["scene", "scheme", "u_p", "status", "cpu_s", "P_rel_err",
                                   "D_rel_err"])  # fmt: skip
if len(cost):
    fig, axes = plt.subplots(1, 2, figsize=(9, 4))
    for ax, col in zip(axes, ("P_rel_err", "D_rel_err"), strict=True):
        for scheme, g in cost.groupby("scheme"):
            ax.loglog(g["cpu_s"], g[col].clip(lower=1e-5), MARK.get(scheme, "x"),
                      color=SCHEME_COLORS.get(scheme, "C4"), label=scheme)  # fmt: skip
        ax.set_xlabel("CPU per point [s]")
        ax.set_ylabel(f"{col.split('_')[0]}: |x / x_ref(u_p) − 1|")
    axes[0].legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(FIGURES / "cost_vs_error.png", dpi=120)
cost

# %% [markdown]
# ## Where the methods failed
# Every point that is not a usable state, with the cause class of its status.

# %%
fails = []
for name, ds in scenes.items():
    for scheme in ds["scheme"].values:
        p = ds.sel(scheme=scheme)
        for i, up in enumerate(p["u_p"].values):
            st = str(p["status"].values[i])
            if st in USABLE:
                continue
            where, why = FAILURES.get(st, ("?", "unregistered status"))
            fails.append({"scene": name, "scheme": str(scheme), "u_p": float(up), "status": st,
                          "stage": where, "cause": why,
                          "diagnostic": str(p["diagnostic"].values[i])[:120]})  # fmt: skip
failures = pd.DataFrame(fails, columns=["scene", "scheme", "u_p", "status", "stage", "cause",
                                        "diagnostic"])  # fmt: skip
failures

# %% [markdown]
# ## The validation campaign
# `snakemake --cores 2 campaign --configfile config/campaign.yaml` runs every scheme at
# several resolutions on the campaign's cases and writes `results/campaign/<name>.nc`: a row
# per point (dim `point`: relative errors of D and P from the case's reference at the
# point's u_p, CPU seconds, status and failure class) and a marker per case, scheme and
# resolution (dim `setting`: mean CPU per point and RMS errors over the piston velocities all
# resolutions ran, the Pareto fronts). Redrawn here: the speed–accuracy chart, the stability
# map, the fronts as a table, the cheapest setting of each scheme that reaches an accuracy,
# and the failures by cause.

# %%
from IPython.display import Image, display  # noqa: E402

from hugomap.figures import speed_accuracy_figure, stability_map_figure  # noqa: E402

campaigns = {f.stem: xr.open_dataset(f, chunks={}).compute()
             for f in sorted((RESULTS / "campaign").glob("*.nc"))}  # fmt: skip
print(f"{len(campaigns)} campaign(s):", list(campaigns))
settings, camp_points = {}, {}
for name, cds in campaigns.items():
    speed_accuracy_figure(cds, FIGURES / f"{name}_speed_accuracy.png")
    stability_map_figure(cds, FIGURES / f"{name}_stability.png")
    display(Image(filename=str(FIGURES / f"{name}_speed_accuracy.png")))
    display(Image(filename=str(FIGURES / f"{name}_stability.png")))
    setting_vars = [k for k in cds.data_vars if k.startswith("setting_")]
    settings[name] = cds[setting_vars].to_dataframe().reset_index(drop=True)
    camp_points[name] = cds.drop_vars(setting_vars).to_dataframe().reset_index()

# %% [markdown]
# The Pareto fronts: no other setting of the case is both cheaper and more accurate.

# %%
fronts = pd.concat(
    [s[(s.setting_pareto_P == 1) | (s.setting_pareto_D == 1)].assign(campaign=n)
     for n, s in settings.items()] or [pd.DataFrame()], ignore_index=True,
)  # fmt: skip
fronts

# %% [markdown]
# The source's claim that AMW converges faster than MW: the cheapest setting of each scheme
# whose RMS error of D (of P) stays within 0.5, 1, 2 and 5 % (NaN: no setting of that scheme got
# there), in mean CPU seconds per point.

# %%
rows = []
for name, s in settings.items():
    for case, g in s.groupby("setting_case"):
        for q in ("D", "P"):
            for tol in (0.005, 0.01, 0.02, 0.05):
                row = {"campaign": name, "case": case, "error": q, "within": tol}
                for scheme, h in g.groupby("setting_scheme"):
                    ok = h[h[f"setting_err_{q}"].abs() <= tol]
                    row[scheme] = ok["setting_cpu_s"].min() if len(ok) else np.nan
                rows.append(row)
cheapest = pd.DataFrame(rows)
cheapest

# %% [markdown]
# Outcomes by cause, per case and scheme (the stability map's colours, counted).

# %%
outcomes = pd.concat(
    [p.assign(campaign=n) for n, p in camp_points.items()] or [pd.DataFrame()],
    ignore_index=True,
)
if len(outcomes):
    outcomes = (outcomes.groupby(["campaign", "case", "scheme", "status", "failure_class"])
                .size().rename("points").reset_index())  # fmt: skip
outcomes
