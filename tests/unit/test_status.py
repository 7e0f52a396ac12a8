"""``python -m hugomap status`` on a synthetic results folder (no MD is run).

The folder holds one file layout per point state, written with the project's own writers
(``point_dataset`` + ``write_netcdf``) where the workflow uses them, so the reader is tested
against the real netCDF layout: a ``status`` variable in point files, a ``status`` attribute
in checkpoints, the ``time``/``step`` attributes of a periodic ``.part.nc`` checkpoint.
"""

from __future__ import annotations

import json
import os
from pathlib import Path

import pytest
import xarray as xr
import yaml

from hugomap.cli import main
from hugomap.config import validate_config
from hugomap.io.atomic import write_netcdf
from hugomap.io.dataset import point_dataset
from hugomap.status import format_table, sweep_status

ROOT = Path(__file__).resolve().parents[2]
NOW = 1.9e9  # a fixed "now" for checkpoint ages [s since the epoch]
U_P = [0.5, 1.0, 1.5, 2.0, 2.5, 3.0, 3.5, 4.0, 5.0]


def _config() -> dict:
    cfg = yaml.safe_load((ROOT / "tests/workflow/tiny/config.yaml").read_text())
    cfg["scenes"]["tiny"]["shock"]["u_p"] = list(U_P)
    return validate_config(cfg)


def _point(path: Path, status: str, diagnostic: str, u: float) -> None:
    values = {"piston_velocity": u, "D": 3.0, "P": 10.0, "converged": status == "ok"}
    ds = point_dataset(values, {"rho0": 0.8}, None, "piston", "tiny", status, diagnostic, {})
    write_netcdf(ds, path)


def _checkpoint(path: Path, **attrs) -> None:
    """A stand-in for an MD checkpoint: the attributes the status reader uses, a variable."""
    ds = xr.Dataset({"x": (("atom", "xyz"), [[0.0, 0.0, 0.0]])})
    ds.attrs.update({"format": "hugomap-md-checkpoint/1", "time": 0.0, "step": 0}, **attrs)
    write_netcdf(ds, path)


@pytest.fixture
def sweep(tmp_path: Path) -> tuple[Path, Path]:
    """results/ with one point in every state; returns (results, config file)."""
    res = tmp_path / "results"
    sc = res / "tiny"
    cfg = _config()
    cfg_file = tmp_path / "my.yaml"
    cfg_file.write_text(yaml.safe_dump(cfg))
    _checkpoint(sc / "sample.nc", stage="sample", status="ok")
    write_netcdf(xr.Dataset({"P": ("ref_point", [1.0, 2.0])}), sc / "reference.nc")
    _point(sc / "up0.5/piston.nc", "ok", "", 0.5)
    _point(sc / "up1/piston.nc", "not_converged", "jump residuals: mass +4.000%", 1.0)
    _point(sc / "up1.5/piston.nc", "cfl", "atom 17 moved 0.2 sigma in one step", 1.5)
    # running: loading checkpoint + a periodic checkpoint written 300 s ago
    _checkpoint(sc / "up2/loaded.nc", stage="loaded", status="ok")
    part = sc / "up2/piston.nc.part.nc"
    _checkpoint(part, stage="drive", status="ok", time=12.5, step=6250)
    os.utime(part, (NOW - 300, NOW - 300))
    # loaded, the piston run not yet checkpointed
    _checkpoint(sc / "up2.5/loaded.nc", stage="loaded", status="ok")
    # failed while loading (pipeline._failure: attributes only)
    write_netcdf(
        xr.Dataset(attrs={"stage": "loaded", "status": "atom_lost", "diagnostic": "atom 3 left"}),
        sc / "up3/loaded.nc",
    )
    # the load job crashed: no file, a traceback in its log
    log = res / "logs/tiny/up3.5/load.log"
    log.parent.mkdir(parents=True)
    log.write_text("Traceback (most recent call last):\n  File x\nMemoryError: out of memory\n")
    # up4: nothing at all (pending). up5: a damaged point file.
    (sc / "up5").mkdir()
    (sc / "up5/piston.nc").write_bytes(b"not a netCDF file")
    # a point from an earlier config
    _point(sc / "up9/piston.nc", "ok", "", 9.0)
    # folders beside the scenes that are not scenes
    (res / "hugoniot").mkdir()
    (res / "figures").mkdir()
    return res, cfg_file


