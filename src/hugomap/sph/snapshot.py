"""Snapshots of CSPH particles: extended XYZ (OVITO, ASE) and PNG pictures.

Extended XYZ (the format of ASE's ``ase.io.extxyz`` and OVITO's XYZ reader; spec:
https://github.com/libAtoms/extxyz): per frame, a count line, a comment line of key=value pairs,

    Lattice="Lx 0 0 0 Ly 0 0 0 Lz" Origin="x_lo y_lo z_lo" pbc="F T F"
    Properties=species:S:1:pos:R:3:<name>:R:1:... Time=<t> length_unit=um time_unit=s
    units="pos:um pressure:Pa ..." <comment_attrs>

then one line per particle: species, x, y, z, then the fields in the order of ``Properties``.
Positions, ``Lattice``, ``Origin`` and the optional ``radius`` column are written in
``length_unit`` (default μm). Not metres: OVITO's XYZ reader takes a file whose coordinates all lie
within [−0.01, 1.01] for *reduced* cell coordinates and rescales them (OVITO source,
``XYZImporter.cpp``), which would misplace a sub-metre sample written in metres; in μm SPH
particles a few μm apart also get sizes of order one in a viewer. 2D (and 1D) positions are
padded with z = 0 (and y = 0), and the missing cell lengths are ``depth`` (default: the largest
box length, so the cell is never singular). ``Time`` is in seconds. Field values are written as
given (SI unless the caller says otherwise in ``units``). Reals are written with 17 significant
digits, so float64 values read back exactly. Writes are atomic (temporary file + rename).

Column names OVITO maps to its standard properties (QUIP conventions): ``species`` → type,
``pos``, ``velo`` → velocity, ``radius``, ``id`` → identifier, ``mass``, ``stress``; other
numeric names become custom properties. ASE needs the species to be chemical symbols ("Cu").

PNG (``write_png``): the 2D particles drawn as dots with axes in mm and equal aspect;
plastically deformed particles (accumulated plastic strain > threshold) in green, as in the
source talk's pore-collapse picture; the others coloured by a field with a colour bar (e.g.
pressure in GPa) or grey. Uses matplotlib's Agg canvas directly (no pyplot, no global state).
"""

from __future__ import annotations

import io
import math
import os
import re
import tempfile
from collections.abc import Mapping, Sequence
from pathlib import Path

import numpy as np

_LENGTH_UNITS = {"m": 1.0, "mm": 1e3, "um": 1e6, "nm": 1e9}
_NAME = re.compile(r"^[A-Za-z_][A-Za-z0-9_]*$")
_RESERVED = {"species", "pos", "Lattice", "Properties", "Time", "Origin", "pbc"}
PLASTIC_GREEN = "#1a9e1a"
"""Colour of plastically deformed particles (the source talk draws them green)."""


class SnapshotError(ValueError):
    """Bad snapshot input (shapes, names, units); the message names the argument."""


def _atomic_write_bytes(path: Path, data: bytes) -> Path:
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent)
    try:
        with os.fdopen(fd, "wb") as fh:
            fh.write(data)
        os.chmod(tmp, 0o644)  # mkstemp creates 0600; a snapshot is for sharing
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise
    return path


def _attr_value(key: str, value: object) -> str:
    if isinstance(value, bool | np.bool_):
        return "T" if value else "F"
    if isinstance(value, int | np.integer):
        return str(int(value))
    if isinstance(value, float | np.floating):
        return repr(float(value))
    text = str(value)
    if any(c in text for c in '"\n\r\\'):
        raise SnapshotError(
            f"comment_attrs[{key!r}] = {text!r} must not contain quotes, backslashes or line breaks"
        )
    return f'"{text}"' if (not text or any(c in text for c in " =,")) else text


def _positions_3d(x: np.ndarray) -> np.ndarray:
    x = np.asarray(x, dtype=np.float64)
    if x.ndim == 1:
        x = x[:, None]
    if x.ndim != 2 or x.shape[1] not in (1, 2, 3):
        raise SnapshotError(f"x has shape {x.shape}; expected (n, dim) with dim in 1, 2, 3")
    out = np.zeros((x.shape[0], 3))
    out[:, : x.shape[1]] = x
    return out


