"""The validation campaign's expansion (hugomap.campaign_expand), dataset, Pareto fronts and
figures (hugomap.campaign).

References: the expansion is checked against the overrides written in the test; the
dataset's errors against the reference line the synthetic aggregates are built from (a point
at D = 1.02 D_ref has err_D = 0.02 exactly, to rounding); the RMS of a setting and the Pareto
fronts against values worked out by hand; the failure labels against ``failures.FAILURES``.
"""

from __future__ import annotations

import contextlib
import copy
import io
import json
import math
from pathlib import Path

import numpy as np
import pytest
import xarray as xr

from hugomap import campaign as cp
from hugomap.cli import main
from hugomap.config import ConfigError, validate_config
from hugomap.failures import FAILURES
from hugomap.figures import stability_map_figure
from hugomap.io.atomic import write_netcdf
from hugomap.io.dataset import point_dataset
from hugomap.registry import backend
from hugomap.stages import aggregate

C0, S = 3940.0, 1.49


def _base() -> dict:
    return {
        "solver": "csph", "dim": 1, "schemes": ["piston", "amw"],
        "material": {"strength": {"model": "none"}},
        "sample": {"length": 4e-3, "dx": 1e-5},
        "shock": {"u_p": [500.0, 1000.0], "load_fraction": 0.5},
        "window": {"length": 2.0e-3, "front_fraction": 0.6, "window_time": 1e-6,
                   "average_time": 4e-6},
    }  # fmt: skip


def _config() -> dict:
    return {
        "campaign": {
            "name": "demo",
            "cases": {
                "cu": {
                    "scene": _base(),
                    "resolutions": {"coarse": {"sample.dx": 2e-5}, "mid": {}},
                    "stability": {
                        "resolution": "mid",
                        "u_p": [100.0, 1000.0],
                        "axes": {
                            "beta": {"schemes": ["amw"], "set": {"window.amw.beta": [0.2, 2.5]}}
                        },
                    },
                }
            },
        }
    }


def test_expansion_makes_one_scene_per_variant():
    cfg = validate_config(_config())
    assert list(cfg["scenes"]) == ["cu__coarse", "cu__mid", "cu__beta1", "cu__beta2"]
    sc = cfg["scenes"]
    assert sc["cu__coarse"]["sample"]["dx"] == 2e-5 and sc["cu__mid"]["sample"]["dx"] == 1e-5
    assert sc["cu__beta2"]["window"]["amw"]["beta"] == 2.5
    assert sc["cu__beta2"]["schemes"] == ["amw"]
    assert sc["cu__beta2"]["shock"]["u_p"] == [100.0, 1000.0]
    assert sc["cu__mid"]["shock"]["u_p"] == [500.0, 1000.0]
    # defaults are filled per variant (CSPH: proportional to its own dx)
    assert sc["cu__coarse"]["shock"]["bin_width"] == pytest.approx(4e-5)
    assert sc["cu__mid"]["shock"]["bin_width"] == pytest.approx(2e-5)
    # validating again (Snakemake, then a stage) changes nothing
    again = validate_config(copy.deepcopy(cfg))
    assert again == cfg
    vs = cp.variants(cfg["campaign"])
    assert [(v.study, v.axis, v.value) for v in vs][2:] == [
        ("stability", "beta", 0.2),
        ("stability", "beta", 2.5),
    ]


