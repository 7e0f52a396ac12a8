"""A pint unit registry that knows the Lennard-Jones reduced units (for tests and analysis,
never for kernels; needs ``pint``, which the ``test`` extra installs).

In a plain pint registry ``sigma`` is the Stefan–Boltzmann constant, so ``sigma**-3`` is
not a number density. ``registry()`` redefines the four LJ symbols:

- without ``lj``: σ (``sigma``, length), ε (``epsilon``, energy) and m (``lj_mass``, mass)
  are base units of their own dimensions ``[lj_length]``, ``[lj_energy]``, ``[lj_mass]``,
  and τ = σ √(m/ε) (``tau``); a reduced quantity then converts only to reduced units, and
  k_B = 1 is ``k_B = epsilon / lj_temperature``, with ``lj_temperature`` ε/k_B.
- with ``lj`` = {sigma [m], epsilon_over_kB [K], mass [kg]} (an MD scene's ``units``
  block), the same names are defined from SI: σ, ε = k_B (ε/k_B), m, τ = σ √(m/ε), and
  ``lj_temperature`` = ε/k_B, so a reduced value converts to SI (``(2.0 * ureg("sigma /
  tau")).to("m/s")``).

The reduced unit strings of ``io.dataset`` (``reduced_units`` in the files, e.g.
``"epsilon sigma^-3"``, ``"epsilon k_B^-1"``) parse with ``quantity``.
"""

from __future__ import annotations

from collections.abc import Mapping

import pint

ARGON = {"sigma": 3.405e-10, "epsilon_over_kB": 119.8, "mass": 6.63e-26}
"""An argon-like LJ set: σ [m], ε/k_B [K], m [kg] (the values of the scene schema's
example)."""


def registry(lj: Mapping[str, float] | None = None) -> pint.UnitRegistry:
    """A pint registry in which ``sigma``, ``epsilon``, ``tau``, ``lj_mass``,
    ``lj_temperature`` and ``k_B`` are the LJ units: reduced base units when ``lj`` is None,
    else defined from its SI values (σ [m], ε/k_B [K], m [kg])."""
    ureg = pint.UnitRegistry(on_redefinition="ignore")
    if lj is None:
        ureg.define("sigma = [lj_length]")
        ureg.define("epsilon = [lj_energy]")
        ureg.define("lj_mass = [lj_mass]")
    else:
        ureg.define(f"sigma = {float(lj['sigma'])!r} * meter")
        ureg.define(f"epsilon = {float(lj['epsilon_over_kB'])!r} * kelvin * boltzmann_constant")
        ureg.define(f"lj_mass = {float(lj['mass'])!r} * kilogram")
    ureg.define("tau = sigma * (lj_mass / epsilon) ** 0.5")
    if lj is None:
        ureg.define("lj_temperature = [lj_temperature]")
    else:
        ureg.define(f"lj_temperature = {float(lj['epsilon_over_kB'])!r} * kelvin")
    ureg.define("k_B = epsilon / lj_temperature")
    return ureg


def quantity(value: float, reduced: str, ureg: pint.UnitRegistry) -> pint.Quantity:
    """``value`` in the reduced unit ``reduced`` as written by ``io.dataset`` (``^`` powers,
    space products, e.g. ``"epsilon sigma^-3"``) — per-atom quantities are per ``lj_mass``
    (m = 1): ``"sigma^3"`` (specific volume) is σ³/m, ``"epsilon"`` (specific energy) ε/m,
    ``"sigma^-3"`` (number density) m/σ³, so that they convert to m3 kg-1, J kg-1, kg m-3."""
    text = reduced.strip()
    per_mass = {"sigma^3": "sigma**3 / lj_mass", "epsilon": "epsilon / lj_mass",
                "sigma^-3": "lj_mass / sigma**3"}  # fmt: skip
    expr = per_mass.get(text) or " * ".join(t.replace("^", "**") for t in text.split())
    return value * ureg(expr)
