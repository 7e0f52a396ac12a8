"""The piston method: a rigid wall drives a shock into the sample (the classic reference).

Frame: the piston's. Every atom of the prepared sample (at rest) gets −u_p, the piston wall at
x_L stays at rest and the far wall moves with the upstream material at −u_p, so the sample
stays confined at its initial state. The shocked material is then near rest, the front moves
at D − u_p, and D, u_p are measured relative to the upstream flow (Galilean-equivalent to a
piston moving at +u_p into material at rest, as in LAMMPS ``fix wall/piston``).

Stages: ``load`` runs until the front has travelled a target distance (then the state is
saved: the window methods branch from it); ``drive`` continues until the front comes within a
margin of the far wall. Profiles are sampled every ``sample_every`` steps.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from ..analysis.shock import front_position
from ..failures import StageFailed
from ..md.profiles import fields_from_sums
from .protocol import ShockSolver


@dataclass
class PistonParams:
    """u_p [σ/τ] piston speed; bin_width [σ]; sample_every [steps]; load_distance [σ] the front
    travel that ends loading; rear_margin [σ] closest approach of the front to the far wall;
    max_time [τ] per stage; area [σ²] transverse area."""

    u_p: float
    bin_width: float
    sample_every: int
    load_distance: float
    rear_margin: float
    max_time: float
    area: float

    def __post_init__(self) -> None:
        if not self.u_p > 0:
            raise ValueError(f"u_p = {self.u_p}: must be > 0 sigma/tau")


@dataclass
class History:
    """Samples taken during a piston run: times [τ], wall positions [σ], front [σ], stage
    (0 load, 1 drive) and the raw profile sums (nsamples, nbins, 11)."""

    t: list = field(default_factory=list)
    x_left: list = field(default_factory=list)
    x_right: list = field(default_factory=list)
    front: list = field(default_factory=list)
    stage: list = field(default_factory=list)
    sums: list = field(default_factory=list)

    def arrays(self) -> dict[str, np.ndarray]:
        return {
            "t": np.asarray(self.t, dtype=float),
            "x_left": np.asarray(self.x_left, dtype=float),
            "x_right": np.asarray(self.x_right, dtype=float),
            "front": np.asarray(self.front, dtype=float),
            "stage": np.asarray(self.stage, dtype=np.int8),
            "sums": np.asarray(self.sums, dtype=float),
        }

    @classmethod
    def from_arrays(cls, a: dict[str, np.ndarray]) -> History:
        h = cls()
        h.t = list(map(float, a["t"]))
        h.x_left = list(map(float, a["x_left"]))
        h.x_right = list(map(float, a["x_right"]))
        h.front = list(map(float, a["front"]))
        h.stage = list(map(int, a["stage"]))
        h.sums = [np.asarray(s) for s in a["sums"]]
        return h


def start_piston(solver: ShockSolver, u_p: float) -> None:
    """Put a sample into the piston frame: material at −u_p, piston wall at rest.

    The sample's own mean x velocity (a thermal drift of order √(T/N) left by the walls and
    thermostat of the preparation) is removed first, so the upstream flow is exactly −u_p and
    the particle-velocity jump is exactly u_p: the shocked material moves with the piston.
    """
    solver.galilean_shift(-u_p - solver.mean_velocity())
    solver.set_walls(0.0, -u_p)


def take_sample(solver: ShockSolver, p: PistonParams, history: History, stage: int) -> float:
    """Record one profile sample and return the front position [σ]."""
    sums = solver.profile_sums(p.bin_width)
    xl, xr = solver.wall_positions()
    edges = np.arange(sums.shape[0] + 1) * p.bin_width
    ux = fields_from_sums(sums, p.area * p.bin_width)["ux"]
    # Piston frame: shocked material at rest, upstream at −u_p.
    xf = front_position(ux, sums[:, 0], edges, xl, xr, u_behind=0.0, u_ahead=-p.u_p)
    history.t.append(solver.time)
    history.x_left.append(xl)
    history.x_right.append(xr)
    history.front.append(xf)
    history.stage.append(stage)
    history.sums.append(sums)
    return xf


def run_stage(
    solver: ShockSolver,
    p: PistonParams,
    history: History,
    stage: int,
    done: Callable[[float, float, float], bool],
    on_sample: Callable[[], None] | None = None,
) -> None:
    """Advance in chunks of ``sample_every`` steps, sampling after each, until
    ``done(front, x_left, x_right)``; raise StageFailed past ``max_time`` of this stage."""
    t_start = solver.time
    while True:
        solver.advance(p.sample_every)
        xf = take_sample(solver, p, history, stage)
        if on_sample is not None:
            on_sample()
        xl, xr = solver.wall_positions()
        if np.isfinite(xf) and done(xf, xl, xr):
            return
        if xr - xl < 2.0 * p.rear_margin:
            raise StageFailed(
                "sample_too_short",
                f"the far wall reached x = {xr:.2f} sigma before the stage ended "
                f"(front at {xf:.2f}); lengthen the sample or lower u_p",
            )
        if solver.time - t_start > p.max_time:
            raise StageFailed(
                "max_time",
                f"stage {stage} ran {p.max_time} tau without reaching its goal "
                f"(front at {xf:.2f} sigma, walls at {xl:.2f}, {xr:.2f})",
            )


def load_to_target(solver: ShockSolver, p: PistonParams, history: History) -> None:
    """Loading stage: drive until the front is ``load_distance`` from the piston."""
    run_stage(solver, p, history, 0, lambda xf, xl, xr: xf - xl >= p.load_distance)


def drive(
    solver: ShockSolver,
    p: PistonParams,
    history: History,
    on_sample: Callable[[], None] | None = None,
) -> None:
    """Measurement stage: drive until the front is ``rear_margin`` from the far wall."""
    run_stage(
        solver, p, history, 1, lambda xf, xl, xr: xr - xf <= p.rear_margin, on_sample=on_sample
    )
