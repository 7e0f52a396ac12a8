"""Why a Hugoniot point is or is not ``ok``: the closure test of a jump residual, the state
ahead of the front (seen at all; off the pole the jump is taken from), and the physical
causes measured on a point that keep its slab from being the steady shocked state the jump
conditions describe (``named_causes``). ``analysis.shock.measure_point`` decides a point's
status with these; the shock-frame schemes (``lammps.shockframe``) share the closure test.
"""

from __future__ import annotations

import numpy as np

from ..keys import MIN_SLAB_BINS
from ..states import Pole

CLOSE_SIGMAS = 3.0  # an ok point's jump residuals are within this many of their errors
# …or below this, whatever their errors: 0.01 % is below any Hugoniot's accuracy (the best
# measured ones hold to ~0.1 %) and about a deterministic solver's own discretisation error
# (CSPH copper at the default dx, 2000 m/s: mass 1e-5, energy 3.4e-5 of residual, its slab
# uniform to 1e-7, so a 3-error test alone would call that point a bias); an exact model's
# residuals are rounding (1e-13)
RESIDUAL_FLOOR = 1e-4
# a slab whose shear stress exceeds this fraction of P − P0 (and CLOSE_SIGMAS errors) is
# behind a front that has not yielded: a plastic state holds at most Y/2 (copper at 100 m/s:
# 0.06 of 3.6 GPa, 1.7 %), a uniaxial elastic one G/(K + 4G/3) ≈ 0.2 of its P − P0 in an
# isotropic metal, and EAM copper along [100] at 500 m/s 10 % (2.23 of 21.6 GPa)
ELASTIC_SHEAR_FRACTION = 0.05


CLOSURES = ("mass", "momentum", "energy", "flow")  # the residuals an ok point closes


def residual_text(values: dict, closures: tuple[str, ...] = CLOSURES) -> str:
    """The jump residuals and the slab's flow residual with their errors, one line; one
    that is not among ``closures`` is marked a diagnostic."""

    def one(k: str) -> str:
        err = values.get(f"residual_{k}_err", float("nan"))
        note = "" if k in closures else " (diagnostic)"
        return f"{k} {values['residual_' + k]:+.3%} ± {err:.2%}{note}"

    return "residuals: " + ", ".join(one(k) for k in CLOSURES if f"residual_{k}" in values)


def closes(r: float, err: float, tol: float) -> bool:
    """|r| ≤ tol and |r| ≤ ``CLOSE_SIGMAS`` errors (or ≤ ``RESIDUAL_FLOOR``)."""
    return bool(abs(r) <= tol and abs(r) <= max(CLOSE_SIGMAS * err, RESIDUAL_FLOOR))


def ahead_off_pole(
    values: dict, residual_tol: float, pole: Pole | None
) -> tuple[float, str, float] | None:
    """The state ahead's worst departure from the pole while the jump is taken from the pole
    (no ``two_wave``), as (fraction of the jump, field, departure), when it is off: its P, u,
    ρ or E differs from the pole's by more than ``CLOSE_SIGMAS`` of its error and more than
    ``residual_tol`` of the jump P − P0, u_p, ρ − ρ0, E − E0 [-]. Such a departure moves the
    jump residuals taken from the state ahead as measured by about that fraction (the
    momentum residual by δu/u_p, the energy residual by δE/(E − E0): material ahead that
    arrives warm, as a window's live inflow does at weak shocks), so the point does not
    close from what is actually ahead of it; else None."""
    if pole is None or values.get("two_wave", 0.0):
        return None
    ahead = (("P", values.get("ahead_P", np.nan) - pole.P0, values.get("P", np.nan) - pole.P0),
             ("u", values.get("ahead_u", np.nan), values.get("u_p", np.nan)),
             ("rho", values.get("ahead_rho", np.nan) - pole.rho0,
              values.get("rho", np.nan) - pole.rho0),
             ("E", values.get("ahead_E", np.nan) - pole.E0,
              values.get("E", np.nan) - pole.E0))  # fmt: skip
    worst = max(
        ((abs(d / j), k, d) for k, d, j in ahead
         if np.isfinite(d) and np.isfinite(j) and j != 0
         and abs(d) > CLOSE_SIGMAS * values.get(f"ahead_{k}_err", np.inf)),
        default=(0.0, "", 0.0),
    )  # fmt: skip
    return worst if worst[0] > residual_tol else None