@pytest.mark.parametrize(
    ("change", "needle"),
    [
        (lambda c: c["resolutions"]["coarse"].update({"window.lenth": 1e-3}),
         "scenes.cu__coarse.window: unknown key(s) ['lenth']"),
        (lambda c: c["resolutions"]["coarse"].update({"sample.dx": -1.0}),
         "[scene made by campaign.cases.cu, resolution coarse]"),
        (lambda c: c["stability"]["axes"]["beta"]["set"].update({"window.z": [1.0]}),
         "campaign.cases.cu.stability.axes.beta.set: the value lists"),
        (lambda c: c["stability"].update({"resolution": "fine"}),
         "campaign.cases.cu.stability.resolution = 'fine': not one of the resolutions"),
        (lambda c: c["stability"]["axes"]["beta"]["set"].update({"window.amw.beta": [4.0, 0.5]}),
         "scenes.cu__beta1.window.amw.beta = 4.0: out of range"),
        (lambda c: c["resolutions"].update({"a_b": {}}), "campaign.cases.cu.resolutions"),
    ],
)  # fmt: skip
def test_bad_campaign_is_refused_naming_the_key(change, needle):
    cfg = _config()
    change(cfg["campaign"]["cases"]["cu"])
    with pytest.raises(ConfigError) as e:
        validate_config(cfg)
    assert needle in str(e.value)


def test_user_scene_with_the_separator_is_refused():
    cfg = _config()
    cfg["scenes"] = {"my__scene": _base()}
    with pytest.raises(ConfigError, match="my__scene: '__' in a scene name is reserved"):
        validate_config(cfg)


def test_pareto_front():
    cost = np.array([1.0, 2.0, 3.0, 4.0, 5.0, np.nan, 0.5])
    err = np.array([0.10, 0.20, 0.05, 0.05, 0.01, 0.0, np.nan])
    # 1 s at 10 % is the cheapest; 2 s is beaten by it; 3 s improves; 4 s ties (not better);
    # 5 s improves; NaN cost or error is never on the front
    assert cp.pareto_front(cost, err).tolist() == [True, False, True, False, True, False, False]
    assert cp.pareto_front(np.array([1.0, 1.0]), np.array([-0.2, 0.1])).tolist() == [False, True]


def test_md_c0_is_the_reference_line_intercept():
    """MD: c0 is the intercept of the line fit to the reference Hugoniot (points on
    D = 7.2 + 1.6 u_p give 7.2 to rounding); CSPH: the EOS's c0."""
    u = np.array([0.3, 0.8, 1.5, 2.5])
    ds = xr.Dataset({"ref_u_p": ("ref_point", u), "ref_D": ("ref_point", 7.2 + 1.6 * u),
                     "ref_P": ("ref_point", u), "ref_D_err": ("ref_point", 0.01 + 0 * u)})  # fmt: skip
    assert cp.case_c0(ds, {"solver": "md"}) == pytest.approx(7.2, abs=1e-9)
    assert cp.case_c0(ds, {"solver": "csph", "material": {"eos": {"c0": C0}}}) == C0
    assert math.isnan(cp.case_c0(xr.Dataset(), {"solver": "md"}))


def _aggregates(
    tmp_path: Path, cfg: dict, outcome, extra=None, ups: np.ndarray | None = None,
    ref_err: float = 0.0,
) -> list[Path]:  # fmt: skip
    """Aggregates of every campaign scene from synthetic point files: D = D_ref (1 + e) with
    e and the status from ``outcome(scene, scheme, u)``; the reference D = c0 + s u_p at
    ``ups`` (30 points, 50-1500; MD's u_p need their own range), D's error ``ref_err`` D;
    ``extra(scene, scheme, u)``: more values of a usable point (e.g. its residuals)."""
    ups = np.linspace(50.0, 1500.0, 30) if ups is None else ups
    ref = xr.Dataset({
        "u_p": ("point", ups), "D": ("point", C0 + S * ups),
        "P": ("point", 8930.0 * (C0 + S * ups) * ups), "V": ("point", np.ones(30)),
    })  # fmt: skip
    if ref_err:
        ref["D_err"] = ref_err * ref["D"]
    ref_path = tmp_path / "reference.nc"
    write_netcdf(ref, ref_path)
    out = []
    for name, scene in cfg["scenes"].items():
        files = []
        for scheme in scene["schemes"]:
            for u in scene["shock"]["u_p"]:
                e, status, cpu = outcome(name, scheme, u)
                D = (C0 + S * u) * (1 + e)
                values = {"piston_velocity": u, "cpu_s": cpu, "wall_s": cpu, "u_p_set": u}
                if status in cp.USABLE:
                    values.update(D=D, D_err=0.001 * D, P=8930.0 * D * u, P_err=1e3,
                                  converged=status == "ok")  # fmt: skip
                    values.update(extra(name, scheme, u) if extra else {})
                f = tmp_path / name / f"{scheme}_{u:g}.nc"
                f.parent.mkdir(exist_ok=True)
                ds = point_dataset(values, {"rho0": 8930.0}, None, scheme, name, status,
                                   "synthetic" if status not in cp.USABLE else "", scene,
                                       backend(scene).units)  # fmt: skip
                write_netcdf(ds, f)
                files.append(str(f))
        out.append(aggregate(files, str(ref_path), cfg, name, tmp_path / f"{name}.nc"))
    return out


