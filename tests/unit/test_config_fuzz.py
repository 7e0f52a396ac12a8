"""Property-based fuzzing of config validation.

Random configs are thrown at ``validate_config``, ``load_config`` and ``check-config``: every
one must be accepted, or refused with a ``ConfigError`` whose every line names a key path of
the config (and, for a mutated valid config, a key the mutation touched). Nothing else may
escape: no TypeError, KeyError or RecursionError traceback. Accepted configs must be usable
downstream: plain JSON (no NaN, no non-string keys) with one point folder per piston velocity.

Three kinds of input:
- structurally random JSON-like values (and random ``scenes`` entries);
- mutations of the two shipped configs (``config/config.yaml`` and the tiny workflow config):
  wrong types, NaN/inf, negative, zero, huge, strings where numbers go, empty containers,
  deleted, renamed and unknown keys, extra nesting, scaled numbers that break cross-key checks;
- configs drawn from the schema itself (mostly in range, edges and just beyond), which reach
  the cross-key checks and are often accepted.
"""

from __future__ import annotations

import contextlib
import copy
import io
import json
import math
import os
import subprocess
import sys
import tempfile
from pathlib import Path

import pytest
import yaml
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from hugomap.config import (
    ConfigError,
    config_hash,
    key_path,
    load_config,
    load_schema,
    point_tag,
    validate_config,
)

ROOT = Path(__file__).resolve().parents[2]
SCHEMA = load_schema()
BASES = {
    "default": yaml.safe_load((ROOT / "config/config.yaml").read_text()),
    "tiny": yaml.safe_load((ROOT / "tests/workflow/tiny/config.yaml").read_text()),
}
CAMPAIGN = yaml.safe_load((ROOT / "config/campaign.yaml").read_text())
# 150 fixed examples per property in the suite (about 20 s); HUGOMAP_FUZZ_EXAMPLES=N runs N
# random ones instead, for a deeper search.
DEEP = os.environ.get("HUGOMAP_FUZZ_EXAMPLES")
FUZZ = settings(
    max_examples=int(DEEP or 150),
    deadline=None,
    derandomize=DEEP is None,
    suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large],
)


def _schema_keys(node: object) -> set[str]:
    """Every property name the schema knows (so random dicts hit real keys often)."""
    out: set[str] = set()
    if isinstance(node, dict):
        out |= set(node.get("properties", {}))
        for v in node.values():
            out |= _schema_keys(v)
    elif isinstance(node, list):
        for v in node:
            out |= _schema_keys(v)
    return out


KNOWN_KEYS = sorted(_schema_keys(SCHEMA) | {"lj_liquid", "lj_fcc", "tiny"})
NASTY = [
    math.nan,
    math.inf,
    -math.inf,
    -1,
    -1.0,
    0,
    0.0,
    1e308,
    -1e308,
    10**30,
    5e-324,
    2**63,
    "",
    "0.5",
    "1e3",
    "nan",
    "abc",
    [],
    {},
    None,
    True,
    False,
    [[]],
    {"value": 1.0},
]

keys = st.one_of(st.sampled_from(KNOWN_KEYS), st.text(max_size=6), st.integers(-2, 2))
leaves = st.one_of(
    st.none(),
    st.booleans(),
    st.integers(),
    st.floats(),
    st.text(max_size=8),
    st.sampled_from(["md", "liquid", "crystal", "piston", "0.5"]),
)
json_like = st.recursive(
    leaves,
    lambda ch: st.lists(ch, max_size=4) | st.dictionaries(keys, ch, max_size=4),
    max_leaves=12,
)
bad_values = st.one_of(st.sampled_from(NASTY), json_like)


# -- checking an outcome ------------------------------------------------------------------


def _all_paths(node: object, where: tuple = ()) -> set[tuple]:
    out = {where}
    if isinstance(node, dict):
        for k, v in node.items():
            out |= _all_paths(v, (*where, k))
    elif isinstance(node, list):
        for i, v in enumerate(node):
            out |= _all_paths(v, (*where, i))
    return out


