"""The validation campaign's expansion: its variants of a few base scenes, as scenes.

A config's ``campaign`` block names *cases* (a base scene each) and, per case,

- ``resolutions``: named sets of overrides (dotted keys, ``window.length: 30.0``) — each
  becomes the scene ``<case>__<name>`` that runs the base's schemes at its piston velocities;
- ``stability`` (optional): the map of where each scheme converges. Its strength axis is the
  resolution variant it names (``resolution``): every scheme at every u_p of that scene.
  Each further ``axes.<axis>`` sets one or more keys to a list of values (the first key's
  value is the axis coordinate), each value becoming the scene ``<case>__<axis><i>`` that
  runs the axis's ``schemes`` at ``stability.u_p`` (default: the base variant's).

``expand_campaign`` turns the block into ordinary scenes before the config is validated
(``config.validate_config`` calls it), so the workflow runs them with its usual rules. Plain
dicts only: this module imports nothing of hugomap but ``keys``, and ``config`` can import
it. The
dataset the campaign's results make is ``hugomap.campaign``.
"""

from __future__ import annotations

import copy
import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

from .keys import key_path, show

SEP = "__"  # <case>__<variant>: reserved in scene names of a config with a campaign
DEFAULT_NAME = "validation"


@dataclass(frozen=True)
class Variant:
    """One scene of the campaign: which case, study and setting it is."""

    scene: str  # the generated scene name
    case: str
    study: str  # "resolution" or "stability"
    label: str  # the resolution's name, or the axis name and value index
    axis: str = ""  # stability: the axis name ("" for the strength axis / resolutions)
    keys: tuple[str, ...] = ()  # the dotted keys the axis sets
    value: float = math.nan  # the axis coordinate: the first key's value
    overrides: dict = field(default_factory=dict, compare=False, hash=False)


class CampaignError(ValueError):
    """A campaign block that cannot be expanded: one problem a line, each naming the key
    (``config.validate_config`` refuses the config with these lines)."""


def _name(x: Any) -> str:
    """A key as text in a message: as it is if printable, else its repr (a key with a line
    break would split the one-line message)."""
    return x if isinstance(x, str) and x.isprintable() and x else show(x)


def _set(scene: dict, dotted: str, value: Any, where: str) -> None:
    """scene[a][b][c] = value for ``a.b.c`` (creating the blocks on the way)."""
    parts = dotted.split(".")
    if not all(parts):
        raise CampaignError(f"{where}: key {dotted!r} is not a dotted key like window.length")
    node = scene
    for i, p in enumerate(parts[:-1]):
        nxt = node.setdefault(p, {})
        if not isinstance(nxt, dict):
            block = ".".join(parts[: i + 1])
            raise CampaignError(
                f"{where}: key {dotted!r} cannot be set: the base scene's {_name(block)} is not a "
                "block of keys"
            )
        node = nxt
    node[parts[-1]] = copy.deepcopy(value)


def get_dotted(scene: Mapping, dotted: str) -> Any:
    """scene[a][b][c] for ``a.b.c``; None where a block or the key is missing."""
    node: Any = scene
    for p in dotted.split("."):
        if not isinstance(node, Mapping) or p not in node:
            return None
        node = node[p]
    return node


def as_number(x: Any) -> float:
    """A key's value as one number (the axis coordinate): a number, the product of a list
    of numbers (cells [80, 4, 4]: the count), else NaN; ±inf beyond the float range."""
    if isinstance(x, bool):
        return math.nan
    if isinstance(x, list | tuple) and x and all(isinstance(v, int | float) for v in x):
        x = math.prod(x)
    if isinstance(x, int | float):
        try:
            return float(x)
        except OverflowError:  # an integer beyond the float range
            return math.inf if x > 0 else -math.inf
    return math.nan


