"""The outputs the field expects: CF-1.11 point files, aggregates and campaign datasets
(checked with the IOOS compliance-checker), LJ units that pint and UDUNITS read right, SI
companions from an MD scene's ``units`` block, group-readable files, and many files opened
as one with ``open_mfdataset``.

References: CF-1.11 as the compliance-checker 6 implements it (0 errors is the target; a
file written the old way is shown to fail it, so the check can fail); the SI values of the
argon-like LJ set (σ = 3.405e-10 m, ε/k_B = 119.8 K, m = 6.63e-26 kg) worked out by hand
below with k_B = 1.380649e-23 J/K (exact): ε = 1.6540175e-21 J, σ³ = 3.9477655125e-29 m³,
τ = σ √(m/ε) = 2.155777e-12 s, σ/τ = 157.9477 m/s, ε/σ³ = 4.189756e7 Pa, m/σ³ =
1679.431 kg/m³, σ³/m = 5.954397e-4 m³/kg, ε/m = 24947.47 J/kg. The hand values carry 7
significant digits, so the tolerance is 1e-6 relative; two codes computing the same
products (``io.dataset`` and pint) agree to 1e-12.
"""

from __future__ import annotations

import json
import os
import re
from pathlib import Path

import netCDF4
import numpy as np
import pytest
import xarray as xr
import yaml

from hugomap import campaign as cp
from hugomap.config import ConfigError, validate_config
from hugomap.io.atomic import write_json, write_netcdf
from hugomap.io.checkpoint import MD_CHECKPOINT, MD_WINDOW_CHECKPOINT, seal_checkpoint
from hugomap.io.dataset import (
    NOT_RUN,
    POINT_VARS,
    POLE_VARS,
    STATUS_FLAGS,
    aggregate_points,
    cf_units,
    control_vars,
    lj_si_factors,
    lj_units,
    open_points,
    open_scenes,
    point_file_problem,
    profile_vars,
)
from hugomap.registry import backend
from hugomap.stages import aggregate
from hugomap.stages.files import write_point

from .test_campaign import _aggregates, _config, _outcome

ROOT = Path(__file__).resolve().parents[2]
ARGON = {"sigma": 3.405e-10, "epsilon_over_kB": 119.8, "mass": 6.63e-26}
HAND = {  # one reduced unit in SI, by hand (module docstring)
    "tau": 2.155777e-12, "sigma tau^-1": 157.9477, "epsilon sigma^-3": 4.189756e7,
    "sigma^-3": 1679.431, "sigma^3": 5.954397e-4, "epsilon": 24947.47, "epsilon k_B^-1": 119.8,
}  # fmt: skip


def _md_config(units: dict | None = ARGON, u_p=(1.5, 2.5)) -> dict:
    cfg = yaml.safe_load((ROOT / "tests/workflow/tiny/config.yaml").read_text())
    sc = cfg["scenes"]["tiny"]
    sc["shock"]["u_p"] = list(u_p)
    if units:
        sc["units"] = dict(units)
    return validate_config(cfg)


class _Control:
    """A control record (``methods.control.ControlHistory``'s arrays) of three windows."""

    t = [0.6, 1.2, 1.8]

    def arrays(self) -> dict[str, np.ndarray]:
        k = np.arange(3.0)
        return {"t": 0.6 * (k + 1), "a": 0.01 * k, "a_err": 0.01 + 0 * k, "omega": 0.5 + 0 * k,
                "u_in": -4.0 + 0 * k, "u_out": -2.5 + 0 * k, "du": 0 * k,
                "samples_t": np.linspace(0, 1.8, 10), "samples_omega": np.full(10, 0.5)}  # fmt: skip


