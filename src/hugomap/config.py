"""Configuration: JSON-Schema validation with defaults, cross-key checks, clear messages.

A bad config is refused before any job starts: ``validate_config`` collects every problem and
raises one ``ConfigError`` whose lines name the key (as a dotted path), the value and the
allowed range. The schema (``workflow/schemas/config.schema.json``, draft 2020-12) holds the
per-key ranges and defaults; the checks here are the ones that involve several keys (a bin
wider than the box, a cutoff longer than half the transverse box, two piston velocities that
would share one point folder).

Whatever the input (YAML allows NaN, ±inf, non-string keys, dates, self-containing anchors),
the only exception is ``ConfigError``: NaN and ±inf are not numbers here (they pass every
range comparison), keys are sorted and printed whatever their type, and every value in a
message is shortened to one line (``tests/unit/test_config_fuzz.py`` fuzzes this).
"""

from __future__ import annotations

import copy
import hashlib
import json
import math
import re
from collections.abc import Iterable
from pathlib import Path
from typing import Any

import jsonschema
import yaml

SCHEMA_PATH = Path(__file__).resolve().parents[2] / "workflow" / "schemas" / "config.schema.json"


class ConfigError(ValueError):
    """A config that cannot run; the message lists every problem, one per line."""


_IDENT = re.compile(r"[A-Za-z_][A-Za-z0-9_]*")
# Integers longer than this (about 308 digits) are out of every range. Beyond about 14,000
# bits Python cannot even print them, which would crash jsonschema's own messages, so they
# are refused before the schema runs.
_MAX_INT_BITS = 1024


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
            out += f"[{_show(p)}]"
    return out or "(top level)"


def point_tag(u: float) -> str:
    """Folder tag of a piston velocity, ``up<tag>`` (6 significant digits: 2.0 -> '2')."""
    return f"{float(u):.6g}"


def _show(value: Any, limit: int = 60) -> str:
    """``repr`` of a config value, shortened to ``limit`` characters for a one-line message."""
    if (
        isinstance(value, int)
        and not isinstance(value, bool)
        and value.bit_length() > _MAX_INT_BITS
    ):
        return f"<integer of about {int(value.bit_length() * math.log10(2)) + 1} digits>"
    try:
        text = repr(value)
    except (ValueError, RecursionError):  # an unprintable number, a self-containing value
        text = f"<{type(value).__name__}>"
    return text if len(text) <= limit else text[: limit - 3] + "..."


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
        if _is_number(err.instance) and s.get("type") in ("number", "integer"):
            return (
                f"{where} = {shown}: not a finite number; allowed range {_range(s)}"
                if isinstance(err.instance, float) and not math.isfinite(err.instance)
                else f"{where} = {shown}: must be of type {s['type']}; allowed range {_range(s)}"
            )
        return f"{where} = {shown}: must be of type {s.get('type')}"
    if v in ("minItems", "maxItems"):
        return f"{where} = {shown}: needs {'at least' if v == 'minItems' else 'at most'} {err.validator_value} item(s)"
    if v == "minProperties":
        return f"{where} = {shown}: needs at least {err.validator_value} entry"
    if v == "uniqueItems":
        return f"{where} = {shown}: items must be distinct"
    return f"{where}: {_show(err.message, 200)}"


def _huge(value: Any) -> bool:
    return _is_number(value) and isinstance(value, int) and value.bit_length() > _MAX_INT_BITS


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
    """The config schema (from ``path`` or the repository's ``workflow/schemas``)."""
    with open(path or SCHEMA_PATH) as fh:
        return json.load(fh)


def lattice_constant(rho: float) -> float:
    """FCC lattice constant a = (4/ρ)^(1/3) [σ] at number density ρ [σ⁻³]."""
    return (4.0 / rho) ** (1.0 / 3.0)