def _outcome(name: str, scheme: str, u: float) -> tuple[float, str, float]:
    if name == "cu__beta2":
        return 0.0, "diverged" if u > 500 else "oscillating", 5.0
    if name == "cu__coarse" and scheme == "amw" and u == 500.0:
        return 0.0, "too_noisy", 2.0
    e = {"cu__coarse": 0.02, "cu__mid": 0.01}.get(name, 0.005)
    return (
        (-e if scheme == "piston" else 1.5 * e),
        "ok",
        {"piston": 1.0, "amw": 3.0}[scheme] * (2.0 if name == "cu__mid" else 1.0),
    )


def test_dataset_errors_labels_and_settings(tmp_path):
    cfg = validate_config(_config())
    aggs = _aggregates(tmp_path, cfg, _outcome)
    ds = cp.campaign_dataset(cfg, {Path(a).stem: a for a in aggs})
    assert ds.sizes["point"] == 2 * 2 + 2 * 2 + 2 + 2
    pts = ds.to_dataframe().reset_index()
    row = pts[(pts.scene == "cu__mid") & (pts.scheme == "piston") & (pts.u_p_over_c0 > 0.2)]
    assert float(row.err_D.iloc[0]) == pytest.approx(-0.01, abs=1e-12)
    assert float(row.err_P.iloc[0]) == pytest.approx(-0.01, abs=1e-12)
    assert float(row.u_p_over_c0.iloc[0]) == pytest.approx(1000.0 / C0)
    # failed points: labelled by their FAILURES class and cause, and no value
    bad = pts[pts.status != "ok"]
    assert set(bad.status) == {"diverged", "oscillating", "too_noisy"}
    for _, r in bad.iterrows():
        assert (r.failure_class, r.cause) == FAILURES[r.status]
        assert math.isnan(r.err_D) and math.isnan(r.err_P) and math.isnan(r.D_over_c0)
        assert math.isnan(r.residual_flow) and math.isnan(r.residual_flow_err)
    assert (pts[pts.status == "ok"].failure_class == "").all()
    # the stability rows carry the axis and its unit
    b = pts[pts.axis == "beta"]
    assert sorted(set(b.axis_value)) == [0.2, 2.5] and set(b.axis_unit) == {"1"}
    assert json.loads(ds.attrs["axes"])["cu"]["beta"]["base"] == 0.5
    # settings: the resolutions' common u_p (500, 1000); coarse amw failed at 500 -> no error
    st = ds[[k for k in ds.data_vars if k.startswith("setting_")]].to_dataframe()
    st = st.reset_index().set_index(["setting_scheme", "setting_variant"])
    assert st.loc[("amw", "coarse"), "setting_n_usable"] == 1
    assert math.isnan(st.loc[("amw", "coarse"), "setting_err_D"])
    assert st.loc[("piston", "coarse"), "setting_err_D"] == pytest.approx(0.02, abs=1e-12)
    # its standard error: two points of e = -0.02, each +- 0.001 (1 + e) (the points' D_err,
    # the reference exact): sqrt(2 (e s)^2) / (2 |e|) = s / sqrt(2)
    assert st.loc[("piston", "coarse"), "setting_err_D_err"] == pytest.approx(
        0.001 * 0.98 / math.sqrt(2), rel=1e-9
    )
    assert math.isnan(st.loc[("amw", "coarse"), "setting_err_D_err"])
    assert st.loc[("amw", "mid"), "setting_cpu_s"] == pytest.approx(6.0)
    # Pareto in D: piston coarse (1 s, 2 %), piston mid (2 s, 1 %), amw mid (6 s, 1.5 %:
    # beaten) -> the two pistons; amw coarse has no error
    front = st[st.setting_pareto_D == 1].index.tolist()
    assert sorted(front) == [("piston", "coarse"), ("piston", "mid")]


