"""Config of a CSPH scene (``solver: csph``, SI units): its defaults and cross-key checks.

``hugomap.config.validate_config`` calls ``resolve_defaults`` and then ``check`` on every
CSPH scene once the schema has passed (and filled its constant defaults); nothing else fills
defaults, so a validated scene is complete. Validation runs when Snakemake parses the
workflow, so this module stays light: no numba, no xarray.
"""

from __future__ import annotations

from ..analysis.linear_hugoniot import shock_velocity
from ..keys import show, window_ahead_room

#: Smallest pore radius in lattice spacings (``hugomap.sph.sample.K_RESOLUTION``).
K_RESOLUTION = 3.0
#: RSA jamming coverage of equal discs (Feder 1980; Hinrichsen, Feder & Jøssang 1986).
RSA_JAMMING = 0.547
#: Particles a CSPH sample must hold along x (front tracking, slabs, window).
MIN_COLUMNS = 40
#: Frozen inflow particles of the 1D window (``sph.window.SPHWindow.from_piston``).
WINDOW_INFLOW = 8
#: Schemes a CSPH scene runs, by dim (the windows: ``sph.window.SPHWindow``, ``SPHWindow2D``).
CSPH_SCHEMES = {1: ("piston", "amw", "mw", "dichotomy"), 2: ("piston", "amw", "mw", "dichotomy")}


def resolve_defaults(scene: dict) -> None:
    """Fill the defaults that scale with the lattice spacing dx = ``sample.dx`` [m] (only
    where the key is absent; idempotent): shock.bin_width = 2 dx, shock.gap = 10 dx,
    shock.avg_length = 20 dx, window.length = 150 dx, window.cut_every = 10 dx.

    The time defaults that depend on the point's u_p stay null (the schema's default) and
    are derived per point by the window stages: window.window_time = L/(c0 + s u_p) (the
    front's crossing of the window, L = window.length), window.average_time = 2
    window_time, window.dichotomy.trial_time = window_time, window.dichotomy.final_time =
    average_time."""
    dx = scene["sample"]["dx"]
    for key, k in (("bin_width", 2.0), ("gap", 10.0), ("avg_length", 20.0)):
        scene["shock"].setdefault(key, k * dx)
    scene["window"].setdefault("length", 150.0 * dx)
    scene["window"].setdefault("cut_every", 10.0 * dx)


# the window points' D of porous copper lay up to 1 % below McQueen's full compaction
# (500 m/s, dx = 10 um): sizing allows three times that
SLOW_FRONT_MARGIN = 0.03


def slowest_front(scene: dict, u_p: float) -> float:
    """The slowest shock speed D [m/s] the scene's material may have at piston speed
    ``u_p`` [m/s], for sizing: the linear Hugoniot D = c0 + s u_p of its EOS; porous (dim
    2), at most McQueen's full compaction of its EOS (``analysis.porous``: below the
    snowplow speed u_p α/(α − 1) once the solid itself compresses; a compaction left
    incomplete runs faster, so room is not overestimated), less ``SLOW_FRONT_MARGIN``."""
    eos = scene["material"]["eos"]
    D = shock_velocity(u_p, eos["c0"], eos["s"])
    por = scene["sample"].get("porous") if scene["dim"] == 2 else None
    if por is not None and por["distention"] > 1.0:
        from ..analysis.porous import MGSolid, porous_hugoniot_from_up

        solid = MGSolid(eos["rho0"], eos["c0"], eos["s"], eos["gamma0"])
        full = float(porous_hugoniot_from_up(u_p, por["distention"], solid).D)
        D = min(D, full) * (1.0 - SLOW_FRONT_MARGIN)
    return D


