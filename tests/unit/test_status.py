"""``python -m hugomap status`` on a synthetic results folder (no MD is run).

The folder holds one file layout per point state, written with the project's own writers
(``point_dataset`` + ``write_netcdf``, ``write_json``) where the workflow uses them, so the
reader is tested against the real layout: a ``status`` variable in point files, a ``status``
attribute in checkpoints (loading and window), the ``time``/``step`` attributes of a periodic
``.part.nc`` checkpoint, the dichotomy's ``state<k>.json`` loop states. Every scheme of the
config (top level, or the scene's own ``schemes``) has its own row per piston velocity.
"""

from __future__ import annotations

import io
import json
import os
import sys
from pathlib import Path

import pytest
import xarray as xr
import yaml

from hugomap.cli import main
from hugomap.config import ConfigError, validate_config
from hugomap.io.atomic import write_json, write_netcdf
from hugomap.io.dataset import lj_units, point_dataset
from hugomap.status import format_table, run_status, sweep_status

ROOT = Path(__file__).resolve().parents[2]


def test_the_results_folder_comes_from_the_config(
    sweep: tuple[Path, Path], capsys: pytest.CaptureFixture[str]
) -> None:
    """A config's ``results`` key names the folder its sweep writes and ``status`` reads
    (no --results); without the key it is ``results``; a folder name with spaces or
    shell characters is refused at validation, naming the key."""
    res, cfg_file = sweep
    cfg = yaml.safe_load(cfg_file.read_text())
    cfg["results"] = str(res)
    cfg_file.write_text(yaml.safe_dump(cfg))
    assert main(["status", "--config", str(cfg_file), "--json"]) == 0
    report = json.loads(capsys.readouterr().out)
    assert report["results"] == str(res) and report["scenes"][0]["counts"]["running"] == 1
    del cfg["results"]
    assert validate_config(cfg)["results"] == "results"
    cfg["results"] = "my results; rm"
    with pytest.raises(ConfigError, match="results"):
        validate_config(cfg)


NOW = 1.9e9  # a fixed "now" for checkpoint ages [s since the epoch]
U_P = [0.5, 1.0, 1.5, 2.0, 2.5, 3.0, 3.5, 4.0, 5.0]


def _config() -> dict:
    cfg = yaml.safe_load((ROOT / "tests/workflow/tiny/config.yaml").read_text())
    cfg["scenes"]["tiny"]["shock"]["u_p"] = list(U_P)
    cfg["schemes"] = ["piston", "amw", "dichotomy"]  # the report's rows below assume these
    return validate_config(cfg)


def _point(path: Path, status: str, diagnostic: str, u: float) -> None:
    values = {"piston_velocity": u, "D": 3.0, "P": 10.0, "converged": status == "ok"}
    ds = point_dataset(
        values, {"rho0": 0.8}, None, path.stem, "tiny", status, diagnostic, {}, lj_units()
    )
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
    # failed while loading (stages.files.failure: attributes only)
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


def _by_tag(scene: dict, scheme: str = "piston") -> dict[str, dict]:
    return {p["tag"]: p for p in scene["points"] if p["scheme"] == scheme}


