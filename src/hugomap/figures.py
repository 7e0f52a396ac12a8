"""Hugoniot figures: P–V and D–u_p, points by scheme with error bars, reference as a line."""

from __future__ import annotations

import os

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import xarray as xr  # noqa: E402


def hugoniot_figures(
    agg: str | os.PathLike, out_pv: str | os.PathLike, out_dup: str | os.PathLike
) -> None:
    """Draw P(V) and D(u_p) for one scene's aggregate; failed points drawn hollow."""
    with xr.open_dataset(agg, engine="netcdf4") as ds:
        ds = ds.load()
    scene = ds.attrs.get("scene", "")
    for out, (xv, yv, xl, yl) in (
        (out_pv, ("V", "P", "specific volume V [σ³]", "longitudinal stress P_xx [ε σ⁻³]")),
        (out_dup, ("u_p_measured", "D", "particle velocity u_p [σ/τ]", "shock velocity D [σ/τ]")),
    ):
        fig, ax = plt.subplots(figsize=(5.5, 4.2), dpi=120)
        for sch in ds["scheme"].values:
            d = ds.sel(scheme=sch)
            ok = d["converged"].values.astype(bool)
            x, y = d[xv].values, d[yv].values
            xe, ye = d[xv + "_err"].values, d[yv + "_err"].values
            ax.errorbar(x[ok], y[ok], xerr=xe[ok], yerr=ye[ok], fmt="o", label=f"{sch} (MD)")
            if (~ok).any():
                ax.plot(x[~ok], y[~ok], "o", mfc="none", mec="gray", label=f"{sch}, not converged")
        rx = {"V": "ref_V", "u_p_measured": "ref_u_p"}[xv]
        ry = {"P": "ref_P", "D": "ref_D"}[yv]
        if rx in ds and ry in ds:
            order = np.argsort(ds[rx].values)
            ax.plot(
                ds[rx].values[order],
                ds[ry].values[order],
                "k-",
                lw=1.2,
                label="reference (equilibrium MD)",
            )
        if xv == "V" and "rho0" in ds:
            ax.plot([1.0 / float(ds["rho0"])], [float(ds["P0"])], "k*", ms=9, label="pole")
        ax.set_xlabel(xl)
        ax.set_ylabel(yl)
        ax.set_title(f"{scene}: LJ rc = {ds.attrs.get('rc', '')}")
        ax.legend(fontsize=8)
        fig.tight_layout()
        fig.savefig(out)
        plt.close(fig)
