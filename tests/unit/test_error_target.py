"""An error target per scene (``methods.target``): a window's average goes on until its
stated errors meet the target or its budget is spent, a point that misses it says so with
the time its own error law needs, and a bad target is refused at validation.

The held front is ``test_steady_average``'s toy: slabs with white noise of relative size 0.1
per bin, so the slab's P error falls as T^(-1/2) — the law the point must find for itself."""

from __future__ import annotations

import copy
import math
from pathlib import Path

import numpy as np
import pytest
import yaml

from hugomap import cost_laws
from hugomap.config import TOL_PER_TARGET, ConfigError, validate_config
from hugomap.keys import scene_points, scheme_choice_at
from hugomap.methods.steady import steady_state
from hugomap.methods.target import (
    K_DEFAULT,
    ErrorTarget,
    error_exponent,
    judge,
    time_to_target,
)
from tests.unit.test_steady_average import _SIGNAL, POLE, _HeldFront, _Profile

CHUNK = 0.16  # the toy's average_time: 16 samples of dt 0.01


def _average(target: ErrorTarget | None, max_duration: float | None = None, cpu=None, seed=1):
    win = _HeldFront(0.1, seed)
    r, _ = steady_state(win, _Profile(), POLE, _SIGNAL, duration=CHUNK, every=1, gap=3.0,
                        avg_length=20.0, residual_tol=0.05, max_duration=max_duration,
                        target=target, cpu=cpu, time_unit="tau")  # fmt: skip
    return r


def test_a_window_averages_on_until_its_errors_meet_the_target():
    """One chunk states P to ~0.7 %; a 0.3 % target needs several times as long. The average
    stops at the first whole chunk that meets it: ok, with time_to_target the time it took;
    without a target the same point stops after its one chunk."""
    plain = _average(None)
    assert plain["average_time"] == CHUNK
    assert plain["P_rel_err"] > 0.003 and math.isnan(plain["target_P"])
    r = _average(ErrorTarget(P=0.003))
    assert r["status"] == "ok", r["diagnostic"]
    assert r["P_rel_err"] <= 0.003 and r["target_P"] == 0.003
    assert CHUNK < r["average_time"] <= 10 * CHUNK
    assert r["time_to_target"] == r["average_time"]
    assert round(r["average_time"] / CHUNK, 9) % 1 == 0  # whole chunks


def test_a_point_that_misses_its_target_says_so_and_how_long_it_needs():
    """Capped at two chunks, a 0.15 % target is out of reach: target_not_reached (the point
    closes and is steady), naming P, the target and the time its own law asks for."""
    capped = _average(ErrorTarget(P=0.0015), max_duration=2 * CHUNK)
    assert capped["status"] == "target_not_reached", capped["diagnostic"]
    assert capped["average_time"] == pytest.approx(2 * CHUNK)
    d = capped["diagnostic"]
    assert "P's error" in d and "target.P = 0.15 %" in d and "tau" in d
    assert capped["time_to_target"] > 2 * CHUNK


def test_the_time_a_point_says_it_needs_is_the_time_it_takes():
    """Over 12 seeds, the time a point capped at four chunks says it needs for a 0.2 %
    target, against the time an uncapped average of the same slab then takes: unbiased
    (geometric mean of the ratios 1.27 measured; allowed 0.67-1.5) though single points
    scatter by a factor ~3, the error of an 8-block error (~27 %) squared into time (each
    allowed within 8x)."""
    ratios = []
    for seed in range(1, 13):
        capped = _average(ErrorTarget(P=0.002), max_duration=4 * CHUNK, seed=seed)
        free = _average(ErrorTarget(P=0.002), max_duration=200 * CHUNK, seed=seed)
        assert free["status"] == "ok", free["diagnostic"]
        ratios.append(capped["time_to_target"] / free["average_time"])
    assert 1 / 8 < min(ratios) and max(ratios) < 8, ratios
    assert 0.67 < math.exp(np.mean(np.log(ratios))) < 1.5, ratios


def test_the_budget_ends_the_average():
    """A CPU clock of 10 s per simulated time unit: a budget of 5 s fits three chunks (1.6 s
    each), not the fourth; the point says the budget was spent."""
    win_time = [0.0]

    def cpu() -> float:
        return 10.0 * win_time[0]

    win = _HeldFront(0.1)
    advance = win.advance

    def timed(n: int) -> None:
        advance(n)
        win_time[0] = win.time

    win.advance = timed
    r, _ = steady_state(win, _Profile(), POLE, _SIGNAL, duration=CHUNK, every=1, gap=3.0,
                        avg_length=20.0, residual_tol=0.05, max_duration=100 * CHUNK,
                        target=ErrorTarget(P=0.0005, cpu_s=5.0), cpu=cpu)  # fmt: skip
    assert r["average_time"] == pytest.approx(3 * CHUNK)
    assert r["status"] == "target_not_reached"
    assert "target.cpu_s = 5 s is spent" in r["diagnostic"]