def test_every_state_is_read(sweep: tuple[Path, Path]) -> None:
    res, _ = sweep
    report = sweep_status(res, _config(), now=NOW)
    (scene,) = report["scenes"]
    pts = _by_tag(scene)
    tags = ["0.5", "1", "1.5", "2", "2.5", "3", "3.5", "4", "5", "9"]
    assert [p["tag"] for p in scene["points"] if p["scheme"] == "piston"] == tags
    assert scene["schemes"] == ["piston", "amw", "dichotomy"]  # the config's, in its order
    assert [(p["tag"], p["scheme"]) for p in scene["points"]] == [
        (t, s) for t in tags for s in ("piston", "amw", "dichotomy")
    ]
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
    assert scene["counts_by_scheme"]["piston"] == {
        "ok": 2, "target_not_reached": 0, "not_converged": 1, "failed": 4, "running": 1, "pending": 2,
        "done": 3, "total": 10,
    }  # fmt: skip
    # The window schemes of these points: no window yet; they fail where the loading failed
    # or its job crashed, and wait elsewhere (up2, up2.5: loaded, window not cut yet).
    for s in ("amw", "dichotomy"):
        w = _by_tag(scene, s)
        assert {t for t, p in w.items() if p["state"] == "failed"} == {"3", "3.5"}
        assert w["3"]["status"] == "atom_lost" and w["3"]["diagnostic"] == "atom 3 left"
        assert w["3.5"]["diagnostic"] == "job crashed (load.log): MemoryError: out of memory"
        assert w["2"]["state"] == w["2.5"]["state"] == "pending"
        assert w["2"]["status"] == w["2.5"]["status"] == "loaded"
        assert w["9"]["in_config"] is False
        assert scene["counts_by_scheme"][s] == {
            "ok": 0, "target_not_reached": 0, "not_converged": 0, "failed": 2, "running": 0, "pending": 8,
            "done": 0, "total": 10,
        }  # fmt: skip
    assert scene["counts"] == {
        "ok": 2, "target_not_reached": 0, "not_converged": 1, "failed": 8, "running": 1, "pending": 18,
        "done": 3, "total": 30,
    }  # fmt: skip
    assert scene["n_u_p"] == 10
    assert scene["sample"] == "ok" and scene["reference"] and not scene["aggregate"]


def test_table(sweep: tuple[Path, Path]) -> None:
    res, _ = sweep
    text = format_table(sweep_status(res, _config(), now=NOW))
    lines = text.splitlines()
    head = next(ln for ln in lines if ln.startswith("scene tiny"))
    assert "30 points (10 u_p x 3 schemes: piston, amw, dichotomy)" in head
    assert "3 done (2 ok, 1 not converged), 1 running, 8 failed, 18 pending" in head
    assert "sample ok, reference written, aggregate missing" in head
    assert "  piston:    10 points: 3 done (2 ok, 1 not converged), 1 running, 4 failed, " in text
    assert "  amw:       10 points: 0 done (0 ok, 0 not converged), 0 running, 2 failed, " in text

    def row(tag: str, scheme: str = "piston") -> str:
        return next(ln for ln in lines if ln.split()[:2] == [tag, scheme])

    assert row("2").split()[2] == "running"
    assert "t = 12.5 tau, step 6250, last checkpoint 5 min ago" in row("2")
    assert row("1.5").split()[2] == "failed" and "cfl: atom 17 moved" in row("1.5")
    assert row("3").split()[2] == "failed" and "atom_lost: atom 3 left" in row("3")
    assert row("3", "dichotomy").split()[2] == "failed"
    assert "atom_lost: atom 3 left" in row("3", "dichotomy")
    assert "loaded; piston run not started" in row("2.5")
    assert "loaded; window not cut yet" in row("2.5", "amw")
    assert row("4").split() == ["4", "piston", "pending"]
    assert row("4", "amw").split() == ["4", "amw", "pending"]
    assert "not in config" in row("9") and "not in config" in row("9", "dichotomy")


def test_cli_json(sweep: tuple[Path, Path], capsys: pytest.CaptureFixture[str]) -> None:
    res, cfg_file = sweep
    rc = main(["status", "--results", str(res), "--config", str(cfg_file), "--json"])
    assert rc == 0
    report = json.loads(capsys.readouterr().out)
    assert report["config"] == str(cfg_file)
    (scene,) = report["scenes"]
    assert scene["scene"] == "tiny" and scene["counts"]["running"] == 1
    assert _by_tag(scene)["2"]["time"] == 12.5
    assert _by_tag(scene, "amw")["2"]["time"] is None
    assert scene["counts_by_scheme"]["dichotomy"]["total"] == 10


