"""Extended XYZ snapshots and trajectories: one writer for every backend.

Format (libAtoms/QUIP extended XYZ, the dialect ASE's ``ase.io.extxyz`` and OVITO's XYZ
reader take; spec: https://github.com/libAtoms/extxyz): per frame a count line, a comment line
of ``key=value`` pairs, then one line per particle::

    Lattice="Lx 0 0 0 Ly 0 0 0 Lz" Origin="x0 y0 z0" pbc="F T T"
    Properties=species:S:1:pos:R:3:velo:R:3:masses:R:1:momenta:R:3:<field>:R:1:...
    Time=<t> length_unit=<unit> time_unit=<unit> units="pos:<unit> velo:<unit> ..."
    velocity_frame=<lab|piston|window> frame_velocity=<v> [x_lo=<x> x_hi=<x>]

A trajectory is frames written back to back (ASE: ``ase.io.read(path, index=":")``; OVITO
detects the frames itself).

Column names and what the readers make of them:

- ``species`` (S): ASE needs a chemical symbol ("Ar", "Cu"); OVITO makes it the particle type.
- ``pos`` (R:3): ASE's positions, OVITO's Position. Neither converts units: ASE takes Å, and
  OVITO draws the numbers as they are (a file whose coordinates all lie in [−0.01, 1.01] is
  taken for *reduced* cell coordinates by OVITO, so positions are never written in metres).
- ``velo`` (R:3): OVITO's Velocity (the QUIP name). ASE keeps it as ``atoms.arrays["velo"]``
  and takes velocities only from ``momenta`` over ``masses``; so both are written too
  (``momenta`` = ``masses`` × ``velo``), and ``atoms.get_velocities()`` returns ``velo``.
- ``masses`` (R:1): ASE's masses (otherwise it would use the species' atomic mass).
- any other name: an ASE array and an OVITO user property of that name; R: float, I: integer,
  L: logical (T/F; ASE reads bool).

``Lattice`` is the orthorhombic cell (ASE's cell, OVITO's simulation cell), ``Origin`` its
corner (OVITO's cell origin; ASE keeps it in ``atoms.info``), ``pbc`` the periodic flags.
``length_unit``, ``time_unit`` and ``units`` (column → unit) say what the numbers mean: the
readers do not convert, so a reader that assumes Å is told here what it gets. Reals are
written with 17 significant digits, so float64 values read back exactly. Writes are atomic
(temporary file + rename).

The velocities' frame (``VelocityFrame``, when the backend gives one): ``velocity_frame``
names it (``lab``: the upstream material at rest; ``piston``: the piston at rest, the
upstream material moving at −u_p; ``window``: a moving window's, the upstream material
flowing in at u_in < 0); ``frame_velocity`` is the x velocity that takes a velocity to the
frame of the material at rest ahead of the front, v_x + frame_velocity (lab: 0; piston:
u_p; window: −u_in), in the ``velo`` column's unit; a window adds its edges ``x_lo`` and
``x_hi`` (the part of the cell that is the window: behind x_lo the frozen outflow layer,
beyond x_hi the inflow not yet released; the cell spans them and the walls), in the
``pos`` unit. ``units`` lists these keys' units after the columns'. Scalars, so ASE reads
them into ``atoms.info`` and OVITO into global attributes.
"""

from __future__ import annotations

import io
import math
import os
import re
import tempfile
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .atomic import write_bytes, write_stream

ANGSTROM_PER_M = 1.0e10
FS_PER_S = 1.0e15
_NAME = re.compile(r"^[A-Za-z_][A-Za-z0-9_]*$")
_SPECIES = re.compile(r"^[A-Za-z][A-Za-z0-9_]*$")
_UNIT = re.compile(r"^[A-Za-z0-9_/^*.\-]+$")
_COLUMNS = ("species", "pos", "velo", "masses", "momenta")
_HEADER = ("Lattice", "Origin", "pbc", "Properties", "Time", "length_unit", "time_unit", "units",
           "velocity_frame", "frame_velocity", "x_lo", "x_hi")  # fmt: skip
#: the frames ``VelocityFrame.name`` may name (module docstring)
FRAMES = ("lab", "piston", "window")


class SnapshotError(ValueError):
    """Bad snapshot input (shapes, names, units); the message names the argument."""