def _line_path(line: str, known: set[str]) -> str:
    """The key path a problem line starts with (the longest known path that fits)."""
    fits = [p for p in known if line.startswith(p + " = ") or line.startswith(p + ": ")]
    assert fits, f"problem line names no key path of the config: {line!r}"
    return max(fits, key=len)


def _related(line: str, lp: str, mutation: tuple) -> bool:
    """Does a problem line (whose key path is ``lp``) concern the mutated key path?"""
    mp = key_path(mutation)
    if lp in {key_path(mutation[:i]) for i in range(len(mutation) + 1)}:
        return True  # the key itself, or the object that misses it / has an unknown key
    if lp.startswith(mp + ".") or lp.startswith(mp + "["):
        return True  # inside a replaced value
    # A cross-key check reported at another key of the same scene must name the mutated key.
    names = [p for p in mutation[2:] if isinstance(p, str)]
    return (
        len(mutation) > 2
        and mutation[0] == "scenes"
        and lp.startswith(key_path(mutation[:2]))
        and bool(names)
        and names[-1] in line
    )


def check(cfg: object, mutations: list[tuple] | None = None) -> str:
    """Validate; assert the outcome is an acceptance or a well-formed ConfigError."""
    original = copy.deepcopy(cfg)
    try:
        out = validate_config(cfg)
    except ConfigError as exc:
        msg = str(exc)
        lines = msg.splitlines()
        assert lines[0] == "invalid config:", msg
        assert len(lines) > 1, msg
        known = {key_path(p) for p in _all_paths(cfg) | _all_paths(original)}
        for line in lines[1:]:
            assert line.startswith("  ") and "\n" not in line, msg
            lp = _line_path(line[2:], known)
            if mutations is not None:
                assert any(_related(line[2:], lp, m) for m in mutations), (
                    f"{line!r} concerns none of the mutated keys {mutations}"
                )
        return "refused"
    # Accepted: usable downstream (Snakemake passes scenes as sorted JSON; u_p -> folders).
    assert out is cfg
    text = json.dumps(out, sort_keys=True, allow_nan=False)
    assert json.loads(text) == out
    config_hash(out)
    for name, scene in out["scenes"].items():
        assert isinstance(name, str) and name.isidentifier()
        tags = [point_tag(u) for u in scene["shock"]["u_p"]]
        assert len(set(tags)) == len(tags)
        rho0 = scene["material"]["eos"]["rho0"] if scene["solver"] == "csph" else None
        rho0 = scene["sample"]["rho0"] if rho0 is None else rho0
        assert rho0 > 0 and all(u > 0 for u in scene["shock"]["u_p"])
    # Validation is idempotent: a resolved config validates to itself.
    again = copy.deepcopy(out)
    assert validate_config(again) == out
    return "accepted"


# -- strategies ---------------------------------------------------------------------------


def _get(cfg: object, path: tuple) -> object:
    for p in path:
        cfg = cfg[p]  # type: ignore[index]
    return cfg


@st.composite
def mutated_configs(draw: st.DrawFn) -> tuple[dict, list[tuple]]:
    """A shipped config with one to three mutations; returns it and the mutated key paths."""
    return _mutate(draw, copy.deepcopy(BASES[draw(st.sampled_from(sorted(BASES)))]), ())


@st.composite
def mutated_campaigns(draw: st.DrawFn) -> tuple[dict, list[tuple]]:
    """config/campaign.yaml with one to three mutations inside its campaign block."""
    return _mutate(draw, copy.deepcopy(CAMPAIGN), ("campaign",))


