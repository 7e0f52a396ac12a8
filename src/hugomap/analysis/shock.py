"""Shock-front tracking, shocked-state averaging and the Rankine–Hugoniot jump conditions.

Frame: the piston frame of ``window.piston`` (piston wall at rest at x_L, shocked material
near rest, upstream material flowing in at u_a ≈ −u_p, front moving at +(D − u_p)).
Reduced LJ units (σ, τ, ε; m = 1).

Jump conditions across a steady front moving at D into material at rest (Zel'dovich &
Raizer, ch. I §17), with u_p the particle-velocity jump and V = 1/ρ:
    mass:      ρ0 D = ρ (D − u_p)
    momentum:  P − P0 = ρ0 D u_p          (P: longitudinal component P_xx)
    energy:    E − E0 = ½ (P + P0)(V0 − V)
``jump_residuals`` returns each as a relative residual (0 when it holds exactly).
"""

from __future__ import annotations

import numpy as np

from ..md.profiles import fields_from_sums


def front_position(
    ux: np.ndarray, count: np.ndarray, x_edges: np.ndarray, x_lo: float, x_hi: float
) -> float:
    """Front position [σ] from one velocity profile by a two-level change-point fit.

    Bins with centres inside (x_lo, x_hi) and at least 2 atoms are fitted with a step: the
    split that best separates two constant levels (largest k (n − k)/n · Δū²) is the rough
    front; within ±3 bins of it the front is refined to sub-bin accuracy by integrating the
    normalised velocity, x_f = x_start + Σ w · clip((u_b − u_a)/(u_s − u_a), 0, 1), with u_s,
    u_a the two fitted levels. Returns NaN if no split exists.
    """
    centres = 0.5 * (x_edges[:-1] + x_edges[1:])
    sel = np.nonzero((centres > x_lo) & (centres < x_hi) & (count >= 2) & np.isfinite(ux))[0]
    n = sel.size
    if n < 4:
        return float("nan")
    u = ux[sel]
    c = np.cumsum(u)
    k = np.arange(1, n)
    left = c[:-1] / k
    right = (c[-1] - c[:-1]) / (n - k)
    score = k * (n - k) / n * (left - right) ** 2
    kb = int(np.argmax(score))
    us, ua = left[kb], right[kb]
    if us == ua:
        return float("nan")
    lo = max(kb + 1 - 3, 0)
    hi = min(kb + 1 + 3, n)
    w = x_edges[sel + 1] - x_edges[sel]
    frac = np.clip((u[lo:hi] - ua) / (us - ua), 0.0, 1.0)
    return float(x_edges[sel[lo]] + np.sum(w[lo:hi] * frac))


def region_sums(
    sums: np.ndarray, x_edges: np.ndarray, x_lo: float, x_hi: float
) -> tuple[np.ndarray, int]:
    """Sum the raw bin sums (nbins, 11) of the bins lying wholly inside [x_lo, x_hi]."""
    inside = (x_edges[:-1] >= x_lo) & (x_edges[1:] <= x_hi)
    return sums[inside].sum(axis=0), int(inside.sum())


def region_state(
    sums: np.ndarray, x_edges: np.ndarray, x_lo: float, x_hi: float, area: float
) -> dict[str, float]:
    """Mean state of the slab [x_lo, x_hi] (whole bins): n, ux, Pxx, Pyy, Pzz, T, e.

    The bins are merged before the fields are formed, so the mean velocity removed is the
    region's (see ``md.profiles``)."""
    s, nb = region_sums(sums, x_edges, x_lo, x_hi)
    if nb == 0:
        return {k: float("nan") for k in ("n", "ux", "Pxx", "Pyy", "Pzz", "T", "e")}
    width = float(x_edges[1] - x_edges[0])
    out = fields_from_sums(s[None, :], area * width * nb)
    return {k: float(v[0]) for k, v in out.items()}


def jump_residuals(
    rho0: float, P0: float, E0: float, D: float, u_p: float, rho: float, P: float, E: float
) -> dict[str, float]:
    """Relative residuals of the three jump conditions (module docstring).

    mass = ρ(D − u_p)/(ρ0 D) − 1;  momentum = (P − P0)/(ρ0 D u_p) − 1;
    energy = (E − E0)/(½(P + P0)(V0 − V)) − 1.
    """
    V0, V = 1.0 / rho0, 1.0 / rho
    with np.errstate(divide="ignore", invalid="ignore"):
        return {
            "mass": float(rho * (D - u_p) / (rho0 * D) - 1.0),
            "momentum": float((P - P0) / (rho0 * D * u_p) - 1.0),
            "energy": float((E - E0) / (0.5 * (P + P0) * (V0 - V)) - 1.0),
        }


