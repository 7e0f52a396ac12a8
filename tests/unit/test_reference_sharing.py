"""The MD reference Hugoniot is computed once per distinct set of its inputs (potential, the
settings that make the sample, whose measured pole it is computed at, and the reference
block: ``Backend.reference_inputs``) and copied into each scene's folder only when the
scene's own sample measured the same pole."""

from __future__ import annotations

import copy
import json
import re
import subprocess
import sys
from pathlib import Path

import pytest
import xarray as xr
import yaml

from hugomap.config import validate_config
from hugomap.io.atomic import write_netcdf
from hugomap.md.backend import MDBackend
from hugomap.registry import backend
from hugomap.stages import reference_stage
from hugomap.stages.reference import reference_key
from hugomap.states import Pole


def reference_inputs(scene):
    return backend(scene).reference_inputs(scene)


ROOT = Path(__file__).resolve().parents[2]


def _tiny_scene() -> dict:
    cfg = yaml.safe_load((ROOT / "tests/workflow/tiny/config.yaml").read_text())
    return cfg["scenes"]["tiny"]


def _resolved(scene: dict) -> dict:
    return validate_config({"scenes": {"s": copy.deepcopy(scene)}})["scenes"]["s"]


def test_key_depends_only_on_what_the_reference_reads() -> None:
    base = _resolved(_tiny_scene())
    key = reference_key(base)
    assert re.fullmatch(r"md_[0-9a-f]{12}", key)
    same = copy.deepcopy(base)
    same["window"]["length"] = 30.0  # the reference reads no window or piston setting
    same["shock"]["u_p"] = [0.5]
    same["shock"]["dt"] = 0.002
    assert reference_key(same) == key
    # ... but everything that makes the sample, whose measured pole it is computed at
    for path, value in [
        (("sample", "T0"), 2.1),
        (("sample", "rho0"), 0.81),
        (("sample", "seed"), 4),
        (("sample", "cells"), [40, 6, 6]),
        (("sample", "equilibrate_time"), 3.0),
        (("shock", "bin_width"), 0.5),
        (("phase",), "crystal"),
        (("potential", "rc"), 3.0),
        (("reference", "production_steps"), 700),
    ]:
        other = copy.deepcopy(base)
        if len(path) == 1:
            other[path[0]] = value
        else:
            other[path[0]][path[1]] = value
        assert reference_key(other) != key, path
    csph = {"solver": "csph", "dim": 1, "sample": {"length": 2e-3, "dx": 1e-5},
            "shock": {"u_p": [100.0]}}  # fmt: skip
    csph = validate_config({"scenes": {"cu": csph}})["scenes"]["cu"]
    assert reference_inputs(csph) is None and reference_key(csph) is None


def _sample_file(path: Path, rho0: float, T0: float) -> Path:
    """A stand-in for a prepared sample: its measured pole as scalar variables."""
    pole = {"rho0": rho0, "rho0_err": 1e-4, "T0": T0, "T0_err": 1e-3, "P0": 6.0, "E0": -0.9}
    return write_netcdf(xr.Dataset({k: ((), v) for k, v in pole.items()},
                                   attrs={"status": "ok"}), path)  # fmt: skip


def test_shared_reference_is_copied_only_for_the_same_inputs(tmp_path: Path) -> None:
    scene = {**_resolved(_tiny_scene()), "name": "tiny"}
    sample = _sample_file(tmp_path / "sample.nc", 0.79994, 2.0012)
    pole = Pole.from_dict({"rho0": 0.79994, "rho0_err": 1e-4, "T0": 2.0012, "T0_err": 1e-3})
    inputs = json.dumps(backend(scene).reference_inputs(scene, pole), sort_keys=True)
    assert json.loads(inputs)["pole"] == {"rho0": 0.79994, "rho0_err": 1e-4, "T0": 2.0012,
                                          "T0_err": 1e-3}  # fmt: skip
    shared = tmp_path / "lj_shared.nc"
    ref = xr.Dataset({"P": ("point", [1.0, 2.0], {"units": "epsilon sigma^-3"})})
    write_netcdf(ref.assign_attrs(reference_inputs=inputs), shared)
    out = reference_stage(scene, tmp_path / "reference.nc", shared, sample)
    with xr.open_dataset(out) as ds:
        assert list(ds["P"].values) == [1.0, 2.0]
        assert json.loads(ds.attrs["scene_config"])["name"] == "tiny"
        assert ds.attrs["reference_inputs"] == inputs
    hotter = {**scene, "sample": {**scene["sample"], "T0": 2.5}}
    with pytest.raises(ValueError, match="lj_shared.nc: this reference was computed for"):
        reference_stage(hotter, tmp_path / "reference2.nc", shared, sample)
    # the same settings, but a sample that measured another pole
    other = _sample_file(tmp_path / "other.nc", 0.79994, 2.0031)
    with pytest.raises(ValueError, match="lj_shared.nc: this reference was computed for"):
        reference_stage(scene, tmp_path / "reference3.nc", shared, other)
    with pytest.raises(ValueError, match="--sample"):
        reference_stage(scene, tmp_path / "reference4.nc", shared)
    failed = write_netcdf(xr.Dataset(attrs={"status": "bad_config", "diagnostic": "x"}),
                          tmp_path / "failed.nc")  # fmt: skip
    with pytest.raises(ValueError, match="the sample failed"):
        reference_stage(scene, tmp_path / "reference5.nc", shared, failed)
    for k in (2, 3, 4, 5):
        assert not (tmp_path / f"reference{k}.nc").exists()