def check(base: str, scene: dict, cfg: dict) -> list[str]:
    """Checks of a CSPH scene (SI units) that involve several keys, on a scene whose
    defaults are resolved (``resolve_defaults``); ``base``: its key path, ``scenes.<name>``;
    ``cfg``: the whole config, for the top-level ``schemes``. Each message names the keys
    involved."""
    out: list[str] = []
    sc = scene
    smp, sh, w = sc["sample"], sc["shock"], sc["window"]
    st = sc["material"]["strength"]
    num = sc["numerics"]
    dx, length, dim = smp["dx"], smp["length"], sc["dim"]
    schemes = sc.get("schemes", cfg.get("schemes", ["piston"]))
    allowed = list(CSPH_SCHEMES[dim])
    other = [s for s in schemes if s not in allowed]
    if other:
        where = f"{base}.schemes" if "schemes" in sc else "schemes"
        own = "" if "schemes" in sc else "; give the scene its own schemes"
        out.append(
            f"{where} = {show(schemes)}: {show(other)} not available for a solver = csph "
            f"scene with dim = {dim} ({base}); allowed: {show(allowed)}{own}"
        )
    if st["model"] == "von_mises" and st["yield_stress"] >= st["shear_modulus"]:
        out.append(
            f"{base}.material.strength.yield_stress = {st['yield_stress']:.4g}: must be below "
            f"material.strength.shear_modulus = {st['shear_modulus']:.4g} Pa; allowed range "
            f"(0, {st['shear_modulus']:.4g}) Pa"
        )
    n_x = length / dx
    if n_x < MIN_COLUMNS:
        out.append(
            f"{base}.sample.length = {length:.4g}: holds {n_x:.3g} particles of sample.dx = "
            f"{dx:.4g} m; allowed range [{MIN_COLUMNS * dx:.4g}, 1.0] m ({MIN_COLUMNS} dx)"
        )
    if dim == 1 and ("width" in smp or "porous" in smp):
        key = "width" if "width" in smp else "porous"
        out.append(f"{base}.sample.{key}: only for dim = 2 (this scene has dim = 1)")
    if dim == 2:
        r_list = (4.0 * num["theta"] + 0.5) * dx  # neighbour-list radius, skin 0.5 l
        if "width" not in smp:
            out.append(f"{base}.sample: 'width' is a required property for dim = 2")
        elif smp["width"] < 2.0 * r_list:
            out.append(
                f"{base}.sample.width = {smp['width']:.4g}: the periodic width must be at least "
                f"twice the neighbour-list radius (4 numerics.theta + 0.5) sample.dx; allowed "
                f"range [{2.0 * r_list:.4g}, 1.0] m"
            )
    por = smp.get("porous")
    if dim == 2 and por is not None and "width" in smp:
        alpha = por["distention"]
        r = por.get("pore_radius")
        if r is None:
            out.append(f"{base}.sample.porous: 'pore_radius' is a required property")
        else:
            r_min, r_max = r
            if r_min > r_max:
                out.append(
                    f"{base}.sample.porous.pore_radius = {show(r)}: r_min must not exceed r_max"
                )
            if r_min < K_RESOLUTION * dx * (1 - 1e-12):
                out.append(
                    f"{base}.sample.porous.pore_radius = {show(r)}: the smallest pore is "
                    f"not resolved by sample.dx = {dx:.4g} m; allowed r_min >= "
                    f"{K_RESOLUTION:g} dx = {K_RESOLUTION * dx:.4g} m (or a smaller dx)"
                )
            if 2.0 * r_max + dx > smp["width"]:
                out.append(
                    f"{base}.sample.porous.pore_radius = {show(r)}: a pore of r_max must fit "
                    f"across sample.width = {smp['width']:.4g} m; allowed r_max <= "
                    f"{(smp['width'] - dx) / 2:.4g} m"
                )
            # RSA with a ligament g = dx jams at coverage 0.547 (r/(r + g/2))^2 (sample.py);
            # the solid end layers (4 dx each) lower the reachable mean porosity further.
            core = max(length - 8.0 * dx, 0.0) / length
            phi_max = RSA_JAMMING * (r_max / (r_max + 0.5 * dx)) ** 2 * core
            phi = 1.0 - 1.0 / alpha
            if phi > phi_max:
                out.append(
                    f"{base}.sample.porous.distention = {alpha:g}: porosity {phi:.3f} cannot be "
                    f"packed with pore_radius max {r_max:.4g} m at sample.dx = {dx:.4g} m "
                    f"(random sequential addition jams near porosity {phi_max:.3f}); allowed "
                    f"range [1, {1.0 / (1.0 - phi_max):.4g})"
                )
    if sh["end_fraction"] <= sh["load_fraction"]:
        out.append(
            f"{base}.shock.end_fraction = {sh['end_fraction']:g}: must exceed "
            f"shock.load_fraction = {sh['load_fraction']:g}; allowed range "
            f"({sh['load_fraction']:g}, 1)"
        )
    behind = sh["load_fraction"] * length
    # the piston has followed the front in: the shocked column at the end of loading is
    # (1 - u_p/D) of what the front crossed, shortest at the largest u_p/D
    D_worst, u_worst = max(((slowest_front(sc, u), u) for u in sh["u_p"]),
                           key=lambda d: d[1] / d[0])  # fmt: skip
    column = behind * (1.0 - u_worst / D_worst)
    need = sh["avg_length"] + 2.0 * sh["gap"]
    if need > column * (1 + 1e-12):
        out.append(
            f"{base}.shock.load_fraction = {sh['load_fraction']:g}: the shocked column "
            f"between piston and front at the end of loading, shock.load_fraction x "
            f"sample.length x (1 - u_p/D) = {column:.4g} m at u_p = {u_worst:g} m/s (D = "
            f"{D_worst:.4g} m/s, the slowest front), must hold the slab "
            f"the window is normalised on, shock.avg_length + 2 shock.gap = {need:.4g} m; "
            f"allowed range [{min(need / (length * column / behind), 1.0):.4g}, "
            f"shock.end_fraction) (or a longer sample.length, a shorter shock.gap)"
        )
    if sh["bin_width"] > 0.25 * sh["avg_length"]:
        out.append(
            f"{base}.shock.bin_width = {sh['bin_width']:.4g}: at most a quarter of "
            f"shock.avg_length = {sh['avg_length']:.4g} m"
        )
    windowed = [s for s in schemes if s != "piston"]
    if "tile_length" in w and dim != 2:
        out.append(f"{base}.window.tile_length: only for dim = 2 (this scene has dim = {dim})")
    if "dichotomy" in windowed:
        d = w["dichotomy"]
        if d["tolerance"] >= 2.0 * d["half_width"]:
            out.append(
                f"{base}.window.dichotomy.tolerance = {d['tolerance']:g}: must be below the "
                f"initial bracket width 2 window.dichotomy.half_width = "
                f"{2.0 * d['half_width']:g} m/s; allowed range (0, {2.0 * d['half_width']:g}) m/s"
            )
    if windowed:
        Lw, ff = w["length"], w["front_fraction"]
        room_ahead = (1.0 - sh["load_fraction"]) * length - WINDOW_INFLOW * dx
        if ff * Lw > column * (1 + 1e-12) or (1.0 - ff) * Lw > room_ahead:
            out.append(
                f"{base}.window.length = {Lw:.4g}: a window with window.front_fraction = {ff:g} "
                f"does not fit around the front at the end of loading (room {column:.4g} m "
                f"behind it at u_p = {u_worst:g} m/s, {room_ahead:.4g} m ahead); shorten it or "
                "lengthen sample.length"
            )
        # the state ahead as measured, here over a whole avg_length (a precursor, material
        # the inflow disturbed; without it the jump is taken from the pole unseen)
        out += window_ahead_room(
            base, w, sh, "m", ("the slab ahead", "shock.avg_length", sh["avg_length"])
        )
        gap_out = w.get("outflow_gap", sh["gap"])
        slab = sh["gap"] + gap_out + sh["avg_length"]
        parts = "shock.gap + window.outflow_gap + " if "outflow_gap" in w else "2 shock.gap + "
        parts += "shock.avg_length"
        if ff * Lw < slab * (1 - 1e-12):
            out.append(
                f"{base}.window.front_fraction = {ff:g}: the front starts {ff * Lw:.4g} m from "
                f"the outflow edge of window.length = {Lw:.4g} m, less than the averaged slab "
                f"behind it needs, {parts} = {slab:.4g} m; allowed range "
                f"[{slab / Lw:.4g}, 0.8] (or a longer window)"
            )
        if dim == 2:
            lt = w.get("tile_length") or (1.0 - ff) * Lw
            key = (
                "window.tile_length"
                if "tile_length" in w
                else ("window.tile_length (default (1 - window.front_fraction) window.length)")
            )
            need = (WINDOW_INFLOW + 1) * dx
            if por is not None and por.get("pore_radius"):
                # a pore must clear its own image along x, as along y
                need = max(need, 2.0 * por["pore_radius"][1] + dx)
            if lt < need * (1 - 1e-12):
                out.append(
                    f"{base}.{key} = {lt:.4g}: the periodic inflow tile must hold the frozen "
                    f"inflow layer ({WINDOW_INFLOW + 1} dx) and, if porous, a pore of r_max "
                    f"with a ligament to its own image (2 r_max + sample.dx); allowed range "
                    f"[{need:.4g}, 1.0] m"
                )
    return out
