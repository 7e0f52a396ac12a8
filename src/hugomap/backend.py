"""The seam between the workflow's stages and a solver: the ``Backend`` protocol and the
neutral records that cross it.

A stage (``hugomap.stages``) never reads ``scene["solver"]``: it asks the registry
(``hugomap.registry``) for the scene's backend and talks to it through this protocol. A
backend owns its units (LJ reduced units for MD, SI for CSPH), its kernels, its checkpoint
layout and its cost model; what it hands back is neutral (``hugomap.states``): a ``Pole``, a
``PistonFrame``, a ``Profile`` reader, ``ControlParams`` and ``Resources``. The methods
(``hugomap.methods``) drive the solver it returns through ``methods.protocol.ShockSolver`` and
``WindowSolver``.
"""

from __future__ import annotations

import copy
import math
import os
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Protocol

import xarray as xr

from .io.dataset import UnitTable
from .methods.protocol import ShockSolver, WindowSolver
from .states import ControlParams, PistonFrame, Pole, Profile, Resources, WindowStart


@dataclass
class ShockFrameResult:
    """One shock-frame point (``Backend.shock_frame_point``) in the backend's units:
    ``values`` named as ``analysis.shock.measure_point`` names a point's (D, u_p_measured,
    ρ, V, P, E, T, the jump residuals, each with ``_err``), its ``status`` and
    ``diagnostic``, and ``attrs`` (the fix, its parameters, the iterations) for the point
    file."""

    values: dict[str, float]
    status: str
    diagnostic: str
    attrs: dict[str, Any] = field(default_factory=dict)
    #: the pole the point's jump is taken from, where it is not the sample's (a crystal's
    #: box measures its own: ``lammps.shockframe``)
    pole: dict[str, float] | None = None


