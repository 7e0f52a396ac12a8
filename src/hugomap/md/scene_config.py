"""Config of an MD scene (``solver: md``, Lennard-Jones reduced units): its cross-key checks.

``hugomap.config.validate_config`` calls ``resolve_defaults`` and then ``check`` on every MD
scene once the schema has passed (and filled its defaults). Validation runs when Snakemake
parses the workflow, so this module stays light: no numba, no xarray.

The optional ``units`` block (``sigma`` [m], ``epsilon_over_kB`` [K], ``mass`` [kg]: the
substance the reduced units stand for) is checked by the schema alone (all three, positive,
in plausible ranges); it changes no run, only adds SI companions (``D_SI``, ...) to the
point files and the aggregate (``io.dataset.with_si``; docs/datasets.md).
"""

from __future__ import annotations

from ..keys import MIN_SLAB_BINS, duplicate_point_tags, room_after_loading, window_ahead_room
from ..particles.fcc import lattice_constant

#: Relative tolerance of a data file's L_x against cells·a [-]: a prepared liquid sample is
#: shorter by the walls' excess layer 2Γ/ρ0 (0.2 % of the default liquid, 0.6 % of a
#: 30-cell box; ``particles.sizing.size_bulk``).
DATA_LX_TOL = 0.01

#: The piston's slab keeps this far from the piston by default [σ]. The layers its start
#: shocked ring: +2 to +5.5 % of the energy jump 5-55 σ from it, -0.2 to -3 % at 55-125 σ,
#: near 0 beyond. From 30 σ the slab's energy residual is -0.03 ± 0.08 %, from 8 σ
#: +0.41 ± 0.08 %, from 60 σ -0.69 ± 0.18 % (22 piston runs of the default liquid, u_p = 1-2.5;
#: docs/window-methods.md "The piston's start").
PISTON_GAP = 30.0

#: Shock methods that run in the moving window (cut out of the loading checkpoint).
WINDOW_SCHEMES = ("amw", "mw", "dichotomy")


def box_lengths(smp: dict) -> list[float]:
    """The sample's box cells·a [σ] along x, y, z (a prepared liquid is shorter in x by the
    walls' excess layer, 0.2 % of the default liquid: ``particles.sizing.size_bulk``)."""
    a = lattice_constant(smp["rho0"])
    return [c * a for c in smp["cells"]]


def piston_gap_room(scene: dict) -> float:
    """The largest ``shock.piston_gap`` [σ] that leaves the piston a slab when its drive
    starts: the front's travel at the end of loading (load_fraction·L_x) less ``shock.gap``
    and ``MIN_SLAB_BINS`` bins."""
    sh = scene["shock"]
    travel = sh["load_fraction"] * box_lengths(scene["sample"])[0]
    return travel - sh["gap"] - MIN_SLAB_BINS * sh["bin_width"]


def resolve_defaults(scene: dict) -> None:
    """Fill ``shock.piston_gap``: ``PISTON_GAP`` where the loading leaves room for it
    (``piston_gap_room``), else ``shock.gap`` (a short sample has no layer clear of the
    piston's start; its points carry that bias). The other defaults are the schema's."""
    sh = scene["shock"]
    if "piston_gap" not in sh:
        sh["piston_gap"] = PISTON_GAP if piston_gap_room(scene) >= PISTON_GAP else sh["gap"]