def _by_tag(scene: dict) -> dict[str, dict]:
    return {p["tag"]: p for p in scene["points"]}


def test_every_state_is_read(sweep: tuple[Path, Path]) -> None:
    res, _ = sweep
    report = sweep_status(res, _config(), now=NOW)
    (scene,) = report["scenes"]
    pts = _by_tag(scene)
    assert [p["tag"] for p in scene["points"]] == [
        "0.5", "1", "1.5", "2", "2.5", "3", "3.5", "4", "5", "9",
    ]  # fmt: skip
    assert pts["0.5"]["state"] == "ok" and pts["0.5"]["status"] == "ok"
    assert pts["1"]["state"] == "not_converged"
    assert pts["1"]["diagnostic"] == "jump residuals: mass +4.000%"
    assert pts["1.5"]["state"] == "failed" and pts["1.5"]["status"] == "cfl"
    assert pts["1.5"]["diagnostic"] == "atom 17 moved 0.2 sigma in one step"
    run = pts["2"]
    assert run["state"] == "running" and run["time"] == 12.5 and run["step"] == 6250
    assert run["checkpoint_age_s"] == pytest.approx(300.0)
    assert pts["2.5"]["state"] == "pending" and pts["2.5"]["status"] == "loaded"
    assert pts["3"]["state"] == "failed" and pts["3"]["status"] == "atom_lost"
    assert pts["3"]["diagnostic"] == "atom 3 left"
    assert pts["3.5"]["state"] == "failed"
    assert pts["3.5"]["diagnostic"] == "job crashed (load.log): MemoryError: out of memory"
    assert pts["4"]["state"] == "pending" and pts["4"]["status"] == ""
    assert pts["5"]["state"] == "failed" and "unreadable piston.nc" in pts["5"]["diagnostic"]
    assert pts["9"]["in_config"] is False and pts["9"]["state"] == "ok"
    assert all(p["in_config"] for t, p in pts.items() if t != "9")
    assert scene["counts"] == {
        "ok": 2, "not_converged": 1, "failed": 4, "running": 1, "pending": 2,
        "done": 3, "total": 10,
    }  # fmt: skip
    assert scene["sample"] == "ok" and scene["reference"] and not scene["aggregate"]


def test_table(sweep: tuple[Path, Path]) -> None:
    res, _ = sweep
    text = format_table(sweep_status(res, _config(), now=NOW))
    lines = text.splitlines()
    head = next(ln for ln in lines if ln.startswith("scene tiny"))
    assert "10 points: 3 done (2 ok, 1 not converged), 1 running, 4 failed, 2 pending" in head
    assert "sample ok, reference written, aggregate missing" in head

    def row(tag: str) -> str:
        return next(ln for ln in lines if ln.split()[:1] == [tag])

    assert row("2").split()[1] == "running"
    assert "t = 12.5 tau, step 6250, last checkpoint 5 min ago" in row("2")
    assert row("1.5").split()[1] == "failed" and "cfl: atom 17 moved" in row("1.5")
    assert row("3").split()[1] == "failed" and "atom_lost: atom 3 left" in row("3")
    assert "loaded; piston run not started" in row("2.5")
    assert row("4").split() == ["4", "pending"]
    assert "not in config" in row("9")


def test_cli_json(sweep: tuple[Path, Path], capsys: pytest.CaptureFixture[str]) -> None:
    res, cfg_file = sweep
    rc = main(["status", "--results", str(res), "--config", str(cfg_file), "--json"])
    assert rc == 0
    report = json.loads(capsys.readouterr().out)
    assert report["config"] == str(cfg_file)
    (scene,) = report["scenes"]
    assert scene["scene"] == "tiny" and scene["counts"]["running"] == 1
    assert _by_tag(scene)["2"]["time"] == 12.5


