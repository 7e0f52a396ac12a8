"""How far a sweep has got: ``python -m hugomap status`` (issue 7, item 4).

Reads the results folder that the workflow writes (see ``workflow/rules``) and never the
Snakemake state, so it works while a sweep runs, after it was killed, or on a copy:

    results/<scene>/sample.nc                      prepared sample
    results/<scene>/up<u>/loaded.nc                loading checkpoint (attr ``status``)
    results/<scene>/up<u>/piston.nc                the point (variable ``status``, ``diagnostic``)
    results/<scene>/up<u>/piston.nc.part.nc        periodic checkpoint of a running point
    results/<scene>/reference.nc                   reference Hugoniot
    results/hugoniot/<scene>.nc                    the scene's aggregate
    results/logs/<scene>/up<u>/{load,piston}.log   job logs (a Python traceback = a crash)

Each piston velocity of the config is in one state: ``ok`` or ``not_converged`` (done),
``failed`` (the solver stopped with a status, the job crashed, or a file is unreadable),
``running`` (a periodic checkpoint exists and no final file; its simulated time and the age of
the checkpoint are shown: an old checkpoint means the job was killed and will resume from it),
or ``pending`` (nothing yet, or only the loading checkpoint). Points found on disk but not in
the config are listed too, marked as such. Where a point folder holds dichotomy loop states
(JSON with ``k``, ``bracket``, ``pending``, ``done``), the latest iteration and its bracket
are shown.
"""

from __future__ import annotations

import json
import math
import time
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any, TextIO

import xarray as xr

from .config import load_config, point_tag

DONE_STATES = ("ok", "not_converged")
STATES = ("ok", "not_converged", "failed", "running", "pending")
RESERVED = ("hugoniot", "figures", "logs")
PART_SUFFIX = ".part.nc"


@dataclass
class PointStatus:
    """The state of one point (one piston velocity of one scene)."""

    u_p: float
    tag: str
    state: str
    status: str = ""
    diagnostic: str = ""
    time: float | None = None
    step: int | None = None
    checkpoint_age_s: float | None = None
    in_config: bool = True
    dichotomy: dict[str, Any] | None = None


def _open_status(path: Path) -> tuple[str, str, dict[str, Any]]:
    """``status``, ``diagnostic`` (variables, else attributes) and the attributes of a file."""
    with xr.open_dataset(path, engine="netcdf4", decode_times=False) as ds:
        out = []
        for key in ("status", "diagnostic"):
            if key in ds.variables:
                out.append(str(ds[key].values))
            else:
                out.append(str(ds.attrs.get(key, "")))
        return out[0], out[1], dict(ds.attrs)


DICHOTOMY_KEYS = {"k", "bracket", "pending", "done", "status"}


def dichotomy_progress(folder: Path) -> dict[str, Any] | None:
    """The latest dichotomy loop state (``window.dichotomy``: a JSON object with k, bracket,
    pending, done, status) found under a point folder, or None. Found by its keys, not its
    file name, so any layout of the state files under the point folder works."""
    best = None
    for f in folder.glob("**/*.json") if folder.is_dir() else []:
        try:
            s = json.loads(f.read_text())
        except (OSError, ValueError):
            continue
        if isinstance(s, dict) and DICHOTOMY_KEYS <= set(s) and isinstance(s["k"], int):
            if best is None or s["k"] > best["k"]:
                best = {k: s[k] for k in ("k", "bracket", "pending", "done", "status")}
                best.update(u_out=s.get("u_out"), reason=s.get("reason", ""))
    return best


def _crash(log: Path) -> str | None:
    """The last line of a job log that ends in a Python traceback, else None."""
    try:
        text = log.read_text(errors="replace")
    except OSError:
        return None
    if "Traceback (most recent call last)" not in text:
        return None
    lines = [ln.strip() for ln in text.splitlines() if ln.strip()]
    return f"job crashed ({log.name}): {lines[-1] if lines else 'no message'}"