def shear_stress(values: dict) -> tuple[float, float]:
    """τ = (P_xx − (P_yy + P_zz)/2)/2 of the slab behind the front and its standard error
    from P_xx's, P_yy's and P_zz's, taken as independent (their errors are positively
    correlated, so this overstates τ's) [stress units of the point]."""
    P, Pyy, Pzz = (values.get(k, np.nan) for k in ("P", "Pyy", "Pzz"))
    e = [values.get(f"{k}_err", np.nan) for k in ("P", "Pyy", "Pzz")]
    tau = 0.5 * (P - 0.5 * (Pyy + Pzz))
    return float(tau), float(0.5 * np.sqrt(e[0] ** 2 + 0.25 * (e[1] ** 2 + e[2] ** 2)))


def elastic_front(values: dict, pole: Pole | None) -> bool:
    """Whether the slab behind the front holds shear as an elastic (uniaxially strained)
    state does: its shear stress (``shear_stress``, in the sense of the jump P − P0) above
    ``ELASTIC_SHEAR_FRACTION`` of P − P0 and ``CLOSE_SIGMAS`` of its error. Such a front has
    not yielded (a perfect crystal below its plastic threshold), and its state lies on the
    uniaxial elastic branch, not on the hydrostatic Hugoniot a plastic front reaches."""
    if pole is None:
        return False
    jump = values.get("P", np.nan) - pole.P0
    tau, err = values.get("shear_stress", np.nan), values.get("shear_stress_err", np.nan)
    lead = tau * np.sign(jump)
    return bool(np.isfinite(lead) and lead > ELASTIC_SHEAR_FRACTION * abs(jump)
                and lead > CLOSE_SIGMAS * err)  # fmt: skip


def elastic_text(values: dict, pole: Pole) -> str:
    """The named cause of a point whose front has not yielded (``elastic_front``)."""
    return (
        f"front not yielded: the slab holds a shear stress of {values['shear_stress']:.4g}"
        f" ± {values['shear_stress_err']:.2g}, "
        f"{values['shear_stress'] / (values['P'] - pole.P0):.1%} of P − P0: an elastic, "
        "uniaxially strained state (a crystal below its plastic threshold), to be compared "
        "with the elastic branch, not the hydrostatic Hugoniot"
    )


def ahead_seen(values: dict) -> bool:
    """Whether the state ahead of the front was measured: ρ, u and P of the slab ahead
    finite (some sample had a slab of ``MIN_SLAB_BINS`` bins clear of the front and of the
    far boundary by ``shock.gap``)."""
    return all(np.isfinite(values.get(f"ahead_{k}", np.nan)) for k in ("rho", "u", "P"))


