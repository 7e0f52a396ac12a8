"""The solver registry: the only code that reads a scene's ``solver`` key.

Each entry names a backend class by module path, so that importing the registry (the
workflow does so when it parses its rules) loads no solver, kernel or numba code; a backend
is imported and made the first time it is asked for. A new backend is a folder of its own
and one line here.
"""

from __future__ import annotations

import functools
import importlib
from collections.abc import Mapping
from typing import Any

REGISTRY: dict[str, str] = {
    "md": "hugomap.md.backend:MDBackend",
    "csph": "hugomap.sph.backend:CSPHBackend",
    "synthetic": "hugomap.synthetic.backend:SyntheticBackend",
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
    module, _, cls = REGISTRY[name].partition(":")
    return getattr(importlib.import_module(module), cls)()


def backend(scene: Mapping[str, Any]):
    """The backend of a scene (``hugomap.backend.Backend``)."""
    return backend_named(solver_of(scene))
