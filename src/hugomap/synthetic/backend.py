"""The synthetic backend: ``hugomap.backend.Backend`` on the exact model of ``model``.

Every number a stage measures on it is known in advance (D = c0 + s u_p, the jump states
exactly), so the stages, the methods and the workflow can be checked end to end without a
solver. Units are SI by convention (the model is unit-free but consistent).
"""

from __future__ import annotations

import logging
import math
import os
from pathlib import Path
from typing import Any

import numpy as np
import xarray as xr

from ..backend import lengthened
from ..io.dataset import si_units
from ..states import ControlParams, PistonFrame, Pole, Resources, SlabState, WindowStart
from .model import FIELDS, PISTON, SyntheticPiston, SyntheticWindow, shocked_state

log = logging.getLogger("hugomap")


class SyntheticProfile:
    """Reader of the model's profile sums (``model.FIELDS``): bins of ``bin_width`` from
    ``x0`` (``nbins`` of them for a piston run)."""

    def __init__(self, x0: float, bin_width: float, nbins: int | None = None):
        self.x0, self.bin_width, self.nbins = float(x0), float(bin_width), nbins

    def sums(self, solver) -> np.ndarray:
        if isinstance(solver, SyntheticWindow):
            return solver.profile_sums(self.bin_width)
        return solver.profile_sums(self.bin_width, self.x0, self.nbins)

    def velocity(self, sums: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        with np.errstate(invalid="ignore", divide="ignore"):
            return sums[:, 2] / sums[:, 1], sums[:, 0]

    def state(self, summed: np.ndarray, n_bins: int) -> SlabState:
        s = dict(zip(FIELDS, summed, strict=True))
        m, vol = s["mass"], s["volume"]
        with np.errstate(invalid="ignore", divide="ignore"):
            P = s["pressure_volume"] / vol
            return SlabState(rho=m / vol, u=s["momentum"] / m, P=P, Pyy=P, Pzz=P,
                             E=s["energy"] / m)  # fmt: skip


class SyntheticBackend:
    """``Backend`` for ``solver: synthetic`` scenes (module docstring)."""

    name = "synthetic"
    units = si_units()

    def prepare(self, scene: dict) -> tuple[Any, Pole, dict[str, Any]]:
        mat, s = scene["material"], scene["sample"]
        sim = SyntheticPiston(mat, s["length"], s["area"], scene["shock"]["dt"], s["particle_mass"])
        return sim, Pole(rho0=mat["rho0"], P0=mat["P0"], E0=mat["E0"]), {"length": s["length"]}

    def save(self, solver, out: str | os.PathLike, extra: xr.Dataset | None, attrs: dict) -> Path:
        return solver.save(out, extra, attrs)

    def read_checkpoint(self, path: str | os.PathLike) -> xr.Dataset:
        from ..io.checkpoint import read_checkpoint

        return read_checkpoint(path, kind=PISTON)

    def load(self, ds: xr.Dataset, source: str | os.PathLike | None = None) -> SyntheticPiston:
        return SyntheticPiston.from_dataset(ds, source)

    def load_window(self, ds: xr.Dataset, source: str | os.PathLike | None = None):
        return SyntheticWindow.from_dataset(ds, source)

    def start_piston(self, solver, scene: dict, u_p: float) -> None:
        solver.set_walls(u_p, 0.0)

    def piston_frame(self, solver, scene: dict, u_p: float, info: dict) -> PistonFrame:
        sh, L = scene["shock"], info["length"]
        return PistonFrame(
            u_behind=u_p, u_ahead=0.0, x_origin=0.0, load_distance=sh["load_fraction"] * L,
            rear_margin=(1.0 - sh["end_fraction"]) * L, max_time=sh["max_time"],
            sample_every=sh["sample_every"], far_end=L,
        )  # fmt: skip

    def profile(self, solver, scene: dict, info: dict) -> SyntheticProfile:
        bw = scene["shock"]["bin_width"]
        if isinstance(solver, SyntheticWindow):
            return SyntheticProfile(solver.geom.x_lo, bw)
        return SyntheticProfile(0.0, bw, int(math.ceil(info["length"] / bw)) + 1)

    def open_window(
        self, solver, loaded: xr.Dataset, scene: dict, u_p: float, front: float,
        D_guess: float, pole: Pole, info: dict,
    ) -> WindowStart:  # fmt: skip
        """The window in the frame of ``D_guess`` (u_in = −D_guess, u_out = u_p − D_guess),
        the front at ``window.front_fraction``, settled for ``window.settle_time``; ω from
        the particle count, normalised by ρ0 and the exact shocked density."""
        from ..methods.control import OmegaSignal

        w = scene["window"]
        win = SyntheticWindow(scene["material"], -D_guess, u_p - D_guess, w["length"],
                              w["front_fraction"], solver.dt, solver.m)  # fmt: skip
        win.advance(int(round(w["settle_time"] / win.dt)))
        q = win.area * win.geom.length / win.m
        sig = OmegaSignal("N", pole.rho0 * q, win.rho1 * q, scene["shock"]["bin_width"])
        return WindowStart(win, pole, sig, {})

    def control_params(self, scene: dict, u_p: float, window) -> ControlParams:
        """The configured times (``ControlParams.from_window``)."""
        sh = scene["shock"]
        return ControlParams.from_window(scene["window"], window.geom.length, sh["gap"],
                                         sh["avg_length"])  # fmt: skip

    def reference_inputs(self, scene: dict) -> None:
        return None

    def reference(self, scene: dict) -> xr.Dataset:
        """The model's exact Hugoniot on a grid to 1.25 max(u_p) and at the scene's u_p."""
        mat = scene["material"]
        grid = np.linspace(0.0, 1.25 * max(scene["shock"]["u_p"]), 41)[1:]
        ups = np.unique(np.concatenate([grid, np.asarray(scene["shock"]["u_p"], float)]))
        D, rho, P, E = shocked_state(mat["rho0"], mat["P0"], mat["E0"], mat["c0"], mat["s"], ups)
        u = self.units.point
        ds = xr.Dataset({
            "u_p": ("point", ups, {"units": u["D"][0], "long_name": "particle velocity"}),
            "D": ("point", D, {"units": u["D"][0], "long_name": "shock velocity"}),
            "P": ("point", P, {"units": u["P"][0], "long_name": "longitudinal stress"}),
            "V": ("point", 1.0 / rho, {"units": u["V"][0], "long_name": "specific volume"}),
            "rho": ("point", rho, {"units": u["rho"][0], "long_name": "density"}),
            "E": ("point", E, {"units": u["E"][0], "long_name": "specific internal energy"}),
        })  # fmt: skip
        ds.attrs.update(reference_model="exact: D = c0 + s u_p",
                        title="Hugoniot of the synthetic model (exact)")  # fmt: skip
        return ds

    def extras(self, solver, out: Path, scene: dict, u_p: float, info: dict) -> None:
        """No snapshots: nothing to look at."""

    def window_extras(
        self, window, out: Path, scene: dict, u_p: float, scheme: str, info: dict
    ) -> None:
        """No snapshots: nothing to look at."""

    def longer_sample(self, scene: dict, factor: float) -> dict | None:
        """A longer ``sample.length`` (``backend.lengthened``)."""
        return lengthened(scene, ("sample", "length"), factor)

    def cost(self, scene: dict, stage: str) -> Resources:
        return Resources(512, 1.0)

    def figure_labels(self, scene: dict) -> dict:
        axes = {
            "V": ("specific volume V", 1.0),
            "P": ("longitudinal stress P", 1.0),
            "u_p_measured": ("particle velocity u_p", 1.0),
            "D": ("shock velocity D", 1.0),
        }
        return {"axes": axes, "tag": "synthetic", "reference": "exact Hugoniot",
                "title": "synthetic front"}  # fmt: skip

    def sound_speed(self, scene: dict) -> float:
        return float(scene["material"]["c0"])

    def scale(self, scene: dict) -> dict[str, float]:
        s, w = scene["sample"], scene.get("window", {})
        spacing = s["particle_mass"] / (scene["material"]["rho0"] * s["area"])
        L = float(w.get("length", np.nan))
        return {"n_window": L / spacing, "window_spacings": L / spacing, "spacing": spacing}


BACKEND = SyntheticBackend()