def _cross_checks(cfg: dict) -> list[str]:
    """Checks that involve several keys; each message names every key it depends on."""
    problems = []
    for name, sc in cfg.get("scenes", {}).items():
        base = f"scenes.{name}"
        if sc.get("solver") == "csph":
            problems += _csph_checks(base, sc, cfg.get("schemes", ["piston"]))
            continue
        smp, pot, sh = sc["sample"], sc["potential"], sc["shock"]
        a = lattice_constant(smp["rho0"])
        L = [c * a for c in smp["cells"]]
        rlist = pot["rc"] + pot["skin"]
        half_t = 0.5 * min(L[1], L[2])
        box = f"sample.cells = {smp['cells']} at sample.rho0 = {smp['rho0']}"
        if rlist > half_t:
            problems.append(
                f"{base}.potential.rc = {pot['rc']}: rc + skin must not exceed half the "
                f"transverse box; allowed range (1.0, {half_t - pot['skin']:.4g}] sigma "
                f"with potential.skin = {pot['skin']} for {box}"
            )
        if sh["bin_width"] >= L[0] / 4:
            problems.append(
                f"{base}.shock.bin_width = {sh['bin_width']}: wider than the box allows; "
                f"allowed range (0, {L[0] / 4:.4g}) sigma (a quarter of L_x = {L[0]:.4g} "
                f"for {box})"
            )
        rest = L[0] * (1 - sh["load_fraction"])
        if 2 * sh["gap"] + sh["rear_margin"] >= rest:
            problems.append(
                f"{base}.shock.gap = {sh['gap']}: 2·gap + shock.rear_margin "
                f"(= {sh['rear_margin']}) must be shorter than the part of the sample left "
                f"after loading, (1 - shock.load_fraction) L_x = {rest:.4g} sigma with "
                f"shock.load_fraction = {sh['load_fraction']} for {box}"
            )
        out = sc["window"]["outflow"]
        if out["tau_fast"] >= out["tau_slow"]:
            problems.append(
                f"{base}.window.outflow.tau_fast = {out['tau_fast']}: must be shorter than "
                f"window.outflow.tau_slow = {out['tau_slow']}; allowed range (0, "
                f"{out['tau_slow']:.4g}) tau"
            )
        seen: dict[str, int] = {}
        for i, u in enumerate(sh["u_p"]):
            tag = point_tag(u)
            if tag in seen:
                problems.append(
                    f"{base}.shock.u_p[{i}] = {u}: same point folder up{tag} as "
                    f"shock.u_p[{seen[tag]}] = {sh['u_p'][seen[tag]]}; piston velocities "
                    f"must differ in their first 6 significant digits"
                )
            seen.setdefault(tag, i)
        if sc["phase"] == "liquid" and "reference" in sc:
            ref = sc["reference"]
            rho_max = smp["rho0"] * max(ref["compressions"])
            Lref = ref["cells"] * lattice_constant(rho_max)
            if Lref < 2 * rlist:
                problems.append(
                    f"{base}.reference.cells = {ref['cells']}: the periodic reference box of a "
                    f"phase = liquid scene at "
                    f"the highest compression (reference.compressions max "
                    f"{max(ref['compressions'])} x sample.rho0 = {smp['rho0']}) is "
                    f"{Lref:.3g} sigma, shorter than 2 (potential.rc + potential.skin) = "
                    f"{2 * rlist:.3g}; use more cells"
                )
    return problems


# -- CSPH scenes (SI units) ---------------------------------------------------------------

#: Smallest pore radius in lattice spacings (``hugomap.sph.sample.K_RESOLUTION``).
K_RESOLUTION = 3.0
#: RSA jamming coverage of equal discs (Feder 1980; Hinrichsen, Feder & Jøssang 1986).
RSA_JAMMING = 0.547
#: Particles a CSPH sample must hold along x (front tracking, slabs, window).
MIN_COLUMNS = 40
#: Frozen inflow particles of the 1D window (``sph.window.SPHWindow.from_piston``).
WINDOW_INFLOW = 8
#: Schemes a CSPH scene runs, by dim (the windows: ``sph.window.SPHWindow``, ``SPHWindow2D``).
CSPH_SCHEMES = {1: ("piston", "amw", "mw", "dichotomy"), 2: ("piston", "amw", "mw", "dichotomy")}


