"""What every stage does with its files: open a checkpoint, write a failure, keep the cost
clock, carry the backend's sample ``info`` and the piston history from file to file."""

from __future__ import annotations

import json
import logging
import os
import resource
import time
from pathlib import Path

import xarray as xr

from ..failures import MEASURED
from ..io.atomic import mpi_size, write_netcdf
from ..io.dataset import point_dataset, scalar_vars
from ..keys import scheme_choice_at
from ..methods.piston import History
from ..states import Pole

log = logging.getLogger("hugomap")
INFO_ATTR = "backend_info"  # the backend's sample info (JSON), carried by every checkpoint


def cpu_s() -> float:
    """CPU seconds of this process so far, all threads [s]."""
    r = resource.getrusage(resource.RUSAGE_SELF)
    return r.ru_utime + r.ru_stime


class Clock:
    """Wall and CPU time of this job since it started, plus ``prior`` (earlier jobs' cost:
    wall_s, cpu_s [s], atom_steps). A job on several MPI ranks counts this rank's CPU time
    once per rank (the ranks hold equal domains and run the same Python) and records
    ``ranks``."""

    def __init__(self, *prior: dict):
        self.t0, self.c0 = time.perf_counter(), cpu_s()
        self.prior = {"wall_s": 0.0, "cpu_s": 0.0, "atom_steps": 0.0}
        for p in prior:
            self.add(p)

    def add(self, prior: dict) -> None:
        """Count an earlier job's cost too."""
        for k in self.prior:
            self.prior[k] += float(prior.get(k, 0.0))

    def cost(self, atom_steps: float = 0.0) -> dict[str, float]:
        """The cost so far with this job's ``atom_steps`` (particles x steps)."""
        ranks = mpi_size()
        return {
            "wall_s": self.prior["wall_s"] + time.perf_counter() - self.t0,
            "cpu_s": self.prior["cpu_s"] + ranks * (cpu_s() - self.c0),
            "atom_steps": self.prior["atom_steps"] + float(atom_steps),
            "ranks": float(ranks),
        }


def open_dataset(path: str | os.PathLike) -> xr.Dataset:
    """A stage's input, read whole and closed."""
    with xr.open_dataset(path, engine="netcdf4") as ds:
        return ds.load()


def is_ok(ds: xr.Dataset) -> bool:
    return ds.attrs.get("status", "ok") == "ok"


def info_of(ds: xr.Dataset) -> dict:
    """The backend's sample info carried by a checkpoint."""
    return json.loads(ds.attrs.get(INFO_ATTR, "{}"))


def failure(out: str | os.PathLike, status: str, diagnostic: str, attrs: dict) -> Path:
    """A checkpoint stage's output when it cannot go on: attributes only."""
    log.error("%s: %s", status, diagnostic)
    return write_netcdf(
        xr.Dataset(attrs={**attrs, "status": status, "diagnostic": diagnostic}), out
    )


def pole_vars(pole: Pole, backend) -> xr.Dataset:
    return xr.Dataset(scalar_vars(pole.as_dict(), backend.units.pole))


def history_vars(h: History) -> xr.Dataset:
    """A piston run's samples as checkpoint variables ``hist_*``."""
    a = h.arrays()
    nb = a["sums"].shape[1] if a["sums"].ndim == 3 else 0
    return xr.Dataset({
        "hist_t": (("sample",), a["t"]), "hist_x_left": (("sample",), a["x_left"]),
        "hist_x_right": (("sample",), a["x_right"]), "hist_front": (("sample",), a["front"]),
        "hist_stage": (("sample",), a["stage"]),
        "hist_sums": (("sample", "bin", "field"), a["sums"].reshape(len(a["t"]), nb, -1)),
    })  # fmt: skip


def history_of(ds: xr.Dataset) -> History:
    return History.from_arrays({k[5:]: ds[k].values for k in ds.data_vars if k.startswith("hist_")})


def write_point(
    out: str | os.PathLike, backend, scene: dict, scheme: str, values: dict, pole: dict,
    history: dict | None, status: str, diagnostic: str, extra: dict | None = None,
    attrs: dict | None = None,
) -> Path:  # fmt: skip
    """A point file (``io.dataset.point_dataset`` in the backend's units) with ``extra``
    variables and ``attrs``; a failed point is logged."""
    if status not in MEASURED:
        log.error("%s: %s", status, diagnostic)
    ds = point_dataset(values, pole, history, scheme, scene.get("name", ""), status, diagnostic,
                       scene, backend.units)  # fmt: skip
    if extra:
        ds = ds.assign(extra)
    why = scheme_choice_at(scene, values["piston_velocity"])
    if why:  # schemes: [auto] (config): which scheme and why
        ds.attrs["scheme_choice"] = why
    ds.attrs.update(attrs or {})
    return write_netcdf(ds, out)


def write_extras(write, *args) -> None:
    """Call a backend's snapshot writer (``extras``, ``window_extras``); a snapshot is an
    extra: one that cannot be written is logged and the point is kept."""
    try:
        write(*args)
    except (ValueError, OSError) as exc:
        log.warning("snapshot not written: %s", exc)
