"""The measured cost laws, and the scheme ``schemes: [auto]`` chooses from them.

``cost_laws.json`` (package data, written by ``benchmarks/target_cost.py --laws`` from a run
of ``config/target_cost.yaml``, with its machine and date) holds per solver and scheme the
CPU a point needs to state D to a relative standard error t, at each piston velocity u_p
it was measured at (the solver's velocity unit),

    cpu_s(t, u_p_k) = c_k t^(m_k)        [s],

fitted over the targets its run reached. A weak shock costs the piston most (its front
wanders more against a smaller jump, so its sample must be longer), a window less, so the
choice depends on u_p as well as on t: between two measured u_p the log of the cost is
interpolated linearly in u_p, beyond them the nearest u_p's law is taken (a law without
``u_p`` holds at every u_p). ``choose`` takes the scheme of least cpu_s at the scene's
``target.D`` and the point's u_p: the choice compares laws measured on one scene, so what a
larger or smaller scene scales in both (its atoms) cancels; a target or u_p outside the
measured range is extrapolated, and the reason says so. Imports nothing of hugomap
(validation reads it).
"""

from __future__ import annotations

import json
import math
from importlib import resources

LAWS_FILE = "cost_laws.json"


def load() -> dict:
    """The cost data: ``{"machine", "date", "solvers": {solver: {scheme: [{u_p, c, m,
    targets}, ...]}}}`` (a scheme's single law may be given as one object); an empty
    ``solvers`` where the file is missing."""
    try:
        text = resources.files("hugomap").joinpath(LAWS_FILE).read_text()
    except (FileNotFoundError, OSError):
        return {"solvers": {}}
    return json.loads(text)


def _laws(entry) -> list[dict]:
    """A scheme's laws sorted by u_p (one law without ``u_p``: a one-element list)."""
    laws = [entry] if isinstance(entry, dict) else list(entry)
    return sorted(laws, key=lambda law: float(law.get("u_p", 0.0)))


def solvers_with_laws(data: dict | None = None) -> list[str]:
    """The solvers the cost data has at least two schemes' laws for (a choice needs two)."""
    data = load() if data is None else data
    return sorted(s for s, laws in data.get("solvers", {}).items() if len(laws) >= 2)


def cost(entry, target_D: float, u_p: float) -> tuple[float, bool]:
    """(cpu_s, inside): one scheme's CPU to state D to ``target_D`` at ``u_p`` (module
    docstring: log-linear in u_p between measured u_p, the nearest beyond them), and whether
    both lie inside what its laws were measured on."""
    laws = _laws(entry)
    at = [float(law["u_p"]) for law in laws if "u_p" in law]

    def one(law: dict) -> float:
        return float(law["c"]) * target_D ** float(law["m"])

    def measured(law: dict) -> bool:
        return min(law["targets"]) <= target_D <= max(law["targets"])

    if len(at) < len(laws) or len(laws) == 1:
        return one(laws[0]), measured(laws[0]) and (not at or at[0] == u_p)
    if u_p <= at[0] or u_p >= at[-1]:
        law = laws[0] if u_p <= at[0] else laws[-1]
        return one(law), measured(law) and u_p in (at[0], at[-1])
    k = next(i for i in range(1, len(at)) if u_p <= at[i])
    w = (u_p - at[k - 1]) / (at[k] - at[k - 1])
    lo, hi = laws[k - 1], laws[k]
    log_cost = (1.0 - w) * math.log(one(lo)) + w * math.log(one(hi))
    return math.exp(log_cost), measured(lo) and measured(hi)


def _where(laws: dict) -> str:
    """The u_p the laws were measured at, as the reason quotes them."""
    ups = sorted({float(law["u_p"]) for e in laws.values() for law in _laws(e) if "u_p" in law})
    return f" at u_p {', '.join(f'{u:g}' for u in ups)}" if ups else ""


def choose(solver: str, target_D: float, u_p: float, data: dict | None = None) -> tuple[str, str]:
    """(scheme, reason): the scheme of least cpu_s (``cost``) at t = ``target_D`` and
    ``u_p`` among the solver's laws; KeyError where the solver has fewer than two."""
    data = load() if data is None else data
    laws = data.get("solvers", {}).get(solver, {})
    if len(laws) < 2:
        raise KeyError(solver)
    got = {s: cost(entry, target_D, u_p) for s, entry in laws.items()}
    best = min(got, key=lambda s: got[s][0])
    others = ", ".join(f"{s} {got[s][0]:.3g} s" for s in sorted(got) if s != best)
    reason = (
        f"auto at u_p = {u_p:g}: {best}, {got[best][0]:.3g} s a point against {others} for "
        f"D to {100 * target_D:g} % by the cost laws cpu_s = c t^m measured{_where(laws)} "
        f"on {data.get('date', '?')} ({data.get('machine', '?')})"
        + ("" if all(inside for _, inside in got.values()) else
           ", extrapolated beyond the targets or u_p they were measured on")
    )  # fmt: skip
    return best, reason


def finite_laws(data: dict) -> bool:
    """Every law of the data has finite c and m."""
    return all(
        math.isfinite(float(law["c"])) and math.isfinite(float(law["m"]))
        for laws in data.get("solvers", {}).values()
        for entry in laws.values()
        for law in _laws(entry)
    )


__all__ = ["LAWS_FILE", "choose", "cost", "finite_laws", "load", "solvers_with_laws"]
