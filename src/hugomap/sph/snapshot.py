"""Snapshots of CSPH particles: extended XYZ frames (OVITO, ASE) and PNG pictures.

Extended XYZ (``sph_frame``): the one writer of ``hugomap.io.extxyz`` (its docstring gives
the format and what ASE and OVITO make of each column), in the units those readers assume:
positions, ``Lattice``, ``Origin`` and ``radius`` in Å (converted from metres), velocities
``velo`` in Å/fs, ``Time`` in fs; ``masses`` is the particle's mass as the solver holds it
(kg per metre of depth in 2D, per m² of cross-section in 1D; so ASE's ``momenta`` are in
those units × Å/fs); the other fields are SI and say so in the ``units`` key. 2D (and 1D)
positions are padded with z = 0 (and y = 0), and the missing cell lengths are ``depth``
(default: the largest box length, so the cell is never singular). The velocities' frame
(``io.extxyz.VelocityFrame``, given in SI) is written in the same units: ``frame_velocity``
in Å/fs, a window's edges ``x_lo``, ``x_hi`` in Å.

PNG (``write_png``): the 2D particles drawn as dots with axes in mm and equal aspect;
plastically deformed particles (accumulated plastic strain > threshold) in green, as in the
source talk's pore-collapse picture; the others coloured by a field with a colour bar (e.g.
pressure in GPa) or grey. Uses matplotlib's Agg canvas directly (no pyplot, no global state).
"""

from __future__ import annotations

import io
import math
import os
from collections.abc import Mapping, Sequence
from pathlib import Path

import numpy as np

from ..io.atomic import write_bytes
from ..io.extxyz import (
    ANGSTROM_PER_M,
    FS_PER_S,
    SnapshotError,
    VelocityFrame,
    format_frame,
)

PLASTIC_GREEN = "#1a9e1a"
"""Colour of plastically deformed particles (the source talk draws them green)."""
PLASTIC_THRESHOLD = 1e-4
"""Accumulated plastic strain above which a particle counts as plastic (flag and picture)."""