def test_replica_study_checks_the_closures_errors_too(tmp_path):
    """A replica case (resolutions that set only the seed) gets chi-square and pulls for each
    closure's residual as for D and P, against 0 with the point's own error. Four seeds
    whose slabs flow by +2, -2, +2, -2 of their errors (0.01 each) and whose mass closes
    exactly: per u_p the weighted mean flow is 0, so chi2_red = 4 * 2^2 / 3 = 16/3 and the
    RMS pull 2; the mass gives 0 and 0."""
    cfg = validate_config({"campaign": {"name": "rep", "cases": {"liq": {
        "scene": {"solver": "md", "phase": "liquid", "schemes": ["piston"],
                  "sample": {"rho0": 0.8, "T0": 2.0, "cells": [36, 4, 4], "seed": 1},
                  "shock": {"u_p": [1.0, 2.0]}},
        "resolutions": {f"s{i}": {"sample.seed": i} for i in range(1, 5)}}}}})  # fmt: skip

    def extra(name: str, scheme: str, u: float) -> dict:
        sign = 1.0 if int(name[-1]) % 2 else -1.0
        return {"residual_flow": 0.02 * sign, "residual_flow_err": 0.01,
                "residual_mass": 0.0, "residual_mass_err": 0.01}  # fmt: skip

    aggs = _aggregates(tmp_path, cfg, lambda *_: (0.0, "ok", 1.0), extra)
    ds = cp.campaign_dataset(cfg, {Path(a).stem: a for a in aggs})
    assert sorted(ds["residual_flow"].values) == [-0.02] * 4 + [0.02] * 4
    assert np.isnan(ds["residual_energy"].values).all()  # the points carry none
    r = json.loads(ds.attrs["replicas"])["liq"]["usable"]
    assert r["residual_flow_chi2_red"] == pytest.approx(16.0 / 3.0, rel=1e-12)
    assert r["residual_flow_pull_rms"] == pytest.approx(2.0, rel=1e-12)
    assert r["residual_mass_chi2_red"] == 0.0 and r["residual_mass_pull_rms"] == 0.0


def test_replica_study_compares_each_window_point_with_its_seeds_piston(tmp_path):
    """Four seeds, piston and AMW: AMW's D lies 0.3 % above the piston's on every seed
    (e = 0 for the piston, D_err = 0.001 D for both), so its RMS pull against the piston is
    0.003/√2·0.001 ≈ 2.1 and the reference's error (0.2 %) plays no part; the piston is not
    compared with itself. The CLI prints the block."""
    cfg = validate_config({"campaign": {"name": "rep", "cases": {"liq": {
        "scene": {"solver": "md", "phase": "liquid", "schemes": ["piston", "amw"],
                  "sample": {"rho0": 0.8, "T0": 2.0, "cells": [36, 4, 4], "seed": 1},
                  "shock": {"u_p": [1.0, 2.0]}},
        "resolutions": {f"s{i}": {"sample.seed": i} for i in range(1, 5)}}}}})  # fmt: skip
    e_amw = 0.003

    def outcome(name: str, scheme: str, u: float) -> tuple[float, str, float]:
        return (e_amw if scheme == "amw" else 0.0), "ok", 1.0

    aggs = _aggregates(tmp_path, cfg, outcome, ups=np.linspace(0.5, 3.0, 30), ref_err=0.002)
    ds = cp.campaign_dataset(cfg, {Path(a).stem: a for a in aggs})
    own = ds["err_D_own_err"].values
    assert own[ds["scheme"].values == "piston"] == pytest.approx(0.001, rel=1e-9)
    assert (own < ds["err_D_err"].values).all()  # the reference's part left out
    vs = json.loads(ds.attrs["replicas"])["liq"]["vs_piston"]["ok"]
    pull = e_amw / math.hypot(0.001 * (1 + e_amw), 0.001)
    assert vs["D_n"] == 8 and vs["D_pull_rms"] == pytest.approx(pull, rel=1e-9)
    assert {tuple(g["label"])[0] for g in vs["groups"]} == {"amw"}
    out = tmp_path / "rep.nc"
    write_netcdf(ds, out)
    lines = _run_cli(["replicas", str(out)])
    assert any(r.get("against") == "piston" and r.get("D_pull_rms") for r in lines)