def named_causes(
    values: dict,
    residual_tol: float,
    spread: dict[str, tuple[float, float]] | None = None,
    pole: Pole | None = None,
    flow_closes: bool = True,
) -> list[str]:
    """Physical causes, measured on the point, that keep its slab from being the steady
    shocked state the jump conditions describe. (A porous slab whose pores stay partly
    open is not one: a steady, uniform slab at distention α > 1 is a Hugoniot state of the
    porous body, compared with the Hugoniot at its own α, ``analysis.porous``; pores still
    closing show as a slab not uniform or not steady.)
    - where the flow is only a diagnostic (a window: not ``flow_closes``), the slab moving
      relative to the boundary behind it by more than ``residual_tol`` of u_p and
      ``CLOSE_SIGMAS`` errors: the shocked region between them is not uniform (porous
      copper at 300 m/s in AMW's window: the slab 1.96 ± 0.12 % slower than the outflow,
      pores still closing behind it, energy residual −3.2 ± 1.1 %);
    - the slab still flows relative to the boundary behind it (``residual_flow`` does not
      close, where it is a closure: ``flow_closes``): a weak front's relaxation tail or
      acoustic ringing between the boundary and the front, averaged over too short a run (the LJ liquid's default 80-cell piston, u_p
      = 1: the material 12-20 σ behind the front moves at 0.96-0.98 u_p, the whole shocked
      column at −0.02 to −0.035 σ/τ in the piston frame for 10 τ, and the wall's pressure
      is 1.4 % below the Rayleigh line);
    - a slab that is not uniform or not steady: ``spread[k]`` = (near half − far half, late
      half of the samples − early half) of field k beyond their noise (``measure_point``)
      larger than ``residual_tol`` of the jump k − k0 in ρ, P or E (a relaxation zone, the
      tail of a broad front; the state still changing);
    - no state ahead measured (``ahead_seen``): a point is not ``ok`` without it;
    - the state ahead off the pole while the jump is taken from the pole (no ``two_wave``):
      its P, u, ρ or E differs from the pole's by more than ``CLOSE_SIGMAS`` errors and
      ``residual_tol`` of the jump (AMW on the default liquid at u_p = 3: the material
      between the inflow and the front moves at +0.064 ± 0.008 σ/τ, P +0.40 ± 0.02 above P0,
      1.4 % of the jump)."""
    out = []
    spread = spread or {}
    jumps = {} if pole is None else {
        k: values.get(k, np.nan) - k0
        for k, k0 in (("rho", pole.rho0), ("P", pole.P0), ("E", pole.E0))}  # fmt: skip
    for i, (what, how) in enumerate(
        (("slab not uniform", "its near and far halves differ by"),
         ("slab not steady", "its state moved between the run's halves by"))
    ):  # fmt: skip
        worst = max(
            ((abs(spread[k][i] / j), k) for k, j in jumps.items()
             if k in spread and np.isfinite(j) and j != 0 and np.isfinite(spread[k][i])),
            default=(0.0, ""),
        )  # fmt: skip
        if worst[0] > residual_tol:
            out.append(f"{what}: {how} {worst[0]:.2%} of the jump in {worst[1]} beyond their "
                       "noise (a relaxation zone, a broad front's tail, a state still "
                       "changing): measure further behind the front (raise shock.gap past "
                       "the relaxation zone, with window.length to hold it) or later")  # fmt: skip
    r, e = values.get("residual_flow", np.nan), values.get("residual_flow_err", np.nan)
    if flow_closes and np.isfinite(r) and not closes(r, e, residual_tol):
        out.append(
            f"slab not at rest: it moves at "
            f"{values['u_p_measured'] - values['u_p']:+.3g} ± {values['u_p_measured_err']:.2g} "
            f"relative to the boundary behind it (u_p_measured {values['u_p_measured']:.5g}); "
            "a weak front's relaxation tail or ringing between that boundary and the front: "
            "measure further behind the front (shock.gap) or over a longer run"
        )
    elif not flow_closes and np.isfinite(r) and abs(r) > max(residual_tol, CLOSE_SIGMAS * e):
        out.append(
            f"shocked region not uniform: the slab moves {r:+.2%} ± {e:.2%} of u_p relative to "
            "the boundary behind it, beyond the tolerance and 3 errors, so the material between "
            "them is in another state (a relaxation zone longer than shock.gap, pores still "
            "closing, or the boundary's control ringing): the slab is not yet the end state"
        )
    if not ahead_seen(values):
        out.append(
            f"no state ahead measured: no sample had a slab of {MIN_SLAB_BINS} bins between "
            "shock.gap ahead of the front and shock.gap before the far boundary, so the jump "
            "starts from the pole unseen (a precursor or a disturbed inflow would go "
            "unnoticed): leave more room ahead of the front"
        )
    if elastic_front(values, pole):
        out.append(elastic_text(values, pole))
    off = ahead_off_pole(values, residual_tol, pole)
    if off is not None:
        frac, key, d = off
        out.append(
            f"state ahead off the pole: its {key} differs by {d:+.3g} ({frac:.2%} of the "
            f"jump, beyond {CLOSE_SIGMAS:g} errors) while the jump is taken from the pole "
            "(material the inflow or the far end disturbed; a compression wave ahead, denser "
            "and set moving in the sense of u_p, is read as a first wave)"
        )
    return out
