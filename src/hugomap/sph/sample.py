"""Initial CSPH samples: 1D and 2D lattices and a 2D porous sample with random circular pores.

Conventions shared with the solver (SI units throughout):

- positions ``x`` (n, dim) [m], particle size ``l`` (n,) [m] = (m/ρ)^(1/dim), the solver's
  definition: the lattice spacing dx for the line and the square lattice, (√3/2)^(1/2)·dx for
  the hexagonal one (whose nearest-neighbour distance is dx),
  mass ``m`` (n,), density ``rho`` (n,) [kg/m³] (every particle carries the solid density; the
  pores lower the *mean* density, not a particle's);
- 1D: ``m = ρ·dx`` is a mass per unit cross-section area [kg/m²];
- 2D (plane strain, per unit thickness): ``m = ρ·a_p`` is a mass per metre of depth [kg/m],
  with ``a_p`` the lattice area per particle [m²]: dx² (square), (√3/2)·dx² (hexagonal).

The box is [x_lo, x_hi] × [y_lo, y_hi] (1D: y_lo = y_hi = 0). Requested lengths are rounded to
a whole number of lattice cells (rows for y); the box records the lengths actually used, which
differ from the request by at most half a cell. Lattice sites sit half a cell inside the box
(square: x = (i + ½)dx, y = (j + ½)dx), so no particle is on a wall and the lattice is periodic
in y with period y_hi − y_lo. The hexagonal lattice has rows spaced (√3/2)·dx along y, sites at
x = (i + ¼)dx on even rows and (i + ¾)dx on odd rows, and an even number of rows.

Distention α = ρ_solid/ρ_mean (ρ0/ρ00 in shock-physics notation; 1 for a full-density solid).
The measured α counts the particles actually kept: α = A / (N_kept·a_p) over a region of area A,
i.e. ρ_mean = ρ_solid·N_kept·a_p/A.

Porous sample (``porous_2d``): circular pores placed by random sequential addition (RSA; each
new pore is drawn with a uniform centre and accepted only if it overlaps no earlier pore, with
a solid ligament of at least ``min_gap`` between pores), the lattice sites strictly inside a pore
removed. Choices, with reasons:

- Pores are **periodic in y** by default (a pore crossing y_hi reappears at y_lo), so the sample
  is statistically uniform across y and a y-periodic solver sees no pore-free strip. With
  ``periodic_y=False`` pores are instead kept ``min_gap`` away from the y walls.
- Pores are kept ``x_margin`` away from both x ends, so the piston face and the far end are solid.
- The target distention is met in the **porous core**, x ∈ [x_lo + m·dx, x_hi − m·dx] with
  m = ⌈x_margin/dx⌉ whole columns (``region="core"``, default: the shock state is measured in the
  porous material, and the solid end layers would otherwise bias it), or over the whole box
  (``region="box"``: α = ρ_solid·N_kept·a_p/(L_x·L_y)). Both measured values are returned.
- Pore radii are drawn uniformly in [r_min, r_max] (or fixed). Pores are added while the next one
  leaves a remainder of at least one smallest resolvable pore (radius K_RESOLUTION·dx); the
  remainder is then removed by one or two final pores whose radius is found by bisection on the
  lattice count (so it may be smaller than r_min, never smaller than K_RESOLUTION·dx, never larger
  than r_max). The result is accepted only if the measured α is within ``tolerance`` (relative) of
  the target.
- Resolution: r_min ≥ K_RESOLUTION·dx with K_RESOLUTION = 3. A pore of radius 3dx is six
  particle spacings across and removes 26 to 32 lattice sites depending on where its centre
  falls (πr²/dx² = 28.3 on average), so its lattice area is within ~15 % of πr²; and its
  diameter, 6·dx, exceeds the CSPH kernel support (at most 2h = 2θ(l_i + l_j) = 4θ·dx) for
  θ ≤ 1.5, so the solver sees a void rather than a smeared density dip.
- Packing limit: RSA of equal discs jams at a covered fraction ≈ 0.547 (J. Feder, J. Theor. Biol.
  87, 237 (1980); E. L. Hinrichsen, J. Feder, T. Jøssang, J. Stat. Phys. 44, 793 (1986)), and the
  approach to jamming is slow (coverage deficit ∝ t^(-1/2)). A porosity φ = 1 − 1/α above
  PHI_MAX = 0.5 (α > 2) is refused up front; below it the packer still gives up, with an error,
  after ``max_attempts`` consecutive rejected positions. A ligament ``min_gap`` = g between pores
  makes discs of effective radius r + g/2 jam, so the reachable porosity is about
  0.547·(r/(r + g/2))² (0.40 for r = 3dx, g = dx, the defaults' worst case) and lower with the
  margins; polydisperse radii jam somewhat higher.
- Defaults: ``min_gap`` = dx (about one particle spacing of solid between two pores, so they
  do not merge into one void on the lattice) and ``x_margin`` = 4·dx (at least the kernel support,
  at most 2h = 2θ(l_i + l_j) = 4θ·dx, for θ ≤ 1, so the piston face sees only solid).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Literal

import numpy as np

K_RESOLUTION = 3.0
"""Smallest allowed pore radius in lattice spacings (r ≥ K_RESOLUTION·dx); see the module doc."""

PHI_MAX = 0.5
"""Largest porosity 1 − 1/α accepted (RSA jamming coverage of equal discs ≈ 0.547)."""

_HEX_DY = math.sqrt(3.0) / 2.0


class SampleError(ValueError):
    """A sample parameter outside its allowed range; the message names it and the range."""


@dataclass(frozen=True, eq=False)
class Sample:
    """A CSPH sample (SI units). The dataclass is frozen; its arrays are ordinary numpy arrays,
    so a solver that updates them in place should work on copies (``np.array(sample.x)``).

    ``x`` (n, dim) [m]; ``l`` (n,) [m]; ``m`` (n,) [kg/m² in 1D, kg/m in 2D]; ``rho`` (n,)
    [kg/m³]. ``rho_mean`` [kg/m³] and ``distention`` = rho_solid/rho_mean are measured over the
    whole box from the particles kept; ``distention_core`` over the porous core
    [core_x_lo, core_x_hi] (equal to ``distention`` when there are no pores).
    """

    x: np.ndarray
    l: np.ndarray
    m: np.ndarray
    rho: np.ndarray
    x_lo: float
    x_hi: float
    y_lo: float
    y_hi: float
    dim: int
    kind: str
    dx: float
    rho_solid: float
    rho_mean: float
    distention: float
    distention_core: float
    core_x_lo: float
    core_x_hi: float
    periodic_y: bool = True
    target_distention: float = 1.0
    seed: int | None = None
    pore_centres: np.ndarray = field(default_factory=lambda: np.zeros((0, 2)))
    pore_radii: np.ndarray = field(default_factory=lambda: np.zeros(0))
    periodic_x: bool = False

    @property
    def n(self) -> int:
        """Number of particles."""
        return int(self.x.shape[0])

    @property
    def box(self) -> tuple[float, float, float, float]:
        """(x_lo, x_hi, y_lo, y_hi) [m]."""
        return (self.x_lo, self.x_hi, self.y_lo, self.y_hi)


def _array(a: np.ndarray) -> np.ndarray:
    return np.ascontiguousarray(a, dtype=np.float64)


def _positive(name: str, value: float) -> float:
    value = float(value)
    if not math.isfinite(value) or value <= 0.0:
        raise SampleError(f"{name} = {value!r} must be a finite number > 0")
    return value


def _cells(name: str, length: float, dx: float, minimum: int = 1) -> int:
    n = int(round(length / dx))
    if n < minimum:
        raise SampleError(
            f"{name} = {length!r} m holds {length / dx:.3g} lattice cells of dx = {dx!r} m; "
            f"it must hold at least {minimum}"
        )
    return n


def lattice_1d(length: float, dx: float, rho0: float) -> Sample:
    """A 1D homogeneous solid: n = round(length/dx) particles at x = (i + ½)·dx, i = 0 … n−1.

    length [m], dx [m] (particle size l = dx), rho0 [kg/m³]; mass per unit area m = ρ0·dx
    [kg/m²]. Box [0, n·dx]; y_lo = y_hi = 0.
    """
    dx = _positive("dx", dx)
    length = _positive("length", length)
    rho0 = _positive("rho0", rho0)
    n = _cells("length", length, dx)
    x = ((np.arange(n, dtype=np.float64) + 0.5) * dx)[:, None]
    return Sample(
        x=_array(x),
        l=_array(np.full(n, dx)),
        m=_array(np.full(n, rho0 * dx)),
        rho=_array(np.full(n, rho0)),
        x_lo=0.0,
        x_hi=n * dx,
        y_lo=0.0,
        y_hi=0.0,
        dim=1,
        kind="line",
        dx=dx,
        rho_solid=rho0,
        rho_mean=rho0,
        distention=1.0,
        distention_core=1.0,
        core_x_lo=0.0,
        core_x_hi=n * dx,
        periodic_y=False,
    )


class _Grid:
    """A 2D lattice stored row by row: site (j, i) at (xoff[j] + i·dx, (j + ½)·dy)."""

    def __init__(self, lx: float, ly: float, dx: float, kind: str) -> None:
        if kind not in ("square", "hex"):
            raise SampleError(f"kind = {kind!r} must be 'square' or 'hex'")
        self.kind = kind
        self.dx = dx
        self.dy = dx if kind == "square" else dx * _HEX_DY
        self.nx = _cells("lx", lx, dx)
        ny = _cells("ly", ly, self.dy, minimum=1 if kind == "square" else 2)
        if kind == "hex" and ny % 2:
            ny += 1  # an even row count keeps the hexagonal lattice periodic in y
        self.ny = ny
        self.lx = self.nx * dx
        self.ly = self.ny * self.dy
        self.area_per_particle = dx * self.dy
        if kind == "square":
            self.xoff = np.full(self.ny, 0.5 * dx)
        else:
            self.xoff = np.where(np.arange(self.ny) % 2 == 0, 0.25 * dx, 0.75 * dx)
        self.keep = np.ones((self.ny, self.nx), dtype=bool)

    def positions(self) -> np.ndarray:
        j, i = np.nonzero(self.keep)  # particle order: rows in y order, x fastest in a row
        return np.column_stack([self.xoff[j] + i * self.dx, (j + 0.5) * self.dy])

    def disc_sites(
        self, cx: float, cy: float, r: float, periodic_y: bool, periodic_x: bool = False
    ) -> tuple:
        """(rows, cols) of the kept sites strictly inside the disc |p − c| < r (with
        ``periodic_x`` a disc crossing x = 0 or x = L_x wraps round, as in y)."""
        j0 = math.floor((cy - r) / self.dy - 0.5)
        j1 = math.ceil((cy + r) / self.dy - 0.5)
        jj = np.arange(j0, j1 + 1)
        if periodic_y:
            jw = np.mod(jj, self.ny)
        else:
            ok = (jj >= 0) & (jj < self.ny)
            jj, jw = jj[ok], jj[ok]
        i0 = math.floor((cx - r) / self.dx) - 1
        i1 = math.ceil((cx + r) / self.dx) + 1
        if periodic_x:
            i1 = min(i1, i0 + self.nx - 1)  # one period at most: no site counted twice
            ii = np.arange(i0, i1 + 1)
            iw = np.mod(ii, self.nx)
        else:
            ii = np.arange(max(i0, 0), min(i1, self.nx - 1) + 1)
            iw = ii
        px = self.xoff[jw][:, None] + ii[None, :] * self.dx
        py = ((jj + 0.5) * self.dy)[:, None]
        inside = (px - cx) ** 2 + (py - cy) ** 2 < r * r
        inside &= self.keep[jw][:, iw]
        rows, cols = np.nonzero(inside)
        return jw[rows], iw[cols]


def _make_sample(
    grid: _Grid,
    rho_solid: float,
    core_cols: tuple[int, int],
    periodic_y: bool,
    target: float,
    seed: int | None,
    centres: np.ndarray,
    radii: np.ndarray,
    periodic_x: bool = False,
) -> Sample:
    x = grid.positions()
    n = x.shape[0]
    a_p = grid.area_per_particle
    # α = A/(N_kept·a_p) with A = (lattice sites in the region)·a_p exactly: a ratio of counts.
    alpha_box = grid.nx * grid.ny / n
    c0, c1 = core_cols
    n_core = int(grid.keep[:, c0:c1].sum())
    alpha_core = (c1 - c0) * grid.ny / n_core
    return Sample(
        x=_array(x),
        l=_array(np.full(n, math.sqrt(a_p))),  # (m/ρ)^(1/2); dx for the square lattice
        m=_array(np.full(n, rho_solid * a_p)),
        rho=_array(np.full(n, rho_solid)),
        x_lo=0.0,
        x_hi=grid.lx,
        y_lo=0.0,
        y_hi=grid.ly,
        dim=2,
        kind=grid.kind,
        dx=grid.dx,
        rho_solid=rho_solid,
        rho_mean=rho_solid / alpha_box,
        distention=alpha_box,
        distention_core=alpha_core,
        core_x_lo=c0 * grid.dx,
        core_x_hi=c1 * grid.dx,
        periodic_y=periodic_y,
        target_distention=target,
        seed=seed,
        pore_centres=_array(np.asarray(centres, dtype=np.float64).reshape(-1, 2)),
        pore_radii=_array(np.asarray(radii, dtype=np.float64)),
        periodic_x=periodic_x,
    )


def lattice_2d(
    lx: float, ly: float, dx: float, rho0: float, kind: Literal["square", "hex"] = "square"
) -> Sample:
    """A full-density 2D plane-strain lattice filling [0, L_x] × [0, L_y] (lengths rounded to
    whole cells/rows, see the module doc). lx, ly, dx [m]; rho0 [kg/m³]; mass per metre of depth
    m = ρ0·a_p [kg/m] with a_p = dx² (square) or (√3/2)·dx² (hex); particle size l = √a_p
    (= dx for the square lattice)."""
    dx = _positive("dx", dx)
    _positive("lx", lx)
    _positive("ly", ly)
    rho0 = _positive("rho0", rho0)
    grid = _Grid(lx, ly, dx, kind)
    return _make_sample(grid, rho0, (0, grid.nx), True, 1.0, None, np.zeros((0, 2)), np.zeros(0))


def porous_2d(
    lx: float,
    ly: float,
    dx: float,
    rho_solid: float,
    *,
    pore_radius: float | tuple[float, float],
    distention: float = 1.35,
    seed: int = 0,
    tolerance: float = 0.005,
    min_gap: float | None = None,
    x_margin: float | None = None,
    periodic_y: bool = True,
    region: Literal["core", "box"] = "core",
    kind: Literal["square", "hex"] = "square",
    max_attempts: int = 20000,
    periodic_x: bool = False,
) -> Sample:
    """A 2D plane-strain sample of solid density ``rho_solid`` [kg/m³] with random circular pores
    bringing the measured distention α = ρ_solid/ρ_mean to ``distention`` within ``tolerance``
    (relative: |α − α_target| ≤ tolerance·α_target). Reproducible: the same arguments and
    ``seed`` give the same sample.

    lx, ly, dx [m]: box and lattice spacing. pore_radius [m]: a fixed radius or (r_min, r_max),
    radii drawn uniformly. min_gap [m] (default dx): least solid ligament between pores (and,
    with ``periodic_y=False``, between a pore and a y wall). x_margin [m] (default 4·dx): least
    solid between a pore and either x end. region: where α is measured against the target ("core"
    between the solid end layers, or "box"). max_attempts: consecutive rejected RSA positions
    after which the packer gives up. periodic_x: pores wrap round x as round y (a tile that
    repeats along x without a seam, ``porous_tile_2d``; no solid end layers: x_margin must be
    None or 0 and α is measured over the whole box). Method, limits and reasons: see the
    module doc.

    Raises SampleError (a ValueError) naming the parameter and its allowed range.
    """
    dx = _positive("dx", dx)
    lx = _positive("lx", lx)
    ly = _positive("ly", ly)
    rho_solid = _positive("rho_solid", rho_solid)
    alpha = float(distention)
    if not math.isfinite(alpha) or alpha < 1.0:
        raise SampleError(
            f"distention = {distention!r} must be ≥ 1 (α = ρ_solid/ρ_mean; 1 = no pores)"
        )
    phi = 1.0 - 1.0 / alpha
    if phi > PHI_MAX:
        raise SampleError(
            f"distention = {alpha:g} (porosity {phi:.3f}) cannot be packed with random "
            f"non-overlapping pores: allowed 1 ≤ distention ≤ {1.0 / (1.0 - PHI_MAX):g} "
            f"(porosity ≤ {PHI_MAX}; random sequential addition of equal discs jams at a "
            "covered fraction ≈ 0.547)"
        )
    tolerance = float(tolerance)
    if not (0.0 < tolerance <= 0.1):
        raise SampleError(f"tolerance = {tolerance!r} must be in (0, 0.1] (relative)")
    if isinstance(pore_radius, (tuple, list)):
        if len(pore_radius) != 2:
            raise SampleError(f"pore_radius = {pore_radius!r} must be r or (r_min, r_max)")
        r_min, r_max = (float(v) for v in pore_radius)
    else:
        r_min = r_max = float(pore_radius)
    if not (math.isfinite(r_min) and math.isfinite(r_max)) or r_min <= 0 or r_max < r_min:
        raise SampleError(
            f"pore_radius = {pore_radius!r} must satisfy 0 < r_min ≤ r_max (finite, metres)"
        )
    r_floor = K_RESOLUTION * dx
    if r_min < r_floor * (1.0 - 1e-12):
        raise SampleError(
            f"pore_radius r_min = {r_min:g} m is too small for dx = {dx:g} m: need "
            f"r_min ≥ {K_RESOLUTION:g}·dx = {r_floor:g} m (≥ {K_RESOLUTION:g} particle spacings "
            f"across a pore radius), i.e. dx ≤ r_min/{K_RESOLUTION:g} = {r_min / K_RESOLUTION:g} m"
        )
    gap = dx if min_gap is None else float(min_gap)
    if not math.isfinite(gap) or gap < 0:
        raise SampleError(f"min_gap = {min_gap!r} must be ≥ 0 (metres)")
    margin = 4.0 * dx if x_margin is None else float(x_margin)
    if not math.isfinite(margin) or margin < 0:
        raise SampleError(f"x_margin = {x_margin!r} must be ≥ 0 (metres)")
    if periodic_x:
        if x_margin not in (None, 0, 0.0):
            raise SampleError(f"x_margin = {x_margin!r} must be None or 0 with periodic_x")
        margin, region = 0.0, "box"  # a periodic tile has no ends: α over the whole tile
    if region not in ("core", "box"):
        raise SampleError(f"region = {region!r} must be 'core' or 'box'")
    if int(max_attempts) < 1:
        raise SampleError(f"max_attempts = {max_attempts!r} must be ≥ 1")

    grid = _Grid(lx, ly, dx, kind)
    lx, ly = grid.lx, grid.ly
    mcols = math.ceil(margin / dx - 1e-9)
    core = (mcols, grid.nx - mcols)
    x_min, x_max = mcols * dx, (grid.nx - mcols) * dx  # pore discs stay inside [x_min, x_max]
    if periodic_y:
        y_span = ly - 2.0 * r_max - gap  # a pore must not touch its own periodic image
    else:
        y_span = ly - 2.0 * (r_max + gap)
    x_span = lx - 2.0 * r_max - gap if periodic_x else x_max - x_min - 2.0 * r_max
    if x_span < 0 or y_span < 0:
        walls = "" if periodic_y else " + 2·min_gap"
        raise SampleError(
            f"pore_radius r_max = {r_max:g} m does not fit the sample: need "
            f"2·r_max ≤ lx − 2·x_margin = {x_max - x_min:g} m and "
            f"2·r_max + min_gap{walls} ≤ ly = {ly:g} m"
        )
    if alpha == 1.0:
        return _make_sample(grid, rho_solid, core, periodic_y, alpha, seed, [], [], periodic_x)

    a_p = grid.area_per_particle
    if region == "core":
        n_region = int(grid.keep[:, core[0] : core[1]].sum())
    else:
        n_region = grid.nx * grid.ny
    area_region = n_region * a_p
    to_remove = n_region - area_region / (alpha * a_p)  # particles, fractional
    n_floor = math.pi * r_floor**2 / a_p  # particles in the smallest resolvable pore (approx.)

    rng = np.random.default_rng(seed)
    centres: list[tuple[float, float]] = []
    radii: list[float] = []
    cx_arr = np.zeros(0)
    cy_arr = np.zeros(0)
    r_arr = np.zeros(0)

    def free_spot(r: float) -> tuple[float, float] | None:
        """A uniformly drawn centre where a pore of radius r clears every earlier pore by gap."""
        lo_y = 0.0 if periodic_y else r + gap
        hi_y = ly if periodic_y else ly - r - gap
        lo_x, hi_x = (0.0, lx) if periodic_x else (x_min + r, x_max - r)
        for _ in range(int(max_attempts)):
            cx = rng.uniform(lo_x, hi_x)
            cy = rng.uniform(lo_y, hi_y)
            if r_arr.size:
                ddy = cy_arr - cy
                if periodic_y:
                    ddy -= ly * np.round(ddy / ly)
                ddx = cx_arr - cx
                if periodic_x:
                    ddx -= lx * np.round(ddx / lx)
                d2 = ddx**2 + ddy**2
                if np.any(d2 < (r_arr + r + gap) ** 2):
                    continue
            return cx, cy
        return None

    def place(r: float, cx: float, cy: float) -> int:
        nonlocal cx_arr, cy_arr, r_arr
        rows, cols = grid.disc_sites(cx, cy, r, periodic_y, periodic_x)
        grid.keep[rows, cols] = False
        centres.append((cx, cy))
        radii.append(r)
        cx_arr, cy_arr, r_arr = np.append(cx_arr, cx), np.append(cy_arr, cy), np.append(r_arr, r)
        return int(rows.size)

    def give_up(r: float) -> SampleError:
        removed = to_remove - to_remove_left
        got = area_region / ((n_region - removed) * a_p)
        return SampleError(
            f"distention = {alpha:g} could not be packed: after {len(radii)} pores "
            f"(distention reached {got:.4f}, porosity {1 - 1 / got:.3f}) no free place for a pore "
            f"of radius {r:g} m in {max_attempts} random tries. Random non-overlapping pores with "
            f"min_gap = {gap:g} m and radii {r_min:g}–{r_max:g} m jam below the requested "
            f"porosity {phi:.3f}: lower the distention, min_gap or x_margin, or use smaller pores"
        )

    to_remove_left = to_remove
    while True:
        r = r_min if r_max == r_min else float(rng.uniform(r_min, r_max))
        if math.pi * r * r / a_p > to_remove_left - n_floor:
            break
        spot = free_spot(r)
        if spot is None:
            raise give_up(r)
        to_remove_left -= place(r, *spot)

    # Final pores: one (or two, if the remainder exceeds one r_max pore) sized by bisection on
    # the lattice count; every final radius lies in [K_RESOLUTION·dx, r_max].
    n_final = 1 if to_remove_left <= math.pi * r_max**2 / a_p else 2
    for k in range(n_final):
        want = to_remove_left / (n_final - k)
        if want < 0.5:
            break
        r_guess = min(max(math.sqrt(want * a_p / math.pi), r_floor), r_max)
        spot = free_spot(r_guess)
        if spot is None:
            raise give_up(r_guess)
        cx, cy = spot
        lo, hi = r_floor, (r_max if periodic_x else min(r_max, x_max - cx, cx - x_min))
        if periodic_x:  # nor touch its own image along x
            hi = min(hi, 0.5 * (lx - gap))
        if not periodic_y:
            hi = min(hi, cy - gap, ly - gap - cy)
        if r_arr.size:  # stay clear of the pores already placed
            ddy = cy_arr - cy
            if periodic_y:
                ddy -= ly * np.round(ddy / ly)
            ddx = cx_arr - cx
            if periodic_x:
                ddx -= lx * np.round(ddx / lx)
            hi = min(hi, float(np.min(np.sqrt(ddx**2 + ddy**2) - r_arr - gap)))
        if hi < lo:
            raise give_up(r_guess)

        def count(rad: float, cx: float = cx, cy: float = cy) -> int:
            return int(grid.disc_sites(cx, cy, rad, periodic_y, periodic_x)[0].size)

        if count(hi) <= want:
            r = hi
        else:
            for _ in range(60):  # the count is a step function of the radius: bracket the target
                mid = 0.5 * (lo + hi)
                if count(mid) <= want:
                    lo = mid
                else:
                    hi = mid
            r = lo if abs(count(lo) - want) <= abs(count(hi) - want) else hi
        to_remove_left -= place(r, cx, cy)

    sample = _make_sample(
        grid,
        rho_solid,
        core,
        periodic_y,
        alpha,
        seed,
        np.array(centres),
        np.array(radii),
        periodic_x,
    )
    got = sample.distention_core if region == "core" else sample.distention
    if abs(got - alpha) > tolerance * alpha:
        raise SampleError(
            f"tolerance = {tolerance:g}: the packed distention {got:.5f} misses the target "
            f"{alpha:g} by {abs(got / alpha - 1):.3%} (a pore's particle count changes in steps, "
            "or the last pores found too little room): use a smaller dx, a larger sample or "
            "another seed"
        )
    return sample


def porous_tile_2d(
    lx: float,
    ly: float,
    dx: float,
    rho_solid: float,
    *,
    pore_radius: float | tuple[float, float],
    distention: float,
    seed: int = 0,
    tolerance: float = 0.005,
    min_gap: float | None = None,
    kind: Literal["square", "hex"] = "square",
) -> Sample:
    """A porous tile periodic in x and y (``porous_2d`` with ``periodic_x``): pores wrap round
    both periods, so copies laid end to end along x (or cut at any x and continued from the
    same x modulo L_x) join without a seam, gap or overlap; the lattice is periodic in x with
    period L_x = n_x dx. The distention α = ρ_solid/ρ_mean = n_x n_y/N_kept is measured over
    the whole tile and met within ``tolerance`` (relative). Units and the other arguments as
    in ``porous_2d``: the moving window's inflow material (``sph.window.SPHWindow2D``)."""
    return porous_2d(
        lx, ly, dx, rho_solid, pore_radius=pore_radius, distention=distention, seed=seed,
        tolerance=tolerance, min_gap=min_gap, x_margin=0.0, periodic_y=True, region="box",
        kind=kind, periodic_x=True,
    )  # fmt: skip