def test_judge_keeps_physical_verdicts_and_failures():
    """Only an ok point becomes target_not_reached; a not_converged one keeps its status
    and its cause, the missed target added; a failure is left alone; no target: NaN."""
    values = {"D": 10.0, "D_err": 0.05, "P": 21.0, "P_err": 0.5}
    v = dict(values)
    assert judge(None, v, "ok", "", 4.0) == ("ok", "")
    assert math.isnan(v["time_to_target"]) and v["D_rel_err"] == pytest.approx(0.005)
    t = ErrorTarget(D=0.001)
    v = dict(values)
    status, diag = judge(t, v, "not_converged", "slab not steady", 4.0, P0=1.0)
    assert status == "not_converged" and diag.startswith("slab not steady; target not reached")
    assert v["P_rel_err"] == pytest.approx(0.5 / 20.0)
    # law T^-1/2: 0.5 % -> 0.1 % needs 25 times as long
    assert v["time_to_target"] == pytest.approx(100.0)
    assert judge(t, dict(values), "too_noisy", "x", 4.0) == ("too_noisy", "x")
    status, _ = judge(ErrorTarget(D=0.01), dict(values), "ok", "", 4.0)
    assert status == "ok"


def test_error_exponent_finds_the_law_and_holds_its_range():
    T = np.array([1.0, 2.0, 4.0, 8.0])
    assert error_exponent(T, 0.1 * T**-0.5) == pytest.approx(-0.5)
    assert error_exponent(T, 0.1 * T**-1.0) == pytest.approx(-1.0)
    assert error_exponent(T, 0.1 * T**-3.0) == -1.0  # steeper than a bounded signal: held
    assert error_exponent(T, 0.1 * T**0.5) == -0.5  # errors growing: the slow law
    assert error_exponent([1.0], [0.1]) == K_DEFAULT
    assert time_to_target(2.0, 0.01, 0.005, -1.0) == pytest.approx(4.0)
    assert time_to_target(2.0, 0.004, 0.005, -0.5) == 2.0


QUICK = Path(__file__).resolve().parents[2] / "config" / "quick.yaml"


def _cfg(**top) -> dict:
    cfg = yaml.safe_load(QUICK.read_text())
    cfg.pop("target", None)  # the quick try's own; each test sets what it checks
    cfg.update(top)
    return cfg


def _scene(cfg: dict) -> dict:
    return next(iter(validate_config(cfg)["scenes"].values()))


@pytest.mark.parametrize(
    ("target", "words"),
    [
        ({"D": 0.0}, "target.D = 0.0: out of range; allowed range (0.0, 1.0]"),
        ({"P": -0.1}, "target.P = -0.1: out of range; allowed range (0.0, 1.0]"),
        ({"D": 1.5}, "target.D = 1.5: out of range; allowed range (0.0, 1.0]"),
        ({"cpu_s": 10.0}, "target = {'cpu_s': 10.0}: asks for no error; give D or P"),
        ({"D": 0.01, "cpu_s": 0.01}, "target.cpu_s = 0.01: below one control window"),
        ({"D": 0.01, "dt": 1}, "unknown key(s) ['dt']"),
    ],
)
def test_a_bad_target_is_refused_naming_key_and_range(target, words):
    with pytest.raises(ConfigError, match=None) as exc:
        _scene(_cfg(target=target))
    assert words in str(exc.value), str(exc.value)


def test_a_budget_is_checked_only_where_a_window_runs():
    """A piston-only scene holds no control window: a small budget is its own business."""
    sc = _scene(_cfg(target={"D": 0.01, "cpu_s": 0.01}, schemes=["piston"]))
    assert sc["target"]["cpu_s"] == 0.01


def test_scenes_inherit_the_top_level_target_and_the_tolerance_follows_it():
    """A scene without its own target takes the top level's; shock.residual_tol becomes
    TOL_PER_TARGET times the larger error asked, unless the scene gives it; a scene's own
    target wins over the top level's."""
    sc = _scene(_cfg(target={"D": 0.002, "P": 0.004}))
    assert sc["target"] == {"D": 0.002, "P": 0.004}
    assert sc["shock"]["residual_tol"] == pytest.approx(TOL_PER_TARGET * 0.004)
    loose = _scene(_cfg(target={"D": 0.5}))
    assert loose["shock"]["residual_tol"] == 1.0  # held in its range
    cfg = _cfg(target={"D": 0.002})
    own = copy.deepcopy(cfg)
    name = next(iter(own["scenes"]))
    own["scenes"][name]["shock"]["residual_tol"] = 0.02
    own["scenes"][name]["target"] = {"P": 0.01}
    sc = _scene(own)
    assert sc["target"] == {"P": 0.01} and sc["shock"]["residual_tol"] == 0.02
    assert _scene(_cfg())["shock"]["residual_tol"] == 0.01  # no target: the schema's


