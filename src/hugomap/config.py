"""Configuration: JSON-Schema validation with defaults, cross-key checks, clear messages.

A bad config is refused before any job starts: ``validate_config`` collects every problem and
raises one ``ConfigError`` whose lines name the key (as a dotted path), the value and the
allowed range. The schema (``workflow/schemas/config.schema.json``, draft 2020-12) holds the
per-key ranges and the constant defaults; each solver's scene config (``md.scene_config``,
``sph.scene_config``) resolves the defaults that follow from other keys (CSPH: multiples of
dx) and holds the checks that involve several keys (a bin wider than the box, a cutoff longer
than half the transverse box, two piston velocities that would share one point folder).
Defaults are filled here and nowhere else: after ``validate_config`` every scene is complete,
except the CSPH times that depend on the point's u_p, which stay null (derived per point; the
schema says how).

Whatever the input (YAML allows NaN, ±inf, non-string keys, dates, self-containing anchors),
the only exception is ``ConfigError``: NaN and ±inf are not numbers here (they pass every
range comparison), keys are sorted and printed whatever their type, and every value in a
message is shortened to one line (``tests/unit/test_config_fuzz.py`` fuzzes this).
"""

from __future__ import annotations

import copy
import json
import math
import re
from pathlib import Path
from typing import Any

import jsonschema
import yaml

from . import campaign_expand, cost_laws, registry
from .keys import MAX_INT_BITS, config_hash, key_path, point_tag
from .keys import show as _show

__all__ = [
    "ConfigError",
    "config_hash",
    "key_path",
    "load_config",
    "load_schema",
    "point_tag",
    "validate_config",
]

SCHEMA_PATH = Path(__file__).resolve().parents[2] / "workflow" / "schemas" / "config.schema.json"


class ConfigError(ValueError):
    """A config that cannot run; the message lists every problem, one per line."""


def _is_number(value: Any) -> bool:
    return isinstance(value, int | float) and not isinstance(value, bool)


def _finite(value: Any) -> bool:
    """A number JSON can carry: not NaN or ±inf (which every range check lets through)."""
    return _is_number(value) and (not isinstance(value, float) or math.isfinite(value))


def _is_integer(value: Any) -> bool:
    """An int, or a float with an integral finite value (JSON Schema's ``integer``)."""
    if isinstance(value, float):
        return math.isfinite(value) and value.is_integer()
    return _is_number(value)


def _range(schema: dict) -> str:
    lo = schema.get("minimum", schema.get("exclusiveMinimum"))
    hi = schema.get("maximum", schema.get("exclusiveMaximum"))
    lb = "[" if "minimum" in schema else "("
    rb = "]" if "maximum" in schema else ")"
    return f"{lb}{'-inf' if lo is None else lo}, {'inf' if hi is None else hi}{rb}"


def _message(err: jsonschema.ValidationError) -> str:
    where = key_path(err.absolute_path)
    s = err.schema if isinstance(err.schema, dict) else {}
    v = err.validator
    shown = _show(err.instance)
    if "propertyNames" in err.absolute_schema_path:
        # The instance is a key of the object at ``where``, not a value.
        reserved = s.get("not", {}).get("enum", [])
        return (
            f"{where}: key {shown} is not allowed; names must be a letter followed by letters, "
            f"digits or _ (pattern {s.get('pattern')})"
            + (f", and not one of {reserved}" if reserved else "")
        )
    if v in ("minimum", "maximum", "exclusiveMinimum", "exclusiveMaximum"):
        desc = f" ({s['description']})" if "description" in s else ""
        return f"{where} = {shown}: out of range; allowed range {_range(s)}{desc}"
    if v == "additionalProperties":
        allowed = sorted(s.get("properties", {}))
        extra = sorted(set(err.instance) - set(allowed), key=str)
        return f"{where}: unknown key(s) {_show(extra, 200)}; allowed keys: {allowed}"
    if v in ("enum", "const"):
        allowed = s.get("enum", [s.get("const")])
        return f"{where} = {shown}: allowed values {allowed}"
    if v == "required":
        return f"{where}: {err.message}"
    if v == "type":
        nonfinite = isinstance(err.instance, float) and not math.isfinite(err.instance)
        types = s.get("type")
        if isinstance(types, list) and "null" in types:  # a time derived per point when null
            num = next((t for t in types if t != "null"), "number")
            what = "not a finite number" if nonfinite else f"must be of type {num} or null"
            return (
                f"{where} = {shown}: {what}; allowed range {_range(s)}, or null (derived per point)"
            )
        if _is_number(err.instance) and types in ("number", "integer"):
            return (
                f"{where} = {shown}: not a finite number; allowed range {_range(s)}"
                if nonfinite
                else f"{where} = {shown}: must be of type {types}; allowed range {_range(s)}"
            )
        return f"{where} = {shown}: must be of type {types}"
    if v in ("minItems", "maxItems"):
        return f"{where} = {shown}: needs {'at least' if v == 'minItems' else 'at most'} {err.validator_value} item(s)"
    if v == "minProperties":
        return f"{where} = {shown}: needs at least {err.validator_value} entry"
    if v == "uniqueItems":
        return f"{where} = {shown}: items must be distinct"
    return f"{where}: {_show(err.message, 200)}"