class Backend(Protocol):
    """What the stages need of a solver (module docstring). Every member is required but
    those in ``OPTIONAL_MEMBERS``; ``tests/unit/test_backend_protocol.py`` checks each
    registered backend against this class (members, signatures)."""

    name: str
    units: UnitTable

    def prepare(self, scene: dict) -> tuple[ShockSolver, Pole, dict[str, Any]]:
        """Build the scene's sample and measure its pole; returns the solver, the pole and
        ``info``: what the backend must know of its sample later (JSON-able; every later
        checkpoint carries it, and the methods below that take ``info`` get it back)."""

    def save(
        self, solver: ShockSolver | WindowSolver, out: str | os.PathLike,
        extra: xr.Dataset | None, attrs: dict[str, Any],
    ) -> Path:  # fmt: skip
        """The solver's complete state as a verified checkpoint (bit-exact on resume)."""

    def read_checkpoint(self, path: str | os.PathLike) -> xr.Dataset:
        """A simulation checkpoint of this backend read whole and verified (format, checksum);
        ``CheckpointError`` naming the file otherwise (unreadable, foreign, altered)."""

    def load(self, ds: xr.Dataset, source: str | os.PathLike | None = None) -> ShockSolver:
        """The simulation of a sample, loading or partial checkpoint (verified)."""

    def load_window(self, ds: xr.Dataset, source: str | os.PathLike | None = None) -> WindowSolver:
        """The window of a window checkpoint (verified)."""

    def start_piston(self, solver: ShockSolver, scene: dict, u_p: float) -> None:
        """Set a prepared sample in motion: the piston at ``u_p`` (in the backend's frame)."""

    def piston_frame(self, solver: ShockSolver, scene: dict, u_p: float, info: dict) -> PistonFrame:
        """How a piston run at ``u_p`` is measured (no change to the solver)."""

    def profile(self, solver: ShockSolver | WindowSolver, scene: dict, info: dict) -> Profile:
        """The profile reader of ``solver`` at the scene's bin width."""

    def open_window(
        self, solver: ShockSolver, loaded: xr.Dataset, scene: dict, u_p: float,
        front: float, D_guess: float, pole: Pole, info: dict,
    ) -> WindowStart:  # fmt: skip
        """Cut the moving window out of a loading checkpoint at the front position ``front``,
        in the frame of ``D_guess``, and let it settle; raises a ``failures`` exception (or
        ``ValueError`` for a window that cannot be made) with its status."""

    def control_params(self, scene: dict, u_p: float, window: WindowSolver) -> ControlParams:
        """The window schemes' times and gains for this point, in the backend's units."""

    def reference(self, scene: dict) -> xr.Dataset:
        """The scene's reference Hugoniot (dim ``point``: u_p, D, P, V, rho, E, …)."""

    def reference_inputs(self, scene: dict) -> dict | None:
        """What the reference depends on, when it is worth sharing between scenes (a run
        of its own, e.g. equilibrium MD); None when each scene computes its own.

        A backend may set ``reference_from_sample = True``: its reference is computed at
        the pole its prepared sample measured. The reference stage then reads that
        ``Pole`` from the scene's sample file and calls ``reference_inputs(scene, pole)``
        and ``reference(scene, pole)``; ``reference_inputs(scene)`` without it (the
        workflow's sharing key, known before any sample exists) must name every setting
        that decides the sample."""

    def extras(self, solver: ShockSolver, out: Path, scene: dict, u_p: float, info: dict) -> None:
        """Write a piston run's extras beside its point file ``out`` (snapshots: the last
        state as extended XYZ, ``io.extxyz``; a trajectory when the scene asks for one); may
        do nothing."""

    def window_extras(
        self, window: WindowSolver, out: Path, scene: dict, u_p: float, scheme: str,
        info: dict,
    ) -> None:  # fmt: skip
        """Write a window run's extras beside its point file ``out`` (``scheme``: amw, mw,
        dichotomy), as ``extras``; may do nothing."""

    def cost(self, scene: dict, stage: str) -> Resources:
        """Resources of one job of ``stage`` (prepare, load, piston, reference, window)."""

    def longer_sample(self, scene: dict, factor: float) -> dict | None:
        """The scene with a sample ``factor`` (> 1) times as long along the shock and its
        stages' ``shock.max_time`` as much longer (``lengthened``), for a piston that
        missed its error target (``stages.piston``); None where the sample cannot grow (a
        sample read from a file)."""

    def figure_labels(self, scene: dict) -> dict:
        """Figure text: ``axes`` (label and scale factor of V, P, u_p_measured, D), ``tag``
        (of the points), ``reference`` (the reference curve's name), ``title``."""

    def scale(self, scene: dict) -> dict[str, float]:
        """Dimensionless resolution of a scene's window: n_window (particles in it at the
        upstream density), window_spacings (its length in particle spacings), spacing."""

    def sound_speed(self, scene: dict) -> float | None:
        """The material model's sound speed c0 where it has one (None: fit the reference)."""

    def shock_frame_point(
        self, scene: dict, scheme: str, u_p: float, pole: Pole, info: dict
    ) -> ShockFrameResult:
        """Optional (solver lammps only; the ``shockframe`` stage refuses a backend without
        it): a Hugoniot point at ``u_p`` [the frame's velocity units] from a shock-frame
        method (``scheme``: msst, nphug) on a homogeneous periodic box of the material at
        the sample's ``pole``, held on that pole's Hugoniot by the solver
        (``lammps.shockframe``)."""


def lengthened(scene: dict, key: tuple, factor: float) -> dict:
    """A copy of ``scene`` whose sample length at ``key`` (a path of keys and indices, e.g.
    ("sample", "cells", 0)) is ``factor`` times as long (an integer count rounded up) and
    whose ``shock.max_time``, the longest a stage may run, grows as much: a piston's drive
    lasts as long as its front needs to cross the sample."""
    out = copy.deepcopy(scene)
    *head, last = key
    box = out
    for k in head:
        box = box[k]
    old = box[last]
    box[last] = int(math.ceil(old * factor)) if isinstance(old, int) else float(old) * factor
    out["shock"]["max_time"] = float(out["shock"]["max_time"]) * factor
    return out


#: ``Backend`` members a backend may lack: the stage that needs one asks for it with
#: ``getattr`` and writes its point with a diagnostic when it is missing.
OPTIONAL_MEMBERS: frozenset[str] = frozenset({"shock_frame_point"})