# -- schemes: [auto] -------------------------------------------------------------------------

LAWS = {
    "machine": "test", "date": "2026-12-07",
    "solvers": {"md": {"piston": {"c": 1e-3, "m": -2.0, "targets": [0.001, 0.01]},
                       "amw": {"c": 1.0, "m": -1.0, "targets": [0.001, 0.01]}}},
}  # fmt: skip


def test_auto_takes_the_cheaper_law_at_the_target():
    """cpu = c t^m: the piston's t^-2 against the window's t^-1 cross at t = 0.1 %; looser
    targets go to the piston, tighter ones to AMW, and the reason quotes both costs. A law
    without u_p holds at every u_p."""
    assert cost_laws.choose("md", 0.005, 1.0, LAWS)[0] == "piston"
    scheme, why = cost_laws.choose("md", 0.0005, 3.0, LAWS)
    assert scheme == "amw"
    assert "auto at u_p = 3: amw, 2e+03 s a point against piston 4e+03 s" in why
    assert "extrapolated" in why  # 0.05 % lies outside the measured 0.1-1 %
    assert "extrapolated" not in cost_laws.choose("md", 0.005, 3.0, LAWS)[1]
    with pytest.raises(KeyError):
        cost_laws.choose("csph", 0.01, 1.0, LAWS)


# Laws measured at two u_p: the piston's cost at 0.5 % falls 100 -> 10 s from u_p 1 to 3,
# the window's stays 30 s; log-linear in u_p between them, they cross where
# log 100 + w (log 10 - log 100) = log 30, w = log(10/3) / log 10 = 0.523, u_p = 2.05.
PER_U = {
    "machine": "test", "date": "2026-12-07",
    "solvers": {"md": {
        "piston": [{"u_p": 1.0, "c": 100.0 * 0.005**2, "m": -2.0, "targets": [0.001, 0.01]},
                   {"u_p": 3.0, "c": 10.0 * 0.005**2, "m": -2.0, "targets": [0.001, 0.01]}],
        "amw": [{"u_p": 1.0, "c": 30.0 * 0.005, "m": -1.0, "targets": [0.001, 0.01]},
                {"u_p": 3.0, "c": 30.0 * 0.005, "m": -1.0, "targets": [0.001, 0.01]}],
    }},
}  # fmt: skip


def test_auto_interpolates_the_laws_in_u_p():
    """Between the measured u_p the log of the cost is linear in u_p (the worked crossing
    above), beyond them the nearest u_p's law holds and the reason says it extrapolated."""
    piston = PER_U["solvers"]["md"]["piston"]
    assert cost_laws.cost(piston, 0.005, 1.0) == (pytest.approx(100.0), True)
    assert cost_laws.cost(piston, 0.005, 2.0)[0] == pytest.approx(math.sqrt(100.0 * 10.0))
    assert cost_laws.cost(piston, 0.005, 4.0) == (pytest.approx(10.0), False)
    assert cost_laws.cost(piston, 0.005, 0.5) == (pytest.approx(100.0), False)
    assert cost_laws.choose("md", 0.005, 2.0, PER_U)[0] == "amw"
    assert cost_laws.choose("md", 0.005, 2.1, PER_U)[0] == "piston"
    scheme, why = cost_laws.choose("md", 0.005, 0.5, PER_U)
    assert scheme == "amw" and "measured at u_p 1, 3" in why and "extrapolated" in why
    assert "extrapolated" not in cost_laws.choose("md", 0.005, 1.5, PER_U)[1]


