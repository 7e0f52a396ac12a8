"""The dichotomy's loop state (hugomap.window.dichotomy) on synthetic slopes.

Reference: a linear ⟨dω/dt⟩(u_out) = c (u_out − u*) with a known root u*; bisection must end
with a bracket narrower than the tolerance that contains u*, and the regula-falsi root of a
linear function is exact (to rounding). Loops that cannot converge must end with a reason.
"""

from __future__ import annotations

import pytest

from hugomap.window import dichotomy as dich

P = dich.DichotomyParams(
    half_width=0.4, growth=1.0, max_expansions=4, max_iterations=20, tolerance=0.01
)


def _run(slope, u0: float, p: dich.DichotomyParams = P) -> dict:
    s = dich.initial_state(u0, p)
    for _ in range(100):  # far more than any loop may take
        if s["done"]:
            return s
        trials = [{"u_out": u, "slope": slope(u), "slope_err": 0.0} for u in s["pending"]]
        s = dich.update(s, trials, p)
    raise AssertionError("the loop did not end")


@pytest.mark.parametrize("root", [-8.7, -8.4321, -9.0777])  # on and off the midpoints
def test_bisection_finds_the_root(root):
    s = _run(lambda u: 0.3 * (u - root), u0=-8.7)
    assert s["status"] == "ok"
    lo, hi = s["bracket"]
    assert lo <= root <= hi and hi - lo <= P.tolerance
    assert s["u_out"] == pytest.approx(root, abs=1e-9)  # linear: regula falsi is exact


def test_bracket_is_expanded_until_the_sign_changes():
    root = -6.0  # 2.7 above the start: needs expansions upward
    s = _run(lambda u: 0.3 * (u - root), u0=-8.7)
    assert s["status"] == "ok" and s["expansions"] >= 1
    assert s["u_out"] == pytest.approx(root, abs=1e-9)


def test_no_sign_change_ends_with_bracket_not_found():
    s = _run(lambda u: 1.0, u0=-8.7)
    assert s["status"] == "bracket_not_found"
    assert s["expansions"] == P.max_expansions and "expansions" in s["reason"]
    assert s["u_out"] is None and s["pending"] == []


def test_iteration_limit_ends_with_max_iterations():
    p = dich.DichotomyParams(0.4, 1.0, 4, 3, 1e-6)
    s = _run(lambda u: u + 8.6, u0=-8.7, p=p)
    assert s["status"] == "max_iterations" and s["k"] == 3 and "still wider" in s["reason"]
