"""An error target per scene: the accuracy a user asks for, and the verdict on a point.

``target: {D: δ_D, P: δ_P, cpu_s: B}`` asks that a point's stated standard errors meet

    D_err / D ≤ δ_D,    P_err / |P − P0| ≤ δ_P        (relative, dimensionless)

within a CPU budget of ``B`` seconds a point (its loading and window set-up counted, as its
``cpu_s`` is). A window's steady average goes on until they do (``methods.steady``); a
piston's error is fixed once its front nears the far end, so it is judged and told the
drive it would have needed. A point whose jump conditions close and whose slab is steady but
whose errors miss the target is ``target_not_reached`` (a measured point with its value);
a point that is not ok for a physical reason stays ``not_converged`` and its diagnostic says
the target was missed too.

How long a point would need follows its error-vs-time law err ∝ T^k: measured on the
point's own extended average where it has two or more lengths (k fitted in log–log, held in
[K_FASTEST, K_SLOWEST]), else k = −1/2, the law of a mean of correlated samples (the slowest
of the usual ones, so the time it states is not an underestimate). With the target the
jump-residual tolerance follows it (``config.TOL_PER_TARGET``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

# Error-vs-time exponents a point's law may take: a bounded signal's slope (a window's ω)
# falls as 1/T, a correlated mean as 1/√T; steeper or shallower fits are noise.
K_FASTEST, K_SLOWEST = -1.0, -0.5
K_DEFAULT = -0.5
# A window average with a target and no window.max_average_time may go on this many times
# its own average_time (the budget, target.cpu_s, may end it sooner).
AVERAGE_FACTOR = 10.0
QUANTITIES = ("D", "P")


@dataclass(frozen=True)
class ErrorTarget:
    """The scene's ``target`` block: relative standard errors ``D``, ``P`` (None: not asked)
    and the CPU budget ``cpu_s`` [s] per point (None: no budget)."""

    D: float | None = None
    P: float | None = None
    cpu_s: float | None = None

    @classmethod
    def of_scene(cls, scene: dict) -> ErrorTarget | None:
        """The validated scene's target, or None where it has none."""
        t = scene.get("target")
        if not t:
            return None
        return cls(D=t.get("D"), P=t.get("P"), cpu_s=t.get("cpu_s"))

    @staticmethod
    def relative_errors(values: dict, P0: float = 0.0) -> dict[str, float]:
        """D_err/D and P_err/|P − P0| of a point's values, P0 the pole's (NaN where it has
        none)."""
        D, P = (float(values.get(k, np.nan)) for k in ("D", "P"))
        return {
            "D": _ratio(values.get("D_err"), abs(D)),
            "P": _ratio(values.get("P_err"), abs(P - P0)),
        }

    def missed(self, values: dict, P0: float = 0.0) -> dict[str, tuple[float, float]]:
        """{quantity: (reached, target)} for each asked error above its target (an error
        that is NaN misses too: nothing was measured)."""
        rel = self.relative_errors(values, P0)
        out = {}
        for q in QUANTITIES:
            want = getattr(self, q)
            if want is not None and not rel[q] <= want:
                out[q] = (rel[q], float(want))
        return out


def _ratio(err, value: float) -> float:
    e = float(np.nan if err is None else err)
    return e / value if value > 0 and np.isfinite(e) else math.nan


def error_exponent(times: list[float], errors: list[float]) -> float:
    """The exponent k of err ∝ T^k from a point's errors at growing average lengths (a
    log–log line through them, held in [K_FASTEST, K_SLOWEST]); K_DEFAULT with fewer than
    two finite, positive pairs."""
    t = np.asarray(times, dtype=float)
    e = np.asarray(errors, dtype=float)
    use = np.isfinite(t) & np.isfinite(e) & (t > 0) & (e > 0)
    if use.sum() < 2 or np.ptp(np.log(t[use])) == 0:
        return K_DEFAULT
    k = float(np.polyfit(np.log(t[use]), np.log(e[use]), 1)[0])
    return min(max(k, K_FASTEST), K_SLOWEST)


def time_to_target(elapsed: float, reached: float, want: float, k: float) -> float:
    """The time T at which err = ``want`` on the law err = reached (T/elapsed)^k [the time
    unit of ``elapsed``]; ``elapsed`` itself where it is met already."""
    if not (np.isfinite(reached) and reached > want):
        return float(elapsed)
    return float(elapsed * (reached / want) ** (-1.0 / k))


def judge(
    target: ErrorTarget | None, values: dict, status: str, diagnostic: str, elapsed: float,
    P0: float = 0.0, exponents: dict[str, float] | None = None, what: str = "average",
    unit: str = "",
) -> tuple[str, str]:  # fmt: skip
    """The point's status and diagnostic against ``target`` (module docstring), and its
    ``values`` completed in place: ``target_D``, ``target_P``, ``D_rel_err``, ``P_rel_err``
    and ``time_to_target`` (the ``what`` time — a window's average, a piston's drive — the
    point would need, in the unit of ``elapsed``; NaN where there is no target); ``P0`` the
    pole's P, ``exponents`` the point's measured error laws (``error_exponent``). Only an
    ``ok`` point becomes ``target_not_reached``; other statuses keep theirs."""
    rel = ErrorTarget.relative_errors(values, P0)
    values["D_rel_err"], values["P_rel_err"] = rel["D"], rel["P"]
    values["target_D"] = math.nan if target is None or target.D is None else target.D
    values["target_P"] = math.nan if target is None or target.P is None else target.P
    values["time_to_target"] = math.nan
    if target is None or status not in ("ok", "not_converged"):
        return status, diagnostic
    missed = target.missed(values, P0)
    if not missed:
        values["time_to_target"] = float(elapsed)
        return status, diagnostic
    ks = exponents or {}
    need = {q: time_to_target(elapsed, r, w, ks.get(q, K_DEFAULT)) for q, (r, w) in missed.items()}
    values["time_to_target"] = max(need.values())
    parts = [
        f"{q}'s error {100 * r:.3g} % above target.{q} = {100 * w:.3g} %"
        + (f" (law T^{ks.get(q, K_DEFAULT):.2f}: ~{need[q]:.4g}{unit})" if np.isfinite(r) else "")
        for q, (r, w) in missed.items()
    ]
    note = f"target not reached after {elapsed:.4g}{unit} of {what}: " + "; ".join(parts)
    if status == "ok":
        return "target_not_reached", note
    return status, f"{diagnostic}; {note}" if diagnostic else note


__all__ = [
    "AVERAGE_FACTOR",
    "ErrorTarget",
    "error_exponent",
    "judge",
    "time_to_target",
]
