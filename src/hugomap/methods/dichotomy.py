"""The dichotomy's loop state: bracket expansion and bisection on u_out (SEED-en.md, steps 3–4).

Every trial is an independent run from the same window checkpoint at one outflow velocity
u_out (the amplitude u_p = u_out − u_in held), measuring ⟨dω/dt⟩. In the window frame the
front drifts upstream (dω/dt > 0) when the window is slower than the shock, i.e. when u_out
is too large, so ⟨dω/dt⟩ grows with u_out and its root is the steady state, D = −u_in.

The state is a small JSON-able dict, written by one Snakemake checkpoint job per iteration:
    k, bracket [lo, hi] or None, trials (all so far), pending (u_out values the next
    iteration must run), done, status (running, ok, bracket_not_found, max_iterations,
    too_noisy), reason, u_out (the root, when ok), stop (how an ok loop ended: tolerance or
    noise), expansions.
A loop that cannot converge ends with a status and a reason; it never runs forever.

Noise (each trial's slope carries its standard error s, ``slope_err``). Every trial restarts
from the same checkpoint at a Galilean-shifted frame, so the slope is linear in u_out with
the known coefficient 1/L, and two trials differ by (u_2 − u_1)/L plus noise:
- a bracket whose two end slopes do not differ by more than z √(s_1² + s_2²) was found by
  noise, not by the root: the loop ends as ``too_noisy`` (a longer trial_time is needed);
  on the LJ liquid at u_p = 0.5 every trial of a 2-τ bisection had |slope| < 2 s and the
  "root" it bisected onto gave D 3.5 % high;
- a bisection trial whose |slope| ≤ z s is at the root within the resolution of a trial:
  the loop stops there (``stop`` = noise) instead of bisecting on noise, and the root is that
  of the weighted least-squares line slope = c (u_out − u*) through all trials (weights
  1/s²; the regula falsi of the bracket ends, generalised to every trial), kept inside the
  bracket. On the LJ liquid at u_p 1–3 the loop stopped after 3–4 trials where bisection to
  the 0.02 σ/τ tolerance took 8–9 (replayed from the recorded trials); taking the stopping
  trial's own u_out as the root instead left the front drifting at up to 0.3 σ/τ in the
  final run (P −2.9 % at u_p = 1.5).
"""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class DichotomyParams:
    """half_width: initial bracket u_out0 ± half_width; growth: factor by which a side that
    has the wrong sign is pushed out; max_expansions, max_iterations: loop limits;
    tolerance: bracket width at which the bisection stops (all velocities in solver units);
    z: a slope with |slope| ≤ z slope_err is zero (module docstring)."""

    half_width: float
    growth: float
    max_expansions: int
    max_iterations: int
    tolerance: float
    z: float = 2.0


def params_from_config(window: dict) -> DichotomyParams:
    """The loop's parameters from a scene's validated ``window`` config (its ``dichotomy``
    block and ``z``), in the solver's velocity units (σ/τ for MD, m/s for CSPH)."""
    d = window["dichotomy"]
    return DichotomyParams(
        half_width=d["half_width"], growth=d["growth"], max_expansions=d["max_expansions"],
        max_iterations=d["max_iterations"], tolerance=d["tolerance"], z=window["z"],
    )  # fmt: skip


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
        "stop": None,
        "expansions": 0,
    }


def _sign(trial: dict) -> int:
    return 1 if trial["slope"] > 0 else -1


def _err(trial: dict) -> float:
    """The slope's standard error (0 for a trial that has none, e.g. an exact one)."""
    e = trial.get("slope_err", 0.0)
    return float(e) if e is not None and e == e else 0.0


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
                diff = b["slope"] - a["slope"]
                noise = p.z * (_err(a) ** 2 + _err(b) ** 2) ** 0.5
                if not diff > noise:
                    return _finish(
                        s, "too_noisy",
                        f"the bracket's end slopes {a['slope']:.3g} +- {_err(a):.2g} and "
                        f"{b['slope']:.3g} +- {_err(b):.2g} (u_out {a['u_out']:.4g}, "
                        f"{b['u_out']:.4g}) differ by less than {p.z:g} standard errors: the "
                        "sign change is noise; lengthen dichotomy.trial_time or widen "
                        "dichotomy.half_width",
                    )  # fmt: skip
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
        if _err(t) > 0 and abs(t["slope"]) <= p.z * _err(t):
            # at the root within a trial's resolution: more bisection would follow noise
            return _finish(s, "ok", "", root=_fit_root(s), stop="noise")
    lo, hi = s["bracket"]
    if hi - lo <= p.tolerance:
        return _finish(s, "ok", "", root=_root(s), stop="tolerance")
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


def _fit_root(s: dict) -> float:
    """The root u* of the weighted least-squares line slope = c (u_out − u*) through every
    trial with a slope error (weights 1/s²), clipped to the bracket; the bracket's regula
    falsi (``_root``) when the line does not rise with u_out."""
    lo, hi = s["bracket"]
    pts = [(float(t["u_out"]), float(t["slope"]), _err(t)) for t in s["trials"]]
    pts = [(u, a, 1.0 / e**2) for u, a, e in pts if e > 0 and a == a]
    sw = sum(w for *_, w in pts)
    if len(pts) < 2 or sw <= 0:
        return _root(s)
    um = sum(u * w for u, _, w in pts) / sw
    am = sum(a * w for _, a, w in pts) / sw
    suu = sum(w * (u - um) ** 2 for u, _, w in pts)
    if suu <= 0:
        return _root(s)
    c = sum(w * (u - um) * (a - am) for u, a, w in pts) / suu
    if not c > 0:
        return _root(s)
    return min(max(um - am / c, lo), hi)


def _finish(
    s: dict, status: str, reason: str, root: float | None = None, stop: str | None = None
) -> dict:
    s.update(done=True, status=status, reason=reason, u_out=root, stop=stop, pending=[])
    return s
