"""The measured cost laws, and the scheme ``schemes: [auto]`` chooses from them.

``cost_laws.json`` (package data, written by ``benchmarks/target_cost.py --laws`` from a run
of ``config/target_cost.yaml``, with its machine and date) holds per solver and scheme the
CPU a point needs to state D to a relative standard error t,

    cpu_s(t) = c t^m        [s],

fitted over the targets its run reached. ``choose`` takes the scheme of least cpu_s at the
scene's ``target.D``: the choice compares laws measured on one scene, so what a larger or
smaller scene scales in both (its atoms) cancels; a target outside the measured range is
extrapolated, and the reason says so. Imports nothing of hugomap (validation reads it).
"""

from __future__ import annotations

import json
import math
from importlib import resources

LAWS_FILE = "cost_laws.json"


def load() -> dict:
    """The cost data: ``{"machine", "date", "solvers": {solver: {scheme: {c, m,
    targets}}}}``; an empty ``solvers`` where the file is missing."""
    try:
        text = resources.files("hugomap").joinpath(LAWS_FILE).read_text()
    except (FileNotFoundError, OSError):
        return {"solvers": {}}
    return json.loads(text)


def solvers_with_laws(data: dict | None = None) -> list[str]:
    """The solvers the cost data has at least two schemes' laws for (a choice needs two)."""
    data = load() if data is None else data
    return sorted(s for s, laws in data.get("solvers", {}).items() if len(laws) >= 2)


def choose(solver: str, target_D: float, data: dict | None = None) -> tuple[str, str]:
    """(scheme, reason): the scheme of least cpu_s = c t^m at t = ``target_D`` among the
    solver's laws; KeyError where the solver has fewer than two."""
    data = load() if data is None else data
    laws = data.get("solvers", {}).get(solver, {})
    if len(laws) < 2:
        raise KeyError(solver)
    cost = {s: float(law["c"]) * target_D ** float(law["m"]) for s, law in laws.items()}
    best = min(cost, key=lambda s: cost[s])
    lo, hi = (
        (min(law["targets"]) for law in laws.values()),
        (max(law["targets"]) for law in laws.values()),
    )
    inside = max(lo) <= target_D <= min(hi)
    others = ", ".join(f"{s} {cost[s]:.3g} s" for s in sorted(cost) if s != best)
    reason = (
        f"auto: {best}, {cost[best]:.3g} s a point against {others} for D to "
        f"{100 * target_D:g} % by the cost laws cpu_s = c t^m measured on "
        f"{data.get('date', '?')} ({data.get('machine', '?')})"
        + ("" if inside else ", extrapolated beyond the targets they were measured on")
    )
    return best, reason


def finite_laws(data: dict) -> bool:
    """Every law of the data has finite c and m."""
    return all(
        math.isfinite(float(law["c"])) and math.isfinite(float(law["m"]))
        for laws in data.get("solvers", {}).values()
        for law in laws.values()
    )


__all__ = ["LAWS_FILE", "choose", "finite_laws", "load", "solvers_with_laws"]
