"""The synthetic shock: a piston run and a moving window whose every state is known exactly.

The material at rest (ρ0, P0, E0) has the Hugoniot D = c0 + s u_p; behind a steady shock of
amplitude u_p the state (ρ1, P1, E1) satisfies the three jump conditions exactly
(``shocked_state``). Units are arbitrary but consistent; no equation of motion is solved.

Piston run (lab frame): the sample fills [0, L] across the area A; a piston started at x_p0
moves at u_p, and the front, which starts on the piston, at D. Window: ``methods.synthetic``'s
``SyntheticFront`` (the front moves at u_in + c0 + s u_p in the window frame), given the
profile, boundaries and checkpoint a stage needs. Profile sums, per bin of width w from x0:
count (mass over the particle mass ``m``), mass, x momentum, mass·E, P·volume, volume.
"""

from __future__ import annotations

import json
import math
import os
from pathlib import Path

import numpy as np
import xarray as xr

from ..analysis.linear_hugoniot import jump_state
from ..io.atomic import write_netcdf
from ..io.checkpoint import CheckpointKind, seal_checkpoint, verify_checkpoint
from ..methods.synthetic import SyntheticFront

PISTON = CheckpointKind(
    "a synthetic piston checkpoint", "synthetic_format", "hugomap-synthetic-piston/1"
)
WINDOW = CheckpointKind(
    "a synthetic window checkpoint", "synthetic_format", "hugomap-synthetic-window/1"
)
FIELDS = ("count", "mass", "momentum", "energy", "pressure_volume", "volume")


def shocked_state(rho0: float, P0: float, E0: float, c0: float, s: float, u_p: float):
    """(D, ρ1, P1, E1) behind a steady shock of amplitude u_p: D = c0 + s u_p,
    ρ1 = ρ0 D/(D − u_p), P1 = P0 + ρ0 D u_p, E1 = E0 + ½ (P1 + P0)(1/ρ0 − 1/ρ1)
    (Zel'dovich & Raizer, ch. I §17; ``analysis.linear_hugoniot.jump_state``). Units: the
    scene's, consistent; u_p may be an array."""
    D, rho1, _, P1, E1 = jump_state(u_p, rho0, c0, s, P0, E0)
    return D, rho1, P1, E1


def _bin_sums(x0: float, width: float, nbins: int, regions, area: float, m: float) -> np.ndarray:
    """Sums of ``FIELDS`` over bins, from ``regions``: (a, b, ρ, u, P, E) uniform slabs."""
    out = np.zeros((nbins, len(FIELDS)))
    lo = x0 + np.arange(nbins) * width
    hi = lo + width
    for a, b, rho, u, P, E in regions:
        length = np.clip(np.minimum(hi, b) - np.maximum(lo, a), 0.0, None)
        vol = length * area
        out[:, 1] += rho * vol
        out[:, 2] += rho * vol * u
        out[:, 3] += rho * vol * E
        out[:, 4] += P * vol
        out[:, 5] += vol
    out[:, 0] = out[:, 1] / m
    return out


def _save(state: dict, kind: CheckpointKind, out, extra: xr.Dataset | None, attrs: dict) -> Path:
    """A checkpoint: ``extra`` variables, ``attrs`` and the model's state (JSON), sealed."""
    ds = xr.Dataset() if extra is None else extra.copy()
    ds.attrs.update(attrs, synthetic_state=json.dumps(state))
    return write_netcdf(seal_checkpoint(ds, kind), out)


def _state(ds: xr.Dataset, source, kind: CheckpointKind) -> dict:
    """The model's state in a checkpoint of ``kind``, verified first."""
    verify_checkpoint(ds, source, kind)
    return json.loads(ds.attrs["synthetic_state"])


