"""Stage ``reference``: the scene's reference Hugoniot (``Backend.reference``).

A backend whose reference is a run of its own (equilibrium MD) names the inputs it depends
on (``Backend.reference_inputs``): the workflow computes it once per distinct inputs
(``results/references/<key>.nc``) and each scene copies it; a shared file made from other
inputs is refused. A backend with ``reference_from_sample`` set computes its reference at
the pole its prepared sample measured (the sample file, ``--sample``): the pole is part of
the inputs the file records, and a scene copies the shared file only if its own sample
measured the same pole.
"""

from __future__ import annotations

import json
import os
from pathlib import Path

import xarray as xr

from ..io.atomic import write_netcdf
from ..keys import config_hash
from ..registry import backend as backend_of
from ..states import Pole
from .files import is_ok, open_dataset


def reference_key(scene: dict) -> str | None:
    """The shared reference's file stem: the solver's name and the first 12 hex digits of
    ``config_hash(reference_inputs)``; None when the backend does not share references.
    (Computed when the workflow is parsed, before any sample exists: for a backend with
    ``reference_from_sample`` the inputs are the settings that make the sample, which
    decide its measured pole.)"""
    b = backend_of(scene)
    inputs = b.reference_inputs(scene)
    if inputs is None:
        return None
    return f"{b.name}_" + config_hash(inputs)[:12]


def needs_sample(scene: dict) -> bool:
    """Whether the scene's reference is computed at its sample's measured pole."""
    return bool(getattr(backend_of(scene), "reference_from_sample", False))


def sample_pole(sample: str | os.PathLike) -> Pole:
    """The pole a prepared sample file measured (``ValueError`` if its preparation failed)."""
    ds = open_dataset(sample)
    if not is_ok(ds):
        raise ValueError(
            f"{sample}: the sample failed ({ds.attrs.get('status')}: "
            f"{ds.attrs.get('diagnostic', '')}); no pole to compute a reference at"
        )
    return Pole.from_dataset(ds)


def reference_stage(
    scene: dict,
    out: str | os.PathLike,
    shared: str | os.PathLike | None = None,
    sample: str | os.PathLike | None = None,
) -> Path:
    """The scene's reference: computed, or, with ``shared``, copied from a reference computed
    for the same ``reference_inputs`` (stored as the ``reference_inputs`` attribute). A
    backend with ``reference_from_sample`` needs the scene's prepared ``sample`` file: its
    measured pole goes into the inputs and into the computation."""
    b = backend_of(scene)
    if needs_sample(scene):
        if sample is None:
            raise ValueError(
                f"scene {scene.get('name', '?')!r}: its reference is computed at the pole "
                "its sample measured; give the sample file (--sample)"
            )
        pole = sample_pole(sample)
        inputs = b.reference_inputs(scene, pole)
    else:
        pole, inputs = None, b.reference_inputs(scene)
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
        ds = b.reference(scene) if pole is None else b.reference(scene, pole)
    ds.attrs["scene_config"] = json.dumps(scene)
    return write_netcdf(ds, out)