def _huge(value: Any) -> bool:
    return _is_number(value) and isinstance(value, int) and value.bit_length() > MAX_INT_BITS


def _huge_integers(cfg: Any) -> list[str]:
    """Paths of integers too long to print or compare sensibly (walked without recursion;
    shared or self-containing YAML anchors are visited once)."""
    out, seen, todo = [], set(), [((), cfg)]
    while todo:
        where, node = todo.pop()
        if isinstance(node, dict | list):
            if id(node) in seen:
                continue
            seen.add(id(node))
            items = node.items() if isinstance(node, dict) else enumerate(node)
            for k, v in items:
                if _huge(k):
                    out.append(f"{key_path(where)}: key {_show(k)} is not allowed")
                else:
                    todo.append(((*where, k), v))
        elif _huge(node):
            out.append(f"{key_path(where)} = {_show(node)}: out of range")
    return sorted(out)


def _with_defaults(cls):
    validate_props = cls.VALIDATORS["properties"]

    def set_defaults(validator, properties, instance, schema):
        if isinstance(instance, dict):
            for key, sub in properties.items():
                if "default" in sub and key not in instance:
                    instance[key] = copy.deepcopy(sub["default"])
        yield from validate_props(validator, properties, instance, schema)

    # NaN and ±inf pass every minimum/maximum comparison, so they are not numbers here.
    checker = cls.TYPE_CHECKER.redefine_many(
        {"number": lambda _, x: _finite(x), "integer": lambda _, x: _is_integer(x)}
    )
    return jsonschema.validators.extend(cls, {"properties": set_defaults}, type_checker=checker)


_Validator = _with_defaults(jsonschema.Draft202012Validator)


def load_schema(path: str | Path | None = None) -> dict:
    """The config schema (from ``path`` or the repository's ``workflow/schemas``) with the
    scene schema of every registered solver (``registry.scene_schema``) as ``$defs``
    ``<solver>_scene``: a scene whose ``solver`` is one of them is validated by its schema,
    one without the key by the default solver's, and one naming no registered solver only
    by an enum of every registered solver (its one message lists them all, not the default
    solver's own value and its required keys)."""
    with open(path or SCHEMA_PATH) as fh:
        schema = json.load(fh)
    defs = schema.setdefault("$defs", {})
    default = registry.DEFAULT_SOLVER
    branch: dict = {
        # no solver key (or not an object): the default solver's schema says what is wrong
        "if": {"properties": {"solver": {"const": default}}},
        "then": {"$ref": f"#/$defs/{default}_scene"},
        "else": {"properties": {"solver": {"enum": list(registry.REGISTRY)}}},
    }
    for name in reversed(list(registry.REGISTRY)):
        defs[f"{name}_scene"] = registry.scene_schema(name)
        # the error target is every solver's: one definition, in the top-level schema; so is
        # auto, the scheme chosen from measured costs (refused where a solver has none)
        props = defs[f"{name}_scene"]["properties"]
        props["target"] = {"$ref": "#/$defs/target"}
        props["scheme_at"] = {"$ref": "#/$defs/scheme_at"}
        props["scheme_choice"] = {"$ref": "#/$defs/scheme_choice"}
        enum = props.get("schemes", {}).get("items", {}).get("enum")
        if isinstance(enum, list) and AUTO not in enum:
            enum.append(AUTO)
        if name == registry.DEFAULT_SOLVER:
            continue
        branch = {
            "if": {"type": "object", "required": ["solver"],
                   "properties": {"solver": {"const": name}}},
            "then": {"$ref": f"#/$defs/{name}_scene"},
            "else": branch,
        }  # fmt: skip
    schema["properties"]["scenes"]["additionalProperties"] = branch
    return schema


def _scene_config(solver: str):
    """The scene config module of a solver: ``resolve_defaults(scene)``, ``check(base,
    scene, cfg)``."""
    return registry.scene_config(solver)