def variants(campaign: Mapping) -> list[Variant]:
    """The campaign's scenes, in a fixed order (cases, resolutions, then stability axes).

    Raises CampaignError on a block that the schema would accept but cannot be expanded
    (an axis whose value lists differ in length, a stability resolution that is not defined).
    """
    out: list[Variant] = []
    for case, spec in campaign["cases"].items():
        where = key_path(("campaign", "cases", case))
        for label, over in spec["resolutions"].items():
            out.append(Variant(f"{case}{SEP}{label}", case, "resolution", label,
                               overrides=dict(over)))  # fmt: skip
        st = spec.get("stability")
        if not st:
            continue
        base = st["resolution"]
        if base not in spec["resolutions"]:
            raise CampaignError(
                f"{where}.stability.resolution = {base!r}: not one of the resolutions "
                f"({', '.join(_name(r) for r in spec['resolutions'])})"
            )
        for axis, ax in st.get("axes", {}).items():
            keys = tuple(ax["set"])
            lengths = {len(v) for v in ax["set"].values()}
            if len(lengths) != 1:
                raise CampaignError(
                    f"{key_path(('campaign', 'cases', case, 'stability', 'axes', axis, 'set'))}: "
                    f"the value lists of {', '.join(_name(k) for k in keys)} differ in length ({sorted(lengths)}); give one value "
                    "per key for each point of the axis"
                )
            for i in range(lengths.pop()):
                over = dict(spec["resolutions"][base])
                over.update({k: ax["set"][k][i] for k in keys})
                over["schemes"] = list(ax["schemes"])
                if "u_p" in st:
                    over["shock.u_p"] = list(st["u_p"])
                out.append(Variant(
                    f"{case}{SEP}{axis}{i + 1}", case, "stability", f"{axis}{i + 1}", axis,
                    keys, as_number(ax["set"][keys[0]][i]), over,
                ))  # fmt: skip
    return out


def expand_campaign(cfg: dict) -> list[Variant]:
    """Add the campaign's scenes to ``cfg["scenes"]`` (in place); return them.

    A block the schema will refuse anyway (not a mapping, missing keys) is left alone and
    nothing is added, so the schema's message names the key. A user scene whose name
    contains ``__`` and is not one of the campaign's is refused (the separator is the
    campaign's), and a generated scene replaces only its own earlier expansion. Raises
    CampaignError on a block that cannot be expanded.
    """
    camp = cfg.get("campaign") if isinstance(cfg, dict) else None
    if not _well_formed(camp):
        return []
    vs = variants(camp)
    scenes = cfg.setdefault("scenes", {})
    if not isinstance(scenes, dict):
        return []
    names = {v.scene for v in vs}
    clash = sorted(str(n) for n in scenes if SEP in str(n) and n not in names)
    if clash:
        raise CampaignError(
            "\n  ".join(f"{key_path(('scenes', n))}: '{SEP}' in a scene name is reserved for the "
                          "campaign's variants (<case>__<variant>)" for n in clash)
        )  # fmt: skip
    for v in vs:
        scene = copy.deepcopy(camp["cases"][v.case]["scene"])
        for k, val in v.overrides.items():
            _set(scene, k, val, _origin(camp, v, k))
        scenes[v.scene] = scene
    return vs


def _origin(camp: Mapping, v: Variant, key: str) -> str:
    """The campaign key path an override of variant ``v`` comes from (for messages)."""
    case = ("campaign", "cases", v.case)
    if v.study == "resolution":
        return key_path((*case, "resolutions", v.label))
    st = camp["cases"][v.case]["stability"]
    if key in v.keys:
        return key_path((*case, "stability", "axes", v.axis, "set"))
    if key == "shock.u_p" and "u_p" in st:
        return key_path((*case, "stability", "u_p"))
    if key == "schemes":
        return key_path((*case, "stability", "axes", v.axis, "schemes"))
    return key_path((*case, "resolutions", st["resolution"]))


def _well_formed(camp: Any) -> bool:
    """Whether the block has the shape ``variants`` walks (the schema checks the rest)."""
    if not isinstance(camp, dict) or not isinstance(camp.get("cases"), dict):
        return False
    for spec in camp["cases"].values():
        if not isinstance(spec, dict) or not isinstance(spec.get("scene"), dict):
            return False
        res = spec.get("resolutions")
        if not isinstance(res, dict) or not res:
            return False
        if not all(isinstance(o, dict) and all(isinstance(k, str) for k in o)
                   for o in res.values()):  # fmt: skip
            return False
        st = spec.get("stability")
        if st is None:
            continue
        if not isinstance(st, dict) or not isinstance(st.get("resolution"), str):
            return False
        if "u_p" in st and not isinstance(st["u_p"], list):
            return False
        axes = st.get("axes", {})
        if not isinstance(axes, dict):
            return False
        for ax in axes.values():
            if not (isinstance(ax, dict) and isinstance(ax.get("set"), dict) and ax["set"]
                    and isinstance(ax.get("schemes"), list)
                    and all(isinstance(k, str) and isinstance(v, list) and v
                            for k, v in ax["set"].items())):  # fmt: skip
                return False
    return True


def campaign_name(cfg: Mapping) -> str:
    """The campaign's name (its files: ``results/campaign/<name>.nc``, ``…_*.png``)."""
    return str(cfg.get("campaign", {}).get("name", DEFAULT_NAME))
