"""The dichotomy's loop state: bracket expansion and bisection on u_out (SEED-en.md, steps 3–4).

Every trial is an independent run from the same window checkpoint at one outflow velocity
u_out (the amplitude u_p = u_out − u_in held), measuring ⟨dω/dt⟩. In the window frame the
front drifts upstream (dω/dt > 0) when the window is slower than the shock, i.e. when u_out
is too large, so ⟨dω/dt⟩ grows with u_out and its root is the steady state, D = −u_in.

The state is a small JSON-able dict, written by one Snakemake checkpoint job per iteration:
    k, bracket [lo, hi] or None, trials (all so far), pending (u_out values the next
    iteration must run), done, status (running, ok, bracket_not_found, max_iterations),
    reason, u_out (the root, when ok), expansions.
A loop that cannot converge ends with a status and a reason; it never runs forever.
"""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class DichotomyParams:
    """half_width: initial bracket u_out0 ± half_width; growth: factor by which a side that
    has the wrong sign is pushed out; max_expansions, max_iterations: loop limits;
    tolerance: bracket width at which the bisection stops (all velocities in solver units)."""

    half_width: float
    growth: float
    max_expansions: int
    max_iterations: int
    tolerance: float


def initial_state(u_out0: float, p: DichotomyParams) -> dict:
    """Iteration 0: the two bracket runs, to be run in parallel."""
    return {
        "k": 0,
        "bracket": None,
        "trials": [],
        "pending": [u_out0 - p.half_width, u_out0 + p.half_width],
        "done": False,
        "status": "running",
        "reason": "",
        "u_out": None,
        "expansions": 0,
    }


def _sign(trial: dict) -> int:
    return 1 if trial["slope"] > 0 else -1


def update(state: dict, new_trials: list[dict], p: DichotomyParams) -> dict:
    """The next state from the trials of ``state['pending']`` (each: u_out, slope, ...)."""
    s = {**state, "k": state["k"] + 1, "trials": [*state["trials"], *new_trials]}
    s["pending"] = []
    if s["bracket"] is None:
        lo = min(s["trials"], key=lambda t: t["u_out"])
        hi = max(s["trials"], key=lambda t: t["u_out"])
        neg = [t for t in s["trials"] if _sign(t) < 0]
        pos = [t for t in s["trials"] if _sign(t) > 0]
        if neg and pos:
            # the tightest bracket among the trials: largest negative, smallest positive u_out
            a = max(neg, key=lambda t: t["u_out"])
            b = min(pos, key=lambda t: t["u_out"])
            if a["u_out"] < b["u_out"]:
                s["bracket"] = [a["u_out"], b["u_out"]]
        if s["bracket"] is None:
            if s["expansions"] >= p.max_expansions:
                return _finish(
                    s, "bracket_not_found",
                    f"<domega/dt> kept one sign over u_out in [{lo['u_out']:.4g}, "
                    f"{hi['u_out']:.4g}] after {s['expansions']} expansions",
                )  # fmt: skip
            width = hi["u_out"] - lo["u_out"]
            s["expansions"] += 1
            # All slopes positive: the window is too slow everywhere, lower u_out; and back.
            if not neg:
                s["pending"] = [lo["u_out"] - p.growth * width]
            else:
                s["pending"] = [hi["u_out"] + p.growth * width]
            return s
    else:
        lo, hi = s["bracket"]
        (t,) = new_trials
        s["bracket"] = [t["u_out"], hi] if _sign(t) < 0 else [lo, t["u_out"]]
    lo, hi = s["bracket"]
    if hi - lo <= p.tolerance:
        return _finish(s, "ok", "", root=_root(s))
    if s["k"] >= p.max_iterations:
        return _finish(
            s, "max_iterations",
            f"bracket [{lo:.5g}, {hi:.5g}] still wider than {p.tolerance:.3g} after "
            f"{s['k']} iterations",
        )  # fmt: skip
    s["pending"] = [0.5 * (lo + hi)]
    return s


def _root(s: dict) -> float:
    """The root within the final bracket: linear interpolation of the slopes at its ends
    (regula falsi), or the midpoint when they are not of opposite signs."""
    lo, hi = s["bracket"]
    ends = {}
    for t in s["trials"]:
        if t["u_out"] in (lo, hi):
            ends[t["u_out"]] = t["slope"]
    if len(ends) == 2 and ends[lo] <= 0 <= ends[hi] and ends[hi] > ends[lo]:
        return lo + (hi - lo) * (-ends[lo]) / (ends[hi] - ends[lo])
    return 0.5 * (lo + hi)


def _finish(s: dict, status: str, reason: str, root: float | None = None) -> dict:
    s.update(done=True, status=status, reason=reason, u_out=root, pending=[])
    return s
