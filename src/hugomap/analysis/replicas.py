"""Do the stated errors hold? Replica statistics of a campaign's points.

A replica study runs the same scene with independent samples (seeds) and nothing else
changed. For each group of replicas (one scheme at one u_p), with e_i a point's relative
deviation from its reference Hugoniot and s_i the combined error of e_i (the point's and the
reference's; each replica has its own sample, pole and reference):
    reduced χ² about the replicas' mean  χ²_ν = Σ (e_i − ē)² / s_i² / (n − 1),
        ē = Σ e_i/s_i² / Σ 1/s_i² (weighted mean);
    pooled over groups                   χ²_ν = Σ_groups Σ (e_i − ē)²/s_i² / Σ (n − 1);
    pull of a point                      z_i = e_i / s_i,  RMS pull = √⟨z_i²⟩.
Errors that hold give χ²_ν near 1 (for ν = 7, 90 % of values fall in 0.31–2.0) and an RMS
pull near 1; χ²_ν ≫ 1 means errors too small, ≪ 1 too large; an RMS pull well above √χ²_ν
means a bias that the replicas share (the reference, or the method).

Do the methods agree? A window point against the piston point of the same sample and
nominal u_p (``against_base``): d_i = e_i − e_piston, with the two points' own errors
s_i = √(σ_i² + σ_piston²) (relative; the reference's error, common to both, cancels). Its
pull d_i/s_i has an RMS near 1 when the two schemes agree within their errors.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import numpy as np

SEED_KEY = "sample.seed"


def replica_cases(campaign: Mapping) -> list[str]:
    """The campaign's cases that are replica studies: at least two resolutions, each setting
    nothing but ``sample.seed``."""
    out = []
    for case, spec in campaign.get("cases", {}).items():
        res = spec.get("resolutions", {})
        if len(res) >= 2 and all(set(r) == {SEED_KEY} for r in res.values()):
            out.append(case)
    return out


def against_base(
    pairs: Sequence[tuple], schemes: Sequence[str], e: np.ndarray, s: np.ndarray,
    base: str = "piston",
) -> tuple[list[int], np.ndarray, np.ndarray]:  # fmt: skip
    """Each point's deviation from the ``base`` scheme's point of the same pair key (module
    docstring): (indices of the points that have one, d = e_i − e_base, √(s_i² + s_base²)).
    ``pairs``: one key a point (e.g. (scene, u_p)); ``e``, ``s``: relative deviations from
    a common reference and the points' own errors. A key with no base point, or with more
    than one, pairs nothing; a point or base without a finite value gives NaN."""
    e, s = np.asarray(e, float), np.asarray(s, float)
    bases: dict[tuple, list[int]] = {}
    for i, (k, sch) in enumerate(zip(pairs, schemes, strict=True)):
        if sch == base:
            bases.setdefault(k, []).append(i)
    idx, d, sd = [], [], []
    for i, (k, sch) in enumerate(zip(pairs, schemes, strict=True)):
        j = bases.get(k, [])
        if sch == base or len(j) != 1:
            continue
        idx.append(i)
        d.append(e[i] - e[j[0]])
        sd.append(float(np.hypot(s[i], s[j[0]])))
    return idx, np.array(d, dtype=float), np.array(sd, dtype=float)


def group_chi2(e: np.ndarray, s: np.ndarray) -> tuple[float, int, float]:
    """(Σ (e_i − ē)²/s_i², degrees of freedom n − 1, weighted mean ē) of one group; finite,
    positive s only; (nan, 0, nan) with fewer than two."""
    e, s = np.asarray(e, float), np.asarray(s, float)
    ok = np.isfinite(e) & np.isfinite(s) & (s > 0)
    e, s = e[ok], s[ok]
    if e.size < 2:
        return float("nan"), 0, float("nan")
    w = 1.0 / s**2
    m = float(np.sum(w * e) / np.sum(w))
    return float(np.sum(w * (e - m) ** 2)), int(e.size - 1), m


def replica_summary(
    groups: Sequence[tuple[str, ...]],
    values: Mapping[str, tuple[np.ndarray, np.ndarray]],
) -> dict:
    """Replica statistics (module docstring) of points labelled by ``groups`` (one tuple a
    point, e.g. (scheme, u_p); replicas share a label) for each quantity of ``values``
    (name → (e, s): relative deviations and their errors, one a point).

    Returns {"groups": [{label, n, and per quantity: mean, sd, mean_err (the mean stated
    error), chi2_red}], and per quantity "<q>_chi2_red" (pooled), "<q>_pull_rms",
    "<q>_n"}."""
    labels = sorted(set(groups))
    idx = {g: [i for i, x in enumerate(groups) if x == g] for g in labels}
    out: dict = {}
    rows: dict = {g: {"label": list(g), "n": len(idx[g])} for g in labels}
    for q, (e_all, s_all) in values.items():
        e_all, s_all = np.asarray(e_all, float), np.asarray(s_all, float)
        chi, dof = 0.0, 0
        for g in labels:
            e, s = e_all[idx[g]], s_all[idx[g]]
            c, k, _ = group_chi2(e, s)
            if k:
                chi, dof = chi + c, dof + k
            ok = np.isfinite(e) & np.isfinite(s)
            rows[g][q] = {
                "mean": float(np.mean(e[ok])) if ok.any() else float("nan"),
                "sd": float(np.std(e[ok], ddof=1)) if ok.sum() > 1 else float("nan"),
                "mean_err": float(np.mean(s[ok])) if ok.any() else float("nan"),
                "chi2_red": c / k if k else float("nan"),
            }
        out[f"{q}_chi2_red"] = chi / dof if dof else float("nan")
        ok = np.isfinite(e_all) & np.isfinite(s_all) & (s_all > 0)
        z = e_all[ok] / s_all[ok]
        out[f"{q}_pull_rms"] = float(np.sqrt(np.mean(z**2))) if z.size else float("nan")
        out[f"{q}_n"] = int(z.size)
    out["groups"] = [rows[g] for g in labels]
    return out
