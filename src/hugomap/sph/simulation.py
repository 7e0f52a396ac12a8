"""The CSPH simulation: time loop, walls (piston), neighbour lists and blow-up checks (SI).

``CSPHSimulation`` owns an ``SPHState`` and advances it with the seed's explicit scheme
(``csph`` module: pair sums, Δt formula, density exp(−μ̇Δt), kinetic correction of the energy,
stress rotation and radial return). Geometry: positions along x are bounded by optional rigid
walls (``walls`` = [x_L, u_L, x_R, u_R]; a wall that is None is absent, so that end is a free
surface); each dimension may instead be periodic on [lo, lo + length). 1D runs are uniaxial
strain, 2D runs plane strain (per metre of depth).

A piston is a wall moving into the material: in the lab frame (material at rest) the left wall
moves at u_L = u_p. Walls are free-slip and act through mirror ghosts (``csph.fill_ghosts``).

Blow-up checks (``SPHUnstable``, a ``SolverUnstable`` with ``status`` and ``diagnostic``):
``nan`` (a non-finite state), ``eos_range`` (ρ beyond the EOS cap), ``particle_lost`` (a
particle behind a wall, or farther from the initial extent than ``escape_distance`` plus
twice the fastest wall's travel: a free surface moves at most at twice the particle velocity
of the wave that reaches it),
``dt_collapse`` (Δt below ``dt_floor`` × the first step's Δt).
"""

from __future__ import annotations

import math
from contextlib import contextmanager

import numba
import numpy as np

from ..eos import EOS
from ..eos.mie_gruneisen import ETA_MAX_FRACTION
from ..failures import SPHUnstable
from ..strength import Strength, hydrodynamic
from . import csph
from .neighbors import build_list, cell_grid, sort_by_cell
from .state import SPHState

#: Below this many particles the parallel kernels run on one thread: a step of a small (1D)
#: system is shorter than waking the other threads (on a shared 2-core machine: 2000-particle
#: 1D runs took 3× longer on two threads than on one). Results do not depend on the thread
#: count (the pair sums are per row), so switching is safe.
SERIAL_BELOW = 8192

#: Density updates (``csph`` module docstring, Density); "auto": kernel_ratio in 1D,
#: continuity in 2D.
DENSITY_MODES = ("auto", "kernel_ratio", "continuity")
#: Passes of the kernel_ratio step that recompute n̂(t+Δt) with the sizes l = (m/ρ)^(1/dim)
#: of the previous pass's ρ (the first pass uses the continuity prediction's). The next step
#: divides by n̂ at the sizes of its own ρ, so the product of the ratios telescopes only to
#: the extent these agree: behind a 1D copper shock at 4000 m/s the density's memory of the
#: front was −0.069 % with no extra pass, −0.025 % with one, −0.011 % with two (D −0.040,
#: −0.009, −0.003 %); a pass is one kernel sum (a fifth of a 1D step).
KERNEL_RATIO_PASSES = 2


@contextmanager
def _threads_for(n: int):
    try:
        before = numba.get_num_threads()
    except Exception:  # pragma: no cover - numba without a threading layer
        before = 1
    if n >= SERIAL_BELOW or before == 1:
        yield
        return
    numba.set_num_threads(1)
    try:
        yield
    finally:
        numba.set_num_threads(before)


def profile_fields(sums: np.ndarray) -> dict[str, np.ndarray]:
    """Per-bin means from ``profile_sums`` (columns ``csph.PROFILE_FIELDS``; NaN in empty
    bins): count, ρ = Σm/ΣV [kg/m³], u = Σ m v_x/Σm [m/s], σ_xx, σ_yy = ΣVσ/ΣV and
    P = ΣVP/ΣV [Pa] (volume averages: the stress a slab carries), e = Σ m e/Σm [J/kg],
    eps_p = Σ m ε_p/Σm, and the mass per bin [kg/m² in 1D, kg/m in 2D]."""
    s = np.asarray(sums, dtype=np.float64)
    with np.errstate(invalid="ignore", divide="ignore"):
        m, vol = s[:, 1], s[:, 2]
        return {
            "count": s[:, 0], "mass": m, "rho": m / vol, "u": s[:, 3] / m,
            "sxx": s[:, 6] / vol, "syy": s[:, 7] / vol, "P": s[:, 8] / vol,
            "e": s[:, 5] / m, "eps_p": s[:, 9] / m,
        }  # fmt: skip


