"""Checkpoint kinds, format versions and integrity: every checkpoint hugomap writes or reads.

A checkpoint is a netCDF dataset whose attributes name its kind and format version and carry
a SHA-256 checksum (attribute ``checksum``, ``"sha256:<hex>"``) over every variable and every
other attribute. The kinds (``CheckpointKind``):

    MD_CHECKPOINT             ``format``  hugomap-md-checkpoint/2   an MD sample or loading state
    MD_WINDOW_CHECKPOINT      + ``window_format``  hugomap-md-window/2   an MD window
    CSPH_CHECKPOINT           ``sim_format``  hugomap-sph-checkpoint/1   a CSPH simulation
    CSPH_WINDOW_CHECKPOINT    + ``window_format``  hugomap-sph-window/2  a 1D CSPH window
    CSPH_WINDOW_2D_CHECKPOINT + ``window_format``  hugomap-sph-window2d/1  a 2D CSPH window
    LAMMPS_CHECKPOINT         ``format``  hugomap-lammps-checkpoint/1   a LAMMPS run's state
    LAMMPS_WINDOW_CHECKPOINT  + ``window_format``  hugomap-lammps-window/1  a LAMMPS window

A window checkpoint is its solver's checkpoint with the window's variables and attributes
added, all under the one checksum. ``seal_checkpoint`` sets the format attributes and the
checksum; ``verify_checkpoint`` refuses (``CheckpointError``, naming the file) a dataset that
is foreign, of an older or newer format, without a checksum, or altered after it was sealed;
``read_checkpoint`` also refuses a file that cannot be read (truncated, not netCDF, missing).
What the variables mean is the solvers' business (``MDSimulation.to_dataset``,
``sph.checkpoint``): this module knows only the kinds, the formats and the checksum.
"""

from __future__ import annotations

import hashlib
import os
from dataclasses import dataclass

import numpy as np
import xarray as xr

from ..failures import CheckpointError

CHECKSUM_ATTR = "checksum"
IN_MEMORY = "(in-memory dataset)"  # what a refusal names for a dataset not read from a file


@dataclass(frozen=True)
class CheckpointKind:
    """One kind of checkpoint: the attribute ``attr`` holding its format string ``format``.

    ``what`` names the kind in a refusal ("an MD checkpoint"); ``inside``: the kind this one
    extends (a window checkpoint is its solver's checkpoint plus the window); ``family``: the
    prefix every version of this format shares (set, a format of the family other than
    ``format`` is refused as an unsupported version rather than as foreign); ``unchecked``:
    older versions of the family written before checkpoints had checksums.
    """

    what: str
    attr: str
    format: str
    inside: CheckpointKind | None = None
    family: str | None = None
    unchecked: tuple[str, ...] = ()

    def chain(self) -> tuple[CheckpointKind, ...]:
        """This kind and those it extends, innermost (the solver's) first."""
        return (*(self.inside.chain() if self.inside else ()), self)


# /2: a SHA-256 checksum (attribute ``checksum``); /1 had none.
MD_CHECKPOINT = CheckpointKind(
    "an MD checkpoint",
    "format",
    "hugomap-md-checkpoint/2",
    family="hugomap-md-checkpoint/",
    unchecked=("hugomap-md-checkpoint/1",),
)
# /2: inside a checksummed MD checkpoint (format /2).
MD_WINDOW_CHECKPOINT = CheckpointKind(
    "an MD window checkpoint", "window_format", "hugomap-md-window/2", inside=MD_CHECKPOINT
)
CSPH_CHECKPOINT = CheckpointKind("a CSPH checkpoint", "sim_format", "hugomap-sph-checkpoint/1")
# /2: the simulation inside is a CSPH checkpoint (format hugomap-sph-checkpoint/1).
CSPH_WINDOW_CHECKPOINT = CheckpointKind(
    "an SPH window checkpoint", "window_format", "hugomap-sph-window/2", inside=CSPH_CHECKPOINT
)
CSPH_WINDOW_2D_CHECKPOINT = CheckpointKind(
    "a 2D SPH window checkpoint",
    "window_format",
    "hugomap-sph-window2d/1",
    inside=CSPH_CHECKPOINT,
)

#: The checkpoint of a LAMMPS run (``lammps.simulation.LammpsSimulation``): positions,
#: velocities, ids, box, walls, clock. /1: first.
LAMMPS_CHECKPOINT = CheckpointKind(
    "a LAMMPS checkpoint", "format", "hugomap-lammps-checkpoint/1",
    family="hugomap-lammps-checkpoint/",
)  # fmt: skip
#: A moving window on LAMMPS (``particles.window.ParticleWindow`` over a ``LammpsSimulation``,
#: kit ``lammps.window.LammpsKit``): the LAMMPS checkpoint plus the reservoir snapshot and the
#: window's boundaries. /1: first.
LAMMPS_WINDOW_CHECKPOINT = CheckpointKind(
    "a LAMMPS window checkpoint", "window_format", "hugomap-lammps-window/1",
    inside=LAMMPS_CHECKPOINT, family="hugomap-lammps-window/",
)  # fmt: skip


