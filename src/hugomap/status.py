"""How far a sweep has got: ``python -m hugomap status``.

Reads the results folder that the workflow writes (see ``workflow/rules``) and never the
Snakemake state, so it works while a sweep runs, after it was killed, or on a copy:

    results/<scene>/sample.nc                      prepared sample
    results/<scene>/up<u>/loaded.nc                loading checkpoint (attr ``status``)
    results/<scene>/up<u>/piston.nc                a point (variable ``status``, ``diagnostic``)
    results/<scene>/up<u>/piston.nc.part.nc        periodic checkpoint of a running piston point
    results/<scene>/up<u>/window.nc                window checkpoint (attr ``status``)
    results/<scene>/up<u>/{amw,mw,dichotomy}.nc    window points (as piston.nc)
    results/<scene>/up<u>/{msst,nphug}.nc          shock-frame points, from sample.nc alone
    results/<scene>/up<u>/dichotomy/state<k>.json  the dichotomy's loop state, iteration k
    results/<scene>/reference.nc                   reference Hugoniot
    results/hugoniot/<scene>.nc                    the scene's aggregate
    results/logs/<scene>/up<u>/<stage>.log         job logs (a Python traceback = a crash)

One line per piston velocity and scheme of the config (top-level ``schemes``, or the scene's
own ``scenes.<s>.schemes``), in one state: ``ok``, ``target_not_reached`` or ``not_converged`` (done: ``failures.MEASURED``), ``failed`` (the
solver stopped with a status, a stage it depends on failed, the job crashed, or a file is
unreadable), ``running``, or ``pending`` (nothing yet, or only the checkpoints it starts
from). Running means: the piston has a periodic checkpoint and no final file (its simulated
time and the age of the checkpoint are shown: an old checkpoint means the job was killed and
will resume from it); an AMW/MW run has a job log newer than the window checkpoint; a
dichotomy has loop states (its latest iteration and bracket are shown, from the JSON object
with ``k``, ``bracket``, ``pending``, ``done``, ``status``; a loop that ended without a root
is failed with its ``reason``); a shock-frame point (msst, nphug) has a job log newer than the
sample. Points and schemes found on disk but not in the config are
listed too, marked as such.
"""

from __future__ import annotations

import json
import math
import time
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any, TextIO

import xarray as xr

from .config import load_config
from .failures import MEASURED
from .keys import point_tag, scene_points
from .methods.target import ErrorTarget

DONE_STATES = MEASURED
STATES = (*MEASURED, "failed", "running", "pending")
RESERVED = ("hugoniot", "figures", "logs", "campaign", "references")
PART_SUFFIX = ".part.nc"
SCHEMES = ("piston", "amw", "mw", "dichotomy", "msst", "nphug")  # every scheme the workflow knows
WINDOW_SCHEMES = ("amw", "mw", "dichotomy")  # those that start from the window checkpoint
SHOCK_FRAME_SCHEMES = ("msst", "nphug")  # those that start from the sample (solver lammps)


@dataclass
class PointStatus:
    """The state of one point: one scheme at one piston velocity of one scene."""

    u_p: float
    tag: str
    state: str
    scheme: str = "piston"
    status: str = ""
    diagnostic: str = ""
    time: float | None = None
    step: int | None = None
    checkpoint_age_s: float | None = None
    log_age_s: float | None = None
    in_config: bool = True
    dichotomy: dict[str, Any] | None = None
    accuracy: str = ""


def _open_status(path: Path) -> tuple[str, str, dict[str, Any]]:
    """``status``, ``diagnostic`` (variables, else attributes) and the attributes of a file
    (with ``accuracy``, a point's: ``_accuracy``)."""
    with xr.open_dataset(path, engine="netcdf4", decode_times=False) as ds:
        out = []
        for key in ("status", "diagnostic"):
            if key in ds.variables:
                out.append(str(ds[key].values))
            else:
                out.append(str(ds.attrs.get(key, "")))
        return out[0], out[1], {**ds.attrs, "accuracy": _accuracy(ds)}