def point_status(
    results: str | Path, scene: str, u_p: float, now: float | None = None
) -> PointStatus:
    """The state of the point of ``scene`` at piston velocity ``u_p`` under ``results``."""
    results = Path(results)
    tag = point_tag(u_p)
    folder = results / scene / f"up{tag}"
    final = folder / "piston.nc"
    part = folder / ("piston.nc" + PART_SUFFIX)
    loaded = folder / "loaded.nc"
    logs = results / "logs" / scene / f"up{tag}"
    p = PointStatus(u_p=float(u_p), tag=tag, state="pending")
    p.dichotomy = dichotomy_progress(folder)
    if final.exists():
        try:
            p.status, p.diagnostic, _ = _open_status(final)
        except Exception as exc:  # any unreadable file is reported, not raised
            p.state, p.diagnostic = "failed", f"unreadable {final.name}: {exc}"
            return p
        p.state = p.status if p.status in DONE_STATES else "failed"
        return p
    if part.exists():
        p.state = "running"
        try:
            _, _, attrs = _open_status(part)
            t = float(attrs["time"]) if "time" in attrs else math.nan
            p.time = t if math.isfinite(t) else None
            p.step = int(attrs["step"]) if "step" in attrs else None
        except Exception as exc:
            p.diagnostic = f"unreadable checkpoint {part.name}: {exc}"
        p.checkpoint_age_s = max((time.time() if now is None else now) - part.stat().st_mtime, 0.0)
        return p
    if loaded.exists():
        try:
            p.status, p.diagnostic, _ = _open_status(loaded)
        except Exception as exc:
            p.state, p.diagnostic = "failed", f"unreadable {loaded.name}: {exc}"
            return p
        if p.status not in ("", "ok"):
            p.state = "failed"
            return p
        p.status = "loaded"
        crash = _crash(logs / "piston.log")
    else:
        crash = _crash(logs / "load.log")
    if crash:
        p.state, p.diagnostic = "failed", crash
    return p


def _disk_points(results: Path, scene: str) -> dict[str, float]:
    """Tags of the point folders of ``scene`` on disk (results or logs) → piston velocity."""
    out = {}
    folders = [*(results / scene).glob("up*"), *(results / "logs" / scene).glob("up*")]
    for d in sorted(folders):
        try:
            u = float(d.name[2:])
        except ValueError:
            continue
        if d.is_dir() and math.isfinite(u):
            out[d.name[2:]] = u
    return out


def scene_status(
    results: str | Path, scene: str, u_values: list[float] | None, now: float | None = None
) -> dict[str, Any]:
    """The state of every point of one scene (``u_values`` from the config; None: the
    folders found on disk), with counts and the scene-level files."""
    results = Path(results)
    wanted = {point_tag(u): float(u) for u in (u_values or [])}
    on_disk = _disk_points(results, scene)
    points = [point_status(results, scene, u, now) for u in wanted.values()]
    for tag, u in on_disk.items():
        if tag not in wanted:
            p = point_status(results, scene, u, now)
            p.in_config = u_values is None
            points.append(p)
    points.sort(key=lambda p: p.u_p)
    counts = {s: sum(p.state == s for p in points) for s in STATES}
    counts["done"] = counts["ok"] + counts["not_converged"]
    counts["total"] = len(points)
    sample = results / scene / "sample.nc"
    if sample.exists():
        sample_state = "ok"
    else:
        crash = _crash(results / "logs" / scene / "prepare.log")
        sample_state = crash or "missing"
    return {
        "scene": scene,
        "counts": counts,
        "sample": sample_state,
        "reference": (results / scene / "reference.nc").exists(),
        "aggregate": (results / "hugoniot" / f"{scene}.nc").exists(),
        "points": [asdict(p) for p in points],
    }


def sweep_status(
    results: str | Path = "results", config: dict | None = None, now: float | None = None
) -> dict[str, Any]:
    """The state of a sweep: per scene of ``config`` (or, without one, per scene folder
    found under ``results`` or ``results/logs``), see ``scene_status``."""
    results = Path(results)
    if config is not None:
        scenes = {name: sc["shock"]["u_p"] for name, sc in config["scenes"].items()}
    else:
        found = [
            d
            for top in (results, results / "logs")
            for d in (top.iterdir() if top.is_dir() else [])
            if d.is_dir() and not (top == results and d.name in RESERVED)
        ]
        scenes = {
            name: None
            for name in sorted(
                {
                    d.name
                    for d in found
                    if any((d / f).exists() for f in ("sample.nc", "prepare.log"))
                }
                | {d.name for d in found if any(d.glob("up*"))}
            )
        }
    return {
        "results": str(results),
        "scenes": [scene_status(results, name, ups, now) for name, ups in scenes.items()],
    }


def _is_num(x: Any) -> bool:
    return isinstance(x, int | float) and not isinstance(x, bool)