def _run_cli(args: list[str]) -> list[dict]:
    buf = io.StringIO()
    with contextlib.redirect_stdout(buf):
        assert main(args) == 0
    return [json.loads(x) for x in buf.getvalue().splitlines()]


def test_cli_writes_dataset_chart_and_map(tmp_path):
    cfg = validate_config(_config())
    aggs = _aggregates(tmp_path, cfg, _outcome)
    out = tmp_path / "campaign" / "demo.nc"
    chart, smap = tmp_path / "chart.png", tmp_path / "map.png"
    rc = main(["campaign", "--config-json", json.dumps(_config()), "--out", str(out),
               "--chart", str(chart), "--map", str(smap), *map(str, aggs)])  # fmt: skip
    assert rc == 0
    ds = xr.load_dataset(out)
    assert ds.attrs["campaign"] == "demo" and ds["cpu_s"].attrs["units"] == "s"
    for png in (chart, smap):
        assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n" and png.stat().st_size > 10_000
    with pytest.raises(ValueError, match="no aggregate for scene"):
        main(["campaign", "--config-json", json.dumps(_config()), "--out", str(out),
              "--chart", str(chart), "--map", str(smap), *map(str, aggs[:-1])])  # fmt: skip


def test_default_row_only_where_the_axis_keeps_the_base_settings(tmp_path):
    """An axis that sets a second key away from the base (beta with a start_offset) cannot
    borrow the strength panel's points for its default value: base_row = 0; the map then
    draws only the axis's own rows."""
    raw = _config()
    axes = raw["campaign"]["cases"]["cu"]["stability"]["axes"]
    axes["kick"] = {"schemes": ["amw"],
                    "set": {"window.amw.beta": [0.5, 2.5], "window.start_offset": [0.02, 0.02]}}  # fmt: skip
    # keys that vary together along the axis keep the base on it
    axes["avg"] = {"schemes": ["amw"],
                   "set": {"window.window_time": [2e-7, 2e-6], "window.average_time": [1e-6, 8e-6]}}  # fmt: skip
    cfg = validate_config(raw)
    assert cfg["scenes"]["cu__kick1"]["window"]["start_offset"] == 0.02
    assert cfg["scenes"]["cu__mid"]["window"]["start_offset"] == 0.0
    aggs = _aggregates(tmp_path, cfg, _outcome)
    ds = cp.campaign_dataset(cfg, {Path(a).stem: a for a in aggs})
    meta = json.loads(ds.attrs["axes"])["cu"]
    assert meta["beta"]["base_row"] == 1 and meta["kick"]["base_row"] == 0
    assert meta["avg"]["base_row"] == 1 and meta["avg"]["keys"][0] == "window.window_time"
    assert meta["kick"]["base"] == 0.5
    stability_map_figure(ds, tmp_path / "map.png")
    assert (tmp_path / "map.png").stat().st_size > 10_000