def write_extxyz(
    path: str | os.PathLike,
    x: np.ndarray,
    fields: Mapping[str, np.ndarray],
    box: Sequence[float],
    comment_attrs: Mapping[str, object] | None = None,
    *,
    time: float = 0.0,
    species: str | Sequence[str] = "Cu",
    units: Mapping[str, str] | None = None,
    length_unit: str = "um",
    periodic: Sequence[bool] = (False, False, False),
    depth: float | None = None,
    radius: np.ndarray | None = None,
    append: bool = False,
) -> Path:
    """Write one extended-XYZ frame (see the module doc) atomically; return the path.

    x (n, dim) [m]; fields: name → (n,) or (n, k) array (float → R, integer → I, bool → L);
    box: (x_lo, x_hi) in 1D, (x_lo, x_hi, y_lo, y_hi) in 2D, six values in 3D [m];
    comment_attrs: extra key=value pairs for the comment line (str, int, float, bool);
    time [s]; species: one symbol for all or one per particle; units: field name → unit string,
    written in the ``units`` key (pos gets ``length_unit``); length_unit: m, mm, um or nm;
    periodic: pbc flags per axis; depth [m]: cell length along the padded axes; radius (n,) [m]:
    written as the ``radius`` column in ``length_unit`` (OVITO draws particles with it; e.g.
    half the particle size l); append: add the frame to an existing file (a trajectory), still
    by writing a new file and renaming it.
    """
    path = Path(path)
    pos = _positions_3d(x)
    n = pos.shape[0]
    if length_unit not in _LENGTH_UNITS:
        raise SnapshotError(f"length_unit = {length_unit!r} must be one of {list(_LENGTH_UNITS)}")
    scale = _LENGTH_UNITS[length_unit]
    box = [float(b) for b in box]
    if len(box) not in (2, 4, 6) or not all(math.isfinite(b) for b in box):
        raise SnapshotError(f"box = {box!r} must hold 2, 4 or 6 finite numbers (lo, hi per axis)")
    lo = np.zeros(3)
    length = np.zeros(3)
    for k in range(len(box) // 2):
        lo[k], length[k] = box[2 * k], box[2 * k + 1] - box[2 * k]
    filled = length > 0
    if not filled[0]:
        raise SnapshotError(f"box = {box!r}: x_hi must exceed x_lo")
    pad = float(depth) if depth is not None else float(length[filled].max())
    if not (math.isfinite(pad) and pad > 0):
        raise SnapshotError(f"depth = {depth!r} must be a finite length > 0 (metres)")
    length[~filled] = pad
    if isinstance(species, str):
        if not re.fullmatch(r"[A-Za-z][A-Za-z0-9_]*", species):
            raise SnapshotError(f"species = {species!r} must be a name like 'Cu'")
        spec = None
    else:
        spec = np.asarray(species, dtype=str)
        if spec.shape != (n,) or not all(re.fullmatch(r"[A-Za-z][A-Za-z0-9_]*", s) for s in spec):
            raise SnapshotError("species must be one name or n names like 'Cu'")
    pbc = [bool(p) for p in periodic]
    if len(pbc) != 3:
        raise SnapshotError(f"periodic = {periodic!r} must hold three flags (x, y, z)")

    props = ["species:S:1", "pos:R:3"]
    columns: list[np.ndarray] = [pos * scale]
    fmts: list[str] = ["%.17g"] * 3
    unit_map = {"pos": length_unit}
    if radius is not None:
        rad = np.asarray(radius, dtype=np.float64).reshape(-1)
        if rad.shape != (n,) or "radius" in fields:
            raise SnapshotError(f"radius must have shape ({n},) and not also be a field")
        props.append("radius:R:1")
        columns.append(rad[:, None] * scale)
        fmts.append("%.17g")
        unit_map["radius"] = length_unit
    for name, arr in fields.items():
        if not _NAME.match(name) or name in _RESERVED:
            raise SnapshotError(
                f"field name {name!r} must match [A-Za-z_][A-Za-z0-9_]* and not be one of "
                f"{sorted(_RESERVED)}"
            )
        a = np.asarray(arr)
        if a.ndim == 1:
            a = a[:, None]
        if a.ndim != 2 or a.shape[0] != n:
            raise SnapshotError(
                f"field {name!r} has shape {np.shape(arr)}; expected ({n},) or ({n}, k)"
            )
        if a.dtype == bool:
            code, fmt, a = "L", "%s", np.where(a, "T", "F")
        elif np.issubdtype(a.dtype, np.integer):
            code, fmt = "I", "%d"
        elif np.issubdtype(a.dtype, np.floating):
            code, fmt, a = "R", "%.17g", a.astype(np.float64)
        else:
            raise SnapshotError(f"field {name!r} has dtype {a.dtype}; expected float, int or bool")
        props.append(f"{name}:{code}:{a.shape[1]}")
        columns.append(a)
        fmts += [fmt] * a.shape[1]

    for name, unit in (units or {}).items():
        if name not in fields:
            raise SnapshotError(f"units names {name!r}, which is not a field")
        if not re.fullmatch(r"[A-Za-z0-9_/^*.\-]+", unit):
            raise SnapshotError(f"units[{name!r}] = {unit!r}: use a compact token such as Pa, m/s")
        unit_map[name] = unit
    cell = np.diag(length * scale)
    header = {
        "Lattice": '"' + " ".join(f"{v:.17g}" for v in cell.ravel()) + '"',
        "Origin": '"' + " ".join(f"{v:.17g}" for v in lo * scale) + '"',
        "pbc": '"' + " ".join("T" if p else "F" for p in pbc) + '"',
        "Properties": ":".join(props),
        "Time": repr(float(time)),
        "length_unit": length_unit,
        "time_unit": "s",
        "units": '"' + " ".join(f"{k}:{v}" for k, v in unit_map.items()) + '"',
    }
    for key, value in (comment_attrs or {}).items():
        if not _NAME.match(key) or key in header:
            raise SnapshotError(
                f"comment_attrs key {key!r} must be a name and not one of {sorted(header)}"
            )
        header[key] = _attr_value(key, value)

    body = io.StringIO()
    body.write(f"{n}\n")
    body.write(" ".join(f"{k}={v}" for k, v in header.items()) + "\n")
    if n:
        table = np.empty((n, len(fmts)), dtype=object)
        c = 0
        for col in columns:
            table[:, c : c + col.shape[1]] = col
            c += col.shape[1]
        row = " ".join(fmts)
        if spec is None:
            np.savetxt(body, table, fmt=f"{species} {row}")
        else:
            np.savetxt(body, np.column_stack([spec.astype(object), table]), fmt=f"%s {row}")
    data = body.getvalue().encode()
    if append and path.exists():
        data = path.read_bytes() + data
    return _atomic_write_bytes(path, data)


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
    return _atomic_write_bytes(path, buf.getvalue())
