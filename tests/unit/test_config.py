"""Config validation: defaults filled, bad values refused with the key and allowed range."""

from __future__ import annotations

import copy
from pathlib import Path

import pytest
import yaml

from hugomap.config import ConfigError, load_config, load_schema, validate_config

ROOT = Path(__file__).resolve().parents[2]


def tiny() -> dict:
    return yaml.safe_load((ROOT / "tests/workflow/tiny/config.yaml").read_text())


def test_default_config_is_valid_and_filled() -> None:
    cfg = load_config(ROOT / "config/config.yaml")
    sh = cfg["scenes"]["lj_liquid"]["shock"]
    assert sh["bin_width"] == 1.0 and sh["sample_every"] == 25  # schema defaults
    assert len(sh["u_p"]) >= 5 and cfg["scenes"]["lj_liquid"]["target"]["D"] == 0.005
    assert sh["residual_tol"] == pytest.approx(0.015)  # follows the target: 3 x 0.5 %


@pytest.mark.parametrize("path", sorted((ROOT / "config").glob("*.yaml")), ids=lambda p: p.name)
def test_every_shipped_config_validates(path: Path) -> None:
    """Each config the README names runs through the same validation as a sweep: a schema
    change that leaves one behind is caught here, not by the user's first job."""
    cfg = load_config(path)
    assert cfg["scenes"], f"{path.name}: no scenes after expansion"


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


# -- CSPH scenes (solver: csph, SI units) ---------------------------------------------------


def copper() -> dict:
    return yaml.safe_load((ROOT / "config/copper.yaml").read_text())


def test_copper_config_is_valid_and_filled() -> None:
    cfg = load_config(ROOT / "config/copper.yaml")
    solid, porous = cfg["scenes"]["cu_solid"], cfg["scenes"]["cu_porous"]
    eos = solid["material"]["eos"]
    assert (eos["rho0"], eos["c0"], eos["s"], eos["gamma0"]) == (8930.0, 3940.0, 1.49, 2.0)
    assert solid["shock"]["bin_width"] == pytest.approx(2e-5)  # 2 dx, filled from sample.dx
    assert solid["window"]["length"] == pytest.approx(2.4e-3)  # 240 dx (set)
    assert solid["window"]["cut_every"] == pytest.approx(1e-4)  # 10 dx, filled
    assert solid["schemes"] == ["piston", "amw", "mw", "dichotomy"]
    assert solid["window"]["dichotomy"]["half_width"] == 100.0  # m/s, schema default
    assert porous["material"]["strength"]["model"] == "von_mises"
    assert porous["numerics"]["dev_mean"] is True
    assert porous["schemes"] == ["piston", "amw", "mw", "dichotomy"]  # the 2D window: all
    assert load_config(ROOT / "tests/workflow/tiny_cu/config.yaml")["scenes"]["tiny_cu"]


