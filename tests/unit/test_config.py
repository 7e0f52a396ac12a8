"""Config validation: defaults filled, bad values refused with the key and allowed range."""

from __future__ import annotations

import copy
from pathlib import Path

import pytest
import yaml

from hugomap.config import ConfigError, load_config, validate_config

ROOT = Path(__file__).resolve().parents[2]


def tiny() -> dict:
    return yaml.safe_load((ROOT / "tests/workflow/tiny/config.yaml").read_text())


def test_default_config_is_valid_and_filled() -> None:
    cfg = load_config(ROOT / "config/config.yaml")
    sh = cfg["scenes"]["lj_liquid"]["shock"]
    assert sh["bin_width"] == 1.0 and sh["sample_every"] == 25  # schema defaults
    assert len(sh["u_p"]) >= 6 and len(cfg["scenes"]["lj_fcc"]["shock"]["u_p"]) >= 6


@pytest.mark.parametrize(
    ("path", "value", "expect"),
    [
        (
            ("shock", "u_p"),
            [-1.0],
            "scenes.tiny.shock.u_p[0] = -1.0: out of range; allowed range [0.01, 20.0]",
        ),
        (
            ("shock", "dt"),
            0.5,
            "scenes.tiny.shock.dt = 0.5: out of range; allowed range (0.0, 0.01]",
        ),
        (("sample", "rho0"), 3.0, "scenes.tiny.sample.rho0 = 3.0: out of range"),
        (("phase",), "gas", "allowed values ['liquid', 'crystal']"),
        (
            ("shock", "bin_width"),
            30.0,
            "scenes.tiny.shock.bin_width = 30.0: wider than the box allows",
        ),
        (
            ("potential", "rc"),
            3.2,
            "scenes.tiny.potential.rc = 3.2: rc + skin must not exceed half the transverse box",
        ),
    ],
)
def test_bad_values_name_key_and_range(path: tuple, value, expect: str) -> None:
    cfg = tiny()
    node = cfg["scenes"]["tiny"]
    for p in path[:-1]:
        node = node[p]
    node[path[-1]] = value
    with pytest.raises(ConfigError) as ei:
        validate_config(cfg)
    assert expect in str(ei.value)


def test_unknown_keys_are_named() -> None:
    cfg = tiny()
    cfg["scenes"]["tiny"]["shock"]["colour"] = "red"
    cfg["speed"] = 1
    with pytest.raises(ConfigError) as ei:
        validate_config(copy.deepcopy(cfg))
    msg = str(ei.value)
    assert "unknown key(s) ['colour']" in msg and "unknown key(s) ['speed']" in msg