def test_reference_at_follows_the_rayleigh_line():
    """On a linear Us-up Hugoniot with a pole P0 (D = c0 + s u, P = P0 + rho0 D u) sampled
    every 100 m/s, reference_at is exact between the points (D linear; P from the pole the
    two bracketing points define; D's error from the two points' in quadrature), where
    interpolating P linearly errs by
    rho0 s (u - u_a)(u_b - u); NaN outside the sampled range."""
    rho0, p0 = 8930.0, 1.0e8
    ru = np.arange(100.0, 1001.0, 100.0)
    D = C0 + S * ru
    ref = {"D": D, "P": p0 + rho0 * D * ru, "D_err": 0.01 * D, "P_err": np.zeros_like(ru)}
    for u in (100.0, 150.0, 437.5, 999.0):
        at = cp.reference_at(u, ru, ref)
        assert at["D"] == pytest.approx(C0 + S * u, rel=1e-13)
        assert at["P"] == pytest.approx(p0 + rho0 * (C0 + S * u) * u, rel=1e-13)
        # independent points' errors (no u error: an EOS's) weigh in quadrature
        b = min(max(int(np.searchsorted(ru, u)), 1), ru.size - 1)
        w = (u - ru[b - 1]) / 100.0
        want = math.hypot((1 - w) * ref["D_err"][b - 1], w * ref["D_err"][b])
        assert at["D_err"] == pytest.approx(want, rel=1e-13)
    linear = float(np.interp(150.0, ru, ref["P"]))
    assert linear - cp.reference_at(150.0, ru, ref)["P"] == pytest.approx(rho0 * S * 50 * 50)
    assert all(math.isnan(v) for v in cp.reference_at(50.0, ru, ref).values())
    assert all(math.isnan(v) for v in cp.reference_at(1001.0, ru, ref).values())


def test_reference_errors_at_fixed_u_follow_the_points_along_their_rayleigh_rays():
    """Reference: 4000 draws of an equilibrium-MD-like reference, its points at fixed
    densities on D = c0 + s u with P errors σ_P, u and D recomputed from each drawn P by the
    jump conditions (u = √((P − P0)(V0 − V)), D = V0 √((P − P0)/(V0 − V))). reference_at's
    D and P errors at fixed u match the draws' sd at that u within 6 % (the sd of a sd over
    4000 draws is 1.1 %; the rest is first order against the draws' curvature), while the
    errors as stated (at fixed density, interpolated linearly) are about twice as large."""
    c0, s, rho0, P0, sP = 4.0, 1.5, 0.8, 6.0, 0.05
    u_true = np.array([0.8, 1.2, 1.7, 2.2])
    D_true = c0 + s * u_true
    P_true = P0 + rho0 * D_true * u_true
    V0, V = 1 / rho0, (1 / rho0) * (1 - u_true / D_true)

    def jump(P):
        return np.sqrt((P - P0) * (V0 - V)), V0 * np.sqrt((P - P0) / (V0 - V))

    rel = 0.5 * sP / (P_true - P0)
    stated = {"D": D_true, "P": P_true, "D_err": D_true * rel, "P_err": np.full(4, sP),
              "u_p_err": u_true * rel}  # fmt: skip
    rng = np.random.default_rng(11)
    draws = {"D": [], "P": []}
    for _ in range(4000):
        P = P_true + sP * rng.standard_normal(4)
        u, D = jump(P)
        at = cp.reference_at(1.45, u, {"D": D, "P": P, "D_err": D * 0, "P_err": P * 0})
        draws["D"].append(at["D"])
        draws["P"].append(at["P"])
    at = cp.reference_at(1.45, u_true, stated)
    for q in ("D", "P"):
        assert at[q + "_err"] == pytest.approx(np.std(draws[q]), rel=0.06), q
    assert at["D_slope"] == pytest.approx(s, rel=1e-12)
    assert at["P_slope"] == pytest.approx(rho0 * (c0 + 2 * s * 1.45), rel=1e-12)
    assert 1.8 < float(np.interp(1.45, u_true, stated["D_err"])) / at["D_err"] < 2.4