@pytest.mark.parametrize(
    ("scene", "edit", "expect"),
    [
        (  # porosity beyond what random sequential addition can pack
            "cu_porous",
            lambda s: s["sample"]["porous"].update(distention=1.9),
            "scenes.cu_porous.sample.porous.distention = 1.9: porosity 0.474 cannot be packed",
        ),
        (
            "cu_porous",
            lambda s: s["sample"]["porous"].update(distention=2.5),
            "scenes.cu_porous.sample.porous.distention = 2.5: out of range; allowed range [1.0, 2.0]",
        ),
        (
            "cu_porous",
            lambda s: s["material"]["strength"].update(yield_stress=5e10),
            "scenes.cu_porous.material.strength.yield_stress = 5e+10: must be below "
            "material.strength.shear_modulus = 4.77e+10 Pa",
        ),
        (  # resolution too coarse for the smallest pore (r_min >= 3 dx)
            "cu_porous",
            lambda s: s["sample"].update(dx=2e-5),
            "scenes.cu_porous.sample.porous.pore_radius = [3e-05, 6e-05]: the smallest pore is "
            "not resolved by sample.dx = 2e-05 m; allowed r_min >= 3 dx = 6e-05 m",
        ),
        (
            "cu_solid",
            lambda s: s["sample"].update(colour="red"),
            "scenes.cu_solid.sample: unknown key(s) ['colour']",
        ),
        (  # the inflow tile must hold a pore of r_max clear of its own image along x
            "cu_porous",
            lambda s: s["window"].update(tile_length=1.0e-4),
            "scenes.cu_porous.window.tile_length = 0.0001: the periodic inflow tile must hold "
            "the frozen inflow layer (9 dx) and, if porous, a pore of r_max with a ligament to "
            "its own image (2 r_max + sample.dx); allowed range [0.00013, 1.0] m",
        ),
        (
            "cu_solid",
            lambda s: s["window"].update(tile_length=1.0e-3),
            "scenes.cu_solid.window.tile_length: only for dim = 2 (this scene has dim = 1)",
        ),
        (  # the slab behind the front: shock.gap + window.outflow_gap + shock.avg_length
            "cu_porous",
            lambda s: s["window"].update(outflow_gap=2.0e-4),
            "scenes.cu_porous.window.front_fraction = 0.44: the front starts 0.000616 m from the "
            "outflow edge of window.length = 0.0014 m, less than the averaged slab behind it "
            "needs, shock.gap + window.outflow_gap + shock.avg_length = 0.00065 m",
        ),
        (  # the window must fit between piston and front at the end of loading (snowplow D)
            "cu_porous",
            lambda s: s["window"].update(length=2.0e-3),
            "scenes.cu_porous.window.length = 0.002: a window with window.front_fraction = "
            "0.44 does not fit around the front at the end of loading",
        ),
        (  # the shocked column at the end of loading, (1 - u_p/D) of what the front crossed
            # (D = 0.97 x McQueen's 384.4 m/s at 100 m/s), must hold 2 gap + avg_length
            "cu_porous",
            lambda s: s["shock"].update(load_fraction=0.4),
            "scenes.cu_porous.shock.load_fraction = 0.4: the shocked column between piston and "
            "front at the end of loading, shock.load_fraction x sample.length x (1 - u_p/D) = "
            "0.0007025 m at u_p = 100 m/s (D = 372.9 m/s, the slowest front), must hold the "
            "slab the window is normalised on, shock.avg_length + 2 shock.gap = 0.00075 m; "
            "allowed range [0.427, shock.end_fraction)",
        ),
        (  # at 500 m/s the compressed solid makes full compaction slower than the snowplow
            # (1798 against 1929 m/s): a window the snowplow let fit does not (seen at run
            # time as no_inflow before)
            "cu_porous",
            lambda s: (s["shock"].update(u_p=[100.0, 500.0]), s["window"].update(length=1.8e-3)),
            "scenes.cu_porous.window.length = 0.0018: a window with window.front_fraction = "
            "0.44 does not fit around the front at the end of loading (room 0.0007704 m behind "
            "it at u_p = 500 m/s",
        ),
        (  # the state ahead: 2 gap + avg_length = 1.2 mm of the 2.4-mm window ahead of the front
            "cu_solid",
            lambda s: s["window"].update(front_fraction=0.6),
            "scenes.cu_solid.window.front_fraction = 0.6: the window's (1 - front_fraction) x "
            "window.length = 0.00096 m ahead of the front must hold the slab ahead, 2 "
            "shock.gap + shock.avg_length = 0.0012 m, to measure the state the jump starts "
            "from; allowed range (0, 0.5]",
        ),
        (
            "cu_solid",
            lambda s: s.update(schemes=["piston", "amx"]),
            "scenes.cu_solid.schemes[1] = 'amx': allowed values ['piston', 'amw', 'mw', "
            "'dichotomy', 'auto']",
        ),
        (
            "cu_solid",
            lambda s: s["window"].update(dichotomy={"half_width": 20.0, "tolerance": 50.0}),
            "scenes.cu_solid.window.dichotomy.tolerance = 50: must be below the initial "
            "bracket width 2 window.dichotomy.half_width = 40 m/s; allowed range (0, 40) m/s",
        ),
        (
            "cu_solid",
            lambda s: s["window"].update(dichotomy={"half_width": 0.0}),
            "scenes.cu_solid.window.dichotomy.half_width = 0.0: out of range; allowed range "
            "(0.0, 5000.0]",
        ),
        (
            "cu_solid",
            lambda s: s["window"].update(mw={"gain_rate": -0.1}),
            "scenes.cu_solid.window.mw.gain_rate = -0.1: out of range; allowed range [0.0, 10.0]",
        ),
        (
            "cu_solid",
            lambda s: s["window"].update(dichotomy={"trial_time": 2.0}),
            "scenes.cu_solid.window.dichotomy.trial_time = 2.0: out of range; allowed range "
            "(0.0, 1.0]",
        ),
        (  # the slab behind the front (gap + outflow_gap + avg_length = 0.8 mm) must fit
            "cu_solid",
            lambda s: s["window"].update(front_fraction=0.3),
            "scenes.cu_solid.window.front_fraction = 0.3: the front starts 0.00072 m from the "
            "outflow edge of window.length = 0.0024 m, less than the averaged slab behind it "
            "needs, shock.gap + window.outflow_gap + shock.avg_length = 0.0008 m; allowed "
            "range [0.3333, 0.8] (or a longer window)",
        ),
        (
            "cu_solid",
            lambda s: s["shock"].update(u_p=[-100.0]),
            "scenes.cu_solid.shock.u_p[0] = -100.0: out of range; allowed range [1.0, 5000.0]",
        ),
        (
            "cu_solid",
            lambda s: s["window"].update(length=3e-3),
            "scenes.cu_solid.window.length = 0.003: a window with window.front_fraction",
        ),
        (
            "cu_porous",
            lambda s: s["sample"].pop("width"),
            "scenes.cu_porous.sample: 'width' is a required property for dim = 2",
        ),
    ],
)
def test_bad_csph_values_name_key_and_range(scene: str, edit, expect: str) -> None:
    cfg = copper()
    edit(cfg["scenes"][scene])
    with pytest.raises(ConfigError) as ei:
        validate_config(cfg)
    assert expect in str(ei.value)


