"""Aggregating a thousand point files and more in bounded memory.

``N_POINTS`` (1000; ``HUGOMAP_SCALE_POINTS`` overrides) point files in the real format are
aggregated by the workflow's own stage (``python -m hugomap aggregate``'s ``cli.main``, run in
a subprocess so its peak resident memory is its own: ``VmHWM`` of ``/proc/self/status``,
reset just before the stage runs; not ``ru_maxrss``, which Linux carries over from the
parent across fork and exec, so that the pytest worker's own size hid any growth below
it). Each file carries a front history of ``N_HISTORY`` samples (t, front: float64; stage: int8), 136 kB per point
(twice a real piston run's 68 kB, so that a reader of the histories exceeds the bound at
1000 points), which aggregation must not read.

The bound: peak RSS growth during aggregation ≤ ``BASE_MB`` + ``PER_POINT_KB`` × N.
- What must be held grows with N only as the aggregate: about 70 numbers and two strings per
  point (held as one dict per point while reading, ~6 kB), so 16 kB per point is generous;
  ``BASE_MB`` = 64 MB covers the netCDF/HDF5 library's buffers, writing the output, and
  allocator slack. Measured (2 cores, December 2026): +40 MB at 300 points, +46 MB at 1000,
  i.e. about 9 kB per point on top of ~37 MB.
- It fails an implementation that loads the files' histories (136 kB per point: 133 MB at
  1000 points, beyond the 80 MB bound; measured: the same stage holding every history as it
  read them grew +147 MB), or that concatenates lazily with dask per file and
  variable: the ``open_mfdataset`` version this replaced needed +430 MB and 8 minutes for
  300 points, because beyond xarray's 128 cached file handles it reopened a file for every
  variable of every point.
Time is bounded too (≤ 0.2 s of CPU per point: CPU time, since the wall time of a shared
machine is not the aggregation's; a loaded run took 486 s of wall time for 2000 points), so
a reopen-per-variable regression fails rather than hangs. Measured: 0.05-0.07 s per point of wall time on 2 cores shared with an MD run (about
27 ms of CPU: opening a netCDF file of 70 scalar variables and reading each is the cost).

The files are copies of templates made by ``point_dataset`` + ``write_netcdf`` (the writer of
``piston.nc``): four kinds (converged; not converged with a long diagnostic; a solver failure
without standard errors; a failed load without pole or values). Per copy the piston velocity
and D are set by overwriting the 8 bytes of a sentinel value (netCDF4/HDF5 stores a scalar
variable's value in place, unchecksummed), which takes 0.2 ms instead of 40 ms per file; the
result is read back and checked point by point, so a patch that missed would fail the test.
"""

from __future__ import annotations

import json
import os
import struct
import subprocess
import sys
from pathlib import Path

import netCDF4
import numpy as np
import pytest
import xarray as xr

from hugomap.io.atomic import write_netcdf
from hugomap.io.dataset import POINT_VARS, POLE_VARS, STATUS_FLAGS, lj_units, point_dataset

N_POINTS = int(os.environ.get("HUGOMAP_SCALE_POINTS", "1000"))
N_HISTORY = 8000
BASE_MB = 64.0
PER_POINT_KB = 16.0
MAX_S_PER_POINT = 0.2
SENTINEL_U, SENTINEL_D = 4321.123456789012, 8765.987654321098
LONG_DIAGNOSTIC = "jump residuals: " + ", ".join(f"residual {i} +{i}.000%" for i in range(30))
POLE = {k: 1.0 + i for i, k in enumerate(POLE_VARS)} | {k + "_err": 0.01 for k in POLE_VARS}


def _templates(folder: Path) -> list[tuple[bytes, str, str, bool]]:
    """(file bytes, status, diagnostic, has D) of the four kinds of point file."""
    rng = np.random.default_rng(7)
    hist = {
        "t": np.linspace(0.0, 50.0, N_HISTORY),
        "front": rng.random(N_HISTORY),
        "stage": np.ones(N_HISTORY, np.int8),
    }
    full = {k: float(rng.normal()) for k in POINT_VARS} | {k + "_err": 0.01 for k in POINT_VARS}
    kinds = [
        ("ok", "", full | {"converged": True}, POLE, hist),
        ("not_converged", LONG_DIAGNOSTIC, full, POLE, hist),
        ("cfl", "atom 17 moved 0.2 sigma in one step", {"wall_s": 1.0}, POLE, hist),
        ("atom_lost", "atom 3 left the box while loading", {}, {}, None),
    ]
    out = []
    for i, (status, diag, values, pole, h) in enumerate(kinds):
        values = dict(values, piston_velocity=SENTINEL_U)
        has_d = "D" in values
        if has_d:
            values["D"] = SENTINEL_D
        ds = point_dataset(
            values, pole, h, "piston", "scale", status, diag, {"name": "scale"}, lj_units()
        )
        path = write_netcdf(ds, folder / f"template{i}.nc")
        out.append((path.read_bytes(), status, diag, has_d))
    return out


def _offset(data: bytes, value: float) -> int:
    packed = struct.pack("<d", value)
    at = data.find(packed)
    return at if at >= 0 and data.find(packed, at + 1) < 0 else -1