def analyse_piston(
    h: dict[str, np.ndarray],
    pole: dict[str, float],
    area: float,
    bin_width: float,
    gap: float,
    n_blocks: int = 8,
    residual_tol: float = 0.03,
    min_region: float = 3.0,
    avg_length: float | None = None,
) -> dict[str, float | str | bool]:
    """One Hugoniot point from the drive-stage samples of a piston run.

    ``h`` holds the history arrays of ``window.piston.History``; ``pole`` the initial state
    (rho0, P0, E0 and their errors). For each drive sample, the shocked slab is
    [max(x_L + gap, x_f − gap − avg_length), x_f − gap] — the most recently shocked material:
    the material shocked first keeps the entropy of the piston's start-up transient — and the
    upstream slab [x_f + gap, x_R − gap] (whole bins). Then
      D_w = d x_f/dt (line fit over the drive samples), u_a, u_s = upstream and shocked mean
      x velocities, D = D_w − u_a, u_p = u_s − u_a (both relative to the upstream material),
      ρ, P = P_xx, E = e, T: block averages over the samples of the shocked slab's state.
    Converged when every |jump residual| ≤ ``residual_tol`` (their own statistical errors are
    a few 1e-3 here) and the fit has at least 2·n_blocks samples.
    """
    from .stats import block_average, line_fit

    drive = h["stage"] == 1
    t = h["t"][drive]
    xf = h["front"][drive]
    xl = h["x_left"][drive]
    xr = h["x_right"][drive]
    sums = h["sums"][drive]
    nbins = sums.shape[1] if sums.ndim == 3 else 0
    edges = np.arange(nbins + 1) * bin_width
    keys = ("n", "ux", "Pxx", "Pyy", "Pzz", "T", "e")
    shocked = {k: [] for k in keys}
    upstream_u = []
    for i in range(t.size):
        lo, hi = xl[i] + gap, xf[i] - gap
        if avg_length is not None:
            lo = max(lo, hi - avg_length)
        if not (np.isfinite(xf[i]) and hi - lo >= min_region):
            for k in keys:
                shocked[k].append(np.nan)
            upstream_u.append(np.nan)
            continue
        st = region_state(sums[i], edges, lo, hi, area)
        for k in keys:
            shocked[k].append(st[k])
        upstream_u.append(region_state(sums[i], edges, xf[i] + gap, xr[i] - gap, area)["ux"])
    D_w, _, D_w_err, _ = line_fit(t, xf)
    out: dict[str, float | str | bool] = {}
    u_a, u_a_err = block_average(np.asarray(upstream_u), n_blocks)
    u_s, u_s_err = block_average(np.asarray(shocked["ux"]), n_blocks)
    D = D_w - u_a
    u_p = u_s - u_a
    out["D"], out["D_err"] = D, float(np.hypot(D_w_err, u_a_err))
    out["u_p"], out["u_p_err"] = u_p, float(np.hypot(u_s_err, u_a_err))
    for key, name in (
        ("n", "rho"),
        ("Pxx", "P"),
        ("Pyy", "Pyy"),
        ("Pzz", "Pzz"),
        ("T", "T"),
        ("e", "E"),
    ):
        out[name], out[name + "_err"] = block_average(np.asarray(shocked[key]), n_blocks)
    rho, P, E = out["rho"], out["P"], out["E"]
    out["V"] = 1.0 / rho
    out["V_err"] = out["rho_err"] / rho**2
    out["P_rh"] = pole["P0"] + pole["rho0"] * D * u_p
    out["P_rh_err"] = float(
        pole["rho0"] * np.hypot(out["D_err"] * u_p, D * out["u_p_err"]) + pole.get("P0_err", 0.0)
    )
    out["E_minus_E0"] = E - pole["E0"]
    out["E_minus_E0_err"] = float(np.hypot(out["E_err"], pole.get("E0_err", 0.0)))
    out["shear_stress"] = 0.5 * (P - 0.5 * (out["Pyy"] + out["Pzz"]))
    res = jump_residuals(pole["rho0"], pole["P0"], pole["E0"], D, u_p, rho, P, E)
    out.update({f"residual_{k}": v for k, v in res.items()})
    n_ok = int(np.isfinite(np.asarray(shocked["n"])).sum())
    out["n_samples"] = n_ok
    finite = all(np.isfinite(v) for v in (D, u_p, rho, P, E))
    converged = bool(
        finite and n_ok >= 2 * n_blocks and all(abs(v) <= residual_tol for v in res.values())
    )
    out["converged"] = converged
    if not finite or n_ok < 2 * n_blocks:
        out["status"] = "too_few_samples"
    else:
        out["status"] = "ok" if converged else "not_converged"
    return out