def _mutate(draw: st.DrawFn, cfg: dict, under: tuple) -> tuple[dict, list[tuple]]:
    mutations: list[tuple] = []
    for _ in range(draw(st.integers(1, 3))):
        paths = sorted((p for p in _all_paths(cfg) if p and p[: len(under)] == under), key=key_path)
        if not paths:
            break
        path = draw(st.sampled_from(paths))
        parent, key = _get(cfg, path[:-1]), path[-1]
        node = parent[key]
        op = draw(
            st.sampled_from(
                ["replace", "scale", "delete", "add_key", "wrap", "stringify", "rename", "empty"]
            )
        )
        if op == "scale" and isinstance(node, int | float) and not isinstance(node, bool):
            factor = draw(st.sampled_from([-1, 0, 0.5, 2, 10, 1e3, 1e-3, 1e300]))
            parent[key] = node * factor
        elif op == "delete":
            del parent[key]
        elif op == "add_key" and isinstance(node, dict):
            new = draw(keys)
            node[new] = draw(json_like)
            path = (*path, new)
        elif op == "wrap":
            parent[key] = draw(st.sampled_from([[node], {"value": node}, [node, node]]))
        elif op == "stringify":
            parent[key] = str(node)
        elif op == "rename" and isinstance(parent, dict):
            new = draw(keys)
            if new not in parent:
                parent[new] = parent.pop(key)
                mutations.append((*path[:-1], new))
        elif op == "empty" and isinstance(node, dict | list):
            parent[key] = type(node)()
        else:
            parent[key] = draw(bad_values)
        mutations.append(path)
    return cfg, mutations


def _resolve(sub: dict) -> dict:
    ref = sub.get("$ref")
    return SCHEMA["$defs"][ref.rsplit("/", 1)[1]] if ref else sub


_NONE = object()


def _from_schema(sub: dict, example: object = _NONE, wild: bool = True) -> st.SearchStrategy:
    """Values for a subschema. ``wild``: anywhere in range, the range's edges, just beyond
    them, wrong lengths and, now and then, something random. Otherwise near ``example`` (a
    value of the tiny config, else the default), which reaches the cross-key checks."""
    sub = _resolve(sub)
    if example is _NONE:
        example = sub.get("default", _NONE)
    if "const" in sub:
        good: st.SearchStrategy = st.just(sub["const"])
    elif "enum" in sub:
        good = st.sampled_from(sub["enum"])
    elif sub.get("type") in ("number", "integer"):
        integer = sub["type"] == "integer"
        lo = sub.get("minimum", sub.get("exclusiveMinimum", 0))
        hi = sub.get("maximum", sub.get("exclusiveMaximum", lo + 1000))
        if integer:
            inner = st.integers(int(lo), int(min(hi, lo + 100)))
            edges = st.sampled_from([int(lo), int(hi), int(lo) - 1, int(hi) + 1])
        else:
            inner = st.floats(lo, hi, exclude_min=True, exclude_max=True)
            edges = st.sampled_from([lo, hi, lo - 0.1 * (hi - lo), hi + 0.1 * (hi - lo)])
        if example is _NONE or not wild and isinstance(example, bool):
            near = inner
        else:
            x = float(example)  # type: ignore[arg-type]
            near = st.floats(0.8, 1.25).map(
                lambda f: min(max(round(x * f) if integer else x * f, lo), hi)
            )
        good = st.one_of(inner, near, edges) if wild else near
    elif sub.get("type") == "boolean":
        good = st.booleans()
    elif sub.get("type") == "array":
        n_lo, n_hi = sub.get("minItems", 0), sub.get("maxItems", 4)
        item_ex = example[0] if isinstance(example, list) and example else _NONE
        items = _from_schema(sub["items"], item_ex, wild)
        if wild:
            good = st.lists(items, min_size=max(n_lo - 1, 0), max_size=n_hi + 1)
        elif isinstance(example, list) and example:
            good = st.tuples(*(_from_schema(sub["items"], e, wild) for e in example)).map(list)
        else:
            good = st.lists(items, min_size=n_lo, max_size=n_hi)
    elif sub.get("type") == "object":
        props = sub.get("properties", {})
        ex = example if isinstance(example, dict) else {}
        required = set(sub.get("required", [])) | (set() if wild else set(ex) & set(props))

        def one(k: str, v: dict) -> st.SearchStrategy:
            return _from_schema(v, ex.get(k, _NONE), wild)

        # near the tiny config, a block the config has keeps to its keys (a key it lacks
        # would mostly be drawn where it conflicts with the others: the wild draws try them)
        optional = {} if not wild and ex else {
            k: one(k, v) for k, v in props.items() if k not in required
        }  # fmt: skip
        good = st.fixed_dictionaries(
            {k: one(k, v) for k, v in props.items() if k in required}, optional=optional
        )
        if not wild and sub.get("minProperties"):  # near the tiny config: a valid size
            good = good.filter(lambda d, n=sub["minProperties"]: len(d) >= n)
    else:
        good = json_like
    if not wild:
        return good
    return st.integers(0, 29).flatmap(lambda i: bad_values if i == 0 else good)