def _canonical_bytes(value: object) -> bytes:
    """The bytes that stand for an array or attribute value in the checksum.

    Numbers are widened to little-endian float64 / int64 and every NaN is the same NaN, so
    the bytes do not depend on how netCDF stored the value (an int8 flag array, a 1-element
    list attribute read back as a scalar, a NaN's payload) but change with any value; text
    is UTF-8. The kind, shape and length are part of the bytes.
    """
    if isinstance(value, str):
        raw = value.encode()
        return b"s" + len(raw).to_bytes(8, "little") + raw
    a = np.asarray(value)
    if a.dtype.kind in "USO":
        raw = "\x1f".join(str(x) for x in a.ravel()).encode()
        head = b"S"
    elif a.dtype.kind == "f":
        f = np.ascontiguousarray(a, dtype="<f8")
        raw = np.where(np.isnan(f), np.nan, f).astype("<f8").tobytes()
        head = b"f"
    elif a.dtype.kind in "iub":
        raw = np.ascontiguousarray(a, dtype="<i8").tobytes()
        head = b"i"
    else:
        raise TypeError(f"cannot checksum values of dtype {a.dtype}")
    shape = np.asarray(a.shape if a.ndim > 0 else (1,), dtype="<i8").tobytes()
    return head + len(shape).to_bytes(8, "little") + shape + len(raw).to_bytes(8, "little") + raw


def checkpoint_checksum(ds: xr.Dataset) -> str:
    """SHA-256 (hex) over every variable of a checkpoint (name, kind, shape, values) and every
    global attribute except ``checksum`` itself, in name order: the solver's state arrays,
    the extra variables (history, pole, a window's reservoir or tile) and the attributes
    (formats, clock, time step, solver parameters, window state...)."""
    h = hashlib.sha256()
    for name in sorted(map(str, ds.variables)):
        h.update(b"var" + _canonical_bytes(name) + _canonical_bytes(ds[name].values))
    for name in sorted(k for k in map(str, ds.attrs) if k != CHECKSUM_ATTR):
        h.update(b"attr" + _canonical_bytes(name) + _canonical_bytes(ds.attrs[name]))
    return h.hexdigest()


def seal_checkpoint(ds: xr.Dataset, kind: CheckpointKind = MD_CHECKPOINT) -> xr.Dataset:
    """Set ``ds``'s format attributes (``kind`` and those it extends) and its checksum, in
    place; return ``ds``.

    Call it last, once every variable and attribute of the checkpoint is in place. A format
    attribute already set keeps its place among the attributes."""
    for k in kind.chain():
        ds.attrs[k.attr] = k.format
    ds.attrs[CHECKSUM_ATTR] = "sha256:" + checkpoint_checksum(ds)
    return ds


def checkpoint_source(ds: xr.Dataset, source: str | os.PathLike | None = None) -> str:
    """What a refusal names: ``source``, else the file ``ds`` was opened from, else
    ``IN_MEMORY``."""
    if source is not None:
        return str(source)
    return str(ds.encoding.get("source", IN_MEMORY))


def _check_format(ds: xr.Dataset, kind: CheckpointKind, where: str) -> None:
    """Refuse ``ds`` unless its ``kind.attr`` is ``kind.format``."""
    fmt = ds.attrs.get(kind.attr)
    if fmt == kind.format:
        return
    if kind.family is None:
        raise CheckpointError(
            where,
            f"not {kind.what} ({kind.attr} {fmt!r}, this hugomap reads {kind.format!r})",
        )
    if not isinstance(fmt, str) or not fmt.startswith(kind.family):
        raise CheckpointError(where, f"not {kind.what} ({kind.attr} {fmt!r})")
    if fmt in kind.unchecked:
        raise CheckpointError(
            where,
            f"format {fmt!r} predates checkpoint checksums, so it cannot be checked; "
            "delete it and rerun the stage that wrote it",
        )
    raise CheckpointError(
        where, f"unsupported format version {fmt!r} (this hugomap reads {kind.format!r})"
    )


def verify_checkpoint(
    ds: xr.Dataset,
    source: str | os.PathLike | None = None,
    kind: CheckpointKind = MD_CHECKPOINT,
) -> None:
    """Refuse (``CheckpointError``) a dataset that is not an intact checkpoint of ``kind``.

    The format attributes are checked first, the solver's then the window's (foreign: no or
    another format; older: written before checksums; newer), then the checksum (missing, or
    not matching the contents: edited, truncated, bit-flipped). ``source`` names the file in
    the message (default: the file ``ds`` was opened from).
    """
    where = checkpoint_source(ds, source)
    for k in kind.chain():
        _check_format(ds, k, where)
    stored = ds.attrs.get(CHECKSUM_ATTR)
    if not isinstance(stored, str) or not stored.startswith("sha256:"):
        raise CheckpointError(where, f"no valid {CHECKSUM_ATTR!r} attribute ({stored!r})")
    try:
        actual = "sha256:" + checkpoint_checksum(ds)
    except (TypeError, ValueError) as exc:
        raise CheckpointError(where, f"contents cannot be checksummed: {exc}") from exc
    if actual != stored:
        raise CheckpointError(
            where,
            f"checksum mismatch (stored {stored[:19]}..., contents give {actual[:19]}...): "
            "the file was altered or corrupted after it was written",
        )


def read_checkpoint(
    path: str | os.PathLike, verify: bool = True, kind: CheckpointKind = MD_CHECKPOINT
) -> xr.Dataset:
    """Read a checkpoint file into memory and (``verify``) check it as ``kind`` with
    ``verify_checkpoint``.

    An unreadable file (truncated, not netCDF, missing) is refused with ``CheckpointError``."""
    try:
        with xr.open_dataset(path, engine="netcdf4") as ds:
            ds.load()
    except (OSError, ValueError, RuntimeError) as exc:
        raise CheckpointError(str(path), f"unreadable ({type(exc).__name__}: {exc})") from exc
    if verify:
        verify_checkpoint(ds, path, kind)
    return ds