def test_csph_scenes_inherit_every_scheme() -> None:
    """A CSPH scene, 1D or 2D, inherits every scheme from the top level."""
    cfg = copper()
    cfg["schemes"] = ["piston", "dichotomy"]
    del cfg["scenes"]["cu_solid"]["schemes"]
    del cfg["scenes"]["cu_porous"]["schemes"]
    out = validate_config(cfg)
    for name in ("cu_solid", "cu_porous"):
        assert out["scenes"][name].get("schemes", out["schemes"]) == ["piston", "dichotomy"]


def test_md_scene_without_solver_is_still_md() -> None:
    """The if/then on solver leaves MD scenes (and their messages) as they were."""
    cfg = tiny()
    del cfg["scenes"]["tiny"]["solver"]
    with pytest.raises(ConfigError) as ei:
        validate_config(cfg)
    assert "scenes.tiny: 'solver' is a required property" in str(ei.value)


@pytest.mark.parametrize("solver", ["foo", 3, None])
def test_unknown_solver_lists_every_registered_one(solver: object) -> None:
    """A scene naming no registered solver gets one message listing all of them, not the
    default solver's own value and the keys its schema requires."""
    from hugomap.registry import REGISTRY

    cfg = tiny()
    cfg["scenes"]["tiny"]["solver"] = solver
    with pytest.raises(ConfigError) as ei:
        validate_config(cfg)
    assert str(ei.value).splitlines()[1:] == [
        f"  scenes.tiny.solver = {solver!r}: allowed values {list(REGISTRY)}"
    ]
    assert {"md", "csph", "lammps"} <= set(REGISTRY)


