"""The MD reference Hugoniot is computed once per distinct set of its inputs (potential, pole,
seed, reference block: ``Backend.reference_inputs``) and copied into each scene's folder."""

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
from hugomap.registry import backend
from hugomap.stages import reference_stage
from hugomap.stages.reference import reference_key


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
    same["window"]["length"] = 30.0  # the reference reads no window, shock or cells setting
    same["shock"]["u_p"] = [0.5]
    same["sample"]["cells"] = [40, 6, 6]
    assert reference_key(same) == key
    for path, value in [
        (("sample", "T0"), 2.1),
        (("sample", "rho0"), 0.81),
        (("sample", "seed"), 4),
        (("potential", "rc"), 3.0),
        (("reference", "production_steps"), 700),
    ]:
        other = copy.deepcopy(base)
        other[path[0]][path[1]] = value
        assert reference_key(other) != key, path
    csph = {"solver": "csph", "dim": 1, "sample": {"length": 2e-3, "dx": 1e-5},
            "shock": {"u_p": [100.0]}}  # fmt: skip
    csph = validate_config({"scenes": {"cu": csph}})["scenes"]["cu"]
    assert reference_inputs(csph) is None and reference_key(csph) is None


def test_shared_reference_is_copied_only_for_the_same_inputs(tmp_path: Path) -> None:
    scene = {**_resolved(_tiny_scene()), "name": "tiny"}
    inputs = json.dumps(reference_inputs(scene), sort_keys=True)
    shared = tmp_path / "lj_shared.nc"
    ref = xr.Dataset({"P": ("point", [1.0, 2.0], {"units": "epsilon sigma^-3"})})
    write_netcdf(ref.assign_attrs(reference_inputs=inputs), shared)
    out = reference_stage(scene, tmp_path / "reference.nc", shared)
    with xr.open_dataset(out) as ds:
        assert list(ds["P"].values) == [1.0, 2.0]
        assert json.loads(ds.attrs["scene_config"])["name"] == "tiny"
        assert ds.attrs["reference_inputs"] == inputs
    hotter = {**scene, "sample": {**scene["sample"], "T0": 2.5}}
    with pytest.raises(ValueError, match="lj_shared.nc: this reference was computed for"):
        reference_stage(hotter, tmp_path / "reference2.nc", shared)
    assert not (tmp_path / "reference2.nc").exists()


def test_dry_run_computes_one_reference_for_scenes_that_share_it(tmp_path: Path) -> None:
    """Two scenes that differ only in the window share one shared_reference job; a third at
    another T0 gets its own."""
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
