"""The neutral records that cross the backend seam, in the backend's own units.

A ``Pole`` (the initial state of a Hugoniot), a ``SlabState``, a ``PistonFrame`` (how a piston run is
measured), ``ControlParams`` (a window point's times and gains), ``Resources`` (a job's cost)
a ``WindowStart`` (what opening a window gives) and the ``Profile`` protocol: a backend's reader of its raw profile sums into neutral fields
ρ, u, P = P_xx, P_yy, P_zz, E, T. The analysis and the methods read these and nothing of a
backend's own.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Protocol

import numpy as np
import xarray as xr

POLE_KEYS = ("rho0", "P0", "E0", "T0", "Pyy0")


@dataclass(frozen=True)
class Pole:
    """The initial state a Hugoniot starts from, in the backend's units, with standard errors
    (``None`` where the backend has no such quantity, e.g. T0 of a CSPH sample):
    rho0 density [σ⁻³ | kg m⁻³], P0 longitudinal stress P_xx [ε σ⁻³ | Pa], E0 specific
    internal energy [ε per atom | J kg⁻¹], T0 temperature [ε/k_B | K], Pyy0 transverse stress.
    """

    rho0: float
    P0: float = 0.0
    E0: float = 0.0
    T0: float | None = None
    Pyy0: float | None = None
    rho0_err: float = 0.0
    P0_err: float = 0.0
    E0_err: float = 0.0
    T0_err: float | None = None
    Pyy0_err: float | None = None

    def as_dict(self) -> dict[str, float]:
        """The quantities the pole has (and their errors), by name."""
        return {k: float(v) for k, v in self.__dict__.items() if v is not None}

    @classmethod
    def from_dict(cls, d: dict[str, Any]) -> Pole:
        names = [*POLE_KEYS, *(k + "_err" for k in POLE_KEYS)]
        return cls(**{k: float(d[k]) for k in names if k in d})

    @classmethod
    def from_dataset(cls, ds: xr.Dataset) -> Pole:
        """The pole stored as scalar variables of a checkpoint or point file."""
        return cls.from_dict({k: float(ds[k]) for k in ds.data_vars if k in _POLE_NAMES})

    def replace(self, **changes: float) -> Pole:
        return Pole(**{**self.__dict__, **changes})


_POLE_NAMES = frozenset([*POLE_KEYS, *(k + "_err" for k in POLE_KEYS)])


@dataclass(frozen=True)
class Resources:
    """Cluster resources of one job: ``mem_mb`` [MiB] and ``cpu_s``, the CPU seconds of one
    thread (an upper bound; the workflow divides by the job's threads); ``ranks``: MPI ranks
    (the workflow starts the job with ``mpiexec -n ranks`` when > 1, one thread each)."""

    mem_mb: int
    cpu_s: float
    ranks: int = 1


@dataclass(frozen=True)
class PistonFrame:
    """How a piston run is measured in the backend's frame and units.

    ``u_behind``/``u_ahead``: flow velocity of the shocked and of the upstream material in the
    simulation frame (MD piston frame: 0 and −u_p; CSPH lab frame: u_p and 0), so D = front
    speed − u_ahead and u_p = u_behind − u_ahead exactly. ``x_origin``: where the piston
    started (the front's travel is counted from it); ``far_end``: the far boundary when the
    solver has no wall there (CSPH's free end), else None (the solver's right wall).
    ``load_distance``: the front travel that ends loading; ``rear_margin``: the closest the
    front may come to the far end; ``max_time``: the longest a stage may run; ``area``: the
    transverse area (per unit depth in 2D, 1 in 1D); lengths, times and velocities in the
    backend's units. ``gap``, ``avg_length``: the measured slabs' (``shock.gap``,
    ``shock.avg_length``) in these units where the scene gives them in others (LAMMPS units
    metal: the scene in Å, the frame in m); None: the scene's. ``piston_gap``: how far the
    slab behind the front keeps from the piston (``shock.piston_gap``, clear of the layers
    the piston's start shocked); None: ``gap``. ``ahead_gap``: how far the slab ahead keeps
    from the front (``shock.ahead_gap``); None: ``gap``."""

    u_behind: float
    u_ahead: float
    x_origin: float
    load_distance: float
    rear_margin: float
    max_time: float
    sample_every: int
    far_end: float | None = None
    gap: float | None = None
    avg_length: float | None = None
    piston_gap: float | None = None
    ahead_gap: float | None = None


@dataclass(frozen=True)
class ControlParams:
    """A window point's control and averaging, in the backend's time and velocity units:
    ``window_time`` (one averaging window of AMW/MW), ``average_time`` (the steady average),
    ``trial_time``/``final_time`` (the dichotomy's trials and final average), ``every``
    (steps between ω samples), ``calm_windows``, ``max_windows``, ``z`` (|a| ≤ z s is zero),
    ``max_drift`` (the front-speed resolution a calm window must reach), AMW's ``beta``, MW's
    ``gain_rate`` (dimensionless) and ``gain_position`` (per unit time) and ``target`` (the
    front's place in the window, ω*); ``outflow_gap``: the measured slab behind the front
    stays this far from the outflow edge; ``gap`` and ``avg_length``: the measured slabs'
    distance from the front and their length (``shock.gap``, ``shock.avg_length``), in the
    window's length unit, as ``PistonFrame`` carries them for a piston run; ``ahead_gap``:
    the slab ahead's distance from the front (``shock.ahead_gap``; None: ``gap``);
    ``max_average_time``: how long a steady average (AMW/MW's, the dichotomy's final one)
    may go on while its point is unresolved (``methods.steady.steady_state``); ``recentre``:
    AMW brings the front back to ``target`` before its average (``methods.control.recentre``)."""

    window_time: float
    average_time: float
    trial_time: float
    final_time: float
    every: int
    calm_windows: int
    max_windows: int
    z: float
    max_drift: float
    beta: float
    gain_rate: float
    gain_position: float
    target: float
    outflow_gap: float
    gap: float
    avg_length: float
    max_average_time: float = 0.0
    ahead_gap: float | None = None
    recentre: bool = False

    @classmethod
    def from_window(
        cls, w: dict, length: float, gap: float, avg_length: float,
        times: tuple[float, float] | None = None, ahead_gap: float | None = None,
    ) -> ControlParams:  # fmt: skip
        """From a validated ``window`` block: ``times`` (window_time, average_time) where the
        backend derives them, else the configured ones; the dichotomy's trial as long as one
        averaging window and its final average as AMW/MW's unless configured; max_drift =
        drift_fraction L/average_time for a window of ``length``; MW's gain_position per
        window_time; the slab behind the front ``window.outflow_gap`` (default ``gap``) from
        the outflow edge; ``window.max_average_time`` where the block has one (else no
        average goes on past its own time)."""
        wt, avg = times if times is not None else (w["window_time"], w["average_time"])
        d = w["dichotomy"]
        return cls(
            window_time=wt, average_time=avg, trial_time=d.get("trial_time") or wt,
            final_time=d.get("final_time") or avg, every=w["sample_every"],
            calm_windows=w["calm_windows"], max_windows=w["max_windows"], z=w["z"],
            max_drift=w["drift_fraction"] * length / avg, beta=w["amw"]["beta"],
            gain_rate=float(w["mw"]["gain_rate"]),
            gain_position=float(w["mw"]["gain_position"]) / wt, target=w["front_fraction"],
            outflow_gap=w.get("outflow_gap") or gap, gap=gap, avg_length=avg_length,
            max_average_time=float(w.get("max_average_time") or 0.0), ahead_gap=ahead_gap,
            recentre=bool(w["amw"].get("recentre", False)),
        )  # fmt: skip


@dataclass(frozen=True)
class SlabState:
    """The neutral state of a slab of whole bins, in the backend's units: ``rho`` density
    [σ⁻³ | kg m⁻³], ``u`` mass-mean x velocity in the simulation frame [σ/τ | m s⁻¹], ``P`` =
    P_xx = −σ_xx, ``Pyy``, ``Pzz`` [ε σ⁻³ | Pa], ``E`` specific internal energy (the
    kinetic part relative to the slab's mean velocity) [ε per atom | J kg⁻¹], ``T``
    temperature [ε/k_B | K] (None where the backend has none), and ``extra`` fields of the
    backend (CSPH: P_eos [Pa], eps_p [1]). Read like a mapping of the fields it has."""

    rho: float
    u: float
    P: float
    Pyy: float
    Pzz: float
    E: float
    T: float | None = None
    extra: tuple[tuple[str, float], ...] = ()

    def keys(self) -> list[str]:
        base = ["rho", "u", "P", "Pyy", "Pzz", "E"] + ([] if self.T is None else ["T"])
        return base + [k for k, _ in self.extra]

    def __iter__(self):
        return iter(self.keys())

    def __getitem__(self, k: str) -> float:
        if k in ("rho", "u", "P", "Pyy", "Pzz", "E") or (k == "T" and self.T is not None):
            return getattr(self, k)
        for name, v in self.extra:
            if name == k:
                return v
        raise KeyError(k)


class Profile(Protocol):
    """A backend's reader of its raw profile sums (``solver.profile_sums(bin_width)``, bins
    from ``x0``): per-bin flow velocity and particle count, and the neutral state of a slab of
    whole bins (its sums added up first, so the mean velocity removed is the slab's)."""

    x0: float
    bin_width: float

    def sums(self, solver: Any) -> np.ndarray:
        """The solver's raw profile sums now, (nbins, nfields), bins from ``x0``."""

    def velocity(self, sums: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(u, count) per bin: mass-mean x velocity and particles."""

    def state(self, summed: np.ndarray, n_bins: int) -> SlabState:
        """Neutral state of ``n_bins`` bins whose sums were added into ``summed``."""


@dataclass(frozen=True)
class WindowStart:
    """What ``Backend.open_window`` returns: the settled window, the pole of its inflow
    material, its ω signal (normalised by that pole and the shocked state), and attributes
    to keep in the window checkpoint."""

    window: Any  # methods.protocol.WindowSolver
    pole: Pole
    signal: Any  # methods.control.OmegaSignal
    attrs: dict[str, Any] = field(default_factory=dict)