class SyntheticPiston:
    """A piston run of the model (module docstring), with the ``ShockSolver`` protocol."""

    def __init__(self, material: dict, length: float, area: float, dt: float, m: float):
        self.material, self.length, self.area = dict(material), float(length), float(area)
        self.dt, self.m = float(dt), float(m)
        self.steps, self.v_left, self.t_start, self.x_start = 0, 0.0, 0.0, 0.0

    @property
    def time(self) -> float:
        return self.steps * self.dt

    @property
    def n_particles(self) -> int:
        return int(round(self.material["rho0"] * self.length * self.area / self.m))

    def advance(self, n_steps: int) -> None:
        self.steps += int(n_steps)

    def _piston(self) -> float:
        return self.x_start + self.v_left * (self.time - self.t_start)

    def _front(self) -> float:
        mat = self.material
        if self.v_left <= 0:
            return self.x_start
        D = shocked_state(mat["rho0"], mat["P0"], mat["E0"], mat["c0"], mat["s"], self.v_left)[0]
        return min(self.x_start + D * (self.time - self.t_start), self.length)

    def wall_positions(self) -> tuple[float, float]:
        return self._piston(), self.length

    def set_walls(self, v_left: float, v_right: float) -> None:
        self.x_start, self.t_start, self.v_left = self._piston(), self.time, float(v_left)

    def mean_velocity(self) -> float:
        s = self.profile_sums(1.0, 0.0, int(math.ceil(self.length)) + 1).sum(axis=0)
        return float(s[2] / s[1])

    def galilean_shift(self, du: float) -> None:
        raise ValueError("the synthetic piston runs in the lab frame")

    def regions(self):
        mat = self.material
        xp, xf = self._piston(), self._front()
        rho0, P0, E0 = mat["rho0"], mat["P0"], mat["E0"]
        out = []
        if self.v_left > 0:
            _, rho1, P1, E1 = shocked_state(rho0, P0, E0, mat["c0"], mat["s"], self.v_left)
            out.append((xp, xf, rho1, self.v_left, P1, E1))
        out.append((xf, self.length, rho0, 0.0, P0, E0))
        return out

    def profile_sums(self, width: float, x0: float = 0.0, nbins: int | None = None) -> np.ndarray:
        nb = nbins if nbins is not None else int(math.ceil(self.length / width)) + 1
        return _bin_sums(x0, width, nb, self.regions(), self.area, self.m)

    def state(self) -> dict:
        return {"material": self.material, "length": self.length, "area": self.area,
                "dt": self.dt, "m": self.m, "steps": self.steps, "v_left": self.v_left,
                "t_start": self.t_start, "x_start": self.x_start}  # fmt: skip

    def save(self, out: str | os.PathLike, extra: xr.Dataset | None, attrs: dict) -> Path:
        return _save(self.state(), PISTON, out, extra, attrs)

    @classmethod
    def from_dataset(cls, ds: xr.Dataset, source=None) -> SyntheticPiston:
        st = _state(ds, source, PISTON)
        sim = cls(st["material"], st["length"], st["area"], st["dt"], st["m"])
        sim.steps, sim.v_left = st["steps"], st["v_left"]
        sim.t_start, sim.x_start = st["t_start"], st["x_start"]
        return sim


class SyntheticWindow(SyntheticFront):
    """``SyntheticFront`` with the rest of the ``WindowSolver`` protocol: the profile along
    the window (shocked material at u_out behind the front, upstream at u_in ahead, each in
    its exact state), boundaries, step count, particle mass and checkpoints."""

    def __init__(self, material: dict, u_in: float, u_out: float, length: float,
                 front: float, dt: float, m: float):  # fmt: skip
        mat = material
        _, rho1, _, _ = shocked_state(mat["rho0"], mat["P0"], mat["E0"], mat["c0"], mat["s"],
                                      u_out - u_in)  # fmt: skip
        super().__init__(mat["c0"], mat["s"], u_in, u_out, length, front, mat["rho0"], rho1, dt)
        self.material, self.m = dict(mat), float(m)

    @property
    def steps(self) -> int:
        return self.step

    @property
    def n_particles(self) -> int:
        return int(round(self.count_in_window() / self.m))

    def count_in_window(self) -> float:
        return super().count_in_window() / self.m

    def wall_positions(self) -> tuple[float, float]:
        return self.geom.x_lo, self.geom.x_hi

    def mean_velocity(self) -> float:
        s = self.profile_sums(1.0).sum(axis=0)
        return float(s[2] / s[1])

    def profile_sums(self, width: float) -> np.ndarray:
        mat = self.material
        u_p = self._u_p_eff(self.time)
        _, rho1, P1, E1 = shocked_state(mat["rho0"], mat["P0"], mat["E0"], mat["c0"],
                                        mat["s"], u_p)  # fmt: skip
        g = self.geom
        regions = [(g.x_lo, self.x_f, rho1, self.u_out, P1, E1),
                   (self.x_f, g.x_hi, mat["rho0"], self.u_in, mat["P0"], mat["E0"])]  # fmt: skip
        nb = int(math.ceil(g.length / width - 1e-9))
        return _bin_sums(g.x_lo, width, nb, regions, self.area, self.m)

    def state(self) -> dict:
        return {"material": self.material, "m": self.m, "dt": self.dt, "step": self.step,
                "u_in": self.u_in, "u_out": self.u_out, "length": self.geom.length,
                "x_f": self.x_f, "rho1": self.rho1,
                "amplitudes": [[a if math.isfinite(a) else -1e300, b]
                               for a, b in self._amplitudes]}  # fmt: skip

    def save(self, out: str | os.PathLike, extra: xr.Dataset | None, attrs: dict) -> Path:
        return _save(self.state(), WINDOW, out, extra, attrs)

    @classmethod
    def from_dataset(cls, ds: xr.Dataset, source=None) -> SyntheticWindow:
        st = _state(ds, source, WINDOW)
        w = cls(st["material"], st["u_in"], st["u_out"], st["length"], 0.0, st["dt"], st["m"])
        w.step, w.x_f, w.rho1 = st["step"], st["x_f"], st["rho1"]
        w._amplitudes = [(a if a > -1e300 else -np.inf, b) for a, b in st["amplitudes"]]
        return w
