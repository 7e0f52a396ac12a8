"""LAMMPS data files (``atom_style atomic``, ``units lj``) out of and into MD states.

The format is the one LAMMPS ``read_data`` reads and ``write_data`` writes (LAMMPS manual,
``read_data`` command): a title line, a header of ``<count> <keyword>`` and ``<lo> <hi>
<axis>lo <axis>hi`` lines, then sections, each a keyword line, a blank line and one line per
entry::

    <title>

    N atoms
    2 atom types
    x_lo x_hi xlo xhi
    y_lo y_hi ylo yhi
    z_lo z_hi zlo zhi

    Masses

    1 1
    2 1

    Atoms # atomic

    id type x y z

    Velocities

    id vx vy vz

Reduced LJ units are LAMMPS ``units lj``: lengths [σ], velocities [σ/τ], masses [m] (every
atom has m = 1). Type 1 is a mobile atom, type 2 a frozen one (hugomap's ids < 0: a window's
rigid outflow layer or inflow copy; in LAMMPS, e.g. ``group frozen type 2`` with
``fix setforce 0 0 0`` keeps them rigid). The LAMMPS id of a mobile atom is its hugomap id + 1
(ids are stable labels, not the storage order); frozen atoms are numbered after the largest
one. The box spans the periodic lengths in y and z and, along x (bounded by walls in
hugomap, ``boundary f p p`` in LAMMPS), the walls and every atom. The title line records
what LAMMPS cannot: step, time and the walls ``x_k0 + v_k t`` (to 6 significant digits).

Reading (``read_data``) takes the subset of the format such a file uses: an orthogonal box
(a ``xy xz yz`` tilt line is refused), one atom style (``id type x y z`` with optional image
flags ``ix iy iz``, applied), ``Masses`` all 1, an optional ``Velocities`` section (absent:
zero velocities), ``#`` comments. Anything else (other sections, missing or duplicated ids,
counts that do not match) raises ``LammpsDataError`` naming the file and line.

This module needs numpy only: config validation reads data files with it.
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path

import numpy as np

MOBILE, FROZEN = 1, 2
_SECTIONS = ("Masses", "Atoms", "Velocities")


class LammpsDataError(ValueError):
    """A LAMMPS data file that cannot be read (or a state that cannot be written)."""


@dataclass
class LammpsData:
    """The contents of a data file: ids (n,) LAMMPS ids; types (n,) 1 mobile, 2 frozen;
    x (n, 3) positions [σ] (image flags applied); v (n, 3) velocities [σ/τ]; lo, hi (3,)
    the box bounds [σ]; title: the first line."""

    ids: np.ndarray
    types: np.ndarray
    x: np.ndarray
    v: np.ndarray
    lo: np.ndarray
    hi: np.ndarray
    title: str = ""

    @property
    def L(self) -> np.ndarray:
        return self.hi - self.lo


def _num(value: float) -> str:
    return f"{float(value):.17g}"


def format_data(
    x: np.ndarray, v: np.ndarray, ids: np.ndarray, lo: np.ndarray, hi: np.ndarray, title: str
) -> str:
    """The data file's text (module docstring) for hugomap ``ids`` (< 0: frozen, type 2)."""
    x = np.asarray(x, dtype=np.float64)
    v = np.asarray(v, dtype=np.float64)
    ids = np.asarray(ids, dtype=np.int64)
    n = x.shape[0]
    if x.shape != (n, 3) or v.shape != (n, 3) or ids.shape != (n,):
        raise LammpsDataError(
            f"positions {x.shape}, velocities {v.shape}, ids {ids.shape}: expected (n, 3), "
            "(n, 3), (n,)"
        )
    if not (np.all(np.isfinite(x)) and np.all(np.isfinite(v))):
        raise LammpsDataError("positions and velocities must be finite")
    frozen = ids < 0
    lid = ids + 1
    top = int(lid[~frozen].max()) if (~frozen).any() else 0
    lid[frozen] = top + 1 + np.arange(int(frozen.sum()))
    if np.unique(lid).size != n:
        raise LammpsDataError("the atoms' ids are not unique")
    types = np.where(frozen, FROZEN, MOBILE)
    title = " ".join(title.split())  # one line
    out = [
        title or "LAMMPS data file written by hugomap (units lj, atom_style atomic)",
        "",
        f"{n} atoms",
        "2 atom types",
    ]
    out += [f"{_num(a)} {_num(b)} {k}lo {k}hi" for a, b, k in zip(lo, hi, "xyz", strict=True)]
    out += ["", "Masses", "", "1 1", "2 1", "", "Atoms # atomic", ""]
    out += [
        f"{i} {t} {_num(p[0])} {_num(p[1])} {_num(p[2])}"
        for i, t, p in zip(lid, types, x, strict=True)
    ]
    out += ["", "Velocities", ""]
    out += [f"{i} {_num(q[0])} {_num(q[1])} {_num(q[2])}" for i, q in zip(lid, v, strict=True)]
    return "\n".join(out) + "\n"