def test_auto_is_resolved_before_any_job(monkeypatch):
    """The scene lists the chosen schemes itself, which at each u_p, and why; auto without
    target.D, or for a solver the cost data has no laws for, is refused naming the key."""
    monkeypatch.setattr(cost_laws, "load", lambda: LAWS)
    sc = _scene(_cfg(schemes=["auto"], target={"D": 0.005}))
    assert sc["schemes"] == ["piston"] and sc["scheme_at"] == [["piston"]] * 3
    assert [w.split(":")[0] for w in sc["scheme_choice"]] == [
        "auto at u_p = 2", "auto at u_p = 3", "auto at u_p = 4"]  # fmt: skip
    assert scheme_choice_at(sc, 3.0).startswith("auto at u_p = 3: piston")
    sc = _scene(_cfg(schemes=["auto", "amw"], target={"D": 0.0005}))
    assert sc["schemes"] == ["amw"]
    monkeypatch.setattr(cost_laws, "load", lambda: PER_U)
    cfg = _cfg(schemes=["auto", "mw"], target={"D": 0.005})
    next(iter(cfg["scenes"].values()))["shock"]["u_p"] = [1.0, 2.0, 3.0]
    sc = _scene(cfg)
    assert sc["schemes"] == ["amw", "piston", "mw"]
    assert sc["scheme_at"] == [["amw", "mw"], ["amw", "mw"], ["piston", "mw"]]
    assert scene_points(sc) == [("amw", 1.0), ("amw", 2.0), ("piston", 3.0),
                                ("mw", 1.0), ("mw", 2.0), ("mw", 3.0)]  # fmt: skip
    assert scheme_choice_at(sc, 3.0).startswith("auto at u_p = 3: piston, 10 s")
    with pytest.raises(ConfigError) as exc:
        _scene(_cfg(schemes=["auto"], target={"P": 0.005}))
    assert (
        "schemes = ['auto'], inherited as scenes.lj_quick.schemes: auto chooses by the CPU to "
        "state D to scenes.lj_quick.target.D, which is not given" in str(exc.value)
    )
    monkeypatch.setattr(cost_laws, "load", lambda: {"solvers": {}})
    with pytest.raises(ConfigError) as exc:
        _scene(_cfg(schemes=["auto"], target={"D": 0.005}))
    assert "auto needs measured cost laws" in str(exc.value)
    assert "none for solver 'md'" in str(exc.value)


def test_named_schemes_run_at_every_u_p():
    """Without auto a scene's points are every scheme (here the config's, inherited) at every
    u_p, scheme by scheme."""
    cfg = validate_config(_cfg(schemes=["piston", "amw"]))
    sc = next(iter(cfg["scenes"].values()))
    assert "scheme_at" not in sc and scheme_choice_at(sc, 2.0) == ""
    assert scene_points(sc, cfg["schemes"]) == [
        (s, u) for s in ("piston", "amw") for u in (2.0, 3.0, 4.0)
    ]


def test_the_shipped_cost_laws_choose_the_piston_loose_and_the_window_tight():
    """The measured laws (LJ liquid, benchmarks/target_cost.py) carry their machine and
    date, and their curves cross between 1 % and 0.1 %: the piston at 1 %, AMW at 0.1 %
    (measured: piston 9-65 s against AMW 62-85 s at 1 %, 1060-3796 s against 118-140 s
    at 0.1 %); at 0.5 % the weak shock goes to AMW (u_p 1: 93 s against the piston's
    221 s), the stronger to the piston (u_p 2: 37 s against 62 s)."""
    data = cost_laws.load()
    assert data["machine"] and data["date"] and cost_laws.finite_laws(data)
    assert cost_laws.solvers_with_laws(data) == ["md"]
    for u in (1.0, 2.0):
        assert cost_laws.choose("md", 0.01, u, data)[0] == "piston"
        assert cost_laws.choose("md", 0.001, u, data)[0] == "amw"
    assert cost_laws.choose("md", 0.005, 1.0, data)[0] == "amw"
    assert cost_laws.choose("md", 0.005, 2.0, data)[0] == "piston"


def test_a_resolved_choice_validates_again_and_a_bad_one_is_refused():
    """The shipped config (``schemes: [auto]``) validated twice gives the same config; a
    ``scheme_at`` with a scheme the scene does not run, or not one entry a u_p, is refused
    naming the key."""
    cfg = validate_config(yaml.safe_load((QUICK.parent / "config.yaml").read_text()))
    assert validate_config(copy.deepcopy(cfg)) == cfg
    sc = cfg["scenes"]["lj_liquid"]
    assert sc["scheme_at"][0] == ["amw"] and sc["scheme_at"][-1] == ["piston"]
    bad = copy.deepcopy(cfg)
    bad["scenes"]["lj_liquid"]["scheme_at"][0] = ["mw"]
    with pytest.raises(ConfigError) as exc:
        validate_config(bad)
    assert "scenes.lj_liquid.scheme_at[0] = ['mw']: ['mw'] not in the scene's schemes" in str(
        exc.value
    )
    bad = copy.deepcopy(cfg)
    bad["scenes"]["lj_liquid"]["scheme_choice"] = ["one reason"]
    with pytest.raises(ConfigError) as exc:
        validate_config(bad)
    assert "scenes.lj_liquid.scheme_choice: 1 entries for 5 u_p" in str(exc.value)
