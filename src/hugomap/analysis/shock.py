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
    ux: np.ndarray,
    count: np.ndarray,
    x_edges: np.ndarray,
    x_lo: float,
    x_hi: float,
    u_behind: float | None = None,
    u_ahead: float | None = None,
) -> float:
    """Front position [σ] from one velocity profile by a two-level change-point fit.

    Bins with centres inside (x_lo, x_hi) and at least 2 atoms are fitted with a step: the
    split that best separates two constant levels (largest k (n − k)/n · Δū²) is the rough
    front; within ±3 bins of it the front is refined to sub-bin accuracy by integrating the
    normalised velocity, x_f = x_start + Σ w · clip((u_b − u_a)/(u_s − u_a), 0, 1), with u_s,
    u_a the two fitted levels. Returns NaN if no split exists, or, when the expected flow
    velocities behind and ahead of the front are given, if either fitted level is off by more
    than half their difference (a split of noise, e.g. before a weak shock has formed: the
    first sample of a u_p = 0.5 piston run put a "front" at 63 σ and ended its loading).
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
    if u_behind is not None and u_ahead is not None:
        tol = 0.5 * abs(u_behind - u_ahead)
        if abs(us - u_behind) > tol or abs(ua - u_ahead) > tol:
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
    rho1: float,
    P1: float,
    E1: float,
    D: float,
    u: float,
    rho: float,
    P: float,
    E: float,
    u1: float = 0.0,
) -> dict[str, float]:
    """Relative residuals of the three jump conditions (module docstring).

    The state ahead of the front is (ρ1, P1, E1) moving at u1 (the pole at rest by default;
    the elastic precursor's state when a plastic wave follows one), the state behind it
    (ρ, P, E) moving at u, the front at D (all velocities in the frame of the pole material):
    mass = ρ(D − u)/(ρ1(D − u1)) − 1;  momentum = (P − P1)/(ρ1 (D − u1)(u − u1)) − 1;
    energy = (E − E1)/(½(P + P1)(V1 − V)) − 1.
    """
    V1, V = 1.0 / rho1, 1.0 / rho
    with np.errstate(divide="ignore", invalid="ignore"):
        return {
            "mass": float(rho * (D - u) / (rho1 * (D - u1)) - 1.0),
            "momentum": float((P - P1) / (rho1 * (D - u1) * (u - u1)) - 1.0),
            "energy": float((E - E1) / (0.5 * (P + P1) * (V1 - V)) - 1.0),
        }


_JUMP_ARGS = ("rho1", "P1", "E1", "D", "u", "rho", "P", "E", "u1")


def jump_residual_errors(
    values: dict[str, float], errors: dict[str, float], rel_step: float = 1e-6
) -> dict[str, float]:
    """Standard errors of ``jump_residuals`` by first-order propagation.

    ``values``/``errors`` are keyed by the arguments of ``jump_residuals`` (rho1, P1, E1, D,
    u, rho, P, E, u1; missing errors count as 0). The errors are treated as independent,
    σ_r² = Σ (∂r/∂x σ_x)², with the derivatives taken by central differences.
    """
    base = {k: float(values.get(k, 0.0)) for k in _JUMP_ARGS}
    var = {k: 0.0 for k in ("mass", "momentum", "energy")}
    for name in _JUMP_ARGS:
        sx = float(errors.get(name, 0.0) or 0.0)
        if not sx > 0:
            continue
        h = rel_step * max(abs(base[name]), 1.0)
        up = jump_residuals(**{**base, name: base[name] + h})
        dn = jump_residuals(**{**base, name: base[name] - h})
        for k in var:
            var[k] += ((up[k] - dn[k]) / (2 * h) * sx) ** 2
    return {k: float(np.sqrt(v)) for k, v in var.items()}


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
    u_upstream: float | None = None,
    u_piston: float | None = None,
    precursor_sigmas: float = 5.0,
    precursor_fraction: float = 0.03,
    front_speed: tuple[float, float] | None = None,
) -> dict[str, float | str | bool]:
    """One Hugoniot point from the drive-stage samples of a piston run.

    ``front_speed`` (speed, standard error) in the samples' frame replaces the tracked
    front's slope in D when given (a moving window's L dω/dt: the mass balance of the whole
    window, which a broad weak front does not blur); the tracked slope is then kept as
    ``D_front`` as a check.

    ``h`` holds the history arrays of ``window.piston.History``; ``pole`` the initial state
    (rho0, P0, E0 and their errors). For each drive sample, the shocked slab is
    [max(x_L + gap, x_f − gap − avg_length), x_f − gap] — the most recently shocked material:
    the material shocked first keeps the entropy of the piston's start-up transient — the
    slab ahead of the front [x_f + gap, x_f + gap + avg_length] and the upstream slab
    [x_f + gap, x_R − gap] (whole bins). Then
      D_w = d x_f/dt (Theil–Sen fit over the drive samples), u_a, u_s = upstream and shocked mean
      x velocities, D = D_w − u_a, u_p = u_s − u_a (both relative to the upstream material),
      ρ, P = P_xx, E = e, T: block averages over the samples of the shocked slab's state.
    When the upstream velocity ``u_upstream`` is known exactly (the piston removes the sample's
    drift), it replaces the measured u_a, whose thermal noise √(T/N) would otherwise enter D
    and u_p; when the piston velocity ``u_piston`` is given too, u_p = u_piston − u_upstream
    (a steady shocked state moves with the piston). The measured jump u_s − u_a is always
    returned as ``u_p_measured``.

    Two waves: in a crystal an elastic precursor can run ahead of the tracked (plastic) front.
    Its state is the one ahead of the front; it is flagged (``two_wave`` = 1) when its P_xx
    differs from P0 by more than ``precursor_sigmas`` standard errors and more than
    ``precursor_fraction`` of P − P0, and the jump conditions are then checked across the
    tracked front from that state (``ahead_*``) instead of from the pole.
    Converged when every |jump residual| ≤ ``residual_tol`` and the fit has at least
    2·n_blocks samples; ``residual_*_err`` are the residuals' propagated standard errors.
    """
    from .stats import block_average, line_fit, robust_slope

    drive = h["stage"] == 1
    t = h["t"][drive]
    xf = h["front"][drive]
    xl = h["x_left"][drive]
    xr = h["x_right"][drive]
    sums = h["sums"][drive]
    nbins = sums.shape[1] if sums.ndim == 3 else 0
    edges = np.arange(nbins + 1) * bin_width
    keys = ("n", "ux", "Pxx", "Pyy", "Pzz", "T", "e")
    nan_state = {k: np.nan for k in keys}
    shocked = {k: [] for k in keys}
    ahead = {k: [] for k in keys}
    upstream_u = []
    length = avg_length if avg_length is not None else np.inf
    for i in range(t.size):
        lo, hi = max(xl[i] + gap, xf[i] - gap - length), xf[i] - gap
        a_lo, a_hi = xf[i] + gap, min(xr[i] - gap, xf[i] + gap + length)
        ok = np.isfinite(xf[i]) and hi - lo >= min_region
        st = region_state(sums[i], edges, lo, hi, area) if ok else nan_state
        ok_a = np.isfinite(xf[i]) and a_hi - a_lo >= min_region
        st_a = region_state(sums[i], edges, a_lo, a_hi, area) if ok_a else nan_state
        for k in keys:
            shocked[k].append(st[k])
            ahead[k].append(st_a[k])
        upstream_u.append(
            region_state(sums[i], edges, xf[i] + gap, xr[i] - gap, area)["ux"] if ok else np.nan
        )
    # Theil–Sen slope (robust to tracker jumps), with the least-squares standard error.
    _, _, D_w_err, _ = line_fit(t, xf)
    D_w = robust_slope(t, xf)
    out: dict[str, float | str | bool] = {}
    if front_speed is not None:
        out["D_front"], out["D_front_err"] = D_w - (u_upstream or 0.0), D_w_err
        D_w, D_w_err = front_speed
    u_a, u_a_err = block_average(np.asarray(upstream_u), n_blocks)
    u_s, u_s_err = block_average(np.asarray(shocked["ux"]), n_blocks)
    out["u_p_measured"], out["u_p_measured_err"] = u_s - u_a, float(np.hypot(u_s_err, u_a_err))
    if u_upstream is not None:
        u_a, u_a_err = float(u_upstream), 0.0
    D = D_w - u_a
    if u_piston is not None and u_upstream is not None:
        u_p, u_p_err = float(u_piston) - u_a, 0.0
    else:
        u_p, u_p_err = u_s - u_a, float(np.hypot(u_s_err, u_a_err))
    out["D"], out["D_err"] = D, float(np.hypot(D_w_err, u_a_err))
    out["u_p"], out["u_p_err"] = u_p, u_p_err
    for key, name in (
        ("n", "rho"),
        ("Pxx", "P"),
        ("Pyy", "Pyy"),
        ("Pzz", "Pzz"),
        ("T", "T"),
        ("e", "E"),
    ):
        out[name], out[name + "_err"] = block_average(np.asarray(shocked[key]), n_blocks)
    for key, name in (("n", "rho"), ("Pxx", "P"), ("e", "E"), ("ux", "u")):
        out["ahead_" + name], out["ahead_" + name + "_err"] = block_average(
            np.asarray(ahead[key]), n_blocks
        )
    out["ahead_u"] = out["ahead_u"] - u_a  # in the frame of the pole material
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
    dP_ahead = out["ahead_P"] - pole["P0"]
    dP_ahead_err = float(np.hypot(out["ahead_P_err"], pole.get("P0_err", 0.0)))
    two_wave = bool(
        np.isfinite(dP_ahead)
        and abs(dP_ahead) > precursor_sigmas * dP_ahead_err
        and abs(dP_ahead) > precursor_fraction * abs(P - pole["P0"])
    )
    out["two_wave"] = float(two_wave)
    vals = {"D": D, "u": u_p, "rho": rho, "P": P, "E": E}
    errs = {"D": out["D_err"], "u": u_p_err, "rho": out["rho_err"], "P": out["P_err"]}
    errs["E"] = out["E_err"]
    if two_wave:
        vals.update(rho1=out["ahead_rho"], P1=out["ahead_P"], E1=out["ahead_E"])
        vals["u1"] = out["ahead_u"]
        for k, a in (("rho1", "rho"), ("P1", "P"), ("E1", "E"), ("u1", "u")):
            errs[k] = out[f"ahead_{a}_err"]
    else:
        vals.update(rho1=pole["rho0"], P1=pole["P0"], E1=pole["E0"], u1=0.0)
        for k, a in (("rho1", "rho0"), ("P1", "P0"), ("E1", "E0")):
            errs[k] = pole.get(a + "_err", 0.0)
    res = jump_residuals(**vals)
    out.update({f"residual_{k}": v for k, v in res.items()})
    res_err = jump_residual_errors(vals, errs)
    out.update({f"residual_{k}_err": v for k, v in res_err.items()})
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