@dataclass(frozen=True)
class VelocityFrame:
    """The frame a snapshot's velocities are in (module docstring): ``name`` one of
    ``FRAMES``; ``velocity`` the x velocity that takes them to the frame of the material at
    rest ahead of the front (v_x + velocity), in the snapshot's velocity unit; a window's
    edges ``x_lo`` < ``x_hi`` in its length unit (None for a piston run)."""

    name: str
    velocity: float
    x_lo: float | None = None
    x_hi: float | None = None

    def scaled(self, length: float, velocity: float) -> VelocityFrame:
        """The frame in other units: edges times ``length``, velocity times ``velocity``
        (the factors from the given units to the snapshot's)."""
        lo, hi = (None if x is None else x * length for x in (self.x_lo, self.x_hi))
        return VelocityFrame(self.name, self.velocity * velocity, lo, hi)

    def keys(self, length_unit: str, velocity_unit: str) -> tuple[dict[str, str], dict[str, str]]:
        """(comment-line pairs, their units) of the frame; ``SnapshotError`` if it is not
        one of ``FRAMES``, its velocity is not finite, a window lacks an edge or another
        frame has one, or the edges are not finite with x_lo < x_hi."""
        if self.name not in FRAMES:
            raise SnapshotError(f"velocity frame {self.name!r}: one of {list(FRAMES)}")
        if not math.isfinite(self.velocity):
            raise SnapshotError(f"frame velocity = {self.velocity!r} must be finite")
        pairs = {"velocity_frame": self.name, "frame_velocity": repr(float(self.velocity))}
        units = {"frame_velocity": velocity_unit}
        lo, hi = self.x_lo, self.x_hi
        if ((lo, hi) != (None, None)) != (self.name == "window"):
            raise SnapshotError(f"{self.name} frame with edges {lo!r}, {hi!r}: a window has both, "
                                "no other frame has any")  # fmt: skip
        if (lo, hi) != (None, None):
            ok = lo is not None and hi is not None and math.isfinite(lo) and math.isfinite(hi)
            if not (ok and hi > lo):
                raise SnapshotError(f"window edges x_lo = {lo!r}, x_hi = {hi!r}: finite, lo < hi")
            pairs.update(x_lo=repr(float(lo)), x_hi=repr(float(hi)))
            units.update(x_lo=length_unit, x_hi=length_unit)
        return pairs, units


def _value(key: str, value: object) -> str:
    if isinstance(value, bool | np.bool_):
        return "T" if value else "F"
    if isinstance(value, int | np.integer):
        return str(int(value))
    if isinstance(value, float | np.floating):
        return repr(float(value))
    text = str(value)
    if any(c in text for c in '"\n\r\\'):
        raise SnapshotError(
            f"info[{key!r}] = {text!r} must not contain quotes, backslashes or line breaks"
        )
    return f'"{text}"' if (not text or any(c in text for c in " =,")) else text


def _vectors(name: str, a: np.ndarray | None, n: int) -> np.ndarray:
    """(n, 3) float64 from (n,), (n, 1), (n, 2) or (n, 3), padded with zeros."""
    if a is None:
        return np.zeros((n, 3))
    a = np.asarray(a, dtype=np.float64)
    if a.ndim == 1:
        a = a[:, None]
    if a.ndim != 2 or a.shape[0] != n or a.shape[1] not in (1, 2, 3):
        raise SnapshotError(f"{name} has shape {a.shape}; expected ({n}, dim) with dim 1, 2 or 3")
    out = np.zeros((n, 3))
    out[:, : a.shape[1]] = a
    return out


def _column(name: str, arr: np.ndarray, n: int) -> tuple[str, np.ndarray, list[str]]:
    a = np.asarray(arr)
    if a.ndim == 1:
        a = a[:, None]
    if a.ndim != 2 or a.shape[0] != n:
        raise SnapshotError(
            f"field {name!r} has shape {np.shape(arr)}; expected ({n},) or ({n}, k)"
        )
    if a.dtype == bool:
        return f"{name}:L:{a.shape[1]}", np.where(a, "T", "F"), ["%s"] * a.shape[1]
    if np.issubdtype(a.dtype, np.integer):
        return f"{name}:I:{a.shape[1]}", a, ["%d"] * a.shape[1]
    if np.issubdtype(a.dtype, np.floating):
        return f"{name}:R:{a.shape[1]}", a.astype(np.float64), ["%.17g"] * a.shape[1]
    raise SnapshotError(f"field {name!r} has dtype {a.dtype}; expected float, int or bool")