def _scene_checks(cfg: dict, own_tol: set) -> list[str]:
    """Resolve every scene's remaining defaults (the only place they are filled: a validated
    scene is complete) and run its solver's cross-key checks; each message names every key
    it depends on. ``own_tol``: the scenes whose config gave ``shock.residual_tol``."""
    problems = []
    for name, sc in cfg.get("scenes", {}).items():
        solver = _scene_config(registry.solver_of(sc))
        solver.resolve_defaults(sc)
        problems += solver.check(f"scenes.{name}", sc, cfg)
        problems += _target(name, sc, cfg, name in own_tol)
        problems += _auto_scheme(name, sc, cfg)
    return problems


WINDOW_SCHEMES = ("amw", "mw", "dichotomy")


def _scene_schemes(sc: dict, cfg: dict) -> list:
    """The schemes a validated scene runs: its own, else the top level's (default piston)."""
    return list(sc.get("schemes", cfg.get("schemes", ["piston"])))


AUTO = "auto"
# With an error target (methods.target), shock.residual_tol defaults to this many times the
# larger relative error asked: a residual combines the errors of D, u_p, ρ, P and E, each
# near the target, and ok asks |r| ≤ 3 of its errors, so a tight target is held to a tight
# closure and a loose one is not held to a tight one.
TOL_PER_TARGET = 3.0


def _target(name: str, sc: dict, cfg: dict, own_tol: bool) -> list[str]:
    """The scene's error target (``methods.target``): the top-level ``target`` where the
    scene has none; ``shock.residual_tol`` = ``TOL_PER_TARGET`` x the larger relative error
    asked, unless the scene gives its own; refused: a target that asks for neither D nor
    P, and a budget ``cpu_s`` below one control window of a scene that runs a window (the
    backend's ``window_cpu_s``: the window's particles over ``window.window_time`` at its
    fastest kernel rate, so a budget refused could not hold one window on any machine)."""
    if "target" not in sc and cfg.get("target"):
        sc["target"] = copy.deepcopy(cfg["target"])
    t = sc.get("target")
    if not t:
        return []
    at = key_path(("scenes", name, "target"))
    asked = [float(t[q]) for q in ("D", "P") if q in t]
    if not asked:
        return [f"{at} = {_show(t)}: asks for no error; give D or P (relative standard "
                f"errors, allowed range (0, 1])"]  # fmt: skip
    if not own_tol:
        sc["shock"]["residual_tol"] = min(1.0, TOL_PER_TARGET * max(asked))
    schemes = _scene_schemes(sc, cfg)
    window_cpu = getattr(registry.backend(sc), "window_cpu_s", None)
    if "cpu_s" not in t or window_cpu is None or not set(schemes) & set(WINDOW_SCHEMES):
        return []
    one = window_cpu(sc)
    if one is not None and float(t["cpu_s"]) < one:
        return [f"{at}.cpu_s = {_show(t['cpu_s'])}: below one control window of the scene "
                f"({one:.3g} s at the fastest kernel rate: window.length, window.window_time, "
                f"shock.dt); allowed range [{one:.3g}, 1e+09] s"]  # fmt: skip
    return []


def _solver_schemes(schema: dict) -> dict[str, list[str]]:
    """The schemes each registered solver runs: the ``schemes`` enum of its scene schema
    (``$defs`` ``<solver>_scene``, joined by ``load_schema``)."""
    out = {}
    for name in registry.REGISTRY:
        sub = schema.get("$defs", {}).get(f"{name}_scene", {})
        enum = sub.get("properties", {}).get("schemes", {}).get("items", {}).get("enum")
        if isinstance(enum, list):
            out[name] = [str(e) for e in enum]
    return out