def sph_frame(
    x: np.ndarray,
    v: np.ndarray,
    fields: Mapping[str, np.ndarray],
    box: Sequence[float],
    *,
    masses: float | np.ndarray = 1.0,
    mass_unit: str = "kg",
    time: float = 0.0,
    species: str | Sequence[str] = "Cu",
    units: Mapping[str, str] | None = None,
    periodic: Sequence[bool] = (False, False, False),
    depth: float | None = None,
    radius: np.ndarray | None = None,
    info: Mapping[str, object] | None = None,
    frame: VelocityFrame | None = None,
) -> str:
    """One extended-XYZ frame of SPH particles (module docstring) as text.

    x, v (n, dim) [m], [m/s]; fields: name → (n,) or (n, k) array, written as given (say
    their units in ``units``); box: (x_lo, x_hi) in 1D, (x_lo, x_hi, y_lo, y_hi) in 2D, six
    values in 3D [m]; masses (n,) or one value, in ``mass_unit``; time [s]; species: one
    symbol or one per particle (ASE needs chemical symbols); periodic: three flags; depth [m]:
    cell length along the padded axes; radius (n,) [m]: the ``radius`` column in Å (OVITO
    draws particles with it, e.g. half the particle size l); info: more comment-line pairs;
    frame: the velocities' frame, velocity [m/s] and edges [m] (written in Å/fs and Å).
    """
    box = [float(b) for b in box]
    if len(box) not in (2, 4, 6) or not all(math.isfinite(b) for b in box):
        raise SnapshotError(f"box = {box!r} must hold 2, 4 or 6 finite numbers (lo, hi per axis)")
    lo, length = np.zeros(3), np.zeros(3)
    for k in range(len(box) // 2):
        lo[k], length[k] = box[2 * k], box[2 * k + 1] - box[2 * k]
    filled = length > 0
    if not filled[0]:
        raise SnapshotError(f"box = {box!r}: x_hi must exceed x_lo")
    pad = float(depth) if depth is not None else float(length[filled].max())
    if not (math.isfinite(pad) and pad > 0):
        raise SnapshotError(f"depth = {depth!r} must be a finite length > 0 (metres)")
    length[~filled] = pad
    cols = dict(fields)
    unit_map = {"masses": mass_unit, "momenta": f"{mass_unit}*Angstrom/fs", **(units or {})}
    if radius is not None:
        if "radius" in cols:
            raise SnapshotError("radius is given both as an argument and as a field")
        rad = np.asarray(radius, dtype=np.float64).reshape(-1)
        if rad.shape != (np.shape(x)[0],):
            raise SnapshotError(f"radius must have shape ({np.shape(x)[0]},)")
        cols["radius"] = rad * ANGSTROM_PER_M
        unit_map["radius"] = "Angstrom"
    return format_frame(
        np.asarray(x, dtype=np.float64) * ANGSTROM_PER_M,
        length * ANGSTROM_PER_M,
        velocities=np.asarray(v, dtype=np.float64) * (ANGSTROM_PER_M / FS_PER_S),
        masses=masses,
        fields=cols,
        species=species,
        origin=lo * ANGSTROM_PER_M,
        pbc=periodic,
        time=float(time) * FS_PER_S,
        length_unit="Angstrom",
        time_unit="fs",
        units=unit_map,
        info=info,
        frame=None if frame is None else frame.scaled(ANGSTROM_PER_M, ANGSTROM_PER_M / FS_PER_S),
    )


def write_png(
    path: str | os.PathLike,
    x: np.ndarray,
    plastic_strain: np.ndarray,
    threshold: float,
    field: np.ndarray | None = None,
    *,
    field_label: str = "pressure",
    field_unit: str = "GPa",
    field_scale: float = 1e-9,
    box: Sequence[float] | None = None,
    title: str | None = None,
    cmap: str = "plasma",
    vmin: float | None = None,
    vmax: float | None = None,
    particle_size: float | None = None,
    width_in: float = 8.0,
    dpi: int = 150,
) -> Path:
    """Draw 2D particles to a PNG atomically; return the path.

    x (n, 2) [m], drawn in mm; plastic_strain (n,) [-]: particles with plastic_strain > threshold
    are green (PLASTIC_GREEN, as in the source talk); the others are coloured by ``field``
    (multiplied by ``field_scale`` and labelled "field_label [field_unit]" on the colour bar,
    default: Pa → GPa) or grey if ``field`` is None. box [m]: (x_lo, x_hi, y_lo, y_hi) frame
    (default: the particles' extent); particle_size [m] (default: the median nearest-lattice
    spacing estimated from the box area per particle) sets the dot diameter.
    """
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure
    from matplotlib.lines import Line2D
    from mpl_toolkits.axes_grid1 import make_axes_locatable

    path = Path(path)
    x = np.asarray(x, dtype=np.float64)
    if x.ndim != 2 or x.shape[1] != 2:
        raise SnapshotError(f"x has shape {x.shape}; write_png draws 2D particles, (n, 2)")
    n = x.shape[0]
    eps = np.asarray(plastic_strain, dtype=np.float64).reshape(-1)
    if eps.shape != (n,):
        raise SnapshotError(f"plastic_strain has shape {np.shape(plastic_strain)}; expected ({n},)")
    if not math.isfinite(threshold) or threshold < 0:
        raise SnapshotError(f"threshold = {threshold!r} must be a finite number ≥ 0")
    if field is not None:
        field = np.asarray(field, dtype=np.float64).reshape(-1)
        if field.shape != (n,):
            raise SnapshotError(f"field has shape {field.shape}; expected ({n},)")
    if box is None:
        if n == 0:
            raise SnapshotError("box is required when there are no particles")
        box = (x[:, 0].min(), x[:, 0].max(), x[:, 1].min(), x[:, 1].max())
    x_lo, x_hi, y_lo, y_hi = (float(b) for b in box)
    if not (x_hi > x_lo and y_hi > y_lo):
        raise SnapshotError(f"box = {tuple(box)!r} must have x_hi > x_lo and y_hi > y_lo")
    if particle_size is None:
        particle_size = math.sqrt((x_hi - x_lo) * (y_hi - y_lo) / max(n, 1))

    aspect = (y_hi - y_lo) / (x_hi - x_lo)
    height_in = min(max(0.8 * width_in * aspect + 1.2, 2.5), 3 * width_in)
    fig = Figure(figsize=(width_in, height_in), dpi=dpi)
    FigureCanvasAgg(fig)
    ax = fig.add_subplot(1, 1, 1)
    mm = 1e3
    ax.set_xlim(x_lo * mm, x_hi * mm)
    ax.set_ylim(y_lo * mm, y_hi * mm)
    ax.set_aspect("equal", adjustable="box")
    ax.set_xlabel("x [mm]")
    ax.set_ylabel("y [mm]")
    if title:
        ax.set_title(title, loc="left")
    plastic = eps > threshold
    rest = ~plastic
    scatters = []
    if field is None:
        scatters.append(
            ax.scatter(x[rest, 0] * mm, x[rest, 1] * mm, c="0.6", marker="o", linewidths=0)
        )
    else:
        sc = ax.scatter(
            x[rest, 0] * mm,
            x[rest, 1] * mm,
            c=field[rest] * field_scale,
            cmap=cmap,
            vmin=vmin,
            vmax=vmax,
            marker="o",
            linewidths=0,
        )
        scatters.append(sc)
        cax = make_axes_locatable(ax).append_axes("right", size="2%", pad=0.1)  # axes height
        cb = fig.colorbar(sc, cax=cax)
        cb.set_label(f"{field_label} [{field_unit}]")
    scatters.append(
        ax.scatter(
            x[plastic, 0] * mm, x[plastic, 1] * mm, c=PLASTIC_GREEN, marker="o", linewidths=0
        )
    )
    handle = Line2D(
        [],
        [],
        ls="",
        marker="o",
        color=PLASTIC_GREEN,
        label=f"plastic strain > {threshold:g} ({int(plastic.sum())} particles)",
    )
    ax.legend(
        handles=[handle],
        loc="lower right",
        bbox_to_anchor=(1.0, 1.0),
        fontsize="small",
        frameon=False,
        borderaxespad=0.2,
    )
    # Dot diameter in points = particle size [mm] × points per mm, measured on the final layout.
    fig.canvas.draw()
    pts_per_mm = ax.get_window_extent().width / ((x_hi - x_lo) * mm) * 72.0 / dpi
    size = max((particle_size * mm * pts_per_mm) ** 2, 0.05)
    for sc in scatters:
        sc.set_sizes([size])
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=dpi, bbox_inches="tight")
    return write_bytes(buf.getvalue(), path)