def test_reference_P_at_fixed_u_carries_its_pole():
    """Reference: 4000 draws as above, the pole's P0 drawn too (σ_P0 = 0.04) and every
    point's P moving with it (an equilibrium reference's pole sampled hot moves the shocked
    states' P with P0, so the jumps P − P0, and u and D, do not see it). At fixed u,
    P = P0 + rho0 D u scatters by rho0 u σ_D ⊕ σ_P0: reference_at states that within 6 %
    when the curve gives ``P0_err``, and 0.7 times it without. ``_reference_curve`` takes
    P0_err from the reference's row at u_p = 0."""
    c0, s, rho0, P0, sP, sP0 = 4.0, 1.5, 0.8, 6.0, 0.05, 0.04
    u_true = np.array([0.8, 1.2, 1.7, 2.2])
    D_true = c0 + s * u_true
    P_true = P0 + rho0 * D_true * u_true
    V0, V = 1 / rho0, (1 / rho0) * (1 - u_true / D_true)
    rel = 0.5 * sP / (P_true - P0)
    stated = {"D": D_true, "P": P_true, "D_err": D_true * rel, "P_err": np.full(4, sP),
              "u_p_err": u_true * rel, "P0_err": np.full(4, sP0)}  # fmt: skip
    rng = np.random.default_rng(12)
    draws = []
    for _ in range(4000):
        p0 = P0 + sP0 * rng.standard_normal()
        P = P_true + sP * rng.standard_normal(4) + (p0 - P0)
        u, D = np.sqrt((P - p0) * (V0 - V)), V0 * np.sqrt((P - p0) / (V0 - V))
        draws.append(
            cp.reference_at(1.45, u, {"D": D, "P": P, "D_err": D * 0, "P_err": P * 0})["P"]
        )
    sd = float(np.std(draws))
    assert cp.reference_at(1.45, u_true, stated)["P_err"] == pytest.approx(sd, rel=0.06)
    no_pole = {k: v for k, v in stated.items() if k != "P0_err"}
    assert cp.reference_at(1.45, u_true, no_pole)["P_err"] < 0.8 * sd
    ds = xr.Dataset(
        {f"ref_{k}": ("ref_point", np.concatenate([[x0], v]))
         for k, x0, v in (("u_p", 0.0, u_true), ("D", np.nan, D_true), ("P", P0, P_true),
                          ("P_err", sP0, stated["P_err"]), ("D_err", np.nan, stated["D_err"]))}
    )  # fmt: skip
    ru, ref = cp._reference_curve(ds)
    np.testing.assert_allclose(ru, u_true)
    np.testing.assert_allclose(ref["P0_err"], sP0)


def test_reference_deviation_counts_the_u_error_and_its_correlation():
    """e = x/x_ref(u) − 1 with s² = (σ_x/x_r)² + (x σ_r/x_r²)² + (x x_r' σ_u/x_r²)²
    − 2 corr (σ_x/x_r)(x x_r' σ_u/x_r²): a point that slides along the reference (P and u
    errors fully correlated, σ_P = x_r' σ_u) keeps only the reference's error; with
    independent errors the three add in quadrature."""
    at = {"P": 10.0, "P_err": 0.02, "P_slope": 8.0}
    e, s_ = cp.reference_deviation(10.0, 0.08, at, "P", u_err=0.01, corr=1.0)
    assert e == 0.0 and s_ == pytest.approx(0.002, rel=1e-9)
    e, s_ = cp.reference_deviation(10.2, 0.08, at, "P", u_err=0.01, corr=0.0)
    assert e == pytest.approx(0.02)
    assert s_ == pytest.approx(math.sqrt(0.008**2 + 0.00204**2 + 0.00816**2), rel=1e-9)
    assert cp.reference_deviation(10.0, 0.08, at, "P") == (
        0.0,
        pytest.approx(math.hypot(0.008, 0.002)),
    )