def test_cli_table_and_bad_config(
    sweep: tuple[Path, Path], capsys: pytest.CaptureFixture[str]
) -> None:
    res, cfg_file = sweep
    assert main(["status", "--results", str(res), "--config", str(cfg_file)]) == 0
    assert "scene tiny: 30 points (10 u_p x 3 schemes" in capsys.readouterr().out
    bad = yaml.safe_load(cfg_file.read_text())
    bad["scenes"]["tiny"]["shock"]["u_p"] = [-1.0]
    cfg_file.write_text(yaml.safe_dump(bad))
    assert main(["status", "--results", str(res), "--config", str(cfg_file)]) == 2
    assert "scenes.tiny.shock.u_p[0] = -1.0: out of range" in capsys.readouterr().err


def test_without_config_scenes_come_from_disk(sweep: tuple[Path, Path]) -> None:
    """No config: every scene folder with a sample or point folders (in results/ or
    results/logs/); u_p from the folders; hugoniot/, figures/, logs/, campaign/ and
    references/ (and their logs) are not scenes."""
    res, _ = sweep
    other = res / "other"
    _point(other / "up2/piston.nc", "ok", "", 2.0)
    for d in (res / "references", res / "logs" / "references", res / "campaign"):
        d.mkdir(parents=True, exist_ok=True)
    (res / "references" / "lj_0123456789ab.nc").write_bytes(b"")
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
    assert scene["counts"]["pending"] == 3 * len(U_P) == scene["counts"]["total"]
    assert all(c["pending"] == len(U_P) for c in scene["counts_by_scheme"].values())
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


def _window(path: Path, status: str = "ok", diagnostic: str = "") -> None:
    """A stand-in for the window checkpoint (stages.window_start): its attributes."""
    attrs = {"stage": "window", "status": status}
    if status == "ok":
        _checkpoint(path, **attrs, window_state=json.dumps({"u_out": -1.0}))
    else:  # a failed window stage writes the status and diagnostic only
        write_netcdf(xr.Dataset(attrs={**attrs, "diagnostic": diagnostic}), path)


def _aged(path: Path, age: float) -> None:
    os.utime(path, (NOW - age, NOW - age))


def test_dichotomy_bracket(tmp_path: Path) -> None:
    """The latest dichotomy loop state under a point folder is shown on the dichotomy's row,
    whatever its file name; other JSON files are ignored."""
    res = tmp_path / "results"
    point = res / "tiny/up1.5"
    folder = point / "dichotomy"
    _checkpoint(point / "loaded.nc", stage="loaded", status="ok")
    _window(point / "window.nc")
    base = {"trials": [], "done": False, "status": "running", "reason": "", "u_out": None}
    states = [
        {"k": 0, "bracket": None, "pending": [-1.2, -0.8]},
        {"k": 1, "bracket": None, "pending": [-1.6]},
        {"k": 2, "bracket": [-1.6, -1.2], "pending": [-1.4]},
    ]
    for s in states:
        write_json(base | s, folder / f"state{s['k']}.json")
        _aged(folder / f"state{s['k']}.json", 90 - 30 * s["k"])
    write_json({"u_out": -1.2, "slope": 0.3}, folder / "trial0_0.json")
    _aged(folder / "trial0_0.json", 50)
    report = sweep_status(res, _config(), now=NOW)
    row = _by_tag(report["scenes"][0], "dichotomy")["1.5"]
    d = row["dichotomy"]
    assert d["k"] == 2 and d["bracket"] == [-1.6, -1.2] and d["pending"] == [-1.4]
    assert row["state"] == "running" and row["checkpoint_age_s"] == pytest.approx(30.0)
    assert _by_tag(report["scenes"][0])["1.5"]["dichotomy"] is None  # not on the piston row
    assert _by_tag(report["scenes"][0], "dichotomy")["1"]["dichotomy"] is None
    text = format_table(report)
    assert "dichotomy k = 2, bracket [-1.6, -1.2], last state 30 s ago" in text
    done = base | {"k": 7, "bracket": [-1.45, -1.44], "pending": [], "done": True}
    write_json(done | {"status": "ok", "u_out": -1.445}, folder / "state7.json")
    text = format_table(sweep_status(res, _config(), now=NOW))
    assert "1.5  dichotomy  running  dichotomy k = 7, done: ok, u_out = -1.445" in text
    _point(point / "dichotomy.nc", "ok", "", 1.5)
    report = sweep_status(res, _config(), now=NOW)
    assert _by_tag(report["scenes"][0], "dichotomy")["1.5"]["state"] == "ok"
    assert "1.5  dichotomy  ok       dichotomy k = 7, done: ok" in format_table(report)