def format_frame(
    positions: np.ndarray,
    cell: Sequence[float],
    *,
    velocities: np.ndarray | None = None,
    masses: float | np.ndarray = 1.0,
    fields: Mapping[str, np.ndarray] | None = None,
    species: str | Sequence[str] = "X",
    origin: Sequence[float] = (0.0, 0.0, 0.0),
    pbc: Sequence[bool] = (False, False, False),
    time: float = 0.0,
    length_unit: str = "Angstrom",
    time_unit: str = "fs",
    units: Mapping[str, str] | None = None,
    info: Mapping[str, object] | None = None,
    frame: VelocityFrame | None = None,
) -> str:
    """One frame as text (module docstring), every number as given: convert beforehand.

    positions (n, dim), dim ≤ 3 (padded with zeros) and velocities (same; None: zero) in
    ``length_unit`` and ``length_unit``/``time_unit``; cell (3,): the orthorhombic cell's
    lengths, origin (3,) its corner, in ``length_unit``; masses: one value or (n,);
    fields: name → (n,) or (n, k) array (float → R, integer → I, bool → L); species: one
    symbol for all or one per particle; pbc: three flags; time in ``time_unit``; units:
    column → unit for the ``units`` key (pos and velo get theirs from the length and time
    units unless given); info: more comment-line pairs (str, int, float, bool); frame:
    the velocities' frame (``VelocityFrame``, in ``length_unit`` and its velocity unit).
    """
    pos = _vectors("positions", positions, np.shape(positions)[0])
    n = pos.shape[0]
    vel = _vectors("velocities", velocities, n)
    mass = np.broadcast_to(np.asarray(masses, dtype=np.float64), (n,)) if n else np.zeros(0)
    cell = np.asarray(cell, dtype=np.float64).reshape(-1)
    org = np.asarray(origin, dtype=np.float64).reshape(-1)
    if cell.shape != (3,) or not np.all(np.isfinite(cell)) or np.any(cell <= 0):
        raise SnapshotError(f"cell = {cell.tolist()}: three finite lengths > 0 expected")
    if org.shape != (3,) or not np.all(np.isfinite(org)):
        raise SnapshotError(f"origin = {org.tolist()}: three finite numbers expected")
    flags = [bool(p) for p in pbc]
    if len(flags) != 3:
        raise SnapshotError(f"pbc = {pbc!r} must hold three flags (x, y, z)")
    if not math.isfinite(time):
        raise SnapshotError(f"time = {time!r} must be finite")
    if isinstance(species, str):
        if not _SPECIES.match(species):
            raise SnapshotError(f"species = {species!r} must be a name like 'Ar'")
        spec = np.full(n, species, dtype=object)
    else:
        spec = np.asarray(species, dtype=object)
        if spec.shape != (n,) or not all(_SPECIES.match(str(s)) for s in spec):
            raise SnapshotError(f"species must be one name or {n} names like 'Ar'")
    for u in (length_unit, time_unit):
        if not _UNIT.match(u):
            raise SnapshotError(f"unit {u!r}: use a compact token such as Angstrom, fs, sigma")

    vunit = f"{length_unit}/{time_unit}"
    props = ["species:S:1", "pos:R:3", "velo:R:3", "masses:R:1", "momenta:R:3"]
    columns: list[np.ndarray] = [spec[:, None], pos, vel, mass[:, None], mass[:, None] * vel]
    fmts: list[str] = ["%s"] + ["%.17g"] * 10
    for name, arr in (fields or {}).items():
        if not _NAME.match(name) or name in _COLUMNS:
            raise SnapshotError(
                f"field name {name!r} must match [A-Za-z_][A-Za-z0-9_]* and not be one of "
                f"{list(_COLUMNS)}"
            )
        prop, col, fmt = _column(name, arr, n)
        props.append(prop)
        columns.append(col)
        fmts += fmt
    unit_map = {"pos": length_unit, "velo": vunit}
    for name, unit in (units or {}).items():
        if name not in (fields or {}) and name not in _COLUMNS:
            raise SnapshotError(f"units names {name!r}, which is not a column")
        if not _UNIT.match(unit):
            raise SnapshotError(f"units[{name!r}] = {unit!r}: use a compact token such as Pa, m/s")
        unit_map[name] = unit
    frame_pairs: dict[str, str] = {}
    if frame is not None:
        frame_pairs, frame_units = frame.keys(length_unit, vunit)
        unit_map.update(frame_units)
    header = {
        "Lattice": '"' + " ".join(f"{v:.17g}" for v in np.diag(cell).ravel()) + '"',
        "Origin": '"' + " ".join(f"{v:.17g}" for v in org) + '"',
        "pbc": '"' + " ".join("T" if p else "F" for p in flags) + '"',
        "Properties": ":".join(props),
        "Time": repr(float(time)),
        "length_unit": length_unit,
        "time_unit": time_unit,
        "units": '"' + " ".join(f"{k}:{v}" for k, v in unit_map.items()) + '"',
        **frame_pairs,
    }
    for key, value in (info or {}).items():
        if not _NAME.match(key) or key in _HEADER:
            raise SnapshotError(f"info key {key!r} must be a name and not one of {list(_HEADER)}")
        header[key] = _value(key, value)
    body = io.StringIO()
    body.write(f"{n}\n")
    body.write(" ".join(f"{k}={v}" for k, v in header.items()) + "\n")
    if n:
        table = np.empty((n, len(fmts)), dtype=object)
        c = 0
        for col in columns:
            table[:, c : c + col.shape[1]] = col
            c += col.shape[1]
        np.savetxt(body, table, fmt=" ".join(fmts))
    return body.getvalue()