def _md_points(folder: Path, cfg: dict, n_history=(7, 9), failed: bool = False) -> list[Path]:
    """Point files of the MD scene ``tiny`` written by the stages' writer (``write_point``),
    with what the window stages add: profile, control record, the dichotomy's trials (as
    ``stages.dichotomy`` builds them from the backend's axes). ``failed``: the last point
    is a failed load (no values, no pole, no history)."""
    scene, b = cfg["scenes"]["tiny"], backend(cfg["scenes"]["tiny"])
    rng = np.random.default_rng(5)
    paths = []
    for scheme in ("piston", "amw"):
        for j, up in enumerate(scene["shock"]["u_p"]):
            values = {k: 1.0 + rng.random() for k in POINT_VARS}
            values |= {k + "_err": 0.01 for k in POINT_VARS} | {"piston_velocity": up}
            values["converged"] = j == 0
            pole = {k: 0.5 + i for i, k in enumerate(POLE_VARS)} | {"rho0_err": 0.001}
            n = n_history[j % len(n_history)]
            hist = {"t": np.arange(n, dtype=float), "front": np.linspace(0, 5, n),
                    "stage": np.ones(n, np.int8)}  # fmt: skip
            status, diag = ("ok", "") if j == 0 else ("not_converged", "residual_energy 3 %")
            extra = None
            if scheme == "amw":
                extra = control_vars(_Control(), b.units)
                extra |= profile_vars({"x": np.arange(4.0), "rho": np.ones(4), "P": np.ones(4),
                                       "u": np.ones(4), "T": np.ones(4)}, b.units)  # fmt: skip
                v, tm = b.units.axes["velocity"], b.units.axes["time"]
                extra["dichotomy_u_out"] = ("trial", [1.0, 2.0], {"units": v, "long_name": "u"})
                extra["dichotomy_slope"] = ("trial", [0.1, -0.1],
                                            {"units": f"{tm}^-1", "long_name": "slope"})  # fmt: skip
            if failed and scheme == "amw" and j == len(scene["shock"]["u_p"]) - 1:
                values, pole, hist, status, diag = ({"piston_velocity": up}, {}, None,
                                                    "atom_lost", "an atom left")  # fmt: skip
            out = folder / f"{scheme}_{up:g}.nc"
            write_point(out, b, scene, scheme, values, pole, hist, status, diag, extra,
                        {"u_in": -4.0, "u_out": -2.5})  # fmt: skip
            paths.append(out)
    return paths


def _md_reference(path: Path, n: int) -> Path:
    """A reference Hugoniot in the layout ``md.reference`` writes (dim ``point``, reduced
    unit strings, a ``compression`` coordinate), ``n`` points."""
    u = np.linspace(0.5, 3.0, n)
    units = {"u_p": "sigma tau^-1", "D": "sigma tau^-1", "P": "epsilon sigma^-3",
             "V": "sigma^3", "T": "epsilon k_B^-1", "E": "epsilon", "msd": "sigma^2"}  # fmt: skip
    data = {k: ("point", u * (i + 1), {"units": un, "long_name": k})
            for i, (k, un) in enumerate(units.items())}  # fmt: skip
    data["D_err"] = ("point", 0.01 + 0 * u, {"units": "sigma tau^-1", "long_name": "error"})
    data["converged"] = ("point", np.ones(n, np.int8), {"units": "1", "long_name": "|H| small"})
    ds = xr.Dataset(data, coords={"compression": ("point", np.linspace(1.1, 1.6, n),
                                                  {"units": "1", "long_name": "rho/rho0"})})  # fmt: skip
    ds.attrs["reference_model"] = "equilibrium MD"
    return write_netcdf(ds, path)


def _md_aggregate(folder: Path, cfg: dict, n_ref: int = 3, **kw) -> Path:
    folder.mkdir(parents=True, exist_ok=True)
    pts = _md_points(folder, cfg, **kw)
    ref = _md_reference(folder / "reference.nc", n_ref)
    return aggregate([str(p) for p in pts], str(ref), cfg, "tiny", folder / "tiny.nc")