def test_cli_table_and_bad_config(
    sweep: tuple[Path, Path], capsys: pytest.CaptureFixture[str]
) -> None:
    res, cfg_file = sweep
    assert main(["status", "--results", str(res), "--config", str(cfg_file)]) == 0
    assert "scene tiny: 10 points" in capsys.readouterr().out
    bad = yaml.safe_load(cfg_file.read_text())
    bad["scenes"]["tiny"]["shock"]["u_p"] = [-1.0]
    cfg_file.write_text(yaml.safe_dump(bad))
    assert main(["status", "--results", str(res), "--config", str(cfg_file)]) == 2
    assert "scenes.tiny.shock.u_p[0] = -1.0: out of range" in capsys.readouterr().err


def test_without_config_scenes_come_from_disk(sweep: tuple[Path, Path]) -> None:
    """No config: every scene folder with a sample or point folders (in results/ or
    results/logs/); u_p from the folders; hugoniot/, figures/ and logs/ are not scenes."""
    res, _ = sweep
    other = res / "other"
    _point(other / "up2/piston.nc", "ok", "", 2.0)
    report = sweep_status(res, None, now=NOW)
    assert [s["scene"] for s in report["scenes"]] == ["other", "tiny"]
    tiny = report["scenes"][1]
    # up4 has neither a results nor a log folder, so it is unknown without the config; up3.5
    # (only a crashed job's log) is found.
    assert [p["tag"] for p in tiny["points"]] == [
        "0.5",
        "1",
        "1.5",
        "2",
        "2.5",
        "3",
        "3.5",
        "5",
        "9",
    ]
    assert all(p["in_config"] for p in tiny["points"])
    assert report["scenes"][0]["counts"]["ok"] == 1
    assert report["scenes"][0]["sample"] == "missing"


def test_empty_results(tmp_path: Path) -> None:
    """Before anything ran: every point pending; no results folder at all is not an error."""
    report = sweep_status(tmp_path / "results", _config(), now=NOW)
    (scene,) = report["scenes"]
    assert scene["counts"]["pending"] == len(U_P) == scene["counts"]["total"]
    assert scene["sample"] == "missing"
    assert sweep_status(tmp_path / "nothing", None)["scenes"] == []


def test_crashed_preparation(tmp_path: Path) -> None:
    """A scene whose prepare job crashed shows the crash at scene level (found from its log
    alone when there is no config) and in the table."""
    res = tmp_path / "results"
    log = res / "logs/broken/prepare.log"
    log.parent.mkdir(parents=True)
    log.write_text("INFO start\nTraceback (most recent call last):\nValueError: bad cells\n")
    report = sweep_status(res, None, now=NOW)
    (scene,) = report["scenes"]
    assert scene["scene"] == "broken"
    assert scene["sample"] == "job crashed (prepare.log): ValueError: bad cells"
    text = format_table(report)
    assert "sample failed" in text and "sample: job crashed (prepare.log)" in text


def test_dichotomy_bracket(tmp_path: Path) -> None:
    """The latest dichotomy loop state under a point folder is shown, whatever its file name;
    other JSON files are ignored."""
    res = tmp_path / "results"
    folder = res / "tiny/up1.5/dichotomy"
    folder.mkdir(parents=True)
    base = {"trials": [], "done": False, "status": "running", "reason": "", "u_out": None}
    states = [
        {"k": 0, "bracket": None, "pending": [-1.2, -0.8]},
        {"k": 1, "bracket": None, "pending": [-1.6]},
        {"k": 2, "bracket": [-1.6, -1.2], "pending": [-1.4]},
    ]
    for s in states:
        (folder / f"state{s['k']}.json").write_text(json.dumps(base | s))
    (folder / "trial0.json").write_text(json.dumps({"u_out": -1.2, "slope": 0.3}))
    report = sweep_status(res, _config(), now=NOW)
    d = _by_tag(report["scenes"][0])["1.5"]["dichotomy"]
    assert d["k"] == 2 and d["bracket"] == [-1.6, -1.2] and d["pending"] == [-1.4]
    assert _by_tag(report["scenes"][0])["1"]["dichotomy"] is None
    text = format_table(report)
    assert "dichotomy k = 2, bracket [-1.6, -1.2]" in text
    done = base | {"k": 7, "bracket": [-1.45, -1.44], "pending": [], "done": True}
    (folder / "state7.json").write_text(json.dumps(done | {"status": "ok", "u_out": -1.445}))
    text = format_table(sweep_status(res, _config(), now=NOW))
    assert "dichotomy k = 7, done: ok, u_out = -1.445" in text
