"""Failure statuses and the exceptions that carry them (bottom layer: imports nothing of hugomap).

A stage that cannot reach its goal ends with a named status and a diagnostic, never a value:
``FAILURES`` lists every such status with its class and cause, and the stage raises a
``HugomapFailure`` subclass carrying ``status`` and ``diagnostic`` that the stages write
to the point file. ``CheckpointError`` is the other kind: a checkpoint file refused as input
(unreadable, foreign, too old or altered); it carries the file and the problem, not a status.

Hierarchy (what an ``except`` catches)::

    RuntimeError
      HugomapFailure            status, diagnostic; message "status: diagnostic"
        SolverUnstable          a solver's time loop stopped (MD: nan, cfl, atom_lost)
          SPHUnstable           the CSPH solver's (nan, eos_range, particle_lost, dt_collapse...)
        StageFailed             a piston stage ended without reaching its goal
        WindowError             a window cannot be set up or cannot go on
        SlabError               a window measurement without its slab behind the front
    ValueError
      CheckpointError           source, problem; message "refused checkpoint source: problem"
"""

from __future__ import annotations

# The statuses of a point that carries a value: ok (its jump conditions close, its slab is
# steady, its errors meet the scene's target where it has one), target_not_reached (ok but
# for errors above the target: methods.target), not_converged (a physical cause is named).
MEASURED: tuple[str, ...] = ("ok", "target_not_reached", "not_converged")

# Every status a stage may end with other than the measured ones, and its cause (the failure
# labels of the stability map): a point file carries one of these with a diagnostic, never a
# value. Value: (failure class, cause).
FAILURES: dict[str, tuple[str, str]] = {
    "nan": ("unstable solver", "a position or velocity became NaN or infinite"),
    "cfl": ("unstable solver", "an atom moved too far in one step (time step too large)"),
    "atom_lost": ("unstable solver", "an atom escaped through a wall or the window"),
    "particle_lost": ("unstable solver", "an SPH particle escaped through a wall or the window"),
    "eos_range": ("unstable solver", "an SPH particle left the EOS's valid compression range"),
    "dt_collapse": ("unstable solver", "the SPH time step collapsed"),
    "seam_work": (
        "unstable solver",
        "the live inflow's copy did more work at the seam in one step than the atoms there hold",
    ),
    "bad_config": ("bad input", "the stored config cannot run this stage"),
    "sample_too_short": ("piston", "the front reached the far end before the drive ended"),
    "max_time": ("piston", "the front did not reach its target within the time limit"),
    "no_front_speed": ("window set-up", "the loading stage gives no front speed"),
    "too_few_samples": ("averaging", "too few profile samples for block averages"),
    "no_inflow": ("window set-up", "no upstream material to cut the window from"),
    "outflow_reversed": ("window set-up", "the outflow would flow into the window"),
    "reservoir_energy": ("window set-up", "the inflow snapshot cannot reach the pole energy"),
    "front_left_window": ("control", "the front left the window"),
    "never_steady": ("control", "the slope of omega never stayed zero"),
    "oscillating": ("control", "the front speed oscillates without decaying"),
    "diverged": ("control", "the corrections grow (gain too large)"),
    "too_noisy": (
        "control",
        "the averaging window (AMW, MW) or trial (dichotomy) cannot resolve the front speed",
    ),
    "no_shock": ("control", "MW lowered the amplitude to nothing: the held D is below c0"),
    "bracket_not_found": ("dichotomy", "<domega/dt> kept one sign over every trial"),
    "max_iterations": ("dichotomy", "the bracket was still too wide at the iteration limit"),
    "pole_off_pressure": (
        "bad input",
        "the crystal's pole is not at the pressure its lattice was searched for",
    ),
}


class HugomapFailure(RuntimeError):
    """A stage or solver stopped without a value: ``status`` names why (a key of
    ``FAILURES``), ``diagnostic`` says where and how; the message is ``status: diagnostic``."""

    def __init__(self, status: str, diagnostic: str):
        super().__init__(f"{status}: {diagnostic}")
        self.status = status
        self.diagnostic = diagnostic


class SolverUnstable(HugomapFailure):
    """The solver stopped: ``status`` names why (nan, cfl, atom_lost, ...), ``diagnostic`` how."""


class SPHUnstable(SolverUnstable):
    """The CSPH run stopped: ``status`` (nan, eos_range, particle_lost, dt_collapse) and
    ``diagnostic`` (where and how)."""


class StageFailed(HugomapFailure):
    """A stage ended without reaching its goal: ``status`` says which way."""


class WindowError(HugomapFailure):
    """The window cannot be set up or cannot go on: ``status`` says which way."""


class SlabError(HugomapFailure):
    """A window measurement without its slab behind the front (``status``, ``diagnostic``)."""


class CheckpointError(ValueError):
    """A checkpoint that must not be used: unreadable, foreign, too old, or altered.

    ``source`` names the file (or says the dataset was built in memory), ``problem`` what is
    wrong with it; the message gives both.
    """

    def __init__(self, source: str, problem: str):
        super().__init__(f"refused checkpoint {source}: {problem}")
        self.source = source
        self.problem = problem