def check(base: str, scene: dict, cfg: dict) -> list[str]:
    """Checks of an MD scene that involve several keys (``base``: its key path,
    ``scenes.<name>``; ``cfg``: the whole config, for the top-level ``schemes``); each
    message names every key it depends on."""
    problems = []
    smp, pot, sh = scene["sample"], scene["potential"], scene["shock"]
    L = box_lengths(smp)
    rlist = pot["rc"] + pot["skin"]
    half_t = 0.5 * min(L[1], L[2])
    box = f"sample.cells = {smp['cells']} at sample.rho0 = {smp['rho0']}"
    if rlist > half_t:
        # (1.0: the schema's exclusiveMinimum of potential.rc)
        problems.append(
            f"{base}.potential.rc = {pot['rc']}: rc + skin must not exceed half the "
            f"transverse box; allowed range (1.0, {half_t - pot['skin']:.4g}] sigma "
            f"with potential.skin = {pot['skin']} for {box}"
        )
    if sh["bin_width"] >= L[0] / 4:
        problems.append(
            f"{base}.shock.bin_width = {sh['bin_width']}: wider than the box allows; "
            f"allowed range (0, {L[0] / 4:.4g}) sigma (a quarter of L_x = {L[0]:.4g} "
            f"for {box})"
        )
    problems += room_after_loading(base, sh, L[0], box, "sigma")
    # Up to shock.gap is always allowed: the slab as it was before the piston had a gap of
    # its own (on a short sample the drive's first samples may have none; the measurement
    # needs half of them with one).
    allowed = max(piston_gap_room(scene), sh["gap"])
    if sh["piston_gap"] > allowed:
        problems.append(
            f"{base}.shock.piston_gap = {sh['piston_gap']}: leaves the piston no slab when "
            f"its drive starts; allowed range [0, {allowed:.4g}] sigma (the "
            f"front's travel at the end of loading, shock.load_fraction = "
            f"{sh['load_fraction']} of L_x = {L[0]:.4g}, less shock.gap = {sh['gap']} and "
            f"{MIN_SLAB_BINS} bins of shock.bin_width = {sh['bin_width']} for {box}; or "
            "shock.gap)"
        )
    w = scene["window"]
    out = w["outflow"]
    if out["tau_fast"] >= out["tau_slow"]:
        problems.append(
            f"{base}.window.outflow.tau_fast = {out['tau_fast']}: must be shorter than "
            f"window.outflow.tau_slow = {out['tau_slow']}; allowed range (0, "
            f"{out['tau_slow']:.4g}) tau"
        )
    schemes = scene.get("schemes", cfg.get("schemes", ["piston"]))
    if any(s in WINDOW_SCHEMES for s in schemes):
        problems += window_ahead_room(base, w, sh, "sigma")
    if any(s in WINDOW_SCHEMES for s in schemes) and w["ghost_width"] < pot["rc"]:
        # the window stage (md.window.MDWindow) refuses a frozen layer thinner than rc
        problems.append(
            f"{base}.window.ghost_width = {w['ghost_width']}: the frozen outflow layer must "
            f"be at least the cutoff potential.rc = {pot['rc']} thick; allowed range "
            f"[{pot['rc']}, 20.0] sigma"
        )
    if smp.get("data_file"):
        problems += _check_data_file(base, smp, L)
    problems += duplicate_point_tags(base, sh["u_p"])
    if scene["phase"] == "liquid" and "reference" in scene:
        ref = scene["reference"]
        rho_max = smp["rho0"] * max(ref["compressions"])
        Lref = ref["cells"] * lattice_constant(rho_max)
        if Lref < 2 * rlist:
            problems.append(
                f"{base}.reference.cells = {ref['cells']}: the periodic reference box of a "
                f"phase = liquid scene at "
                f"the highest compression (reference.compressions max "
                f"{max(ref['compressions'])} x sample.rho0 = {smp['rho0']}) is "
                f"{Lref:.3g} sigma, shorter than 2 (potential.rc + potential.skin) = "
                f"{2 * rlist:.3g}; use more cells"
            )
    return problems


def _check_data_file(base: str, smp: dict, L: list[float]) -> list[str]:
    """``sample.data_file``: a LAMMPS data file ``md.sample.data_state`` can start from
    (readable, atom_style atomic, no frozen atoms), whose box is the one ``sample.cells``
    and ``sample.rho0`` describe (L = cells·a, a = (4/ρ0)^(1/3): L_y, L_z to 1e-6 relative,
    L_x to ``DATA_LX_TOL``, since a prepared sample's box is shorter than cells·a by the
    walls' excess layer, ``particles.sizing.size_bulk``, and may be exported and read back) and
    which holds 4·nx·ny·nz atoms (so ρ0 is its density): the cost model, the window's
    inflow and the reference read these keys."""
    from .sample import data_state

    key = f"{base}.sample.data_file = {smp['data_file']!r}"
    try:
        st = data_state(smp["data_file"])
    except ValueError as exc:  # LammpsDataError, and a missing or unreadable file
        # the reason holds the path as given: one line, whatever characters it has
        return [f"{key}: {' '.join(repr(str(exc))[1:-1].split())}"]
    problems = []
    n = 4 * smp["cells"][0] * smp["cells"][1] * smp["cells"][2]
    box = [float(v) for v in st.L]
    tol = (DATA_LX_TOL, 1e-6, 1e-6)
    if any(abs(b - e) > t * e for b, e, t in zip(box, L, tol, strict=True)):
        problems.append(
            f"{key}: its box {', '.join(f'{b:.8g}' for b in box)} sigma is not the one "
            f"sample.cells = {smp['cells']} and sample.rho0 = {smp['rho0']} describe "
            f"({', '.join(f'{e:.8g}' for e in L)} sigma; L_x within {DATA_LX_TOL:.0%}, "
            "L_y and L_z to 1e-6); set them to the file's box"
        )
    if st.n != n:
        problems.append(
            f"{key}: {st.n} atoms; sample.cells = {smp['cells']} means {n} "
            f"(4 nx ny nz, so that sample.rho0 is the file's density)"
        )
    return problems