scene_names = st.one_of(
    st.sampled_from(["lj_liquid", "tiny", "a", "hugoniot", "1x", "a b"]), st.text(max_size=5)
)


def _configs(wild: bool) -> st.SearchStrategy:
    scene = _from_schema(SCHEMA["$defs"]["md_scene"], BASES["tiny"]["scenes"]["tiny"], wild)
    names = scene_names if wild else st.sampled_from(["lj_liquid", "tiny", "a"])
    return st.fixed_dictionaries(
        {"scenes": st.dictionaries(names, scene, min_size=1, max_size=2)},
        optional={
            k: _from_schema(SCHEMA["properties"][k], wild=wild) for k in ("threads", "schemes")
        },
    )


# Half the configs are drawn wild, half near the tiny config.
schema_configs = st.booleans().flatmap(_configs)


# -- the properties -----------------------------------------------------------------------


@settings(FUZZ, max_examples=int(DEEP or 60))
@given(mutated_campaigns())
def test_mutated_campaigns_are_accepted_or_refused_by_key(case: tuple[dict, list[tuple]]) -> None:
    """A campaign block with bad values expands (or not) and is accepted or refused with a
    ConfigError whose every line names a key path: of the config, or of a scene the
    campaign made (``scenes.<case>__<variant>...``, tagged with the campaign key)."""
    check(case[0])


@FUZZ
@given(json_like)
def test_random_values_are_accepted_or_refused(cfg: object) -> None:
    """Any JSON-like value at the top level: refused with key paths, never a crash."""
    check(cfg)


@FUZZ
@given(st.dictionaries(keys, json_like, max_size=3), json_like)
def test_random_scenes_are_refused_by_key(scenes: dict, extra: object) -> None:
    """A ``scenes`` mapping of random entries (and a random top-level sibling)."""
    check({"scenes": scenes, "threads": extra})


@FUZZ
@given(mutated_configs())
def test_mutated_configs_name_the_mutated_key(case: tuple[dict, list[tuple]]) -> None:
    """Mutations of the shipped configs are refused naming the key they touched."""
    cfg, mutations = case
    check(cfg, mutations)


@FUZZ
@given(schema_configs)
def test_schema_drawn_configs(cfg: dict) -> None:
    """Configs drawn from the schema (edges, just out of range, cross-key conflicts)."""
    check(cfg)


def test_schema_drawn_configs_reach_both_outcomes() -> None:
    """The schema-driven strategy is not vacuous: draws near the tiny config are sometimes
    accepted, wild draws sometimes refused. (Each kind on its own: Hypothesis mixes
    constants of the modules imported so far into its draws, so a mixed sample's balance
    depended on which tests had run before this one.)"""
    for wild, outcome in ((False, "accepted"), (True, "refused")):
        assert outcome in _outcomes(_configs(wild)), wild


def _outcomes(strategy: st.SearchStrategy) -> set[str]:
    """check()'s outcomes over 60 derandomized draws of ``strategy``."""
    seen: set[str] = set()

    @settings(max_examples=60, deadline=None, derandomize=True, database=None)
    @given(strategy)
    def run(cfg: dict) -> None:
        seen.add(check(cfg))

    run()
    return seen


