"""The frame of a particle snapshot's velocities, for the MD and LAMMPS backends' extended-XYZ
frames (``io.extxyz.VelocityFrame``, written as ``velocity_frame``, ``frame_velocity`` and a
window's ``x_lo``, ``x_hi``; docs/snapshots.md).

The rule, in the simulation's own units (the snapshot's: σ, σ/τ in units lj; Å, Å/ps in
LAMMPS units metal):

- a piston run (``MDBackend.start_piston``, which the LAMMPS backend follows) is in the
  piston's frame: the piston wall at rest, every upstream atom and the far wall moving at
  −u_p, so the velocity to the frame of the material at rest ahead of the front is
  −v_R = u_p, v_R the far wall's velocity (``walls0`` = [x_L0, v_L, x_R0, v_R]);
- a window (``particles.window.ParticleWindow``, over numba MD or LAMMPS) is in its own frame: the
  upstream material flows in at u_in < 0 across x_hi, the shocked material leaves across
  x_lo, so that velocity is −u_in, and the window's edges are ``geom.x_lo``, ``geom.x_hi``
  (the domain beyond them holds the frozen inflow copy and the outflow layer).

An SI view of a LAMMPS window or simulation (``lammps.si``) is looked through to the native
object it wraps (its ``sim``), whose units the snapshot is written in.
"""

from __future__ import annotations

from ..io.extxyz import VelocityFrame


def velocity_frame(solver) -> VelocityFrame:
    """The frame of the velocities of ``solver`` (a simulation, a window or an SI view of
    either) as its snapshot holds them, in its native units (module docstring)."""
    chain = [solver]
    while getattr(chain[-1], "sim", None) is not None:
        chain.append(chain[-1].sim)
    windows = [o for o in chain if hasattr(o, "u_in") and hasattr(o, "geom")]
    if windows:
        w = windows[-1]  # the native window, inside any SI view of it
        return VelocityFrame("window", -float(w.u_in), float(w.geom.x_lo), float(w.geom.x_hi))
    sim = chain[-1]
    walls0 = getattr(sim, "walls0", None)
    if walls0 is None:
        walls0 = sim.state.walls0
    return VelocityFrame("piston", -float(walls0[3]))