# -- CF-1.11 -------------------------------------------------------------------------------
def test_point_aggregate_and_campaign_pass_cf_1_11(tmp_path: Path, cf_errors) -> None:
    """0 compliance-checker errors on an MD window point file (with history, profile,
    control record and trials), an MD aggregate with its reference and SI companions, a
    CSPH aggregate (SI units) and a campaign dataset. (The checker takes ~5 s a file of
    ~100 variables on 2 cores, so the piston point, a subset of the window point's
    variables, is left to the next test.)"""
    cfg = _md_config()
    agg = _md_aggregate(tmp_path / "md", cfg)
    ccfg = validate_config(_config())
    aggs = _aggregates(tmp_path / "cu", ccfg, _outcome)
    camp = cp.write_campaign(ccfg, aggs, tmp_path / "campaign" / "demo.nc")
    files = [agg, tmp_path / "md" / "amw_2.5.nc", aggs[0], camp]
    for f in files:
        assert cf_errors(f) == [], f


def test_an_aggregate_of_schemes_chosen_per_u_p(tmp_path: Path, cf_errors) -> None:
    """Where ``schemes: [auto]`` chose AMW at one u_p and the piston at the other, the
    aggregate's cells without a point are ``not_run`` (text and flag), NaN and not
    converged, each u_p says in ``scheme_choice`` why, and the file is still CF-1.11."""
    cfg = _md_config(units=None)
    sc = cfg["scenes"]["tiny"]
    sc["schemes"], sc["scheme_at"] = ["amw", "piston"], [["amw"], ["piston"]]
    sc["scheme_choice"] = ["auto at u_p = 1.5: amw, 9 s", "auto at u_p = 2.5: piston, 5 s"]
    pts = _md_points(tmp_path, cfg)
    keep = [str(p) for p in pts if p.name in ("amw_1.5.nc", "piston_2.5.nc")]
    ref = _md_reference(tmp_path / "reference.nc", 3)
    agg = aggregate(keep, str(ref), cfg, "tiny", tmp_path / "tiny.nc")
    ds = xr.load_dataset(agg)
    run = {"amw": 1.5, "piston": 2.5}
    for s in ("amw", "piston"):
        for u in (1.5, 2.5):
            cell = ds.sel(scheme=s, u_p=u)
            meanings = cell["status_flag"].attrs["flag_meanings"].split()
            if run[s] == u:
                assert str(cell["status"].values) != NOT_RUN and np.isfinite(float(cell["D"]))
            else:
                assert str(cell["status"].values) == NOT_RUN == meanings[int(cell["status_flag"])]
                assert np.isnan(float(cell["D"])) and int(cell["converged"]) == 0
                assert "schemes: [auto] chose another" in str(cell["diagnostic"].values)
    assert list(ds["scheme_choice"].values) == sc["scheme_choice"]
    with xr.open_dataset(keep[0]) as one:  # a point file says why its scheme ran there
        assert one.attrs["scheme_choice"] == "auto at u_p = 2.5: piston, 5 s"
    assert cf_errors(agg) == []


def test_a_file_written_the_old_way_fails_the_check(tmp_path: Path, cf_errors) -> None:
    """The check can fail: a piston point file passes, and the same dataset written without
    the CF encoding (reduced unit strings) has errors."""
    cfg = _md_config(units=None)
    folder = tmp_path / "md"
    folder.mkdir()
    p = _md_points(folder, cfg)[0]
    assert cf_errors(p) == []
    with xr.open_dataset(p) as ds:
        ds = ds.load()
    for var in ds.variables.values():
        if "reduced_units" in var.attrs:
            var.attrs["units"] = var.attrs.pop("reduced_units")
    ds.attrs.pop("Conventions")
    ds.to_netcdf(tmp_path / "old.nc", engine="netcdf4")  # no cf_dataset
    errors = cf_errors(tmp_path / "old.nc")
    assert any('"sigma tau^-1" are not recognized by UDUNITS' in e for e in errors), errors


