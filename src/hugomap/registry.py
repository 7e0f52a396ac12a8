"""The solver registry: the only code that reads a scene's ``solver`` key.

Each entry names a backend's package. The package holds, by convention:
- ``backend.py`` with ``BACKEND``, the ``hugomap.backend.Backend`` instance (imported the first
  time it is asked for: importing the registry loads no solver, kernel or numba code);
- ``scene.schema.json``, the JSON Schema of its scenes (``hugomap.config.load_schema`` joins
  them into the config schema);
- ``scene_config.py`` with ``resolve_defaults(scene)`` and ``check(base, scene, cfg)``, the
  cross-key checks run at validation (light: no numba, no xarray).
A new backend is a folder of its own and one line here.
"""

from __future__ import annotations

import functools
import importlib
import json
from collections.abc import Mapping
from importlib import resources
from typing import Any

REGISTRY: dict[str, str] = {
    "md": "hugomap.md",
    "csph": "hugomap.sph",
    "synthetic": "hugomap.synthetic",
    "lammps": "hugomap.lammps",
}
DEFAULT_SOLVER = "md"


def solver_of(scene: Mapping[str, Any]) -> str:
    """The scene's solver name (``md`` when the key is absent)."""
    name = scene.get("solver", DEFAULT_SOLVER)
    if name not in REGISTRY:
        raise KeyError(f"solver {name!r}: allowed {sorted(REGISTRY)}")
    return str(name)


@functools.cache
def backend_named(name: str):
    """The backend registered as ``name`` (one instance per process)."""
    return importlib.import_module(REGISTRY[name] + ".backend").BACKEND


def scene_config(name: str):
    """The scene-config module of the solver ``name`` (``resolve_defaults``, ``check``)."""
    return importlib.import_module(REGISTRY[name] + ".scene_config")


def scene_schema(name: str) -> dict:
    """The JSON Schema of the solver's scenes (its package's ``scene.schema.json``)."""
    return json.loads(resources.files(REGISTRY[name]).joinpath("scene.schema.json").read_text())


def backend(scene: Mapping[str, Any]):
    """The backend of a scene (``hugomap.backend.Backend``); a backend whose units follow
    the scene (``solver: lammps``: units lj or metal) gives it by ``for_scene(scene)``."""
    b = backend_named(solver_of(scene))
    for_scene = getattr(b, "for_scene", None)
    return b if for_scene is None else for_scene(scene)