def write_extxyz(
    path: str | os.PathLike, frames: str | Sequence[str], append: bool = False
) -> Path:
    """Write ``frames`` (``format_frame`` texts) to ``path`` atomically; ``append`` adds them
    to the file's frames (still a new file and a rename). Returns the path."""
    path = Path(path)
    text = frames if isinstance(frames, str) else "".join(frames)
    data = text.encode()
    if append and path.exists():
        data = path.read_bytes() + data
    return write_bytes(data, path)


class Trajectory:
    """Frames taken every ``every``-th call of ``offer`` during a run, kept in an anonymous
    temporary file (no memory held, nothing left behind by a killed job) until ``save``.

    ``offer(make)`` counts a sample and, on every ``every``-th, appends ``make()`` (a
    ``format_frame`` text). ``every`` ≥ 1.
    """

    def __init__(self, every: int):
        if int(every) < 1:
            raise SnapshotError(f"every = {every!r} must be an integer >= 1")
        self.every = int(every)
        self.samples = 0
        self.frames = 0
        self._file = tempfile.TemporaryFile(mode="w+b")

    def offer(self, make: Callable[[], str]) -> None:
        self.samples += 1
        if self.samples % self.every == 0:
            self._file.write(make().encode())
            self.frames += 1

    def save(self, path: str | os.PathLike) -> Path | None:
        """Copy the frames taken so far to ``path`` (atomically); None when there are none."""
        if not self.frames:
            return None
        self._file.flush()
        self._file.seek(0)
        try:
            return write_stream(self._file, path)
        finally:
            self._file.seek(0, os.SEEK_END)


class RecordingProfile:
    """A backend's profile reader that also offers a trajectory frame on every ``sums`` call
    (the one call every run makes once a sample: the piston's drive, the window schemes,
    the steady average); every other attribute is the reader's."""

    def __init__(self, inner, trajectory: Trajectory, make: Callable[[object], str]):
        self._inner = inner
        self._trajectory = trajectory
        self._make = make

    def sums(self, solver) -> np.ndarray:
        out = self._inner.sums(solver)
        self._trajectory.offer(lambda: self._make(solver))
        return out

    def __getattr__(self, name: str):
        return getattr(self._inner, name)


def snapshot_paths(out: str | os.PathLike) -> tuple[Path, Path]:
    """The snapshot and trajectory beside a point file ``out``: ``<stem>_snapshot.extxyz``,
    ``<stem>_trajectory.extxyz`` (``up1/piston.nc`` → ``up1/piston_snapshot.extxyz``)."""
    out = Path(out)
    return (
        out.parent / f"{out.stem}_snapshot.extxyz",
        out.parent / f"{out.stem}_trajectory.extxyz",
    )


__all__ = [
    "ANGSTROM_PER_M",
    "FRAMES",
    "FS_PER_S",
    "RecordingProfile",
    "SnapshotError",
    "Trajectory",
    "VelocityFrame",
    "format_frame",
    "snapshot_paths",
    "write_extxyz",
]