@pytest.mark.parametrize(
    ("table", "cf", "reduced"),
    [("sigma tau^-1", "1", "sigma tau^-1"), ("epsilon sigma^-3", "1", "epsilon sigma^-3"),
     ("epsilon k_B^-1", "1", "epsilon k_B^-1"), ("tau^-1", "1", "tau^-1"), ("sigma^2", "1", "sigma^2"),
     ("m s^-1", "m s-1", None), ("m3 kg-1", "m3 kg-1", None), ("kg m^-3", "kg m-3", None),
     ("J kg^-1", "J kg-1", None), ("s^-1", "s-1", None), ("Pa", "Pa", None), ("1", "1", None)],
)  # fmt: skip
def test_cf_units(table: str, cf: str, reduced: str | None) -> None:
    assert cf_units(table) == (cf, reduced)


def test_cf_layout(tmp_path: Path) -> None:
    """What the files carry: global Conventions/title/history/references/source, LJ units as
    "1" + reduced_units, flags on converged and status_flag, coordinates without _FillValue,
    the scheme labels as a character array read back as strings, no stray point attributes
    in the aggregate, SI units the UDUNITS way for CSPH."""
    agg = _md_aggregate(tmp_path, _md_config(units=None), failed=True)
    with netCDF4.Dataset(agg) as nc:
        g = {a: nc.getncattr(a) for a in nc.ncattrs()}
        assert nc.variables["scheme"].dimensions[0] == "scheme"
        assert nc.variables["scheme"].dtype == np.dtype("S1")  # CF label, not a coordinate var
        for c in ("u_p", "ref_point"):
            assert "_FillValue" not in nc.variables[c].ncattrs(), c
    assert g["Conventions"] == "CF-1.11" and g["title"] == "Hugoniot of scene tiny"
    assert "Murzov" in g["references"] and "VANT" in g["references"]
    assert g["source"].startswith("hugomap") and "hugomap" in g["history"]
    assert "scheme" not in g and "u_in" not in g  # not copied from the first point file
    ds = xr.load_dataset(agg)
    assert list(ds["scheme"].values) == ["piston", "amw"]
    assert float(ds.sel(scheme="amw", u_p=1.5)["D"]) == float(ds["D"].values[1, 0])
    assert ds["D"].attrs["units"] == "1" and ds["D"].attrs["reduced_units"] == "sigma tau^-1"
    assert ds["ref_P"].attrs["reduced_units"] == "epsilon sigma^-3"
    assert ds["T0"].attrs["reduced_units"] == "epsilon k_B^-1"
    conv = ds["converged"]
    assert conv.attrs["flag_meanings"] == "not_converged converged"
    assert list(conv.attrs["flag_values"]) == [0, 1] and conv.dtype == np.int8
    meanings = ds["status_flag"].attrs["flag_meanings"].split()
    assert meanings == list(STATUS_FLAGS)
    assert list(ds["status_flag"].attrs["flag_values"]) == list(range(len(meanings)))
    decoded = [[meanings[c] for c in row] for row in ds["status_flag"].values]
    assert decoded == ds["status"].values.tolist()
    assert decoded[1] == ["ok", "atom_lost"]
    # CSPH: SI the UDUNITS way, no reduced_units
    cu = _aggregates(tmp_path / "cu", validate_config(_config()), _outcome)[0]
    ds = xr.load_dataset(cu)
    assert ds["D"].attrs["units"] == "m s-1" and ds["u_p"].attrs["units"] == "m s-1"
    assert ds["rho0"].attrs["units"] == "kg m-3" and "reduced_units" not in ds["D"].attrs


