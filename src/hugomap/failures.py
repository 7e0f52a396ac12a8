"""Failure statuses and the exceptions that carry them (placeholder until merged)."""

from __future__ import annotations


class StageFailed(RuntimeError):
    """A stage ended without reaching its goal: ``status`` says which way."""

    def __init__(self, status: str, diagnostic: str):
        super().__init__(f"{status}: {diagnostic}")
        self.status = status
        self.diagnostic = diagnostic


# placeholder wiring until the failures module lands (removed at merge)
from .md.simulation import CheckpointError, SolverUnstable  # noqa: E402
from .md.window import WindowError  # noqa: E402
from .sph.sample import SampleError  # noqa: E402


class SlabError(Exception):
    def __init__(self, status: str, diagnostic: str):
        super().__init__(f"{status}: {diagnostic}")
        self.status, self.diagnostic = status, diagnostic


Failure = (StageFailed, SolverUnstable, WindowError, SlabError)