def test_validation_resolves_every_default() -> None:
    """Validation is the only place defaults are filled: a validated CSPH scene has its dx
    defaults, and the times derived per point are null; resolving again changes nothing."""
    from hugomap.sph.scene_config import resolve_defaults

    cfg = load_config(ROOT / "config/copper.yaml")
    solid = cfg["scenes"]["cu_solid"]
    dx = solid["sample"]["dx"]
    assert solid["shock"]["gap"] == pytest.approx(5e-4)  # set
    assert solid["window"]["cut_every"] == pytest.approx(10 * dx)
    porous = cfg["scenes"]["cu_porous"]
    assert porous["window"]["dichotomy"]["trial_time"] is None  # derived per point
    assert porous["window"]["dichotomy"]["final_time"] is None
    tiny_cu = load_config(ROOT / "tests/workflow/tiny_cu/config.yaml")["scenes"]["tiny_cu"]
    w = tiny_cu["window"]
    assert w["window_time"] is None and w["average_time"] is None
    before = copy.deepcopy(cfg)
    for scene in cfg["scenes"].values():
        resolve_defaults(scene)
    assert cfg == before
    assert validate_config(copy.deepcopy(before)) == before


def test_null_times_are_allowed_and_named() -> None:
    cfg = load_config(ROOT / "config/copper.yaml")
    cfg["scenes"]["cu_solid"]["window"]["average_time"] = None
    validate_config(cfg)
    cfg["scenes"]["cu_solid"]["window"]["average_time"] = "long"
    with pytest.raises(ConfigError) as ei:
        validate_config(cfg)
    assert (
        "scenes.cu_solid.window.average_time = 'long': must be of type number or null; "
        "allowed range (0.0, 1.0], or null (derived per point)" in str(ei.value)
    )


def test_lj_params_ranges_are_the_schema_ranges() -> None:
    """One range per key: LJParams refuses exactly what the schema refuses."""
    from hugomap.md.potential import LJParams

    schema = load_schema()["$defs"]["md_scene"]["properties"]["potential"]["properties"]
    rc, skin = schema["rc"], schema["skin"]
    LJParams(rc=rc["maximum"], skin=skin["maximum"])
    for bad in ({"rc": rc["exclusiveMinimum"]}, {"rc": rc["maximum"] * 1.001},
                {"skin": skin["exclusiveMinimum"]}, {"skin": skin["maximum"] * 1.001}):  # fmt: skip
        with pytest.raises(ValueError, match=f"potential.{next(iter(bad))} = .*: allowed range"):
            LJParams(**bad)
    with pytest.raises(ValueError, match=r"potential.rc = 7.0: allowed range \(1.0, 6.0\] sigma"):
        LJParams(rc=7.0)


def test_ghost_width_at_least_rc_with_window_schemes() -> None:
    cfg = tiny()
    cfg["scenes"]["tiny"]["potential"].update(rc=3.5, skin=0.2)
    cfg["scenes"]["tiny"]["sample"]["cells"] = [36, 6, 6]
    with pytest.raises(ConfigError) as ei:
        validate_config(copy.deepcopy(cfg))
    assert (
        "scenes.tiny.window.ghost_width = 3.0: the frozen outflow layer must be at least the "
        "cutoff potential.rc = 3.5 thick; allowed range [3.5, 20.0] sigma"
    ) in str(ei.value)
    cfg["schemes"] = ["piston"]  # no window: no frozen layer
    validate_config(copy.deepcopy(cfg))
    cfg["schemes"] = ["piston", "mw"]
    cfg["scenes"]["tiny"]["window"]["ghost_width"] = 3.5
    validate_config(cfg)


def test_window_leaves_room_for_the_slab_ahead() -> None:
    """The tiny window (24 sigma, front at 0.5) leaves 12 sigma ahead of the front, room for
    2 shock.gap + 3 bins = 11; with the front at 0.6 it leaves 9.6: no slab ahead could be
    measured, so the scene is refused (a piston-only scene is not)."""
    cfg = tiny()
    validate_config(copy.deepcopy(cfg))
    cfg["scenes"]["tiny"]["window"]["front_fraction"] = 0.6
    with pytest.raises(ConfigError) as ei:
        validate_config(copy.deepcopy(cfg))
    assert (
        "scenes.tiny.window.front_fraction = 0.6: the window's (1 - front_fraction) x "
        "window.length = 9.6 sigma ahead of the front must hold a slab, 2 shock.gap + 3 "
        "shock.bin_width = 11 sigma, to measure the state the jump starts from; allowed "
        "range (0, 0.5417]"
    ) in str(ei.value)
    cfg["schemes"] = ["piston"]
    validate_config(cfg)


