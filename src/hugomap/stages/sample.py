"""Stage ``prepare``: the scene's sample and its pole, saved as the first checkpoint."""

from __future__ import annotations

import json
import logging
import os
from pathlib import Path

from ..failures import HugomapFailure
from ..registry import backend as backend_of
from .files import INFO_ATTR, failure, pole_vars

log = logging.getLogger("hugomap")


def prepare_sample(scene: dict, out: str | os.PathLike) -> Path:
    """Build the sample (``Backend.prepare``) and save it with its pole as scalar variables
    and the backend's sample info; a sample that cannot be made is written as a failure
    (a named ``HugomapFailure``'s status, else ``bad_config``)."""
    b = backend_of(scene)
    attrs = {"stage": "sample", "scene_config": json.dumps(scene)}
    try:
        solver, pole, info = b.prepare(scene)
    except HugomapFailure as exc:  # a named failure keeps its status
        return failure(out, exc.status, exc.diagnostic, attrs)
    except ValueError as exc:  # e.g. a porous packing that cannot be reached
        return failure(out, "bad_config", str(exc), attrs)
    log.info("pole: %s", json.dumps(pole.as_dict()))
    return b.save(solver, out, pole_vars(pole, b),
                  {**attrs, "status": "ok", INFO_ATTR: json.dumps(info)})  # fmt: skip