def fill_csph_defaults(sc: dict) -> None:
    """Fill the CSPH defaults that scale with the lattice spacing dx [m] (idempotent):
    shock.bin_width = 2 dx, shock.gap = 10 dx, shock.avg_length = 20 dx, window.length =
    150 dx, window.cut_every = 10 dx. Time defaults that depend on u_p (window_time,
    average_time) are resolved per point by the window stages."""
    dx = sc["sample"]["dx"]
    for key, k in (("bin_width", 2.0), ("gap", 10.0), ("avg_length", 20.0)):
        sc["shock"].setdefault(key, k * dx)
    sc["window"].setdefault("length", 150.0 * dx)
    sc["window"].setdefault("cut_every", 10.0 * dx)


def _csph_checks(base: str, sc: dict, top_schemes: list) -> list[str]:
    """Cross-key checks of a CSPH scene (SI units); each message names the keys involved."""
    out: list[str] = []
    smp, sh, w = sc["sample"], sc["shock"], sc["window"]
    eos, st = sc["material"]["eos"], sc["material"]["strength"]
    num = sc["numerics"]
    dx, length, dim = smp["dx"], smp["length"], sc["dim"]
    fill_csph_defaults(sc)
    schemes = sc.get("schemes", top_schemes)
    allowed = list(CSPH_SCHEMES[dim])
    other = [s for s in schemes if s not in allowed]
    if other:
        where = f"{base}.schemes" if "schemes" in sc else "schemes"
        own = "" if "schemes" in sc else "; give the scene its own schemes"
        out.append(
            f"{where} = {_show(schemes)}: {_show(other)} not available for a solver = csph "
            f"scene with dim = {dim} ({base}); allowed: {_show(allowed)}{own}"
        )
    if st["model"] == "von_mises" and st["yield_stress"] >= st["shear_modulus"]:
        out.append(
            f"{base}.material.strength.yield_stress = {st['yield_stress']:.4g}: must be below "
            f"material.strength.shear_modulus = {st['shear_modulus']:.4g} Pa; allowed range "
            f"(0, {st['shear_modulus']:.4g}) Pa"
        )
    n_x = length / dx
    if n_x < MIN_COLUMNS:
        out.append(
            f"{base}.sample.length = {length:.4g}: holds {n_x:.3g} particles of sample.dx = "
            f"{dx:.4g} m; allowed range [{MIN_COLUMNS * dx:.4g}, 1.0] m ({MIN_COLUMNS} dx)"
        )
    if dim == 1 and ("width" in smp or "porous" in smp):
        key = "width" if "width" in smp else "porous"
        out.append(f"{base}.sample.{key}: only for dim = 2 (this scene has dim = 1)")
    if dim == 2:
        r_list = (4.0 * num["theta"] + 0.5) * dx  # neighbour-list radius, skin 0.5 l
        if "width" not in smp:
            out.append(f"{base}.sample: 'width' is a required property for dim = 2")
        elif smp["width"] < 2.0 * r_list:
            out.append(
                f"{base}.sample.width = {smp['width']:.4g}: the periodic width must be at least "
                f"twice the neighbour-list radius (4 numerics.theta + 0.5) sample.dx; allowed "
                f"range [{2.0 * r_list:.4g}, 1.0] m"
            )
    por = smp.get("porous")
    if dim == 2 and por is not None and "width" in smp:
        alpha = por["distention"]
        r = por.get("pore_radius")
        if r is None:
            out.append(f"{base}.sample.porous: 'pore_radius' is a required property")
        else:
            r_min, r_max = r
            if r_min > r_max:
                out.append(
                    f"{base}.sample.porous.pore_radius = {_show(r)}: r_min must not exceed r_max"
                )
            if r_min < K_RESOLUTION * dx * (1 - 1e-12):
                out.append(
                    f"{base}.sample.porous.pore_radius = {_show(r)}: the smallest pore is "
                    f"not resolved by sample.dx = {dx:.4g} m; allowed r_min >= "
                    f"{K_RESOLUTION:g} dx = {K_RESOLUTION * dx:.4g} m (or a smaller dx)"
                )
            if 2.0 * r_max + dx > smp["width"]:
                out.append(
                    f"{base}.sample.porous.pore_radius = {_show(r)}: a pore of r_max must fit "
                    f"across sample.width = {smp['width']:.4g} m; allowed r_max <= "
                    f"{(smp['width'] - dx) / 2:.4g} m"
                )
            # RSA with a ligament g = dx jams at coverage 0.547 (r/(r + g/2))^2 (sample.py);
            # the solid end layers (4 dx each) lower the reachable mean porosity further.
            core = max(length - 8.0 * dx, 0.0) / length
            phi_max = RSA_JAMMING * (r_max / (r_max + 0.5 * dx)) ** 2 * core
            phi = 1.0 - 1.0 / alpha
            if phi > phi_max:
                out.append(
                    f"{base}.sample.porous.distention = {alpha:g}: porosity {phi:.3f} cannot be "
                    f"packed with pore_radius max {r_max:.4g} m at sample.dx = {dx:.4g} m "
                    f"(random sequential addition jams near porosity {phi_max:.3f}); allowed "
                    f"range [1, {1.0 / (1.0 - phi_max):.4g})"
                )
    if sh["end_fraction"] <= sh["load_fraction"]:
        out.append(
            f"{base}.shock.end_fraction = {sh['end_fraction']:g}: must exceed "
            f"shock.load_fraction = {sh['load_fraction']:g}; allowed range "
            f"({sh['load_fraction']:g}, 1)"
        )
    behind = sh["load_fraction"] * length
    need = sh["avg_length"] + 2.0 * sh["gap"]
    if need >= behind:
        out.append(
            f"{base}.shock.avg_length = {sh['avg_length']:.4g}: avg_length + 2 shock.gap "
            f"(= {need:.4g} m) must be shorter than the length the front has crossed at the "
            f"end of loading, shock.load_fraction x sample.length = {behind:.4g} m"
        )
    if sh["bin_width"] > 0.25 * sh["avg_length"]:
        out.append(
            f"{base}.shock.bin_width = {sh['bin_width']:.4g}: at most a quarter of "
            f"shock.avg_length = {sh['avg_length']:.4g} m"
        )
    windowed = [s for s in schemes if s != "piston"]
    if "tile_length" in w and dim != 2:
        out.append(f"{base}.window.tile_length: only for dim = 2 (this scene has dim = {dim})")
    if "dichotomy" in windowed:
        d = w["dichotomy"]
        if d["tolerance"] >= 2.0 * d["half_width"]:
            out.append(
                f"{base}.window.dichotomy.tolerance = {d['tolerance']:g}: must be below the "
                f"initial bracket width 2 window.dichotomy.half_width = "
                f"{2.0 * d['half_width']:g} m/s; allowed range (0, {2.0 * d['half_width']:g}) m/s"
            )
    if windowed:
        Lw, ff = w["length"], w["front_fraction"]
        u_max = max(sh["u_p"])
        D = eos["c0"] + eos["s"] * u_max
        if dim == 2 and por is not None and por["distention"] > 1.0:
            # porous: the snowplow speed u α/(α − 1) (full compaction to the solid density; a
            # compaction left incomplete runs faster, so the room is not overestimated)
            a = por["distention"]
            D = min(D, u_max * a / (a - 1.0))
        room_behind = behind * (1.0 - u_max / D)
        room_ahead = (1.0 - sh["load_fraction"]) * length - WINDOW_INFLOW * dx
        if ff * Lw > room_behind or (1.0 - ff) * Lw > room_ahead:
            out.append(
                f"{base}.window.length = {Lw:.4g}: a window with window.front_fraction = {ff:g} "
                f"does not fit around the front at the end of loading (room {room_behind:.4g} m "
                f"behind it at u_p = {u_max:g} m/s, {room_ahead:.4g} m ahead); shorten it or "
                "lengthen sample.length"
            )
        gap_out = w.get("outflow_gap", sh["gap"])
        slab = sh["gap"] + gap_out + sh["avg_length"]
        parts = "shock.gap + window.outflow_gap + " if "outflow_gap" in w else "2 shock.gap + "
        parts += "shock.avg_length"
        if ff * Lw < slab * (1 - 1e-12):
            out.append(
                f"{base}.window.front_fraction = {ff:g}: the front starts {ff * Lw:.4g} m from "
                f"the outflow edge of window.length = {Lw:.4g} m, less than the averaged slab "
                f"behind it needs, {parts} = {slab:.4g} m; allowed range "
                f"[{slab / Lw:.4g}, 0.8] (or a longer window)"
            )
        if dim == 2:
            lt = w.get("tile_length") or (1.0 - ff) * Lw
            key = (
                "window.tile_length"
                if "tile_length" in w
                else ("window.tile_length (default (1 - window.front_fraction) window.length)")
            )
            need = (WINDOW_INFLOW + 1) * dx
            if por is not None and por.get("pore_radius"):
                # a pore must clear its own image along x, as along y
                need = max(need, 2.0 * por["pore_radius"][1] + dx)
            if lt < need * (1 - 1e-12):
                out.append(
                    f"{base}.{key} = {lt:.4g}: the periodic inflow tile must hold the frozen "
                    f"inflow layer ({WINDOW_INFLOW + 1} dx) and, if porous, a pore of r_max "
                    f"with a ligament to its own image (2 r_max + sample.dx); allowed range "
                    f"[{need:.4g}, 1.0] m"
                )
    return out


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