def _scheme_problems(cfg: dict, schema: dict) -> tuple[list[str], set[str]]:
    """Schemes a scene lists (its own ``schemes`` or the top-level ones it inherits) that
    its solver does not run but another does (the shock-frame schemes msst, nphug: solver
    lammps only), each message naming ``scenes.<name>.schemes`` (after the top-level
    ``schemes`` where the scene inherits them) and the solver the scheme needs; and the scenes so refused (their schema enum errors say less and are dropped)."""
    runs = _solver_schemes(schema)
    scenes = cfg.get("scenes")
    top = cfg.get("schemes", ["piston"])
    problems, refused = [], set()
    if not isinstance(scenes, dict):
        return problems, refused
    for name, sc in scenes.items():
        if not isinstance(sc, dict):
            continue
        try:
            solver = registry.solver_of(sc)
        except (KeyError, TypeError):
            continue
        own = "schemes" in sc
        schemes = sc["schemes"] if own else top
        if solver not in runs or not isinstance(schemes, list):
            continue
        for scheme in schemes:
            if not isinstance(scheme, str) or scheme in runs[solver]:
                continue
            need = [n for n, allowed in runs.items() if scheme in allowed]
            if not need:
                continue
            why = (f"scheme {scheme!r} needs solver: {' or '.join(need)} (scene {name!r} has "
                   f"solver {solver!r})")  # fmt: skip
            # the key path quotes a name that is not an identifier (a control character in
            # it would otherwise break the message's lines)
            at = key_path(("scenes", name, "schemes"))
            if own:
                problems.append(f"{at} = {_show(schemes)}: {why}; allowed "
                                f"values {runs[solver]}")  # fmt: skip
            else:  # inherited: the top-level key is the one set; the scene's would override it
                problems.append(f"schemes = {_show(schemes)}, inherited as {at}:"
                                f" {why}; give {at} from {runs[solver]}")  # fmt: skip
            refused.add(str(name))
    return problems, refused


def _tree_copy(node: Any, ancestors: tuple[int, ...] = ()) -> Any:
    """A copy of ``node`` in which no dict or list appears twice (YAML aliases become
    separate copies); a value that contains itself keeps its cycle (refused later)."""
    if not isinstance(node, dict | list) or id(node) in ancestors:
        return node
    inner = (*ancestors, id(node))
    if isinstance(node, dict):
        return {k: _tree_copy(v, inner) for k, v in node.items()}
    return [_tree_copy(v, inner) for v in node]


def _unshare(cfg: dict) -> None:
    """Replace the values of ``cfg`` by unshared copies before defaults are filled in place:
    a block shared through a YAML anchor (``shock: *common`` in two scenes) would otherwise
    get the first scene's defaults (CSPH: bin_width = 2 dx of that scene) in the other too,
    and the caller's own objects would be changed."""
    try:
        for k in list(cfg):
            cfg[k] = _tree_copy(cfg[k], (id(cfg),))
    except RecursionError:  # nesting too deep to copy: validated as it is
        pass


def _auto_scheme(name: str, sc: dict, cfg: dict) -> list[str]:
    """``auto`` in the scene's schemes (its own or the top level's) becomes, at each of its
    piston velocities, the scheme of least CPU for its ``target.D`` by the measured cost
    laws (``cost_laws.choose``): the scene then lists its schemes itself (the chosen ones in
    the order of u_p, then those named beside auto), ``scheme_at`` the schemes run at each
    u_p (parallel to ``shock.u_p``; ``scene_points``) and ``scheme_choice`` why (one reason
    a u_p). Refused: auto without a ``target.D``, or for a solver the cost data has no laws
    for."""
    schemes = _scene_schemes(sc, cfg)
    if AUTO not in schemes:
        return _given_scheme_at(name, sc, schemes)
    at = key_path(("scenes", name, "schemes"))
    if "schemes" not in sc:  # inherited: name the key that was set
        at = f"schemes = {_show(schemes)}, inherited as {at}"
    else:
        at = f"{at} = {_show(schemes)}"
    solver = registry.solver_of(sc)
    laws = cost_laws.load()  # read once for the check and the choice
    have = cost_laws.solvers_with_laws(laws)
    if solver not in have:
        return [f"{at}: auto needs measured cost laws, and the cost data "
                f"({cost_laws.LAWS_FILE}) has none for solver {solver!r} (it has: "
                f"{', '.join(have) or 'none'}); name the schemes instead"]  # fmt: skip
    D = (sc.get("target") or {}).get("D")
    if D is None:
        return [f"{at}: auto chooses by the CPU to state D to "
                f"scenes.{name}.target.D, which is not given; allowed range (0, 1]"]  # fmt: skip
    named = [s for s in schemes if s != AUTO]
    picks = [cost_laws.choose(solver, float(D), float(u), laws) for u in sc["shock"]["u_p"]]
    sc["scheme_at"] = [list(dict.fromkeys([chosen, *named])) for chosen, _ in picks]
    sc["schemes"] = list(dict.fromkeys([*(chosen for chosen, _ in picks), *named]))
    sc["scheme_choice"] = [why for _, why in picks]
    return []