# -- LJ units: pint and the SI companions --------------------------------------------------
def test_lj_units_in_si_by_hand_and_by_pint() -> None:
    pint = pytest.importorskip("pint")
    from hugomap.units import quantity, registry

    f = lj_si_factors(ARGON)
    si = {"tau": "s", "sigma tau^-1": "m/s", "epsilon sigma^-3": "Pa", "sigma^-3": "kg/m**3",
          "sigma^3": "m**3/kg", "epsilon": "J/kg", "epsilon k_B^-1": "K"}  # fmt: skip
    u = registry(ARGON)
    for red, hand in HAND.items():
        assert f[red][0] == pytest.approx(hand, rel=1e-6), red
        assert quantity(1.0, red, u).to(si[red]).magnitude == pytest.approx(f[red][0], rel=1e-12)
    # reduced: sigma is a length of its own, not the Stefan-Boltzmann constant
    r = registry()
    assert (r("sigma**-3")).dimensionality == r("1/sigma**3").dimensionality
    assert str((r("sigma**-3")).dimensionality) == "1 / [lj_length] ** 3"
    assert "[temperature]" in str(pint.UnitRegistry()("sigma**-3").dimensionality)
    assert (2.0 * r("sigma/tau")).to("sigma/tau").magnitude == 2.0
    with pytest.raises(pint.DimensionalityError):
        (1.0 * r.sigma).to("m")  # no SI without a units block


def test_units_block_gives_si_companions(tmp_path: Path) -> None:
    """With ``units:`` (argon) point files and the aggregate carry ``<name>_SI`` and
    ``<name>_SI_err`` = reduced value × the hand factor, the reference's too; without it,
    none."""
    agg = xr.load_dataset(_md_aggregate(tmp_path / "si", _md_config()))
    point = xr.load_dataset(tmp_path / "si" / "piston_1.5.nc")
    for ds in (agg, point):
        for q, red in (("D", "sigma tau^-1"), ("P", "epsilon sigma^-3"), ("V", "sigma^3"),
                       ("T", "epsilon k_B^-1"), ("rho", "sigma^-3"), ("E", "epsilon")):  # fmt: skip
            np.testing.assert_allclose(ds[q + "_SI"], ds[q] * HAND[red], rtol=1e-6)
        np.testing.assert_allclose(ds["D_SI_err"], ds["D_err"] * HAND["sigma tau^-1"], rtol=1e-6)
        assert ds["D_SI"].attrs["units"] == "m s-1" and ds["P_SI"].attrs["units"] == "Pa"
        assert ds["V_SI"].attrs["units"] == "m3 kg-1" and ds["T_SI"].attrs["units"] == "K"
        assert ds["rho0_SI"].attrs["units"] == "kg m-3" and ds["E_SI"].attrs["units"] == "J kg-1"
        assert ds.attrs["lj_sigma_m"] == ARGON["sigma"]
    np.testing.assert_allclose(agg["u_p_SI"], agg["u_p"] * HAND["sigma tau^-1"], rtol=1e-6)
    np.testing.assert_allclose(agg["ref_P_SI"], agg["ref_P"] * HAND["epsilon sigma^-3"], rtol=1e-6)
    assert float(point["piston_velocity_SI"]) == pytest.approx(1.5 * HAND["sigma tau^-1"])
    plain = xr.load_dataset(_md_aggregate(tmp_path / "plain", _md_config(units=None)))
    assert not [k for k in plain.variables if "_SI" in k] and "lj_sigma_m" not in plain.attrs


@pytest.mark.parametrize(
    ("units", "needle"),
    [({"sigma": 3.405, "epsilon_over_kB": 119.8, "mass": 6.63e-26}, "units.sigma = 3.405"),
     ({"sigma": 3.405e-10, "epsilon_over_kB": 119.8}, "mass"),
     ({"sigma": 3.405e-10, "epsilon_over_kB": -1.0, "mass": 6.63e-26}, "units.epsilon_over_kB"),
     ({"sigma": 3.405e-10, "epsilon_over_kB": 119.8, "mass": 6.63e-26, "k": 1}, "unknown key")],
)  # fmt: skip
def test_bad_units_block_is_refused(units: dict, needle: str) -> None:
    with pytest.raises(ConfigError) as e:
        _md_config(units=units)
    assert needle in str(e.value), str(e.value)


