"""Stage ``aggregate``: all points of a scene → ``results/hugoniot/<scene>.nc`` (dims
scheme × u_p), in the scene backend's units, with its reference beside them, CF-1.11
(``io.dataset.cf_dataset``; an MD scene with a ``units`` block also in SI: ``with_si``)."""

from __future__ import annotations

import json
import os
from pathlib import Path

import netCDF4
import numpy as np
import xarray as xr

from ..io.atomic import write_netcdf
from ..io.dataset import NOT_RUN, aggregate_points, with_si
from ..keys import scheme_choice_at
from ..registry import backend as backend_of

NOT_RUN_TEXT = "no point of this scheme at this u_p (schemes: [auto] chose another here)"
SCHEME_CHOICE = (
    "the scheme schemes: [auto] chose at this u_p and why: the least CPU for target.D by the "
    "measured cost laws"
)


def aggregate(
    points: list[str],
    reference: str | None,
    config: dict,
    scene: str,
    out: str | os.PathLike,
    scheme: str = "piston",
) -> Path:
    """Points are grouped by the ``scheme`` attribute of their files (``scheme`` is the
    default for files without one), each group is joined along u_p, and the groups along
    scheme; a variable that one scheme's points never produced (all failed) is NaN there,
    and a (scheme, u_p) without a point (``schemes: [auto]`` chose another scheme there)
    has NaN values and status ``not_run``, its u_p's ``scheme_choice`` saying why.
    A scene with a ``units`` block (MD) gets ``<name>_SI`` companions (``with_si``)."""
    ref = None
    if reference:
        with xr.open_dataset(reference, engine="netcdf4") as r:
            ref = r.load()
    groups: dict[str, list[str]] = {}
    for p in points:
        with netCDF4.Dataset(p) as nc:
            name = getattr(nc, "scheme", scheme)
            if not groups:  # every point carries its scene's config: the backend's units
                sc = json.loads(getattr(nc, "scene_config", "{}"))
        groups.setdefault(str(name), []).append(p)
    scene_config = config.get("scenes", {}).get(scene, sc)
    be = backend_of(scene_config)
    # a backend may set each point beside a reference of its own state (porous copper: the
    # Hugoniot at the slab's own distention)
    own_ref = getattr(be, "point_references", lambda ds, sc: ds)
    parts = []
    for name, ps in groups.items():
        part = aggregate_points(ps, name, ref, config, scene, be.units)
        parts.append(own_ref(part, scene_config).sortby("u_p"))
    names = {k for part in parts for k, v in part.data_vars.items() if "scheme" in v.dims}
    for i, part in enumerate(parts):
        for k in names - set(part.data_vars):
            src = next(q[k] for q in parts if k in q)
            fill = np.full((1, part.sizes["u_p"]), np.nan if src.dtype.kind == "f" else 0,
                           dtype=src.dtype if src.dtype.kind != "O" else object)  # fmt: skip
            parts[i] = parts[i].assign({k: (("scheme", "u_p"), fill, src.attrs)})
    ds = xr.concat(parts, dim="scheme", data_vars="minimal", coords="minimal", compat="override",
                   join="outer", combine_attrs="override")  # fmt: skip
    st = ds["status"].values
    missing = np.array([not (isinstance(x, str) and x) for x in st.ravel()]).reshape(st.shape)
    if missing.any():  # no point file at this (scheme, u_p): the outer join left NaN
        ds["status"] = (ds["status"].dims, np.where(missing, NOT_RUN, st).astype(object),
                        ds["status"].attrs)  # fmt: skip
        text = np.where(missing, NOT_RUN_TEXT, ds["diagnostic"].values).astype(object)
        ds["diagnostic"] = (ds["diagnostic"].dims, text, ds["diagnostic"].attrs)
        ds["converged"] = ds["converged"].where(~missing, 0).astype(np.int8)
    if scene_config.get("scheme_choice"):  # schemes: [auto]: which scheme at each u_p, why
        why = [scheme_choice_at(scene_config, u) for u in ds["u_p"].values]
        ds["scheme_choice"] = ("u_p", np.array(why, dtype=object))
        ds["scheme_choice"].attrs = {"long_name": SCHEME_CHOICE}
    return write_netcdf(with_si(ds.load(), scene_config), out)