def write_data(path: str | os.PathLike, text: str) -> Path:
    """Write a data file's text atomically (temporary file + rename)."""
    from ..io.atomic import write_bytes

    return write_bytes(text.encode(), path)


def _fail(path, line: int | None, what: str):
    where = f"{path}" if line is None else f"{path}, line {line}"
    raise LammpsDataError(f"LAMMPS data file {where}: {what}")


def read_data(path: str | os.PathLike) -> LammpsData:
    """Read a data file (module docstring); ``LammpsDataError`` naming the file otherwise
    (also for a missing or unreadable one)."""
    path = Path(path)
    try:
        raw = path.read_text()
    except (OSError, UnicodeDecodeError) as exc:
        raise LammpsDataError(f"LAMMPS data file {path} cannot be read: {exc}") from None
    lines = raw.splitlines()
    if not lines:
        _fail(path, None, "the file is empty")
    title = lines[0].strip()
    body = [(k + 1, ln.split("#", 1)[0].strip()) for k, ln in enumerate(lines) if k > 0]
    n_atoms = n_types = None
    lo, hi = np.full(3, np.nan), np.full(3, np.nan)
    k = 0
    while k < len(body):  # the header, up to the first section keyword
        num, text = body[k]
        if not text:
            k += 1
            continue
        words = text.split()
        if words[0] in _SECTIONS or not words[0][:1].isdigit() and words[0][:1] not in "+-.":
            break
        try:
            if words[1:] == ["atoms"]:
                n_atoms = int(words[0])
            elif words[1:] == ["atom", "types"]:
                n_types = int(words[0])
            elif len(words) == 4 and words[2:] in (["xlo", "xhi"], ["ylo", "yhi"], ["zlo", "zhi"]):
                a = "xyz".index(words[2][0])
                lo[a], hi[a] = float(words[0]), float(words[1])
            elif words[-3:] == ["xy", "xz", "yz"]:
                _fail(path, num, "a triclinic box (xy xz yz) is not supported")
            elif int(words[0]) != 0:
                _fail(path, num, f"header {text!r}: only atoms, atom types and the box are read")
        except (ValueError, IndexError) as exc:
            if isinstance(exc, LammpsDataError):
                raise
            _fail(path, num, f"bad header line {text!r}")
        k += 1
    if n_atoms is None or n_types is None:
        _fail(path, None, "the header must give '<n> atoms' and '<n> atom types'")
    if not (np.all(np.isfinite(lo)) and np.all(hi > lo)):
        _fail(path, None, "the header must give xlo xhi, ylo yhi, zlo zhi with hi > lo")
    sections: dict[str, list[tuple[int, list[str]]]] = {}
    current = None
    for num, text in body[k:]:
        if not text:
            continue
        words = text.split()
        if words[0][:1].isalpha():
            if words[0] not in _SECTIONS:
                _fail(path, num, f"section {words[0]!r}: only Masses, Atoms, Velocities are read")
            if words[0] in sections:
                _fail(path, num, f"section {words[0]} appears twice")
            current = words[0]
            sections[current] = []
            continue
        if current is None:
            _fail(path, num, f"line {text!r} outside any section")
        sections[current].append((num, words))
    for name in ("Masses", "Atoms"):
        if name not in sections:
            _fail(path, None, f"no {name} section")

    def table(name: str, ncols: tuple[int, ...], count: int) -> np.ndarray:
        rows = sections[name]
        if len(rows) != count:
            _fail(path, None, f"{name}: {len(rows)} lines for {count} entries in the header")
        width = len(rows[0][1]) if rows else ncols[0]
        for num, words in rows:
            if len(words) not in ncols or len(words) != width:
                _fail(path, num, f"{name}: expected {' or '.join(map(str, ncols))} columns")
        try:
            return np.array([[float(w) for w in words] for _, words in rows]).reshape(count, width)
        except ValueError:
            _fail(path, rows[0][0], f"{name}: a value is not a number")

    masses = table("Masses", (2,), n_types)
    if not np.all(masses[:, 1] == 1.0):
        _fail(path, None, "every mass must be 1 (reduced LJ units: units lj, m = 1)")
    atoms = table("Atoms", (5, 8), n_atoms)
    ids = atoms[:, 0].astype(np.int64)
    types = atoms[:, 1].astype(np.int64)
    if np.any(atoms[:, :2] != np.round(atoms[:, :2])) or np.any(ids < 1):
        _fail(path, None, "Atoms: ids and types must be positive integers (atom_style atomic)")
    if np.unique(ids).size != n_atoms:
        _fail(path, None, "Atoms: the ids are not unique")
    if np.any((types < 1) | (types > n_types)):
        _fail(path, None, f"Atoms: a type outside 1..{n_types}")
    x = atoms[:, 2:5].copy()
    if atoms.shape[1] == 8:  # image flags
        x += atoms[:, 5:8] * (hi - lo)
    v = np.zeros((n_atoms, 3))
    if "Velocities" in sections:
        vel = table("Velocities", (4,), n_atoms)
        order = {int(i): r for r, i in enumerate(ids)}
        try:
            rows = [order[int(i)] for i in vel[:, 0]]
        except KeyError as exc:
            _fail(path, None, f"Velocities: atom id {exc.args[0]} is not in Atoms")
        if len(set(rows)) != n_atoms:
            _fail(path, None, "Velocities: an atom appears twice")
        v[rows] = vel[:, 1:4]
    if not (np.all(np.isfinite(x)) and np.all(np.isfinite(v))):
        _fail(path, None, "positions and velocities must be finite")
    return LammpsData(ids, types, x, v, lo, hi, title)