def validate_config(cfg: Any, schema: dict | None = None) -> dict:
    """Validate ``cfg`` in place (filling defaults) and return it; raise ConfigError. The
    values of ``cfg`` are replaced by unshared copies first (``_unshare``).

    Anything that is not a valid config (wrong types, NaN, unknown keys, non-string keys,
    self-containing YAML anchors) is refused with a ConfigError naming the key path; no
    other exception escapes.
    """
    problems = _huge_integers(cfg)
    generated: list = []
    if isinstance(cfg, dict):
        _unshare(cfg)
        if not problems:
            from .campaign import expand_campaign

            try:
                generated = expand_campaign(cfg)  # the campaign's variants become scenes
            except RecursionError:
                raise ConfigError(
                    "invalid config:\n  campaign: nested too deeply (a recursive YAML anchor?)"
                ) from None
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
        problems = [_message(e) for e in errors]
    if not problems:
        problems = _cross_checks(cfg)
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


def config_hash(obj: Any) -> str:
    """SHA-256 (first 16 hex digits) of the canonical JSON of ``obj``."""
    return hashlib.sha256(json.dumps(obj, sort_keys=True).encode()).hexdigest()[:16]


def reference_inputs(scene: dict) -> dict | None:
    """What an MD scene's equilibrium reference Hugoniot depends on (``pipeline.reference_stage``
    reads nothing else): the potential block, the pole (``sample.rho0`` [σ⁻³], ``sample.T0``
    [ε/k_B]), the sample's seed and the ``reference`` block. Scenes that agree on these share
    one computation, ``results/references/<reference_key>.nc``, so a campaign's variants of
    one scene (or a changed window setting) do not recompute it. None for a CSPH scene: its
    reference is the material model's own Hugoniot, computed per scene in milliseconds."""
    if scene.get("solver") == "csph":
        return None
    s = scene["sample"]
    return {
        "solver": "md",
        "potential": dict(scene.get("potential", {})),
        "sample": {"rho0": s["rho0"], "T0": s["T0"], "seed": s["seed"]},
        "reference": dict(scene["reference"]),
    }


def reference_key(scene: dict) -> str | None:
    """The shared reference's file stem: ``lj_`` and the first 12 hex digits of
    ``config_hash(reference_inputs(scene))``; None for a CSPH scene."""
    inputs = reference_inputs(scene)
    if inputs is None:
        return None
    return "lj_" + config_hash(inputs)[:12]