def test_window_schemes(tmp_path: Path) -> None:
    """AMW, MW and the dichotomy: done or failed from their point files; failed with the
    window stage, its unreadable file or a crashed job; running (a job log newer than the
    window checkpoint, the dichotomy's loop states); pending otherwise. The scene's own
    ``schemes`` replace the top-level ones; a scheme found on disk but not in the config is
    listed, marked as such."""
    cfg = _config()
    cfg["schemes"] = ["piston", "amw"]
    cfg["scenes"]["tiny"]["schemes"] = ["piston", "mw", "dichotomy"]
    cfg["scenes"]["tiny"]["shock"]["u_p"] = [1.0, 1.5, 2.0, 2.5, 3.0, 3.5, 4.0]
    res = tmp_path / "results"
    sc, logs = res / "tiny", res / "logs/tiny"
    for u in ("1", "1.5", "2", "2.5", "3", "3.5", "4"):
        _checkpoint(sc / f"up{u}/loaded.nc", stage="loaded", status="ok")
    # up1: every point written; amw is on disk from an earlier config
    _window(sc / "up1/window.nc")
    _point(sc / "up1/piston.nc", "ok", "", 1.0)
    _point(sc / "up1/mw.nc", "not_converged", "jump residuals: energy +5.000%", 1.0)
    _point(sc / "up1/dichotomy.nc", "bracket_not_found", "slope kept its sign", 1.0)
    _point(sc / "up1/amw.nc", "ok", "", 1.0)
    # up1.5: MW running (its log is newer than the window), the dichotomy looping
    _window(sc / "up1.5/window.nc")
    _aged(sc / "up1.5/window.nc", 600)
    (logs / "up1.5").mkdir(parents=True)
    (logs / "up1.5/mw.log").write_text("INFO steering u_out\n")
    _aged(logs / "up1.5/mw.log", 60)
    state = {"k": 1, "bracket": [-1.2, -0.8], "pending": [-1.0], "done": False,
             "status": "running", "reason": "", "trials": []}  # fmt: skip
    write_json(state, sc / "up1.5/dichotomy/state1.json")
    # up2: the window stage failed: every window scheme fails with its status
    _window(sc / "up2/window.nc", "front_left_window", "front at x = 3.0 sigma")
    # up2.5: crashed jobs (MW; a dichotomy trial)
    _window(sc / "up2.5/window.nc")
    (logs / "up2.5").mkdir(parents=True)
    (logs / "up2.5/mw.log").write_text("Traceback (most recent call last):\nKeyError: 'u'\n")
    write_json(state | {"k": 0}, sc / "up2.5/dichotomy/state0.json")
    (logs / "up2.5/dichotomy_trial0_0.log").write_text(
        "Traceback (most recent call last):\nhugomap.failures.CheckpointError: refused\n"
    )
    # up3: MW not started (an old log from before the window was cut again); the loop ended
    # without a root
    (logs / "up3").mkdir(parents=True)
    (logs / "up3/mw.log").write_text("old\n")
    _aged(logs / "up3/mw.log", 900)
    _window(sc / "up3/window.nc")
    _aged(sc / "up3/window.nc", 600)
    ended = state | {"k": 6, "done": True, "status": "max_iterations", "reason": "6 iterations"}
    write_json(ended, sc / "up3/dichotomy/state6.json")
    # up3.5: a damaged window checkpoint; up4: the window job crashed
    (sc / "up3.5/window.nc").write_bytes(b"garbage")
    (logs / "up4").mkdir(parents=True)
    (logs / "up4/window.log").write_text("Traceback (most recent call last):\nMemoryError\n")

    report = sweep_status(res, cfg, now=NOW)
    (scene,) = report["scenes"]
    assert scene["schemes"] == ["piston", "mw", "dichotomy", "amw"]
    mw, dich, amw = (_by_tag(scene, s) for s in ("mw", "dichotomy", "amw"))
    assert list(amw) == ["1"] and amw["1"]["in_config"] is False and amw["1"]["state"] == "ok"
    assert mw["1"]["state"] == "not_converged"
    assert dich["1"]["state"] == "failed" and dich["1"]["status"] == "bracket_not_found"
    assert mw["1.5"]["state"] == "running" and mw["1.5"]["log_age_s"] == pytest.approx(60.0)
    assert dich["1.5"]["state"] == "running" and dich["1.5"]["dichotomy"]["k"] == 1
    for p in (mw["2"], dich["2"]):
        assert (p["state"], p["status"]) == ("failed", "front_left_window")
        assert p["diagnostic"] == "window stage: front at x = 3.0 sigma"
    assert mw["2.5"]["state"] == "failed"
    assert mw["2.5"]["diagnostic"] == "job crashed (mw.log): KeyError: 'u'"
    assert dich["2.5"]["state"] == "failed"
    assert dich["2.5"]["diagnostic"] == (
        "job crashed (dichotomy_trial0_0.log): hugomap.failures.CheckpointError: refused"
    )
    assert (mw["3"]["state"], mw["3"]["status"]) == ("pending", "window")
    assert (dich["3"]["state"], dich["3"]["status"]) == ("failed", "max_iterations")
    assert dich["3"]["diagnostic"] == "6 iterations"
    assert mw["3.5"]["state"] == "failed" and "unreadable window.nc" in mw["3.5"]["diagnostic"]
    assert mw["4"]["diagnostic"] == "job crashed (window.log): MemoryError"
    assert scene["counts_by_scheme"]["mw"] == {
        "ok": 0, "target_not_reached": 0, "not_converged": 1, "failed": 4, "running": 1, "pending": 1,
        "done": 1, "total": 7,
    }  # fmt: skip
    assert scene["counts_by_scheme"]["dichotomy"]["failed"] == 6
    text = format_table(report)

    def row(tag: str, scheme: str) -> str:
        return next(ln for ln in text.splitlines() if ln.split()[:2] == [tag, scheme])

    assert "7 u_p x 4 schemes: piston, mw, dichotomy, amw" in text
    assert "started, log written 60 s ago" in row("1.5", "mw")
    assert "dichotomy k = 1, bracket [-1.2, -0.8]" in row("1.5", "dichotomy")
    assert "front_left_window: window stage: front at x = 3.0 sigma" in row("2", "mw")
    assert "window ready; mw run not started" in row("3", "mw")
    assert "max_iterations: 6 iterations" in row("3", "dichotomy")
    assert "not in config" in row("1", "amw")
    # without the config: the schemes come from what is on disk
    bare = {p["scheme"] for p in sweep_status(res, None, now=NOW)["scenes"][0]["points"]}
    assert bare == {"piston", "mw", "dichotomy", "amw"}