def checkpoint_to_data(ds) -> str:
    """The data-file text of an MD checkpoint (sample, loading, partial piston or window:
    any dataset with ``x``, ``v``, ``ids``, ``L``, ``walls0`` and the ``time`` attribute).
    Positions are written as they are (a periodic y or z outside [0, L) is LAMMPS's to wrap;
    ``read_data`` does)."""
    for name in ("x", "v", "ids", "L", "walls0"):
        if name not in ds:
            raise LammpsDataError(f"the checkpoint has no variable {name!r}: not an MD checkpoint")
    x, v = ds["x"].values, ds["v"].values
    L, w = ds["L"].values.astype(float), ds["walls0"].values.astype(float)
    t = float(ds.attrs.get("time", 0.0))
    walls = (w[0] + w[1] * t, w[2] + w[3] * t)
    xs = x[:, 0] if x.shape[0] else np.zeros(1)
    lo = np.array([min(0.0, *walls, float(xs.min())), 0.0, 0.0])
    hi = np.array([max(float(L[0]), *walls, float(xs.max())), L[1], L[2]])
    kind = "window" if "window_format" in ds.attrs else "state"
    # the title is for reading: 6 significant digits (the atoms' lines keep 17)
    t6, (a, va, b, vb) = f"{t:.6g}", (f"{float(c):.6g}" for c in w)
    title = (
        f"LAMMPS data file written by hugomap from an MD {kind} checkpoint (units lj, "
        f"atom_style atomic, boundary f p p; type 2 frozen): step {int(ds.attrs.get('step', 0))}"
        f" time {t6} tau, walls at x = {a} + {va} t and {b} + {vb} t"
    )
    return format_data(x, v, ds["ids"].values, lo, hi, title)


__all__ = [
    "FROZEN",
    "MOBILE",
    "LammpsData",
    "LammpsDataError",
    "checkpoint_to_data",
    "format_data",
    "read_data",
    "write_data",
]