@pytest.mark.parametrize(
    ("mutate", "expect"),
    [
        (
            lambda s: s["sample"].update(rho0=math.nan),
            "scenes.tiny.sample.rho0 = nan: not a finite",
        ),
        (lambda s: s["shock"].update(u_p=[math.inf]), "scenes.tiny.shock.u_p[0] = inf: not a"),
        (lambda s: s["shock"].update(u_p=[1.0, 1.0000001]), "scenes.tiny.shock.u_p[1] = 1.0000001"),
        (lambda s: s["sample"].update(cells=[10**400, 4, 4]), "scenes.tiny.sample.cells[0] = <"),
        (lambda s: s["shock"].update({3: 1}), "scenes.tiny.shock: unknown key(s) [3]"),
    ],
)
def test_found_by_fuzzing(mutate, expect: str) -> None:
    """Configs that crashed or slipped through before the fixes (see the module docstring
    of hugomap.config): NaN/inf passed every range check, non-string keys raised TypeError
    while sorting, two velocities could share one point folder, huge ints could not print."""
    cfg = copy.deepcopy(BASES["tiny"])
    mutate(cfg["scenes"]["tiny"])
    with pytest.raises(ConfigError) as ei:
        validate_config(cfg)
    assert expect in str(ei.value)


def test_a_control_character_in_a_scene_name_keeps_the_message_to_its_lines() -> None:
    """Found by the schema-drawn fuzzing: a scene named '\\r' whose inherited scheme its
    solver does not run was written raw into scenes.<name>.schemes, splitting the line."""
    cfg = {"scenes": {"\r": {"solver": "md", "phase": "liquid", "sample": math.nan,
                              "shock": math.nan}}, "schemes": ["msst"]}  # fmt: skip
    assert check(cfg) == "refused"
    with pytest.raises(ConfigError) as ei:
        validate_config(cfg)
    assert "inherited as scenes['\\r'].schemes" in str(ei.value)


def test_non_string_and_reserved_scene_names() -> None:
    """Scene names become folders: non-strings, reserved folders, a newline are refused."""
    cfg = copy.deepcopy(BASES["tiny"])
    scene = cfg["scenes"].pop("tiny")
    # "A\n" matched the old pattern ^...$ (Python's $ matches before a final newline).
    cfg["scenes"].update({1: scene, "hugoniot": copy.deepcopy(scene), "A\n": scene, "ok": 5,
                          "references": copy.deepcopy(scene)})  # fmt: skip
    cfg[2] = 0
    with pytest.raises(ConfigError) as ei:
        validate_config(cfg)
    msg = str(ei.value)
    assert "scenes: key 1 is not allowed" in msg
    assert "scenes: key 'hugoniot' is not allowed" in msg
    assert "scenes: key 'references' is not allowed" in msg
    assert "scenes: key 'A\\n' is not allowed" in msg
    assert "scenes.ok = 5: must be of type object" in msg
    assert "(top level): unknown key(s) [2]" in msg


def test_self_containing_yaml_is_refused(tmp_path: Path) -> None:
    """YAML anchors can make a list contain itself; that is refused, not a RecursionError."""
    text = (ROOT / "tests/workflow/tiny/config.yaml").read_text()
    text = text.replace("u_p: [1.5, 2.5]", "u_p: &a [1.5, *a]")
    (tmp_path / "c.yaml").write_text(text)
    with pytest.raises(ConfigError) as ei:
        load_config(tmp_path / "c.yaml")
    assert "scenes.tiny.shock.u_p[1]" in str(ei.value)


# -- loaders and the command line ---------------------------------------------------------

TINY_TEXT = (ROOT / "tests/workflow/tiny/config.yaml").read_text()