def test_every_failure_status_the_code_emits_is_registered():
    """Each status a stage can end with (the first argument of WindowError, SolverUnstable,
    StageFailed, a failed ControlResult, a dichotomy _finish) has a cause in
    ``failures.FAILURES``: the failure labels of the stability map cannot miss one."""
    import re

    from hugomap.failures import FAILURES

    src = Path(__file__).resolve().parents[2] / "src" / "hugomap"
    pattern = re.compile(
        r"(?:WindowError|SolverUnstable|SPHUnstable|StageFailed|ControlResult\(\s*False,|_finish\(\s*s,)"
        r"\(?\s*\"([a-z_]+)\""
    )
    found = set()
    for f in src.rglob("*.py"):
        found.update(pattern.findall(f.read_text()))
    found.update(
        re.findall(r'return "(diverged|oscillating)"', (src / "methods" / "control.py").read_text())
    )
    from hugomap.md.integrate import STATUS_NAMES

    found.update(v for v in STATUS_NAMES.values() if v not in ("ok", "grow"))
    assert {"nan", "never_steady", "too_noisy", "bracket_not_found", "oscillating"} <= found
    assert found - {"ok"} <= set(FAILURES), found - set(FAILURES)


def test_without_config_the_recorded_one_is_read(
    sweep: tuple[Path, Path], capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    """No --config: the config the results were made with, from the aggregate's
    ``config_json`` (schemes and u_p of the sweep, not of config/config.yaml, which is there
    in the working directory), else from a scene file's ``scene_config``."""
    res, _ = sweep
    monkeypatch.chdir(ROOT)  # config/config.yaml exists here: it must not be read
    cfg = _config()
    agg = xr.Dataset(attrs={"config_json": json.dumps(cfg), "scene": "tiny"})
    write_netcdf(agg, res / "hugoniot" / "tiny.nc")
    assert main(["status", "--results", str(res), "--json"]) == 0
    report = json.loads(capsys.readouterr().out)
    assert report["config"] == f"recorded in {res / 'hugoniot' / 'tiny.nc'}"
    (scene,) = report["scenes"]
    assert scene["scene"] == "tiny" and scene["schemes"] == ["piston", "amw", "dichotomy"]
    assert scene["counts"]["total"] == 30 and scene["counts"]["pending"] == 18
    # No aggregate: the prepared sample's scene_config (its u_p; schemes from disk)
    (res / "hugoniot" / "tiny.nc").unlink()
    scene_cfg = dict(cfg["scenes"]["tiny"], name="tiny")
    _checkpoint(res / "tiny" / "sample.nc", stage="sample", status="ok",
                scene_config=json.dumps(scene_cfg))  # fmt: skip
    assert main(["status", "--results", str(res)]) == 0
    out = capsys.readouterr().out
    assert f"(config recorded in {res / 'tiny' / 'sample.nc'})" in out.splitlines()[0]
    assert "10 points (10 u_p x 1 schemes: piston)" in out
    assert "not in config" in out and out.count("not in config") == 1  # up9 only
    # Nothing recorded: config/config.yaml, as before
    empty = res.parent / "empty"
    empty.mkdir()
    assert main(["status", "--results", str(empty), "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["config"] == "config/config.yaml"


class _Terminal(io.StringIO):
    """A stream that says it is a terminal."""

    def isatty(self) -> bool:
        return True


def test_detail_fits_the_terminal_and_is_whole_elsewhere(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    """A long diagnostic is cut to the terminal's width ($COLUMNS), whatever that width;
    written to a pipe or with --full it is whole."""
    monkeypatch.chdir(tmp_path)  # no config/config.yaml: the scene comes from disk
    res = tmp_path / "results"
    long = "jump residuals: " + ", ".join(f"term {i} +{i}.000%" for i in range(30))
    _point(res / "tiny/up1/piston.nc", "not_converged", long, 1.0)

    def row(text: str) -> str:
        return next(ln for ln in text.splitlines() if ln.split()[:2] == ["1", "piston"])

    for columns in (80, 160, 250):
        monkeypatch.setenv("COLUMNS", str(columns))
        out = _Terminal()
        assert run_status(res, None, stream=out) == 0
        line = row(out.getvalue())
        assert len(line) == columns and line.endswith("...")
        assert line[:-3] in row(format_table(sweep_status(res, None)))
        out = _Terminal()
        assert run_status(res, None, stream=out, full=True) == 0
        assert row(out.getvalue()).endswith(long)
    monkeypatch.setenv("COLUMNS", "80")
    assert main(["status", "--results", str(res)]) == 0  # captured: not a terminal
    assert row(capsys.readouterr().out).endswith(long)
    monkeypatch.setattr("sys.stdout", _Terminal())
    assert main(["status", "--results", str(res), "--full"]) == 0
    assert row(sys.stdout.getvalue()).endswith(long)
    monkeypatch.setattr("sys.stdout", _Terminal())
    assert main(["status", "--results", str(res)]) == 0
    assert len(row(sys.stdout.getvalue())) == 80


def test_a_done_point_shows_the_accuracy_it_bought(tmp_path: Path) -> None:
    """A point's row gives its stated relative errors and the target it was asked for, and a
    point that missed its target is counted as such, not as failed."""
    sc = tmp_path / "tiny"
    values = {"piston_velocity": 0.5, "D": 4.0, "D_err": 0.012, "P": 10.0, "P_err": 0.2,
              "target_D": 0.002, "target_P": 0.01}  # fmt: skip
    ds = point_dataset(values, {"rho0": 0.8, "P0": 0.0}, None, "piston", "tiny",
                       "target_not_reached", "D's error 0.3 % above target.D = 0.2 %", {},
                       lj_units())  # fmt: skip
    write_netcdf(ds, sc / "up0.5" / "piston.nc")
    report = sweep_status(tmp_path, _config(), now=NOW)
    text = format_table(report)
    row = next(ln for ln in text.splitlines() if ln.split()[:2] == ["0.5", "piston"])
    assert row.split()[2] == "target_not_reached"
    assert "D ± 0.3 %, P ± 2 % (target D 0.2 %, P 1 %); D's error 0.3 %" in row
    assert "1 done (0 ok, 1 target not reached, 0 not converged)" in text


def test_a_piston_run_again_says_on_what_sample(tmp_path: Path) -> None:
    """A piston point run a second time on a longer sample (``stages.piston``) says so."""
    values = {"piston_velocity": 0.5, "D": 4.0, "D_err": 0.004, "P": 10.0, "P_err": 0.02,
              "target_D": 0.002, "sample_factor": 1.43}  # fmt: skip
    ds = point_dataset(values, {"rho0": 0.8, "P0": 0.0}, None, "piston", "tiny", "ok", "", {},
                       lj_units())  # fmt: skip
    write_netcdf(ds, tmp_path / "tiny" / "up0.5" / "piston.nc")
    text = format_table(sweep_status(tmp_path, _config(), now=NOW))
    row = next(ln for ln in text.splitlines() if ln.split()[:2] == ["0.5", "piston"])
    assert "D ± 0.1 %, P ± 0.2 % (target D 0.2 %, second run, on a sample 1.4 × as long)" in row


def test_schemes_chosen_per_u_p_are_the_points_expected(tmp_path: Path) -> None:
    """Where ``schemes: [auto]`` chose per u_p (``scheme_at``), each u_p expects only its
    own schemes: the counts are those points, and the header says the grid is not full."""
    cfg = _config()
    sc = cfg["scenes"]["tiny"]
    ups = sc["shock"]["u_p"]
    sc["schemes"] = ["amw", "piston"]
    sc["scheme_at"] = [["amw"]] + [["piston"]] * (len(ups) - 1)
    _point(tmp_path / "tiny" / f"up{ups[0]:g}" / "amw.nc", "ok", "", ups[0])
    report = sweep_status(tmp_path, cfg, now=NOW)
    (scene,) = report["scenes"]
    assert scene["counts"]["total"] == len(ups)
    assert list(_by_tag(scene, "amw")) == [f"{ups[0]:g}"]
    assert list(_by_tag(scene, "piston")) == [f"{u:g}" for u in ups[1:]]
    assert f"{len(ups)} points ({len(ups)} u_p, schemes chosen per u_p: amw, piston)" in (
        format_table(report)
    )
