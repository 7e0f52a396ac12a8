"""Stage ``reference``: the scene's reference Hugoniot (``Backend.reference``).

A backend whose reference is a run of its own (equilibrium MD) names the inputs it depends
on (``Backend.reference_inputs``): the workflow computes it once per distinct inputs
(``results/references/<key>.nc``) and each scene copies it; a shared file made from other
inputs is refused.
"""

from __future__ import annotations

import json
import os
from pathlib import Path

import xarray as xr

from ..io.atomic import write_netcdf
from ..keys import config_hash
from ..registry import backend as backend_of


def reference_key(scene: dict) -> str | None:
    """The shared reference's file stem: the solver's name and the first 12 hex digits of
    ``config_hash(reference_inputs)``; None when the backend does not share references."""
    b = backend_of(scene)
    inputs = b.reference_inputs(scene)
    if inputs is None:
        return None
    return f"{b.name}_" + config_hash(inputs)[:12]


def reference_stage(
    scene: dict, out: str | os.PathLike, shared: str | os.PathLike | None = None
) -> Path:
    """The scene's reference: computed, or, with ``shared``, copied from a reference computed
    for the same ``reference_inputs`` (stored as the ``reference_inputs`` attribute)."""
    b = backend_of(scene)
    inputs = b.reference_inputs(scene)
    if shared is not None:
        want = json.dumps(inputs, sort_keys=True)
        with xr.open_dataset(shared, engine="netcdf4") as r:
            ds = r.load()
        got = ds.attrs.get("reference_inputs")
        if got != want:
            raise ValueError(
                f"{shared}: this reference was computed for {got}, not for scene "
                f"{scene.get('name', '?')!r} ({want}); delete the file and rerun"
            )
    else:
        ds = b.reference(scene)
    ds.attrs["scene_config"] = json.dumps(scene)
    return write_netcdf(ds, out)