# -- files the group can read --------------------------------------------------------------
@pytest.mark.parametrize(("mask", "mode"), [(0o002, 0o664), (0o027, 0o640), (0o077, 0o600)])
def test_written_files_honour_the_umask(tmp_path: Path, mask: int, mode: int) -> None:
    old = os.umask(mask)
    try:
        nc = write_netcdf(xr.Dataset({"x": ("i", [1.0])}), tmp_path / "a" / "x.nc")
        js = write_json({"a": 1}, tmp_path / "b.json")
        again = write_json({"a": 2}, tmp_path / "b.json")  # replacing keeps the rule
    finally:
        os.umask(old)
    for p in (nc, js, again):
        assert p.stat().st_mode & 0o777 == mode, (p, oct(p.stat().st_mode))
    assert json.loads(js.read_text()) == {"a": 2}
    assert not list(tmp_path.rglob("*.tmp"))


@pytest.mark.parametrize(
    ("env", "writes"),
    [({}, True), ({"PMI_RANK": "0"}, True), ({"PMI_RANK": "1"}, False),
     ({"OMPI_COMM_WORLD_RANK": "3"}, False), ({"PMIX_RANK": "0"}, True)],
)  # fmt: skip
def test_only_mpi_rank_0_writes(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, env: dict, writes: bool
) -> None:
    """The ranks of a LAMMPS stage under ``mpiexec`` run the same stage: rank 0 alone writes
    (the launcher's rank variable, ``io.atomic.RANK_VARIABLES``); outside MPI every write
    happens."""
    from hugomap.io.atomic import RANK_VARIABLES

    for name in RANK_VARIABLES:
        monkeypatch.delenv(name, raising=False)
    for name, value in env.items():
        monkeypatch.setenv(name, value)
    out = write_json({"a": 1}, tmp_path / "x.json")
    assert out == tmp_path / "x.json"
    assert out.exists() is writes
    assert not list(tmp_path.rglob("*.tmp"))


# -- many files as one ---------------------------------------------------------------------
def test_open_scenes_and_points(tmp_path: Path) -> None:
    """Two scenes whose references (3 and 5 points) and piston velocities differ open as one
    dask-backed dataset (NaN where a scene lacks a point), with plain ``open_mfdataset`` as
    docs/datasets.md shows it too; point files whose histories (7, 9 samples), window
    records and variables (a failed point) differ open as one along ``point``."""
    a = _md_aggregate(tmp_path / "a", _md_config(u_p=(1.5, 2.5)), n_ref=3)
    cfg_b = _md_config(u_p=(1.0, 2.0, 3.0))
    cfg_b["scenes"] = {"other": cfg_b["scenes"]["tiny"]}
    folder = tmp_path / "b"
    folder.mkdir()
    pts = _md_points(folder, {"scenes": {"tiny": cfg_b["scenes"]["other"]}})
    b = aggregate([str(p) for p in pts], str(_md_reference(folder / "r.nc", 5)), cfg_b,
                  "other", folder / "other.nc")  # fmt: skip
    with open_scenes([a, b]) as ds:
        assert ds["D"].chunks is not None  # lazy, dask
        assert ds.sizes == {"scene": 2, "scheme": 2, "u_p": 5, "ref_point": 5}
        assert list(ds["scene"].values) == ["tiny", "other"]
        assert list(ds["u_p"].values) == [1.0, 1.5, 2.0, 2.5, 3.0]
        d = ds["D"].sel(scheme="piston").compute()
        assert np.isnan(d.sel(scene="tiny", u_p=1.0)) and np.isfinite(d.sel(scene="tiny", u_p=1.5))
        assert np.isnan(d.sel(scene="other", u_p=1.5))
        ref = ds["ref_D"].compute()
        assert np.isfinite(ref.sel(scene="other")).all()
        assert np.isnan(ref.sel(scene="tiny").values[3:]).all()
    with xr.open_mfdataset([a, b], combine="nested", concat_dim="scene", join="outer",
                           data_vars="all", coords="minimal", compat="override") as raw:  # fmt: skip
        assert raw.sizes["ref_point"] == 5 and raw.sizes["u_p"] == 5
    paths = _md_points(tmp_path / "a", _md_config(), failed=True)
    with open_points(paths) as ps:
        assert ps.sizes["point"] == 4 and ps.sizes["sample"] == 9
        h = ps["history_t"].compute()
        assert np.isnan(h.values[0, 7:]).all() and np.isfinite(h.values[1]).all()
        assert list(ps["status"].values) == ["ok", "not_converged", "ok", "atom_lost"]
        assert np.isnan(ps["D"].values[3]) and np.isfinite(ps["D"].values[:3]).all()
        assert np.isnan(ps["control_t"].values[:2]).all() and ps.sizes["window_k"] == 3