def _write_point(template: tuple, path: Path, u: float) -> None:
    data, _, _, has_d = template
    path.parent.mkdir(parents=True)
    at_u, at_d = _offset(data, SENTINEL_U), _offset(data, SENTINEL_D) if has_d else -2
    if at_u < 0 or at_d == -1:  # another HDF5 layout: patch through the library (slower)
        path.write_bytes(data)
        with netCDF4.Dataset(path, "r+") as nc:
            nc["piston_velocity"][...] = u
            if has_d:
                nc["D"][...] = 2 * u + 1
        return
    buf = bytearray(data)
    buf[at_u : at_u + 8] = struct.pack("<d", u)
    if has_d:
        buf[at_d : at_d + 8] = struct.pack("<d", 2 * u + 1)
    path.write_bytes(buf)


@pytest.fixture(scope="module")
def points(tmp_path_factory: pytest.TempPathFactory) -> tuple[list[Path], np.ndarray, list]:
    """N point files in results/<scene>/up<u>/piston.nc layout, written in shuffled order."""
    root = tmp_path_factory.mktemp("scale")
    templates = _templates(root)
    u = np.round(0.01 + 0.005 * np.arange(N_POINTS), 6)
    kinds = [templates[i % len(templates)] for i in range(N_POINTS)]
    order = np.random.default_rng(1).permutation(N_POINTS)
    paths = [root / "results/scale" / f"up{u[i]:.6g}" / "piston.nc" for i in order]
    for path, i in zip(paths, order, strict=True):
        _write_point(kinds[i], path, float(u[i]))
    return paths, u[order], [kinds[i] for i in order]


MEASURE = """
import json, sys, time
import hugomap.stages.aggregation  # its libraries (xarray, netCDF4): not the aggregation's growth
from hugomap.cli import main

def kB(field):  # this process's own memory: its mm, made afresh at exec
    for line in open("/proc/self/status"):
        if line.startswith(field + ":"):
            return int(line.split()[1])

args = json.load(open(sys.argv[1]))
with open("/proc/self/clear_refs", "w") as f:
    f.write("5")  # the peak (VmHWM) starts again from the resident set now
before = kB("VmRSS")
t = time.process_time()
rc = main(args)
print(json.dumps({"rc": rc, "s": time.process_time() - t, "before_kB": before,
                  "peak_kB": kB("VmHWM")}))
"""


@pytest.mark.slow  # ~27 ms of CPU per point file (70 HDF5 scalars): about a minute for 1000
def test_aggregate_thousands_of_points_in_bounded_memory(points, tmp_path: Path) -> None:
    paths, u, kinds = points
    out = tmp_path / "hugoniot" / "scale.nc"
    cfg = json.dumps({"scenes": {"scale": {"solver": "md"}}})  # the stage asks its backend
    args = ["aggregate", "--scene-name", "scale", "--config-json", cfg, "--out", str(out)]
    (tmp_path / "args.json").write_text(json.dumps([*args, *map(str, paths)]))
    # hugomap.cli and the aggregation's libraries are imported before the baseline is taken.
    r = subprocess.run(
        [sys.executable, "-c", MEASURE, str(tmp_path / "args.json")],
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert r.returncode == 0, r.stderr[-3000:]
    m = json.loads(r.stdout.strip().splitlines()[-1])
    grow_mb = (m["peak_kB"] - m["before_kB"]) / 1024
    bound_mb = BASE_MB + PER_POINT_KB * N_POINTS / 1024
    print(f"\naggregate of {N_POINTS} points: {m['s']:.1f} s CPU, peak RSS +{grow_mb:.1f} MB")
    assert m["rc"] == 0
    assert grow_mb <= bound_mb, f"peak RSS grew {grow_mb:.0f} MB > {bound_mb:.0f} MB"
    assert m["s"] <= MAX_S_PER_POINT * N_POINTS, f"{m['s']:.0f} s of CPU for {N_POINTS} points"

    with xr.open_dataset(out, engine="netcdf4") as ds:
        ds.load()
    assert ds.sizes == {"scheme": 1, "u_p": N_POINTS}
    assert "history_t" not in ds and "history_front" not in ds
    np.testing.assert_array_equal(ds["u_p"].values, np.sort(u))  # every point, sorted
    sorted_kinds = [kinds[i] for i in np.argsort(u)]
    status = ds["status"].values[0]
    diagnostic = ds["diagnostic"].values[0]
    D = ds["D"].values[0]
    for j, (_, st, diag, has_d) in enumerate(sorted_kinds):
        assert status[j] == st and diagnostic[j] == diag  # long strings not truncated
        if has_d:
            assert D[j] == 2 * ds["u_p"].values[j] + 1
        else:
            assert np.isnan(D[j])
    assert int(ds["converged"].values[0].sum()) == sum(k[1] == "ok" for k in sorted_kinds)
    assert np.isnan(ds["D_err"].values[0][[k[1] == "cfl" for k in sorted_kinds]]).all()
    for k, v in POLE.items():  # the pole, although failed loads carry none
        assert float(ds[k]) == v
    # CF: LJ reduced units are "1" with the reduced unit beside them
    assert ds["P"].attrs["units"] == "1" and ds["P"].attrs["reduced_units"] == "epsilon sigma^-3"
    assert [STATUS_FLAGS[c] for c in ds["status_flag"].values[0]] == list(status)
