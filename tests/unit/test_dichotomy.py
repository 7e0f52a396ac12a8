"""The dichotomy's loop state (hugomap.methods.dichotomy) on synthetic slopes.

Reference: a linear ⟨dω/dt⟩(u_out) = c (u_out − u*) with a known root u*; bisection must end
with a bracket narrower than the tolerance that contains u*, and the regula-falsi root of a
linear function is exact (to rounding). Loops that cannot converge must end with a reason.
"""

from __future__ import annotations

import pytest

from hugomap.methods import dichotomy as dich

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


def _run_noisy(slope, err: float, u0: float, p: dich.DichotomyParams) -> dict:
    s = dich.initial_state(u0, p)
    for _ in range(100):
        if s["done"]:
            return s
        trials = [{"u_out": u, "slope": slope(u), "slope_err": err} for u in s["pending"]]
        s = dich.update(s, trials, p)
    raise AssertionError("the loop did not end")


def test_a_trial_at_the_root_within_its_error_stops_the_bisection():
    # ⟨dω/dt⟩ = (u_out − u*)/L with L = 50 (the Galilean response) and an error of 0.002:
    # |slope| <= 2 s within 0.2 of the root. From the bracket [-9.1, -8.3] the midpoint
    # -8.7 is 0.1 from the root: the loop must stop there, not bisect on noise, and take the
    # root from the line through its three trials.
    p = dich.DichotomyParams(0.4, 1.0, 4, 20, 0.01, z=2.0)
    root = -8.6
    s = _run_noisy(lambda u: (u - root) / 50.0, 0.002, u0=-8.7, p=p)
    assert s["status"] == "ok" and s["stop"] == "noise"
    assert s["stop"] == "noise" and len(s["trials"]) == 3
    # the slopes are exactly linear: the weighted line through the trials gives the root
    assert s["u_out"] == pytest.approx(root, abs=1e-9)


def test_without_noise_the_bisection_runs_to_the_tolerance():
    s = _run(lambda u: 0.3 * (u + 8.4321), u0=-8.7)
    assert s["status"] == "ok" and s["stop"] == "tolerance"


def test_a_bracket_found_by_noise_is_too_noisy():
    # The LJ liquid at u_p = 0.5 with 2-τ trials (recorded): bracket ends 0.8 σ/τ apart,
    # front-speed errors 0.43 and 0.64 σ/τ, so the 0.8 difference is below 2 √(0.43² +
    # 0.64²) = 1.54: the sign change may be noise.
    p = dich.DichotomyParams(0.4, 1.0, 4, 20, 0.02, z=2.0)
    L = 50.0
    recorded = {-7.686: -0.068 / L, -6.886: 0.924 / L}
    s = dich.initial_state(-7.286, p)
    trials = [{"u_out": u, "slope": recorded[round(u, 3)],
               "slope_err": (0.431 if u < -7.3 else 0.644) / L} for u in s["pending"]]  # fmt: skip
    s = dich.update(s, trials, p)
    assert s["done"] and s["status"] == "too_noisy" and "trial_time" in s["reason"]
    assert s["u_out"] is None and s["pending"] == []