def _md_checkpoint(path: Path, stage: str, kind=MD_CHECKPOINT) -> Path:
    """A stand-in for an MD checkpoint in the point folder (``loaded.nc``, ``window.nc``):
    atoms, a piston history of its own length, the stage's attributes, sealed as the stages
    seal it."""
    ds = xr.Dataset({"x": (("atom", "xyz"), np.zeros((5, 3))),
                     "hist_t": (("sample",), np.arange(4.0)),
                     "hist_sums": (("sample", "bin", "field"), np.zeros((4, 6, 2)))},
                    attrs={"stage": stage, "status": "ok"})  # fmt: skip
    return write_netcdf(seal_checkpoint(ds, kind), path)


def test_open_points_skips_what_is_not_a_point(
    tmp_path: Path, caplog: pytest.LogCaptureFixture
) -> None:
    """A glob of a point folder's ``*.nc`` also finds its checkpoints (their history along
    ``sample`` would not align with the points'), a failed stage's record and an aggregate:
    open_points skips each with a warning naming it and what it is; aggregate_points,
    whose paths are all meant to be points, refuses the first with a ValueError."""
    cfg = _md_config()
    pts = _md_points(tmp_path, cfg)
    others = {
        _md_checkpoint(tmp_path / "loaded.nc", "loaded"): "a checkpoint (format "
        "hugomap-md-checkpoint/2, stage loaded)",
        _md_checkpoint(tmp_path / "window.nc", "window", MD_WINDOW_CHECKPOINT): "a checkpoint "
        "(window_format hugomap-md-window/2, stage window)",
        write_netcdf(xr.Dataset(attrs={"stage": "window", "status": "nan", "diagnostic": "x"}),
                     tmp_path / "failed.nc"): "failure record (stage window, status nan)",
        aggregate([str(p) for p in pts], None, cfg, "tiny", tmp_path / "tiny.nc"):
        "many points (status along scheme, u_p)",
        _md_reference(tmp_path / "reference.nc", 3): "no 0-d status variable",
    }  # fmt: skip
    for path, what in others.items():
        assert what in point_file_problem(path)
    assert all(point_file_problem(p) is None for p in pts)
    with (
        caplog.at_level("WARNING", logger="hugomap"),
        open_points(sorted(tmp_path.glob("*.nc"))) as ps,
    ):
        assert sorted(ps["point"].values) == sorted(str(p) for p in pts)
        assert ps.sizes["sample"] == 9 and "x" not in ps
    skipped = [r.getMessage() for r in caplog.records if "skipping" in r.getMessage()]
    assert len(skipped) == len(others)
    for path, what in others.items():
        assert any(str(path) in m and what in m for m in skipped)
    with pytest.raises(ValueError, match="no point file among 2 path"):
        open_points(list(others)[:2])
    for bad in others:
        with pytest.raises(ValueError, match=re.escape(f"cannot aggregate {bad}: ")):
            aggregate_points([*pts[:1], bad], "piston", None, cfg, "tiny", lj_units())