class CSPHSimulation:
    """A CSPH run (module docstring).

    Parameters: ``state``; ``eos``, ``strength`` (default: none); ``theta`` (h_ij = θ(l_i + l_j));
    ``cfl`` (C of the Δt formula); ``k_comp`` (the Δt compression factor, 16 as printed in the
    seed; 0 drops the term); ``walls`` [x_L, u_L, x_R, u_R] with None for an absent wall;
    ``periodic`` per dimension (x, y) with ``lo``/``length`` of the periodic box;
    ``grad_correction``, ``dev_mean`` (see ``csph``); ``skin`` (neighbour-list skin in units of l_max);
    ``dt_floor``, ``escape_distance`` (m; default 100 l_max) for the blow-up checks;
    ``density``: ``"kernel_ratio"``, ``"continuity"`` or ``"auto"`` (the first in 1D, the
    second in 2D; ``csph`` module docstring, Density), resolved into ``density_mode``.
    """

    def __init__(
        self,
        state: SPHState,
        eos: EOS,
        strength: Strength | None = None,
        *,
        theta: float = 0.6,
        cfl: float = 0.3,
        k_comp: float = 16.0,
        walls: tuple[float | None, float, float | None, float] = (None, 0.0, None, 0.0),
        periodic: tuple[bool, bool] = (False, False),
        lo: tuple[float, float] = (0.0, 0.0),
        length: tuple[float, float] = (1.0, 1.0),
        grad_correction: bool = True,
        dev_mean: bool = False,
        skin: float = 0.5,
        dt_floor: float = 1e-3,
        escape_distance: float | None = None,
        density: str = "auto",
    ):
        self.state = state
        if density not in DENSITY_MODES:
            raise ValueError(f"density must be one of {DENSITY_MODES}, got {density!r}")
        if density == "auto":
            density = "kernel_ratio" if state.dim == 1 else "continuity"
        self.density_mode = density
        self.eos = eos
        self.strength = strength if strength is not None else hydrodynamic()
        if not 0.0 < theta <= 2.0:
            raise ValueError(f"theta must be in (0, 2], got {theta}")
        if not 0.0 < cfl <= 1.0:
            raise ValueError(f"cfl must be in (0, 1], got {cfl}")
        self.theta = float(theta)
        self.cfl = float(cfl)
        self.k_comp = float(k_comp)
        self.has_wall = np.array([walls[0] is not None, walls[2] is not None])
        self.walls = np.array(
            [walls[0] or 0.0, walls[1], walls[2] or 0.0, walls[3]], dtype=np.float64
        )
        self.periodic = np.array(periodic, dtype=np.bool_)
        if state.dim == 1:
            self.periodic[1] = False
        if self.periodic[0] and self.has_wall.any():
            raise ValueError("a periodic x dimension cannot have walls")
        self.lo = np.array(lo, dtype=np.float64)
        self.length = np.array(length, dtype=np.float64)
        self.grad_correction = bool(grad_correction)
        self.dev_mean = bool(dev_mean)
        self.skin = float(skin)
        self.dt_floor = float(dt_floor)
        n = state.n
        self.pressure = np.zeros(n)
        self.rates = np.zeros((n, csph.NRATE))
        self.dt = 0.0
        self.dt0 = 0.0
        self.steps = 0
        self.n_builds = 0
        if eos.name == "mie_gruneisen":
            rho0, s = eos.params[0], eos.params[2]
            self.rho_max = float(rho0 / (1.0 - ETA_MAX_FRACTION / s))
        else:
            self.rho_max = math.inf
        lmax = float(state.l.max())
        self.escape = float(escape_distance) if escape_distance else 100.0 * lmax
        self.extent = (float(state.x[:, 0].min()), float(state.x[:, 0].max()))
        self._nbr = np.zeros((n, 8), dtype=np.int32)
        self._nnb = np.zeros(n, dtype=np.int32)
        self._x_ref = state.x.copy()
        self._walls_ref = self.walls.copy()
        self._rlist = 0.0
        self._src = np.zeros(0, dtype=np.int64)
        self._side = np.zeros(0, dtype=np.int64)
        self._pk = np.zeros((n, csph.NPACK))
        self._rhat = np.zeros((3, n))  # ρ(t), n̂(t), n̂(t+Δt) of the kernel_ratio step
        #: particles moved rigidly at ``frozen_velocity`` and held at ``frozen_state``
        #: (ρ, e, l) with S = 0 (the window's inflow); None: all mobile
        self.frozen: np.ndarray | None = None
        self.frozen_velocity = 0.0
        self.frozen_state = (0.0, 0.0, 0.0)
        self._build()

    # -- protocol-like accessors -------------------------------------------------------------
    @property
    def time(self) -> float:
        return self.state.time

    @property
    def n_particles(self) -> int:
        return self.state.n

    def wall_positions(self) -> tuple[float, float]:
        return float(self.walls[0]), float(self.walls[2])

    def set_walls(self, v_left: float, v_right: float) -> None:
        self.walls[1] = v_left
        self.walls[3] = v_right

    def mean_velocity(self) -> float:
        st = self.state
        return float(np.sum(st.m * st.v[:, 0]) / np.sum(st.m))

    # -- neighbour list ----------------------------------------------------------------------
    def _cut(self) -> float:
        return 2.0 * self.theta * 2.0 * float(self.state.l.max())

    def _build(self) -> None:
        st = self.state
        n = st.n
        lmax = float(st.l.max())
        self._rlist = self._cut() + self.skin * lmax
        for d in range(2):
            if self.periodic[d] and self.length[d] < 2.0 * self._rlist:
                raise ValueError(
                    f"periodic length {self.length[d]:.4g} m along {'xy'[d]} is shorter than "
                    f"twice the neighbour-list radius {self._rlist:.4g} m: a pair would meet "
                    "two images of the same particle (minimum image fails); use more rows"
                )
        src, side = [], []
        xs = st.x[:, 0]
        for k in range(2):
            if self.has_wall[k]:
                xw = self.walls[2 * k]
                near = (
                    np.nonzero(xs - xw < self._rlist)[0]
                    if k == 0
                    else np.nonzero(xw - xs < self._rlist)[0]
                )
                src.append(near)
                side.append(np.full(near.size, k))
        self._src = np.concatenate(src).astype(np.int64) if src else np.zeros(0, np.int64)
        self._side = np.concatenate(side).astype(np.int64) if side else np.zeros(0, np.int64)
        ntot = n + self._src.size
        if self._pk.shape[0] != ntot:
            self._pk = np.zeros((ntot, csph.NPACK))
        self._pack()
        pos = np.ascontiguousarray(self._pk[:, :2])
        origin, sides, nc = cell_grid(pos, self._rlist, self.periodic, self.lo, self.length)
        cell, order, start = sort_by_cell(pos, origin, sides, nc)
        while True:
            need = build_list(
                pos, n, self.periodic, self.length, nc, cell, order, start,
                self._rlist**2, self._nbr, self._nnb,
            )  # fmt: skip
            if need <= self._nbr.shape[1]:
                break
            self._nbr = np.zeros((n, need + 8), dtype=np.int32)
        self._x_ref = st.x.copy()
        self._walls_ref = self.walls.copy()
        self.n_builds += 1

    def _pack(self) -> None:
        st = self.state
        csph.pack(
            st.x, st.v, st.m, st.rho, st.e, st.S, st.l, self.eos.kind, self.eos.params,
            self.strength.params, self._pk, self.pressure,
        )  # fmt: skip
        if self._src.size:
            csph.fill_ghosts(self._pk, st.n, self._src, self._side, self.walls)

    def _list_valid(self) -> bool:
        d = csph.max_displacement(self.state.x, self._x_ref, self.periodic, self.length)
        dw = float(np.max(np.abs(self.walls[[0, 2]] - self._walls_ref[[0, 2]])))
        # a ghost moves by at most d + 2 dw; two particles approach by at most twice that
        return self._cut() + 2.0 * (d + 2.0 * dw) < self._rlist

    # -- the time loop -----------------------------------------------------------------------
    def compute_rates(self) -> np.ndarray:
        """Pack the state, rebuild the list if needed, and return the pair rates (n, NRATE):
        dv_x/dt, dv_y/dt [m/s²], dE/dt [W/kg], L_xx, L_xy, L_yx, L_yy [1/s] (``csph``)."""
        if not self._list_valid():
            self._build()
        else:
            self._pack()
        st = self.state
        csph.correction(
            self._pk, st.n, st.dim, self._nbr, self._nnb, self.theta, self.periodic,
            self.length, self.grad_correction,
        )  # fmt: skip
        if self._src.size:
            csph.fill_ghosts(self._pk, st.n, self._src, self._side, self.walls)
        csph.pair_rates(
            self._pk, st.n, st.dim, self._nbr, self._nnb, self.theta, self.periodic,
            self.length, self.dev_mean, self.rates,
        )  # fmt: skip
        return self.rates

    def step(self, dt: float | None = None) -> float:
        """One time step (Δt from the seed's formula unless given); returns Δt [s]."""
        st = self.state
        self.compute_rates()
        if dt is None:
            dt = csph.time_step(self._pk, self.rates, st.n, self.cfl, self.k_comp)
        if self.steps == 0:
            self.dt0 = dt
        self.dt = dt
        if self.frozen is not None and self.frozen.any():
            x_frozen = st.x[self.frozen, 0].copy()
        ratio = self.density_mode == "kernel_ratio"
        if ratio:
            self._rhat[0] = st.rho
            csph.density_sum(
                self._pk, st.n, st.dim, self._nbr, self._nnb, self.theta, self.periodic,
                self.length, self._rhat[1],
            )  # fmt: skip
        bad = csph.update(
            st.x, st.v, st.m, st.rho, st.e, st.S, st.eps_p, st.l, self.rates, dt,
            self.strength.kind, self.strength.params, self.periodic, self.lo, self.length,
            self.rho_max,
        )  # fmt: skip
        if self.frozen is not None and self.frozen.any():
            f = self.frozen
            st.x[f, 0] = x_frozen + self.frozen_velocity * dt
            st.v[f] = 0.0
            st.v[f, 0] = self.frozen_velocity
            st.rho[f], st.e[f], st.l[f] = self.frozen_state
            st.S[f] = 0.0
            st.eps_p[f] = 0.0
        self.walls[0] += self.walls[1] * dt
        self.walls[2] += self.walls[3] * dt
        if ratio:
            bad = max(bad, self._kernel_ratio_density())
        st.time += dt
        self.steps += 1
        self._check(bad)
        return dt

    def _kernel_ratio_density(self) -> int:
        """ρ(t+Δt) = ρ(t) n̂(x(t+Δt), l*)/n̂(x(t), l(t)) for the mobile particles (``csph``
        module docstring, Density): ``update`` has moved the particles and left the
        continuity prediction's l* in the state, the walls have moved; ρ(t), n̂(t) are in
        ``_rhat``. Then ``KERNEL_RATIO_PASSES`` more passes with l from the last ρ. Returns
        the number of bad particles (``csph.rescale_density``)."""
        st = self.state
        if self._list_valid():
            csph.move_packed(self._pk, st.x, st.l, self._src, self._side, self.walls)
        else:
            self._build()
        mobile = np.ones(st.n, dtype=np.bool_) if self.frozen is None else ~self.frozen
        bad = 0
        for k in range(1 + KERNEL_RATIO_PASSES):
            if k:  # n̂(t+Δt) again with the sizes of the last pass's ρ
                csph.move_packed(self._pk, st.x, st.l, self._src, self._side, self.walls)
            csph.density_sum(
                self._pk, st.n, st.dim, self._nbr, self._nnb, self.theta, self.periodic,
                self.length, self._rhat[2],
            )  # fmt: skip
            bad = csph.rescale_density(
                st.rho, st.l, st.m, self._rhat[0], self._rhat[1], self._rhat[2], mobile,
                st.dim, self.rho_max,
            )  # fmt: skip
        return bad

    def advance(self, n_steps: int) -> None:
        """Run ``n_steps`` steps (raises SPHUnstable)."""
        with _threads_for(self.state.n):
            for _ in range(int(n_steps)):
                self.step()

    def run_until(self, t_end: float, max_steps: int = 10_000_000) -> int:
        """Step until time ≥ t_end [s]; returns the number of steps taken."""
        k = 0
        with _threads_for(self.state.n):
            while self.state.time < t_end:
                if k >= max_steps:
                    raise SPHUnstable(
                        "dt_collapse", f"{max_steps} steps did not reach t={t_end:g} s"
                    )
                self.step()
                k += 1
        return k

    def _check(self, bad: int) -> None:
        st = self.state
        if bad:
            fin = np.isfinite(st.rho) & np.isfinite(st.e) & np.isfinite(st.x[:, 0])
            if not fin.all():
                i = int(np.nonzero(~fin)[0][0])
                raise SPHUnstable(
                    "nan", f"{bad} particle(s) non-finite at step {self.steps}, "
                    f"t={st.time:.6g} s; first i={i} at x={self._x_ref[i, 0]:.6g} m"
                )  # fmt: skip
            i = int(np.argmax(st.rho))
            raise SPHUnstable(
                "eos_range", f"density {st.rho[i]:.6g} kg/m³ of particle {i} beyond the EOS "
                f"cap {self.rho_max:.6g} at step {self.steps}, t={st.time:.6g} s"
            )  # fmt: skip
        if self.dt < self.dt_floor * self.dt0:
            raise SPHUnstable(
                "dt_collapse", f"dt={self.dt:.3g} s fell below {self.dt_floor:g} of the first "
                f"step's {self.dt0:.3g} s at step {self.steps}"
            )  # fmt: skip
        xs = st.x[:, 0]
        tol = 0.5 * float(st.l.max())
        if self.has_wall[0] and xs.min() < self.walls[0] - tol:
            i = int(np.argmin(xs))
            raise SPHUnstable(
                "particle_lost", f"particle {i} at x={xs[i]:.6g} m went through the left wall "
                f"at {self.walls[0]:.6g} m (step {self.steps})"
            )  # fmt: skip
        if self.has_wall[1] and xs.max() > self.walls[2] + tol:
            i = int(np.argmax(xs))
            raise SPHUnstable(
                "particle_lost", f"particle {i} at x={xs[i]:.6g} m went through the right wall "
                f"at {self.walls[2]:.6g} m (step {self.steps})"
            )  # fmt: skip
        # a free end moves with the material: no faster than twice the fastest wall (a free
        # surface doubles the particle velocity of the wave that reaches it), so a sample a
        # piston pushes for long (porous copper at 50 m/s: its free end 1 mm out in 21 us)
        # is not a particle shot away
        reach = self.escape + 2.0 * max(abs(self.walls[1]), abs(self.walls[3])) * st.time
        if not self.periodic[0] and (
            xs.min() < self.extent[0] - reach or xs.max() > self.extent[1] + reach
        ):
            i = int(np.argmax(np.maximum(self.extent[0] - xs, xs - self.extent[1])))
            raise SPHUnstable(
                "particle_lost", f"particle {i} escaped to x={xs[i]:.6g} m (extent "
                f"{self.extent[0]:.6g}..{self.extent[1]:.6g} m) at step {self.steps}"
            )  # fmt: skip

    def replace_particles(self, state: SPHState, frozen: np.ndarray | None = None) -> None:
        """Swap in a new particle set (same dimension; the window adds and removes particles)
        and rebuild the neighbour list; the clock, walls and Δt history are kept."""
        if state.dim != self.state.dim:
            raise ValueError("replace_particles: dimension changed")
        n = state.n
        self.state = state
        self.frozen = None if frozen is None else np.asarray(frozen, dtype=bool).copy()
        self.pressure = np.zeros(n)
        self.rates = np.zeros((n, csph.NRATE))
        self._nbr = np.zeros((n, self._nbr.shape[1]), dtype=np.int32)
        self._nnb = np.zeros(n, dtype=np.int32)
        self._pk = np.zeros((n, csph.NPACK))
        self._rhat = np.zeros((3, n))
        self._build()

    #: Names of the solver's private arrays a bit-exact checkpoint must carry.
    LIST_ARRAYS = ("_nbr", "_nnb", "_x_ref", "_walls_ref", "_src", "_side")

    def checkpoint_arrays(self) -> dict[str, np.ndarray]:
        """Every array that defines the continuation (state, walls, list), by name."""
        st = self.state
        out = {"x": st.x, "v": st.v, "m": st.m, "rho": st.rho, "e": st.e, "S": st.S,
               "eps_p": st.eps_p, "l": st.l, "walls": self.walls}  # fmt: skip
        for k in self.LIST_ARRAYS:
            out[k] = getattr(self, k)
        if self.frozen is not None:
            out["frozen"] = self.frozen
        return {k: np.array(v, copy=True) for k, v in out.items()}

    def checkpoint_scalars(self) -> dict[str, float | int]:
        return {"time": self.state.time, "dt": self.dt, "dt0": self.dt0, "steps": self.steps,
                "n_builds": self.n_builds, "rlist": self._rlist,
                "frozen_velocity": self.frozen_velocity,
                "frozen_rho": self.frozen_state[0], "frozen_e": self.frozen_state[1],
                "frozen_l": self.frozen_state[2]}  # fmt: skip

    def restore(self, arrays: dict[str, np.ndarray], scalars: dict) -> None:
        """Put back what ``checkpoint_arrays``/``checkpoint_scalars`` returned (bit-exact)."""
        st = SPHState(
            x=arrays["x"], v=arrays["v"], m=arrays["m"], rho=arrays["rho"], e=arrays["e"],
            S=arrays["S"], eps_p=arrays["eps_p"], l=arrays["l"], time=float(scalars["time"]),
        )  # fmt: skip
        n = st.n
        self.state = st
        self.walls = np.array(arrays["walls"], dtype=np.float64)
        self.frozen = np.asarray(arrays["frozen"], bool).copy() if "frozen" in arrays else None
        self._nbr = np.ascontiguousarray(arrays["_nbr"], dtype=np.int32)
        self._nnb = np.ascontiguousarray(arrays["_nnb"], dtype=np.int32)
        self._x_ref = np.array(arrays["_x_ref"], dtype=np.float64)
        self._walls_ref = np.array(arrays["_walls_ref"], dtype=np.float64)
        self._src = np.asarray(arrays["_src"], dtype=np.int64).copy()
        self._side = np.asarray(arrays["_side"], dtype=np.int64).copy()
        self.pressure = np.zeros(n)
        self.rates = np.zeros((n, csph.NRATE))
        self._pk = np.zeros((n + self._src.size, csph.NPACK))
        self._rhat = np.zeros((3, n))
        self.dt = float(scalars["dt"])
        self.dt0 = float(scalars["dt0"])
        self.steps = int(scalars["steps"])
        self.n_builds = int(scalars["n_builds"])
        self._rlist = float(scalars["rlist"])
        self.frozen_velocity = float(scalars["frozen_velocity"])
        self.frozen_state = tuple(float(scalars[k]) for k in ("frozen_rho", "frozen_e", "frozen_l"))

    # -- observables -------------------------------------------------------------------------
    def profile_sums(self, width: float, x0: float | None = None, nbins: int | None = None):
        """Per-bin sums along x of ``csph.PROFILE_FIELDS`` in slabs of ``width`` [m] from x0
        (default: the left wall, or the leftmost particle), shape (nbins, 10)."""
        st = self.state
        self._pack()
        if x0 is None:
            x0 = float(self.walls[0]) if self.has_wall[0] else float(st.x[:, 0].min())
        if nbins is None:
            nbins = int(np.ceil((float(st.x[:, 0].max()) - x0) / width)) + 1
        out = np.zeros((nbins, len(csph.PROFILE_FIELDS)))
        csph.profile_sums(
            st.x, st.v, st.m, st.rho, st.e, st.S, self.pressure, st.eps_p, float(x0),
            float(width), out,
        )  # fmt: skip
        return out

    def stress_xx(self) -> np.ndarray:
        """σ_xx = −P + S_xx per particle [Pa] (tension positive)."""
        self._pack()
        return self.state.S[:, 0] - self.pressure


# == the moving window (1D) ================================================================