def _accuracy(ds: xr.Dataset) -> str:
    """The accuracy a point bought: 'D ± 0.31 %, P ± 0.52 % (target D 1 %, P 2 %)' from its
    stated errors (D_err/D, P_err/|P − P0|), and a piston's second run on a longer sample
    (``sample_factor``); empty for a file without them."""

    def num(k: str) -> float:
        return float(ds[k].values) if k in ds.variables and ds[k].ndim == 0 else math.nan

    P0 = num("P0")
    values = {k: num(k) for k in ("D", "D_err", "P", "P_err")}
    rel = ErrorTarget.relative_errors(values, P0 if math.isfinite(P0) else 0.0)
    got = [f"{q} ± {100 * v:.2g} %" for q, v in rel.items() if math.isfinite(v)]
    want = [f"{q} {100 * num('target_' + q):g} %" for q in rel if math.isfinite(num("target_" + q))]
    grown = num("sample_factor")  # a piston run again on a longer sample (stages.piston)
    if grown > 1.0:
        want.append(f"second run, on a sample {grown:.2g} × as long")
    return ", ".join(got) + (f" (target {', '.join(want)})" if got and want else "")


DICHOTOMY_KEYS = {"k", "bracket", "pending", "done", "status"}


def dichotomy_progress(folder: Path) -> dict[str, Any] | None:
    """The latest dichotomy loop state (``methods.dichotomy``: a JSON object with k, bracket,
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


def _seconds_since(path: Path, now: float | None) -> float:
    """Seconds since ``path`` was last written (never negative)."""
    return max((time.time() if now is None else now) - path.stat().st_mtime, 0.0)


def _final(final: Path, p: PointStatus) -> bool:
    """Fill ``p`` from a point file if there is one (done, or failed); True if there was."""
    if not final.exists():
        return False
    try:
        p.status, p.diagnostic, attrs = _open_status(final)
        p.accuracy = str(attrs.get("accuracy", ""))
    except Exception as exc:  # any unreadable file is reported, not raised
        p.state, p.diagnostic = "failed", f"unreadable {final.name}: {exc}"
        return True
    p.state = p.status if p.status in DONE_STATES else "failed"
    return True


def point_status(
    results: str | Path, scene: str, u_p: float, now: float | None = None, scheme: str = "piston"
) -> PointStatus:
    """The state of ``scheme``'s point of ``scene`` at piston velocity ``u_p`` under
    ``results`` (``now``: the time the ages of checkpoints and logs are counted to)."""
    if scheme not in SCHEMES:
        raise ValueError(f"unknown scheme {scheme!r}; known: {', '.join(SCHEMES)}")
    results = Path(results)
    tag = point_tag(u_p)
    folder = results / scene / f"up{tag}"
    logs = results / "logs" / scene / f"up{tag}"
    p = PointStatus(u_p=float(u_p), tag=tag, state="pending", scheme=scheme)
    if scheme == "piston":
        return _piston(folder, logs, p, now)
    if scheme in SHOCK_FRAME_SCHEMES:
        return _shock_frame(results / scene / "sample.nc", folder, logs, p, now)
    if scheme == "dichotomy":
        p.dichotomy = dichotomy_progress(folder)
    if _final(folder / f"{scheme}.nc", p) or not _window_ok(folder, logs, p):
        return p
    if scheme == "dichotomy":
        return _dichotomy(folder, logs, p, now)
    log = logs / f"{scheme}.log"
    crash = _crash(log)
    if crash:
        p.state, p.diagnostic = "failed", crash
    elif log.exists() and log.stat().st_mtime >= (folder / "window.nc").stat().st_mtime:
        p.state, p.log_age_s = "running", _seconds_since(log, now)
    return p


def _shock_frame(
    sample: Path, folder: Path, logs: Path, p: PointStatus, now: float | None
) -> PointStatus:
    """A shock-frame point (msst, nphug): done, crashed, or running (a job log newer than the
    sample it starts from); else pending."""
    if _final(folder / f"{p.scheme}.nc", p):
        return p
    log = logs / f"{p.scheme}.log"
    crash = _crash(log)
    if crash:
        p.state, p.diagnostic = "failed", crash
    elif log.exists() and sample.exists() and log.stat().st_mtime >= sample.stat().st_mtime:
        p.state, p.log_age_s = "running", _seconds_since(log, now)
    return p


def _loaded_ok(folder: Path, logs: Path, p: PointStatus, next_log: str) -> bool:
    """Whether the loading checkpoint is there and ok; else ``p`` says why not (pending, or
    failed: the stage failed, its file is unreadable, or the load job or the ``next_log`` job
    that reads the checkpoint crashed)."""
    loaded = folder / "loaded.nc"
    if loaded.exists():
        try:
            p.status, p.diagnostic, _ = _open_status(loaded)
        except Exception as exc:
            p.state, p.diagnostic = "failed", f"unreadable {loaded.name}: {exc}"
            return False
        if p.status not in ("", "ok"):
            p.state = "failed"
            return False
        p.status = "loaded"
        crash = _crash(logs / next_log)
    else:
        crash = _crash(logs / "load.log")
    if crash:
        p.state, p.diagnostic = "failed", crash
    return loaded.exists() and not crash


def _window_ok(folder: Path, logs: Path, p: PointStatus) -> bool:
    """Whether the window checkpoint is there and ok; else ``p`` says why not."""
    window = folder / "window.nc"
    if not window.exists():
        _loaded_ok(folder, logs, p, "window.log")
        return False
    try:
        status, diagnostic, _ = _open_status(window)
    except Exception as exc:
        p.state, p.diagnostic = "failed", f"unreadable {window.name}: {exc}"
        return False
    if status not in ("", "ok"):
        p.state, p.status, p.diagnostic = "failed", status, f"window stage: {diagnostic}"
        return False
    p.status = "window"
    return True


def _dichotomy(folder: Path, logs: Path, p: PointStatus, now: float | None) -> PointStatus:
    """A dichotomy whose window is ready: a crashed loop job, the loop's progress, or its
    failure (a loop that ended without a root: the state's status and reason)."""
    for log in sorted(logs.glob("dichotomy_*.log")) + [logs / "dichotomy.log"]:
        crash = _crash(log)
        if crash:
            p.state, p.diagnostic = "failed", crash
            return p
    d = p.dichotomy
    if d is None:
        return p
    if d["done"] and d["status"] != "ok":
        p.state, p.status, p.diagnostic = "failed", str(d["status"]), str(d.get("reason", ""))
        return p
    p.state = "running"
    files = [f for f in (folder / "dichotomy").glob("*.json") if f.is_file()]
    if files:
        p.checkpoint_age_s = min(_seconds_since(f, now) for f in files)
    return p


def _piston(folder: Path, logs: Path, p: PointStatus, now: float | None) -> PointStatus:
    """The piston point: done, running (periodic checkpoint), or what its loading says."""
    final = folder / "piston.nc"
    part = folder / ("piston.nc" + PART_SUFFIX)
    if _final(final, p):
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
        p.checkpoint_age_s = _seconds_since(part, now)
        return p
    _loaded_ok(folder, logs, p, "piston.log")
    return p


def _disk_schemes(results: Path, scene: str, tag: str) -> list[str]:
    """The schemes with any trace (point, checkpoint, loop state, job log) in a point folder."""
    folder = results / scene / f"up{tag}"
    logs = results / "logs" / scene / f"up{tag}"
    found = []
    for s in SCHEMES:
        traces = [folder / f"{s}.nc", logs / f"{s}.log"]
        if s == "piston":
            traces.append(folder / ("piston.nc" + PART_SUFFIX))
        if s == "dichotomy":
            traces.append(folder / "dichotomy")
            traces += list(logs.glob("dichotomy_state*.log"))
            traces += list(logs.glob("dichotomy_trial*.log"))
        if any(t.exists() for t in traces):
            found.append(s)
    return found


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


def _counts(points: list[PointStatus]) -> dict[str, int]:
    counts = {s: sum(p.state == s for p in points) for s in STATES}
    counts["done"] = sum(counts[s] for s in MEASURED)
    counts["total"] = len(points)
    return counts


def scene_status(
    results: str | Path,
    scene: str,
    u_values: list[float] | None,
    now: float | None = None,
    schemes: list[str] | None = None,
    schemes_at: dict[str, list[str]] | None = None,
) -> dict[str, Any]:
    """The state of every point of one scene, one per piston velocity and scheme
    (``u_values``, ``schemes`` from the config; None: what is found on disk, the piston
    where a point folder shows no scheme yet; ``schemes_at``: the schemes at each u_p's tag
    where ``schemes: [auto]`` chose per u_p), with counts (all points and per scheme) and
    the scene-level files."""
    results = Path(results)
    wanted = {point_tag(u): float(u) for u in (u_values or [])}
    on_disk = _disk_points(results, scene)
    points = []
    for tag, u in {**wanted, **on_disk}.items():
        here = _disk_schemes(results, scene, tag)
        want = (schemes_at or {}).get(tag, schemes)
        if want is None:
            todo = [(s, True) for s in (here or ["piston"])]
        else:
            todo = [(s, True) for s in want] + [(s, False) for s in here if s not in want]
        for s, listed in todo:
            p = point_status(results, scene, u, now, s)
            p.in_config = listed and (u_values is None or tag in wanted)
            points.append(p)
    order: dict[str, int] = {}
    for s in [*(schemes or []), *SCHEMES]:  # the config's order, then the others
        order.setdefault(s, len(order))
    points.sort(key=lambda p: (p.u_p, order[p.scheme]))
    used = sorted({p.scheme for p in points}, key=order.__getitem__)
    sample = results / scene / "sample.nc"
    if sample.exists():
        sample_state = "ok"
    else:
        crash = _crash(results / "logs" / scene / "prepare.log")
        sample_state = crash or "missing"
    return {
        "scene": scene,
        "schemes": used,
        "n_u_p": len({p.tag for p in points}),
        "chosen_per_u_p": bool(schemes_at),
        "counts": _counts(points),
        "counts_by_scheme": {s: _counts([p for p in points if p.scheme == s]) for s in used},
        "sample": sample_state,
        "reference": (results / scene / "reference.nc").exists(),
        "aggregate": (results / "hugoniot" / f"{scene}.nc").exists(),
        "points": [asdict(p) for p in points],
    }


def sweep_status(
    results: str | Path = "results", config: dict | None = None, now: float | None = None
) -> dict[str, Any]:
    """The state of a sweep: per scene of ``config`` (its piston velocities and schemes) or,
    without one, per scene folder found under ``results`` or ``results/logs``; see
    ``scene_status``."""
    results = Path(results)
    if config is not None:
        top = config.get("schemes", ["piston"])
        scenes = {
            name: (sc["shock"]["u_p"], _schemes(sc.get("schemes", top)), _chosen(sc, top))
            for name, sc in config["scenes"].items()
        }
    else:
        found = [
            d
            for top in (results, results / "logs")
            for d in (top.iterdir() if top.is_dir() else [])
            # logs/references/ holds the shared references' logs: not a scene either
            if d.is_dir() and d.name not in RESERVED
        ]
        scenes = {
            name: (None, None, None)
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
        "scenes": [
            scene_status(results, name, ups, now, schemes, at)
            for name, (ups, schemes, at) in scenes.items()
        ],
    }


def _schemes(s: Any) -> list[str] | None:
    return None if s is None else list(s)


def _chosen(sc: dict, top: list[str]) -> dict[str, list[str]] | None:
    """The schemes ``schemes: [auto]`` chose at each u_p's tag (``keys.scene_points`` of a
    scene with ``scheme_at``), or None."""
    if not sc.get("scheme_at"):
        return None
    at: dict[str, list[str]] = {}
    for s, u in scene_points(sc, top):
        at.setdefault(point_tag(u), []).append(s)
    return at


def _recorded(path: Path, key: str) -> dict | None:
    """The JSON attribute ``key`` of a netCDF file, or None (no file, no attribute, not
    readable)."""
    try:
        with xr.open_dataset(path, engine="netcdf4", decode_times=False) as ds:
            text = ds.attrs.get(key)
        return json.loads(text) if isinstance(text, str) else None
    except Exception:  # an unreadable file records nothing
        return None


def recorded_config(results: str | Path) -> tuple[dict | None, list[str]]:
    """The config the results under ``results`` were made with, and the files it was read
    from: each aggregate's ``config_json`` (``results/hugoniot/<scene>.nc``: the whole
    resolved config), and for a scene without an aggregate the ``scene_config`` of its
    prepared sample or of a file in its point folders (the scene alone: its schemes are then
    its own ``schemes``, or those found on disk). A scene's newest record wins. None (and no
    files) where nothing under ``results`` records a config."""
    results = Path(results)
    scenes: dict[str, tuple[float, dict, Any, Path]] = {}  # name: (mtime, scene, schemes, file)

    def keep(name: str, mtime: float, scene: Any, schemes: Any, path: Path) -> None:
        ok = isinstance(scene, dict) and isinstance(scene.get("shock", {}).get("u_p"), list)
        if ok and (name not in scenes or mtime > scenes[name][0]):
            scenes[name] = (mtime, scene, scene.get("schemes", schemes), path)

    for agg in sorted((results / "hugoniot").glob("*.nc")):
        cfg = _recorded(agg, "config_json")
        if isinstance(cfg, dict) and isinstance(cfg.get("scenes"), dict):
            sc = cfg["scenes"].get(agg.stem)
            keep(agg.stem, agg.stat().st_mtime, sc, cfg.get("schemes"), agg)
    for folder in sorted(results.iterdir()) if results.is_dir() else []:
        if not folder.is_dir() or folder.name in RESERVED:
            continue
        candidates = [folder / "sample.nc", *sorted(folder.glob("up*/*.nc"))]
        for f in (c for c in candidates if c.is_file()):
            sc = _recorded(f, "scene_config")
            if sc is not None:
                if folder.name not in scenes:
                    keep(folder.name, f.stat().st_mtime, sc, None, f)
                break
    if not scenes:
        return None, []
    config = {
        "scenes": {name: {**sc, "schemes": schemes} for name, (_, sc, schemes, _) in scenes.items()}
    }
    return config, sorted({str(f) for (_, _, _, f) in scenes.values()})


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


MIN_DETAIL = 20  # the narrowest detail column a cut leaves [characters]


def _one_line(text: str, limit: int | None = None) -> str:
    """``text`` on one line (whitespace runs made one space), cut to ``limit`` characters
    with a trailing ``...`` where longer; ``limit`` None: never cut."""
    text = " ".join(text.split())
    if limit is None or len(text) <= limit:
        return text
    return text[: max(limit - 3, 0)] + "..."


def _counts_text(c: dict[str, int]) -> str:
    return (
        f"{c['done']} done ({c['ok']} ok, "
        + (f"{c['target_not_reached']} target not reached, " if c["target_not_reached"] else "")
        + f"{c['not_converged']} not converged), "
        f"{c['running']} running, {c['failed']} failed, {c['pending']} pending"
    )


def _detail(p: dict[str, Any]) -> str:
    """The detail column of one point's row."""
    if p["state"] == "running":
        bits = []
        if p.get("dichotomy"):
            bits.append(_dichotomy_text(p["dichotomy"]))
        if p["time"] is not None:
            bits.append(f"t = {p['time']:.4g} tau")
        if p["step"] is not None:
            bits.append(f"step {p['step']}")
        if p["checkpoint_age_s"] is not None:
            what = "state" if p["scheme"] == "dichotomy" else "checkpoint"
            bits.append(f"last {what} {_age(p['checkpoint_age_s'])} ago")
        if p.get("log_age_s") is not None:
            bits.append(f"started, log written {_age(p['log_age_s'])} ago")
        if p["diagnostic"]:
            bits.append(p["diagnostic"])
        detail = ", ".join(bits)
    elif p["state"] == "failed" and p["status"] not in ("", "ok", "loaded", "window"):
        detail = f"{p['status']}: {p['diagnostic']}"
    elif p["state"] == "pending" and p["status"] == "loaded":
        if p["scheme"] == "piston":
            detail = "loaded; piston run not started (or before its first checkpoint)"
        else:
            detail = "loaded; window not cut yet"
    elif p["state"] == "pending" and p["status"] == "window":
        detail = f"window ready; {p['scheme']} run not started"
    else:
        detail = p["diagnostic"]
    if p["state"] in DONE_STATES and p.get("accuracy"):
        detail = "; ".join(x for x in (p["accuracy"], detail) if x)
    if p.get("dichotomy") and p["state"] != "running":
        detail = "; ".join(x for x in (detail, _dichotomy_text(p["dichotomy"])) if x)
    if not p["in_config"]:
        detail = ("not in config; " + detail).rstrip("; ")
    return detail


def format_table(report: dict[str, Any], width: int | None = None) -> str:
    """The report as a human-readable table, one block per scene: counts (all points, then
    per scheme), then one row per piston velocity and scheme.

    ``width``: the line width to fit (a terminal's columns): a row's detail column and a
    crashed sample's message are cut to what is left of it, never to fewer than
    ``MIN_DETAIL`` characters; None: nothing is cut."""
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
        schemes = sc.get("schemes") or []
        n_u = sc.get("n_u_p", c["total"])
        grid = f"{n_u} u_p x {len(schemes)} schemes"
        if sc.get("chosen_per_u_p"):  # schemes: [auto] chose per u_p
            grid = f"{n_u} u_p, schemes chosen per u_p"
        out.append(
            f"\nscene {sc['scene']}: {c['total']} points ({grid}: {', '.join(schemes)}): "
            f"{_counts_text(c)}; {files}"
        )
        if len(schemes) > 1:
            w = max(len(s) for s in schemes)
            for s in schemes:
                cs = sc["counts_by_scheme"][s]
                out.append(f"  {s + ':':<{w + 1}} {cs['total']} points: {_counts_text(cs)}")
        if sc["sample"] not in ("ok", "missing"):
            limit = None if width is None else max(width - len("  sample: "), MIN_DETAIL)
            out.append(f"  sample: {_one_line(sc['sample'], limit)}")
        rows = [("u_p", "scheme", "state", "detail")]
        rows += [(p["tag"], p["scheme"], p["state"], _detail(p)) for p in sc["points"]]
        w0, w1, w2 = (max(len(r[i]) for r in rows) for i in range(3))
        limit = None if width is None else max(width - (w0 + w1 + w2 + 8), MIN_DETAIL)
        rows = [(a, s, b, _one_line(d, limit)) for a, s, b, d in rows]
        out += [f"  {a:>{w0}}  {s:<{w1}}  {b:<{w2}}  {d}".rstrip() for a, s, b, d in rows]
    return "\n".join(out)


def run_status(
    results: str | Path | None = None,
    config_path: str | Path | None = None,
    as_json: bool = False,
    stream: TextIO | None = None,
    full: bool = False,
) -> int:
    """What ``python -m hugomap status`` does: print the report; return the exit status.

    ``results`` None: the folder ``config_path`` names (its ``results`` key), else
    ``results``. ``config_path`` None: the config the results were made with (``recorded_config``: the
    aggregates' ``config_json``, the scene files' ``scene_config``); where the results record
    none (nothing has run yet), ``config/config.yaml`` if it exists; else the scenes on
    disk. A config that does not validate raises ``ConfigError``.

    The table's detail column is cut to the terminal's width (``shutil.get_terminal_size``,
    which honours ``$COLUMNS``) only where ``stream`` is a terminal and ``full`` is False;
    written to a file or a pipe, or with ``full``, every row is whole.
    """
    import shutil
    import sys

    stream = stream or sys.stdout
    config, source = None, None
    if results is None:
        given = load_config(config_path) if config_path is not None else {}
        results = given.get("results", "results")
    if config_path is None:
        config, files = recorded_config(results)
        if config is not None:
            source = "recorded in " + ", ".join(files)
        elif Path("config/config.yaml").exists():
            config_path = "config/config.yaml"
    if config_path is not None:
        config, source = load_config(config_path), str(config_path)
    report = sweep_status(results, config)
    report["config"] = source
    if as_json:
        stream.write(json.dumps(report, indent=2, allow_nan=False) + "\n")
    else:
        if report["config"]:
            report["results"] += f" (config {report['config']})"
        tty = not full and hasattr(stream, "isatty") and stream.isatty()
        width = shutil.get_terminal_size().columns if tty else None
        stream.write(format_table(report, width) + "\n")
    return 0
