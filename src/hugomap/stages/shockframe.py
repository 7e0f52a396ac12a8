"""Stage ``shockframe``: one Hugoniot point of a shock-frame scheme (msst, nphug) at a
scene's u_p, from the prepared sample's measured pole, through the backend's optional
``shock_frame_point`` (solver lammps: ``lammps.shockframe``). No loading, no window: the
backend holds a homogeneous periodic box on the pole's Hugoniot and iterates on the shock
strength. The point file has the other schemes' layout (``io.dataset.point_dataset`` in the
backend's units), the fix's parameters and iterations as attributes, and is written
atomically.
"""

from __future__ import annotations

import logging
import os
from pathlib import Path

from ..failures import HugomapFailure
from ..registry import backend as backend_of
from ..states import Pole
from .files import Clock, is_ok, open_dataset, write_point

log = logging.getLogger("hugomap")
SCHEMES = ("msst", "nphug")


def shock_frame_point(
    sample: str | os.PathLike, scene: dict, scheme: str, u_p: float, out: str | os.PathLike
) -> Path:
    """Run ``scheme`` (msst or nphug) at ``u_p`` [the backend's velocity units] from the pole
    of ``sample`` (the ``prepare`` stage's file; the point's pole variables are the pole the
    backend took the jump from: a crystal's box measures its own) and write the point file
    ``out``; a sample
    that failed, a backend without shock-frame schemes or a solver that stopped gives a
    point file with that status and a diagnostic."""
    if scheme not in SCHEMES:
        raise ValueError(f"scheme {scheme!r}: not a shock-frame scheme ({', '.join(SCHEMES)})")
    b = backend_of(scene)
    ds = open_dataset(sample)
    base = {"piston_velocity": u_p}
    if not is_ok(ds):
        return write_point(out, b, scene, scheme, base, {}, None, ds.attrs["status"],
                           ds.attrs.get("diagnostic", ""))  # fmt: skip
    pole = Pole.from_dataset(ds)
    run = getattr(b, "shock_frame_point", None)
    if run is None:
        return write_point(out, b, scene, scheme, base, pole.as_dict(), None, "bad_config",
                           f"solver {b.name!r} has no shock-frame schemes (msst, nphug need "
                           "solver: lammps)")  # fmt: skip
    clock = Clock()
    try:
        r = run(scene, scheme, u_p, pole, {})
    except HugomapFailure as exc:
        return write_point(out, b, scene, scheme, {**base, **clock.cost()}, pole.as_dict(),
                           None, exc.status, exc.diagnostic)  # fmt: skip
    values = {**base, **r.values}
    values.update(clock.cost(r.values.get("atom_steps", 0.0)))
    log.info("%s point: D = %.6g +- %.2g, u_p %.6g (measured %.6g +- %.2g), P = %.6g +- %.2g, "
             "%s in %d iterations", scheme, values["D"], values["D_err"], u_p,
             values["u_p_measured"], values["u_p_measured_err"], values["P"], values["P_err"],
             r.status, r.attrs.get("shock_frame_iterations", 0))  # fmt: skip
    return write_point(out, b, scene, scheme, values, r.pole or pole.as_dict(), None,
                       r.status, r.diagnostic, attrs=r.attrs)  # fmt: skip
