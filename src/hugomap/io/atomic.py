"""Atomic file writes: a temporary file in the target's folder, then ``os.replace``.

A killed job leaves either the old file or the new one, never half a file (a failed
``to_netcdf`` can leave a partial file at its target path). The final file has the mode a
plain ``open`` would give it, ``0o666 & ~umask`` (``mkstemp`` makes its temporary file
``0o600``), so a group that shares a results folder with ``umask 002`` or ``027`` can read
it. A dataset that declares CF conventions (``Conventions = "CF-…"``: point files,
aggregates, campaign datasets) is written through ``io.dataset.cf_dataset``.

Under MPI (a LAMMPS stage started by ``mpiexec -n N``) every rank runs the same stage and
holds the same results; rank 0 alone writes (``mpi_rank``), so N ranks never race for one
file.
"""

from __future__ import annotations

import json
import os
import shutil
import tempfile
from collections.abc import Callable
from pathlib import Path
from typing import BinaryIO

import xarray as xr


def umask() -> int:
    """The process's umask (read from /proc where it can be, so it is never changed; else
    set and restored at once)."""
    try:
        with open("/proc/self/status") as fh:
            for line in fh:
                if line.startswith("Umask:"):
                    return int(line.split()[1], 8)
    except (OSError, ValueError, IndexError):
        pass
    old = os.umask(0o022)
    os.umask(old)
    return old


#: Where MPI launchers give a process its rank and their number: MPICH's Hydra (the
#: ``mpich`` wheel's ``mpiexec``) and Intel MPI ``PMI_RANK``/``PMI_SIZE``, PMIx launchers
#: ``PMIX_RANK``, Open MPI ``OMPI_COMM_WORLD_RANK``/``OMPI_COMM_WORLD_SIZE``.
RANK_VARIABLES = ("PMI_RANK", "PMIX_RANK", "OMPI_COMM_WORLD_RANK")
SIZE_VARIABLES = ("PMI_SIZE", "OMPI_COMM_WORLD_SIZE")


def _env_int(names: tuple[str, ...], default: int) -> int:
    for name in names:
        value = os.environ.get(name, "")
        if value.isdigit():
            return int(value)
    return default


def mpi_rank() -> int:
    """This process's MPI rank, from its launcher's environment (0 outside MPI)."""
    return _env_int(RANK_VARIABLES, 0)


def mpi_size() -> int:
    """The number of MPI ranks this process runs among (1 outside MPI)."""
    return _env_int(SIZE_VARIABLES, 1)


def _mode() -> int:
    return 0o666 & ~umask()


def _write(path: str | os.PathLike, fill: Callable[[str], None]) -> Path:
    """The one atomic write: ``fill(tmp)`` writes a temporary file in the target's folder,
    which gets mode ``0o666 & ~umask`` and is renamed onto ``path``; a failed write leaves
    no partial file at ``path``. On an MPI rank other than 0 nothing is written."""
    path = Path(path)
    if mpi_rank() != 0:
        return path
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent)
    os.close(fd)
    try:
        fill(tmp)
        os.chmod(tmp, _mode())
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise
    return path


def write_netcdf(ds: xr.Dataset, path: str | os.PathLike) -> Path:
    """Write ``ds`` to ``path`` atomically (netCDF4 format), mode ``0o666 & ~umask``; a
    dataset whose ``Conventions`` attribute starts with ``CF-`` is written CF-encoded
    (``io.dataset.cf_dataset``). Return the path."""
    if str(ds.attrs.get("Conventions", "")).startswith("CF-"):
        from .dataset import cf_dataset

        ds = cf_dataset(ds)
    return _write(path, lambda tmp: ds.to_netcdf(tmp, engine="netcdf4"))


def write_bytes(data: bytes, path: str | os.PathLike) -> Path:
    """Write ``data`` to ``path`` atomically, mode ``0o666 & ~umask``."""
    return _write(path, lambda tmp: Path(tmp).write_bytes(data))


def write_stream(source: BinaryIO, path: str | os.PathLike) -> Path:
    """Copy the open binary file ``source`` (from its current position) to ``path``
    atomically, mode ``0o666 & ~umask``."""

    def fill(tmp: str) -> None:
        with open(tmp, "wb") as fh:
            shutil.copyfileobj(source, fh)

    return _write(path, fill)


def write_text(text: str, path: str | os.PathLike) -> Path:
    """Write ``text`` to ``path`` atomically, mode ``0o666 & ~umask``."""
    return write_bytes(text.encode(), path)


def write_json(obj: object, path: str | os.PathLike) -> Path:
    """Write ``obj`` as indented JSON, atomically (mode ``0o666 & ~umask``)."""
    return write_text(json.dumps(obj, indent=2, sort_keys=True) + "\n", path)
