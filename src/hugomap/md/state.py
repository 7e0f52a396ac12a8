"""The complete dynamical state of an LJ molecular-dynamics run (``MDState``).

Reduced LJ units throughout (σ, ε, m, τ = σ√(m/ε), k_B = 1).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np


@dataclass
class MDState:
    """Complete dynamical state of an MD run (arrays of shape (n, 3) unless stated).

    x, v, f: positions [σ], velocities [σ/τ], forces [ε/σ]; ids (n,) stable atom labels;
    x_ref: positions at the last neighbour-list build; L (3,) box lengths [σ]; periodic (3,)
    bool; walls0 (4,) = [x_L0, v_L, x_R0, v_R] so that wall k sits at x_k0 + v_k t;
    time [τ]; step; impulse (2,) x-momentum given by the left/right wall [m σ/τ];
    epoch_time [τ], epoch_step: the time and step at which the current Δt was set, so that
    time = epoch_time + (step − epoch_step) Δt is computed the same way however a run is split
    (a float sum of chunks would not be bit-for-bit, and the wall positions depend on it);
    ref_velocity [σ/τ], ref_shift [σ]: the uniform x drift discounted from the list-rebuild
    displacement test, and that drift since the last build (``integrate.run_steps``).
    """

    x: np.ndarray
    v: np.ndarray
    L: np.ndarray
    periodic: np.ndarray
    walls0: np.ndarray = field(default_factory=lambda: np.array([0.0, 0.0, 0.0, 0.0]))
    f: np.ndarray | None = None
    ids: np.ndarray | None = None
    x_ref: np.ndarray | None = None
    time: float = 0.0
    step: int = 0
    impulse: np.ndarray = field(default_factory=lambda: np.zeros(2))
    epoch_time: float = 0.0
    epoch_step: int = 0
    ref_velocity: float = 0.0
    ref_shift: float = 0.0

    def __post_init__(self) -> None:
        n = self.x.shape[0]
        self.x = np.ascontiguousarray(self.x, dtype=np.float64)
        self.v = np.ascontiguousarray(self.v, dtype=np.float64)
        self.L = np.asarray(self.L, dtype=np.float64)
        self.periodic = np.asarray(self.periodic, dtype=np.bool_)
        self.walls0 = np.asarray(self.walls0, dtype=np.float64)
        if self.f is None:
            self.f = np.zeros((n, 3))
        if self.ids is None:
            self.ids = np.arange(n, dtype=np.int64)
        if self.x_ref is None:
            self.x_ref = self.x.copy()

    @property
    def n(self) -> int:
        return int(self.x.shape[0])
