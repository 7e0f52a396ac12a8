"""Config keys as text, point folder tags, a scene's points and config hashes.

The small helpers that the config validation, the campaign's expansion, the solvers'
scene checks (``md.scene_config``, ``sph.scene_config``), ``status`` and ``io.dataset`` share.
This module imports nothing of hugomap, so each of them can use it without importing
``config`` (or anything that imports ``config``).
"""

from __future__ import annotations

import hashlib
import json
import math
import re
from collections.abc import Iterable
from typing import Any

_IDENT = re.compile(r"[A-Za-z_][A-Za-z0-9_]*")
#: Integers longer than this (about 308 digits) are out of every range. Beyond about 14,000
#: bits Python cannot even print them, which would crash jsonschema's own messages, so
#: ``config`` refuses them before the schema runs.
MAX_INT_BITS = 1024


def show(value: Any, limit: int = 60) -> str:
    """``repr`` of a config value, shortened to ``limit`` characters for a one-line message."""
    if isinstance(value, int) and not isinstance(value, bool) and value.bit_length() > MAX_INT_BITS:
        return f"<integer of about {int(value.bit_length() * math.log10(2)) + 1} digits>"
    try:
        text = repr(value)
    except (ValueError, RecursionError):  # an unprintable number, a self-containing value
        text = f"<{type(value).__name__}>"
    return text if len(text) <= limit else text[: limit - 3] + "..."


def key_path(parts: Iterable[Any]) -> str:
    """A config key path as text: ``scenes.lj_liquid.shock.u_p[0]``; keys that are not
    identifiers are quoted (``scenes['a b']``); the empty path is ``(top level)``."""
    out = ""
    for p in parts:
        if isinstance(p, int) and not isinstance(p, bool):
            out += f"[{p}]"
        elif isinstance(p, str) and _IDENT.fullmatch(p):
            out += f".{p}" if out else p
        else:
            out += f"[{show(p)}]"
    return out or "(top level)"


def point_tag(u: float) -> str:
    """Folder tag of a piston velocity, ``up<tag>`` (6 significant digits: 2.0 -> '2')."""
    return f"{float(u):.6g}"


def duplicate_point_tags(base: str, u_ps: list[float]) -> list[str]:
    """Problems for piston velocities that share a point folder (``point_tag``), each
    naming its key ``<base>.shock.u_p[i]``."""
    problems, seen = [], {}
    for i, u in enumerate(u_ps):
        tag = point_tag(u)
        if tag in seen:
            problems.append(
                f"{base}.shock.u_p[{i}] = {u}: same point folder up{tag} as "
                f"shock.u_p[{seen[tag]}] = {u_ps[seen[tag]]}; piston velocities must "
                "differ in their first 6 significant digits"
            )
        seen.setdefault(tag, i)
    return problems


#: A slab narrower than this many profile bins is not measured in a sample
#: (``analysis.shock``); the scene checks size the window's room ahead of the front by it.
MIN_SLAB_BINS = 3


def window_ahead_room(
    base: str, window: dict, shock: dict, unit: str, slab: tuple[str, str, float] | None = None
) -> list[str]:
    """A problem if a window (``window.length`` L, ``window.front_fraction`` f) leaves less
    than 2 g_a + a slab ahead of the front, g_a = ``shock.ahead_gap`` (default
    ``shock.gap``; the slab ahead keeps it from the front and from x_hi alike): no slab
    ahead could be measured, so a
    point could never see the state its jump starts from (``analysis.causes.ahead_seen``).
    ``slab``: (what it is, its length's keys, its length) for the message and the test;
    default the narrowest slab measured, ``MIN_SLAB_BINS`` ``shock.bin_width``. ``unit``:
    the lengths' unit, for the message."""
    what, keys, length = slab or (
        "a slab",
        f"{MIN_SLAB_BINS} shock.bin_width",
        MIN_SLAB_BINS * shock["bin_width"],
    )
    L, f = window["length"], window["front_fraction"]
    ahead = shock.get("ahead_gap")
    gap, gap_key = (shock["gap"], "shock.gap") if ahead is None else (ahead, "shock.ahead_gap")
    need = 2.0 * gap + length
    if (1.0 - f) * L >= need * (1 - 1e-12):
        return []
    return [
        f"{base}.window.front_fraction = {f:g}: the window's (1 - front_fraction) x "
        f"window.length = {(1.0 - f) * L:.4g} {unit} ahead of the front must hold {what}, "
        f"2 {gap_key} + {keys} = {need:.4g} {unit}, to measure the state the jump starts "
        f"from; allowed range (0, {max(1.0 - need / L, 0.0):.4g}] (or a longer window.length)"
    ]


def room_after_loading(base: str, shock: dict, L_x: float, box: str, unit: str = "") -> list[str]:
    """A problem if the part of a particle sample left ahead of the front after loading,
    (1 − ``shock.load_fraction``) L_x, cannot hold the slab ahead and the end margin:
    ``shock.gap`` + ``shock.ahead_gap`` (2 ``shock.gap`` without it) + ``shock.rear_margin``.
    ``box``: the sample's keys, for the message; ``unit``: the lengths' unit ('' for none)."""
    rest = L_x * (1 - shock["load_fraction"])
    ahead = shock.get("ahead_gap")
    gaps, text = (
        (2 * shock["gap"], "2·gap") if ahead is None else (shock["gap"] + ahead, "gap + ahead_gap")
    )
    if gaps + shock["rear_margin"] < rest:
        return []
    at = f"{rest:.4g} {unit}".rstrip()
    return [
        f"{base}.shock.gap = {shock['gap']}: {text} + shock.rear_margin "
        f"(= {shock['rear_margin']}) must be shorter than the part of the sample left "
        f"after loading, (1 - shock.load_fraction) L_x = {at} with "
        f"shock.load_fraction = {shock['load_fraction']} for {box}"
    ]


def scene_points(scene: dict, top_schemes: list | None = None) -> list[tuple[str, float]]:
    """The (scheme, u_p) points a validated scene runs, scheme by scheme (the scene's
    ``schemes``, else ``top_schemes``, the config's), each at its u_p in the config's order:
    every u_p, or where ``schemes: [auto]`` chose per u_p (``scheme_at``, parallel to
    ``shock.u_p``) those it chose there."""
    ups = [float(u) for u in scene["shock"]["u_p"]]
    schemes = list(scene.get("schemes", top_schemes or ["piston"]))
    per = scene.get("scheme_at") or [schemes] * len(ups)
    return [(s, u) for s in schemes for u, here in zip(ups, per, strict=True) if s in here]


def scheme_choice_at(scene: dict, u_p: float) -> str:
    """Why ``schemes: [auto]`` chose what it did at ``u_p`` (``scheme_choice``, parallel to
    ``shock.u_p``); "" where the scene's schemes were named."""
    why = scene.get("scheme_choice")
    if not why:
        return ""
    ups = [float(u) for u in scene["shock"]["u_p"]]
    k = min(range(len(ups)), key=lambda i: abs(ups[i] - float(u_p)))
    return str(why[k])


def config_hash(obj: Any) -> str:
    """SHA-256 (first 16 hex digits) of the canonical JSON of ``obj``."""
    return hashlib.sha256(json.dumps(obj, sort_keys=True).encode()).hexdigest()[:16]
