"""Configuration: JSON-Schema validation with defaults, cross-key checks, clear messages.

A bad config is refused before any job starts: ``validate_config`` collects every problem and
raises one ``ConfigError`` whose lines name the key (as a dotted path), the value and the
allowed range. The schema (``workflow/schemas/config.schema.json``, draft 2020-12) holds the
per-key ranges and defaults; the checks here are the ones that involve several keys (a bin
wider than the box, a cutoff longer than half the transverse box).
"""

from __future__ import annotations

import copy
import hashlib
import json
from pathlib import Path
from typing import Any

import jsonschema
import yaml

SCHEMA_PATH = Path(__file__).resolve().parents[2] / "workflow" / "schemas" / "config.schema.json"


class ConfigError(ValueError):
    """A config that cannot run; the message lists every problem, one per line."""


def _path(parts) -> str:
    out = ""
    for p in parts:
        out += f"[{p}]" if isinstance(p, int) else (f".{p}" if out else str(p))
    return out or "(top level)"


def _range(schema: dict) -> str:
    lo = schema.get("minimum", schema.get("exclusiveMinimum"))
    hi = schema.get("maximum", schema.get("exclusiveMaximum"))
    lb = "[" if "minimum" in schema else "("
    rb = "]" if "maximum" in schema else ")"
    return f"{lb}{'-inf' if lo is None else lo}, {'inf' if hi is None else hi}{rb}"


def _message(err: jsonschema.ValidationError) -> str:
    where = _path(err.absolute_path)
    s = err.schema if isinstance(err.schema, dict) else {}
    v = err.validator
    if v in ("minimum", "maximum", "exclusiveMinimum", "exclusiveMaximum"):
        desc = f" ({s['description']})" if "description" in s else ""
        return f"{where} = {err.instance!r}: out of range; allowed range {_range(s)}{desc}"
    if v == "additionalProperties":
        allowed = sorted(s.get("properties", {}))
        extra = sorted(set(err.instance) - set(allowed))
        return f"{where}: unknown key(s) {extra}; allowed keys: {allowed}"
    if v in ("enum", "const"):
        allowed = s.get("enum", [s.get("const")])
        return f"{where} = {err.instance!r}: allowed values {allowed}"
    if v == "required":
        return f"{where}: {err.message}"
    if v == "type":
        return f"{where} = {err.instance!r}: must be of type {s.get('type')}"
    return f"{where}: {err.message}"


def _with_defaults(cls):
    validate_props = cls.VALIDATORS["properties"]

    def set_defaults(validator, properties, instance, schema):
        if isinstance(instance, dict):
            for key, sub in properties.items():
                if "default" in sub and key not in instance:
                    instance[key] = copy.deepcopy(sub["default"])
        yield from validate_props(validator, properties, instance, schema)

    return jsonschema.validators.extend(cls, {"properties": set_defaults})


_Validator = _with_defaults(jsonschema.Draft202012Validator)


def load_schema(path: str | Path | None = None) -> dict:
    """The config schema (from ``path`` or the repository's ``workflow/schemas``)."""
    with open(path or SCHEMA_PATH) as fh:
        return json.load(fh)


def lattice_constant(rho: float) -> float:
    """FCC lattice constant a = (4/ρ)^(1/3) [σ] at number density ρ [σ⁻³]."""
    return (4.0 / rho) ** (1.0 / 3.0)


def _cross_checks(cfg: dict) -> list[str]:
    problems = []
    for name, sc in cfg.get("scenes", {}).items():
        base = f"scenes.{name}"
        a = lattice_constant(sc["sample"]["rho0"])
        L = [c * a for c in sc["sample"]["cells"]]
        pot = sc["potential"]
        rlist = pot["rc"] + pot["skin"]
        half_t = 0.5 * min(L[1], L[2])
        if rlist > half_t:
            problems.append(
                f"{base}.potential.rc = {pot['rc']}: rc + skin must not exceed half the "
                f"transverse box; allowed range (1.0, {half_t - pot['skin']:.4g}] sigma "
                f"for sample.cells = {sc['sample']['cells']} at rho0 = {sc['sample']['rho0']}"
            )
        sh = sc["shock"]
        if sh["bin_width"] >= L[0] / 4:
            problems.append(
                f"{base}.shock.bin_width = {sh['bin_width']}: wider than the box allows; "
                f"allowed range (0, {L[0] / 4:.4g}) sigma (a quarter of L_x = {L[0]:.4g})"
            )
        if 2 * sh["gap"] + sh["rear_margin"] >= L[0] * (1 - sh["load_fraction"]):
            problems.append(
                f"{base}.shock.gap = {sh['gap']}: 2·gap + rear_margin must be shorter than the "
                f"part of the sample left after loading, {L[0] * (1 - sh['load_fraction']):.4g} sigma"
            )
        if sc["phase"] == "liquid" and "reference" in sc:
            cells = sc["reference"]["cells"]
            rho_max = sc["sample"]["rho0"] * max(sc["reference"]["compressions"])
            Lref = cells * lattice_constant(rho_max)
            if Lref < 2 * rlist:
                problems.append(
                    f"{base}.reference.cells = {cells}: the periodic reference box at the highest "
                    f"compression is {Lref:.3g} sigma, shorter than 2 (rc + skin) = {2 * rlist:.3g}; "
                    f"use more cells"
                )
    return problems


def validate_config(cfg: dict, schema: dict | None = None) -> dict:
    """Validate ``cfg`` in place (filling defaults) and return it; raise ConfigError."""
    schema = schema or load_schema()
    errors = sorted(_Validator(schema).iter_errors(cfg), key=lambda e: list(e.absolute_path))
    problems = [_message(e) for e in errors]
    if not problems:
        problems = _cross_checks(cfg)
    if problems:
        raise ConfigError("invalid config:\n  " + "\n  ".join(problems))
    return cfg


def load_config(path: str | Path) -> dict:
    """Read a YAML config and validate it."""
    with open(path) as fh:
        cfg = yaml.safe_load(fh) or {}
    return validate_config(cfg)


def config_hash(obj: Any) -> str:
    """SHA-256 (first 16 hex digits) of the canonical JSON of ``obj``."""
    return hashlib.sha256(json.dumps(obj, sort_keys=True).encode()).hexdigest()[:16]
