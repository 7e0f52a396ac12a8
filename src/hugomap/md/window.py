"""The moving window over the numba MD: the particle window
(``particles.window.ParticleWindow``, its physics in that module's docstring) whose kit,
when none is given, is ``md.kit.MDKit`` of the simulation's potential (reduced LJ units);
loading a checkpoint without one, ``MDKit()`` with the potential the checkpoint carries.
"""

from __future__ import annotations

from ..particles.window import ParticleWindow
from .kit import MDKit
from .simulation import MDSimulation

__all__ = ["MDWindow"]


class MDWindow(ParticleWindow):
    """``ParticleWindow`` around an ``MDSimulation``, ``MDKit`` by default (module
    docstring)."""

    @staticmethod
    def default_kit(sim: MDSimulation | None = None) -> MDKit:
        """``MDKit`` of ``sim``'s potential; without ``sim`` (a checkpoint to load), with
        none."""
        return MDKit(None if sim is None else sim.lj)