def _given_scheme_at(name: str, sc: dict, schemes: list) -> list[str]:
    """A ``scheme_at`` given without auto (a config resolved before, validated again, or
    one that runs fewer schemes at some u_p) must give each u_p of ``shock.u_p`` schemes of
    the scene's, and ``scheme_choice`` one reason a u_p."""
    ups = sc["shock"]["u_p"]
    problems = []
    for key in ("scheme_at", "scheme_choice"):
        given = sc.get(key)
        if given is not None and len(given) != len(ups):
            problems.append(f"{key_path(('scenes', name, key))}: {len(given)} entries for "
                            f"{len(ups)} u_p in scenes.{name}.shock.u_p; give one a u_p")  # fmt: skip
    for i, here in enumerate(sc.get("scheme_at") or []):
        stray = [s for s in here if s not in schemes]
        if stray:
            problems.append(f"{key_path(('scenes', name, 'scheme_at', i))} = {_show(here)}: "
                            f"{_show(stray)} not in the scene's schemes {_show(schemes)}")  # fmt: skip
    return problems


def _own_residual_tol(cfg: dict) -> set:
    """The scenes whose config gives ``shock.residual_tol`` (read before the schema fills
    its default: with a target, the tolerance follows the target unless given)."""
    scenes = cfg.get("scenes")
    if not isinstance(scenes, dict):
        return set()
    return {n for n, sc in scenes.items()
            if isinstance(sc, dict) and isinstance(sc.get("shock"), dict)
            and "residual_tol" in sc["shock"]}  # fmt: skip


def validate_config(cfg: Any, schema: dict | None = None) -> dict:
    """Validate ``cfg`` in place (filling defaults) and return it; raise ConfigError. The
    values of ``cfg`` are replaced by unshared copies first (``_unshare``).

    Anything that is not a valid config (wrong types, NaN, unknown keys, non-string keys,
    self-containing YAML anchors) is refused with a ConfigError naming the key path; no
    other exception escapes.
    """
    problems = _huge_integers(cfg)
    generated: list = []
    own_tol: set = set()
    if isinstance(cfg, dict):
        _unshare(cfg)
        if not problems:
            try:
                # the campaign's variants become scenes
                generated = campaign_expand.expand_campaign(cfg)
            except campaign_expand.CampaignError as exc:
                raise ConfigError(f"invalid config:\n  {exc}") from None
            except RecursionError:
                raise ConfigError(
                    "invalid config:\n  campaign: nested too deeply (a recursive YAML anchor?)"
                ) from None
            own_tol = _own_residual_tol(cfg)
    if not problems:
        schema = schema or load_schema()
        try:
            errors = sorted(
                _Validator(schema).iter_errors(cfg),
                key=lambda e: [(isinstance(p, str), str(p)) for p in e.absolute_path],
            )
        except RecursionError:
            raise ConfigError(
                "invalid config:\n  (top level): a value contains itself (recursive YAML anchor)"
            ) from None
        problems, refused = _scheme_problems(cfg, schema) if isinstance(cfg, dict) else ([], set())
        problems += [
            _message(e)
            for e in errors
            if not (
                len(e.absolute_path) >= 3
                and list(e.absolute_path)[0] == "scenes"
                and str(list(e.absolute_path)[1]) in refused
                and list(e.absolute_path)[2] == "schemes"
                and e.validator == "enum"
            )
        ]
    if not problems:
        problems = _scene_checks(cfg, own_tol)
    if problems:
        for v in generated:  # say where a generated scene's problem comes from
            problems = [
                f"{m} [scene made by campaign.cases.{v.case}, {v.study} {v.label}]"
                if re.match(rf"scenes\.{v.scene}(?![A-Za-z0-9_])", m)
                else m
                for m in problems
            ]
        raise ConfigError("invalid config:\n  " + "\n  ".join(problems))
    return cfg


def load_config(path: str | Path) -> dict:
    """Read a YAML config and validate it; an unreadable file or invalid YAML is a
    ConfigError that names the file (and the line, where YAML gives one)."""
    try:
        with open(path) as fh:
            cfg = yaml.safe_load(fh)
    except OSError as exc:
        raise ConfigError(f"invalid config: {path}: cannot read: {exc.strerror or exc}") from None
    except yaml.MarkedYAMLError as exc:
        mark = exc.problem_mark
        where = f" (line {mark.line + 1}, column {mark.column + 1})" if mark else ""
        raise ConfigError(
            f"invalid config: {path}: not valid YAML{where}: {exc.problem or exc}"
        ) from None
    except (yaml.YAMLError, ValueError, UnicodeDecodeError, RecursionError) as exc:
        # e.g. a date like 2020-13-45, an integer too long to convert, nesting too deep
        reason = " ".join(str(exc).split())[:200] or type(exc).__name__
        raise ConfigError(f"invalid config: {path}: not valid YAML: {reason}") from None
    return validate_config({} if cfg is None else cfg)