@st.composite
def yaml_texts(draw: st.DrawFn) -> str:
    """Random text, the tiny config with random edits, or a YAML dump of a mutated config."""
    kind = draw(st.integers(0, 2))
    if kind == 0:
        return draw(st.text(max_size=60))
    if kind == 1:
        text = TINY_TEXT
        for _ in range(draw(st.integers(1, 4))):
            i = draw(st.integers(0, len(text)))
            j = draw(st.integers(i, min(i + 8, len(text))))
            text = (
                text[:i]
                + draw(
                    st.sampled_from(
                        [
                            "",
                            ":",
                            "[",
                            "- ",
                            "\t",
                            "&a",
                            "*b",
                            "!!x ",
                            "2020-13-45",
                            "\n  x: 1",
                            "'",
                            "{",
                        ]
                    )
                )
                + text[j:]
            )
        return text
    cfg, _ = draw(mutated_configs())
    return yaml.safe_dump(cfg)


@FUZZ
@given(yaml_texts())
def test_load_config_refuses_bad_files(text: str) -> None:
    """Random and damaged YAML files: a config, or a ConfigError naming file or key."""
    with tempfile.TemporaryDirectory(dir="/tmp") as d:
        path = Path(d) / "c.yaml"
        path.write_text(text)
        try:
            cfg = load_config(path)
        except ConfigError as exc:
            msg = str(exc)
            assert msg.startswith("invalid config")
            if msg.startswith("invalid config: "):  # a file-level problem: one line
                assert str(path) in msg and "\n" not in msg
        else:
            check(cfg)


@settings(max_examples=25, deadline=None, derandomize=True)
@given(mutated_configs())
def test_check_config_command_in_process(case: tuple[dict, list[tuple]]) -> None:
    """``hugomap check-config`` on mutated configs: exit 0 or 2, never an exception."""
    from hugomap.cli import main

    cfg, _ = case
    with tempfile.TemporaryDirectory(dir="/tmp") as d:
        path = Path(d) / "c.yaml"
        path.write_text(yaml.safe_dump(cfg))
        err = io.StringIO()
        with contextlib.redirect_stderr(err), contextlib.redirect_stdout(io.StringIO()):
            rc = main(["check-config", str(path)])
        assert rc in (0, 2)
        assert (rc == 2) == err.getvalue().startswith("invalid config")


@pytest.mark.parametrize(
    ("text", "expect"),
    [
        (
            TINY_TEXT.replace("rho0: 0.80", "rho0: .nan").replace("threads: 1", "threads: 1\n7: x"),
            ["scenes.tiny.sample.rho0 = nan: not a finite number", "unknown key(s) [7]"],
        ),
        (TINY_TEXT.replace("u_p: [1.5, 2.5]", "u_p: [1.5, 2.5"), ["not valid YAML (line"]),
        (None, ["cannot read"]),
    ],
    ids=["bad-values", "broken-yaml", "missing-file"],
)
def test_check_config_command(tmp_path: Path, text: str | None, expect: list[str]) -> None:
    """``python -m hugomap check-config`` as a user runs it: exit 2, the problems named, no
    traceback."""
    path = tmp_path / "my.yaml"
    if text is not None:
        path.write_text(text)
    r = subprocess.run(
        [sys.executable, "-m", "hugomap", "check-config", str(path)],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert r.returncode == 2, r.stderr
    assert "Traceback" not in r.stderr
    lines = r.stderr.strip().splitlines()
    assert lines[0].startswith("invalid config"), r.stderr
    assert all(line.startswith("  ") for line in lines[1:]), r.stderr
    for e in expect:
        assert e in r.stderr


def test_campaign_names_that_are_not_printable() -> None:
    """A resolution name with a record separator (str.splitlines splits at it) broke the
    one-line message of a stability resolution that is not defined (found by fuzzing)."""
    cfg = copy.deepcopy(CAMPAIGN)
    res = cfg["campaign"]["cases"]["cu_solid"]["resolutions"]
    res["\x1e"] = res.pop("mid")
    with pytest.raises(ConfigError) as ei:
        validate_config(cfg)
    assert str(ei.value).splitlines()[1:] == [
        "  campaign.cases.cu_solid.stability.resolution = 'mid': not one of the resolutions "
        "(coarse, fine, '\\x1e')"
    ]