def test_piston_gap_clears_the_start_where_the_sample_allows() -> None:
    """The default liquid's loading ends with the front 0.3 x 410.4 = 123 sigma from the
    piston: room for the 30-sigma piston gap, which is filled in. The tiny scene's loading
    leaves less, so it keeps shock.gap (the old slab); a value set beyond the room is
    refused, naming the key and the range; a loading too short even for shock.gap keeps
    shock.gap, as before."""
    from hugomap.md.scene_config import PISTON_GAP, piston_gap_room

    sc = load_config(ROOT / "config/config.yaml")["scenes"]["lj_liquid"]
    assert sc["shock"]["piston_gap"] == PISTON_GAP == 30.0
    cells = sc["sample"]["cells"][0]
    assert piston_gap_room(sc) == pytest.approx(0.3 * cells * 5.0 ** (1 / 3) - 8.0 - 3.0)
    cfg = tiny()
    out = validate_config(copy.deepcopy(cfg))["scenes"]["tiny"]
    room = piston_gap_room(out)
    assert room < PISTON_GAP and out["shock"]["piston_gap"] == out["shock"]["gap"]
    cfg["scenes"]["tiny"]["shock"]["piston_gap"] = room + 1.0
    with pytest.raises(ConfigError) as ei:
        validate_config(copy.deepcopy(cfg))
    assert (
        f"scenes.tiny.shock.piston_gap = {room + 1.0}: leaves the piston no slab when its "
        f"drive starts; allowed range [0, {room:.4g}] sigma"
    ) in str(ei.value)
    cfg["scenes"]["tiny"]["shock"]["piston_gap"] = room
    assert validate_config(copy.deepcopy(cfg))["scenes"]["tiny"]["shock"]["piston_gap"] == room
    # A loading too short even for shock.gap keeps the old slab rather than being refused.
    del cfg["scenes"]["tiny"]["shock"]["piston_gap"]
    cfg["schemes"] = ["piston"]
    cfg["scenes"]["tiny"]["shock"]["load_fraction"] = 0.1
    short = validate_config(cfg)["scenes"]["tiny"]
    assert piston_gap_room(short) < short["shock"]["gap"] == short["shock"]["piston_gap"]


def test_mw_position_gain_is_per_window_time_for_both_solvers() -> None:
    """One meaning: dimensionless, per window_time. The MD default 0.1 at the default
    window_time (2 tau) is the former 0.05 per tau."""
    schema = load_schema()["$defs"]
    md_w = schema["md_scene"]["properties"]["window"]["properties"]
    cs_w = schema["csph_scene"]["properties"]["window"]["properties"]
    for w in (md_w, cs_w):
        assert "per window_time" in w["mw"]["properties"]["gain_position"]["description"]
    assert md_w["mw"]["properties"]["gain_position"]["default"] / md_w["window_time"][
        "default"
    ] == pytest.approx(0.05)


def test_piston_velocities_sharing_a_point_folder_are_refused_naming_the_key():
    """Two u_p with the same 6 significant digits write one folder: refused, both keys named
    (one rule for every backend, ``keys.duplicate_point_tags``)."""
    from hugomap.keys import duplicate_point_tags

    problems = duplicate_point_tags("scenes.s", [1.0, 2.0, 1.0000001])
    assert len(problems) == 1
    assert problems[0].startswith("scenes.s.shock.u_p[2] = 1.0000001: same point folder up1")
    assert "shock.u_p[0] = 1.0" in problems[0]
    assert duplicate_point_tags("scenes.s", [1.0, 1.00001]) == []