def _dichotomy_text(d: dict[str, Any]) -> str:
    """``dichotomy k = 3, bracket [1.2, 1.4]`` (or the outcome once done)."""

    def nums(xs: Any) -> str:
        ok = isinstance(xs, list) and all(_is_num(x) for x in xs)
        return "[" + ", ".join(f"{x:.6g}" for x in xs) + "]" if ok else str(xs)

    text = f"dichotomy k = {d['k']}, "
    if d["done"]:
        text += f"done: {d['status']}"
        if _is_num(d.get("u_out")):
            text += f", u_out = {d['u_out']:.6g}"
        return text + (f" ({d['reason']})" if d.get("reason") else "")
    if d["bracket"] is None:
        return text + f"bracket not yet found, trying u_out = {nums(d['pending'])}"
    return text + f"bracket {nums(d['bracket'])}"


def _age(seconds: float) -> str:
    if seconds < 120:
        return f"{seconds:.0f} s"
    if seconds < 7200:
        return f"{seconds / 60:.0f} min"
    return f"{seconds / 3600:.1f} h"


def _one_line(text: str, limit: int = 100) -> str:
    text = " ".join(text.split())
    return text if len(text) <= limit else text[: limit - 3] + "..."


def format_table(report: dict[str, Any]) -> str:
    """The report as a human-readable table, one block per scene."""
    out = [f"results: {report['results']}"]
    if not report["scenes"]:
        out.append("no scenes found")
    for sc in report["scenes"]:
        c = sc["counts"]
        files = ", ".join(
            [
                f"sample {sc['sample'] if sc['sample'] in ('ok', 'missing') else 'failed'}",
                f"reference {'written' if sc['reference'] else 'missing'}",
                f"aggregate {'written' if sc['aggregate'] else 'missing'}",
            ]
        )
        out.append(
            f"\nscene {sc['scene']}: {c['total']} points: {c['done']} done ({c['ok']} ok, "
            f"{c['not_converged']} not converged), {c['running']} running, {c['failed']} "
            f"failed, {c['pending']} pending; {files}"
        )
        if sc["sample"] not in ("ok", "missing"):
            out.append(f"  sample: {_one_line(sc['sample'])}")
        rows = [("u_p", "state", "detail")]
        for p in sc["points"]:
            if p["state"] == "running":
                bits = []
                if p["time"] is not None:
                    bits.append(f"t = {p['time']:.4g} tau")
                if p["step"] is not None:
                    bits.append(f"step {p['step']}")
                if p["checkpoint_age_s"] is not None:
                    bits.append(f"last checkpoint {_age(p['checkpoint_age_s'])} ago")
                if p["diagnostic"]:
                    bits.append(p["diagnostic"])
                detail = ", ".join(bits)
            elif p["state"] == "failed" and p["status"] not in ("", "ok", "loaded"):
                detail = f"{p['status']}: {p['diagnostic']}"
            elif p["state"] == "pending" and p["status"] == "loaded":
                detail = "loaded; piston run not started (or before its first checkpoint)"
            else:
                detail = p["diagnostic"]
            if p.get("dichotomy"):
                detail = "; ".join(x for x in (detail, _dichotomy_text(p["dichotomy"])) if x)
            if not p["in_config"]:
                detail = ("not in config; " + detail).rstrip("; ")
            rows.append((p["tag"], p["state"], _one_line(detail)))
        w0 = max(len(r[0]) for r in rows)
        w1 = max(len(r[1]) for r in rows)
        out += [f"  {a:>{w0}}  {b:<{w1}}  {d}".rstrip() for a, b, d in rows]
    return "\n".join(out)


def run_status(
    results: str | Path = "results",
    config_path: str | Path | None = None,
    as_json: bool = False,
    stream: TextIO | None = None,
) -> int:
    """What ``python -m hugomap status`` does: print the report; return the exit status.

    ``config_path`` None: ``config/config.yaml`` if it exists, else the scenes on disk. A
    config that does not validate raises ``ConfigError``.
    """
    import sys

    stream = stream or sys.stdout
    if config_path is None and Path("config/config.yaml").exists():
        config_path = "config/config.yaml"
    config = load_config(config_path) if config_path is not None else None
    report = sweep_status(results, config)
    report["config"] = None if config_path is None else str(config_path)
    if as_json:
        stream.write(json.dumps(report, indent=2, allow_nan=False) + "\n")
    else:
        if report["config"]:
            report["results"] += f" (config {report['config']})"
        stream.write(format_table(report) + "\n")
    return 0