def test_reference_is_computed_at_the_measured_pole(monkeypatch) -> None:
    """A fluid's reference runs at the sample's measured (rho0, T0), a crystal's at the
    lattice's rho0 and the measured T0, and the dataset records the pole it was computed at
    and the requested one (with units)."""
    import hugomap.md.reference as mdref

    calls = []

    def fake(rho0, T0, lj, **kw):
        calls.append((rho0, T0))
        return xr.Dataset({"P": ("point", [1.0, 2.0])})

    monkeypatch.setattr(mdref, "reference_hugoniot", fake)
    scene = {**_resolved(_tiny_scene()), "name": "tiny"}
    pole = Pole.from_dict({"rho0": 0.79994, "rho0_err": 1e-4, "T0": 2.0012, "T0_err": 1e-3})
    ds = MDBackend().reference(scene, pole)
    assert calls[-1] == (0.79994, 2.0012)
    assert float(ds["pole_rho0"]) == 0.79994 and ds["pole_rho0"].attrs["units"] == "sigma^-3"
    assert float(ds["pole_T0"]) == 2.0012 and ds["pole_T0"].attrs["units"] == "epsilon k_B^-1"
    assert float(ds["pole_T0_err"]) == 1e-3
    assert float(ds["requested_rho0"]) == 0.80 and float(ds["requested_T0"]) == 2.0
    assert ds.attrs["pole_source"] == "sample"
    assert json.loads(ds.attrs["reference_inputs"])["pole"]["T0"] == 2.0012
    crystal = {**scene, "phase": "crystal"}
    ds = MDBackend().reference(crystal, pole)
    assert calls[-1] == (0.80, 2.0012) and float(ds["pole_rho0_err"]) == 0.0


def test_dry_run_computes_one_reference_for_scenes_that_share_it(tmp_path: Path) -> None:
    """Two scenes that differ only in the window share one shared_reference job, which
    reads the first one's sample; a third at another T0 gets its own."""
    base = _tiny_scene()
    wide = copy.deepcopy(base)
    wide["window"]["length"] = 30.0
    hot = copy.deepcopy(base)
    hot["sample"]["T0"] = 2.5
    cfg = {"threads": 1, "schemes": ["piston"], "scenes": {"a": base, "b": wide, "c": hot}}
    path = tmp_path / "config.yaml"
    path.write_text(yaml.safe_dump(cfg))
    cmd = [sys.executable, "-m", "snakemake", "-s", str(ROOT / "Snakefile"), "--directory",
           str(tmp_path), "--configfile", str(path), "--cores", "1", "-n"]  # fmt: skip
    r = subprocess.run(cmd, capture_output=True, text=True, cwd=tmp_path, timeout=300)
    assert r.returncode == 0, r.stdout[-3000:] + r.stderr[-3000:]
    counts = dict(re.findall(r"^(shared_reference|reference)\s+(\d+)$", r.stdout, re.M))
    assert counts == {"shared_reference": "2", "reference": "3"}, r.stdout[-2000:]
    keys = {reference_key(_resolved(s)) for s in (base, wide, hot)}
    assert len(keys) == 2
    for key in keys:
        assert f"results/references/{key}.nc" in r.stdout
    # each shared reference reads the sample of the first scene with its key
    shared_inputs = re.findall(r"^rule shared_reference:\n\s+input: (\S+)", r.stdout, re.M)
    assert sorted(shared_inputs) == ["results/a/sample.nc", "results/c/sample.nc"], r.stdout
