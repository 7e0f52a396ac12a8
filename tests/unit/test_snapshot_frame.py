"""The frame of a snapshot's velocities in its comment line (``io.extxyz.VelocityFrame``:
``velocity_frame``, ``frame_velocity``, a window's ``x_lo``, ``x_hi``), read back raw and by
ASE; the CSPH backend's piston and window snapshots; the MD and LAMMPS rule
(``particles.snapshot.velocity_frame``).

References: the extended-XYZ comment line as the spec defines it (key=value pairs; here
split on spaces outside quotes), ASE's reader (``atoms.info``); and the frames' physics:
material the shock has not reached is at rest in the lab frame of a CSPH piston run, and
the inflow beyond a window's x_hi moves at exactly u_in (frozen), so v_x + frame_velocity
is 0 there; an MD piston run gives every atom −u_p (``MDBackend.start_piston``), so its
mean velocity plus frame_velocity is 0. Tolerances: CSPH velocities are written in Å/fs
(one multiplication by 1e-5 each way, a few ulp); the frozen inflow's 0 to 1e-9 m/s; the
material ahead of a CSPH piston's front to 1e-6 u_p (25 dx ahead the smeared front's tail
is far below that).
"""

from __future__ import annotations

import re
import shlex
from types import SimpleNamespace

import numpy as np
import pytest

from hugomap.io.extxyz import SnapshotError, VelocityFrame, format_frame, write_extxyz

ase_io = pytest.importorskip("ase.io")


def _comment(path) -> dict[str, str]:
    """The comment line's pairs (the frame's second line), values unquoted."""
    line = path.read_text().splitlines()[1]
    return dict(tok.split("=", 1) for tok in shlex.split(line))


def _frame(frame: VelocityFrame | None) -> str:
    x = np.array([[1.0, 0.5, 0.5], [40.0, 1.0, 1.0], [90.0, 1.5, 1.5]])
    v = np.array([[-2.5, 0.1, 0.0], [0.3, 0.0, 0.2], [1.0, 0.0, 0.0]])
    return format_frame(x, (123.0, 4.0, 4.0), velocities=v, masses=1.0, species="Ar",
                        pbc=(False, True, True), time=7.0, length_unit="sigma",
                        time_unit="tau", info={"run": "amw", "u_p": 2.0},
                        frame=frame)  # fmt: skip


def test_window_frame_keys_are_written_and_ase_reads_them(tmp_path):
    path = write_extxyz(tmp_path / "w.extxyz", _frame(VelocityFrame("window", 2.5, 3.0, 78.0)))
    pairs = _comment(path)
    assert pairs["velocity_frame"] == "window" and float(pairs["frame_velocity"]) == 2.5
    assert (float(pairs["x_lo"]), float(pairs["x_hi"])) == (3.0, 78.0)
    assert pairs["units"] == (
        "pos:sigma velo:sigma/tau frame_velocity:sigma/tau x_lo:sigma x_hi:sigma"
    )
    (atoms,) = ase_io.read(path, index=":", format="extxyz")
    info = atoms.info
    assert info["velocity_frame"] == "window" and info["frame_velocity"] == 2.5
    assert (info["x_lo"], info["x_hi"]) == (3.0, 78.0) and info["run"] == "amw"
    v = atoms.get_velocities()
    assert v[0, 0] + info["frame_velocity"] == 0.0  # -2.5 in the window: at rest ahead
    assert atoms.cell.array[0, 0] == 123.0 and len(atoms) == 3


def test_piston_frame_has_no_edges_and_no_frame_writes_no_keys(tmp_path):
    path = write_extxyz(tmp_path / "p.extxyz", _frame(VelocityFrame("piston", 2.0)))
    pairs = _comment(path)
    assert pairs["velocity_frame"] == "piston" and float(pairs["frame_velocity"]) == 2.0
    assert "x_lo" not in pairs and "x_hi" not in pairs
    (atoms,) = ase_io.read(path, index=":", format="extxyz")
    assert atoms.info["velocity_frame"] == "piston" and atoms.info["frame_velocity"] == 2.0
    bare = _comment(write_extxyz(tmp_path / "n.extxyz", _frame(None)))
    assert not {"velocity_frame", "frame_velocity", "x_lo", "x_hi"} & set(bare)


@pytest.mark.parametrize(
    ("frame", "words"),
    [
        (VelocityFrame("moving", 1.0), "one of"),
        (VelocityFrame("lab", float("nan")), "finite"),
        (VelocityFrame("window", 1.0, 3.0), "window edges"),
        (VelocityFrame("window", 1.0), "a window has both"),
        (VelocityFrame("piston", 1.0, 0.0, 5.0), "no other frame"),
        (VelocityFrame("window", 1.0, 5.0, 5.0), "lo < hi"),
        (VelocityFrame("window", 1.0, 0.0, float("inf")), "finite"),
    ],
)
def test_bad_frames_are_refused(frame, words):
    with pytest.raises(SnapshotError, match=re.escape(words)):
        _frame(frame)


def test_frame_keys_cannot_be_forged_through_info():
    with pytest.raises(SnapshotError, match="info key 'frame_velocity'"):
        format_frame(np.zeros((1, 3)), (1.0, 1.0, 1.0), info={"frame_velocity": 0.0})


DX, UP = 1e-5, 500.0  # [m], [m/s]


def test_csph_piston_and_window_snapshots_say_their_frame(tmp_path):
    from hugomap.eos import copper
    from hugomap.sph.backend import BACKEND
    from hugomap.sph.simulation import CSPHSimulation
    from hugomap.sph.state import SPHState
    from hugomap.sph.window import SPHWindow

    rho0, n = 8930.0, 90
    st = SPHState(x=(np.arange(n) + 0.5) * DX, v=np.zeros(n), m=rho0 * DX, rho=rho0, e=0.0)
    sim = CSPHSimulation(st, copper(), walls=(0.0, UP, None, 0.0))
    us = 3940.0 + 1.49 * UP
    sim.run_until(35 * DX / us)
    scene = {"name": "cu", "shock": {"snapshots": True}}
    BACKEND.extras(sim, tmp_path / "piston.nc", scene, UP, {})
    path = tmp_path / "piston_snapshot.extxyz"
    assert _comment(path)["velocity_frame"] == "lab"
    (atoms,) = ase_io.read(path, index=":", format="extxyz")
    assert atoms.info["frame_velocity"] == 0.0 and "x_lo" not in atoms.info
    vx = (atoms.get_velocities()[:, 0] + atoms.info["frame_velocity"]) * 1e5  # Å/fs → m/s
    ahead = atoms.positions[:, 0] * 1e-10 > 60 * DX  # the front is near 35 dx
    assert ahead.sum() > 20 and np.all(np.abs(vx[ahead]) < 1e-6 * UP)  # at rest
    assert vx.max() == pytest.approx(UP, rel=0.05)  # the shocked material at ~u_p

    xf = st.x[int(np.nonzero(st.v[:, 0] > 0.5 * UP)[0].max()), 0]
    win = SPHWindow.from_piston(sim, xf, UP, us, 30 * DX, cut_every=3 * DX, sync_steps=5)
    win.advance(20)
    BACKEND.window_extras(win, tmp_path / "amw.nc", scene, UP, "amw", {})
    path = tmp_path / "amw_snapshot.extxyz"
    pairs = _comment(path)
    assert pairs["velocity_frame"] == "window"
    assert pairs["units"].endswith("frame_velocity:Angstrom/fs x_lo:Angstrom x_hi:Angstrom")
    (atoms,) = ase_io.read(path, index=":", format="extxyz")
    info = atoms.info
    assert info["frame_velocity"] * 1e5 == pytest.approx(-win.u_in, rel=1e-14)
    assert info["x_lo"] * 1e-10 == pytest.approx(win.geom.x_lo, rel=1e-14)
    assert info["x_hi"] * 1e-10 == pytest.approx(win.geom.x_hi, rel=1e-14)
    x = atoms.positions[:, 0]
    assert x.min() < info["x_lo"] and x.max() > info["x_hi"]  # the cell holds more
    inflow = atoms.arrays["frozen"] & (x > info["x_hi"])
    assert inflow.any()
    vx = (atoms.get_velocities()[:, 0] + info["frame_velocity"]) * 1e5
    assert np.all(np.abs(vx[inflow]) < 1e-9)  # the inflow is the material at rest ahead


def test_md_rule_piston_run_window_and_si_view():
    from hugomap.md.backend import BACKEND as MD
    from hugomap.md.potential import LJParams
    from hugomap.md.sample import fcc_state
    from hugomap.md.simulation import MDSimulation
    from hugomap.particles.snapshot import velocity_frame

    sim = MDSimulation(fcc_state((4, 4, 4), 0.8, 1.0, 3, periodic_x=False), LJParams(), 0.004)
    MD.start_piston(sim, {"shock": {"dt": 0.004}}, 2.0)
    frame = velocity_frame(sim)
    assert frame == VelocityFrame("piston", 2.0)
    assert np.mean(sim.state.v[:, 0]) + frame.velocity == pytest.approx(0.0, abs=1e-12)
    # a window (``ParticleWindow``'s u_in, geom, sim) and an SI view of it: the native window's
    geom = SimpleNamespace(x_lo=3.0, x_hi=78.0)
    window = SimpleNamespace(u_in=-7.5, u_out=-5.5, geom=geom, sim=sim)
    view = SimpleNamespace(u_in=-7.5e2, geom=SimpleNamespace(x_lo=3e-10, x_hi=7.8e-9), sim=window)
    for solver in (window, view):
        assert velocity_frame(solver) == VelocityFrame("window", 7.5, 3.0, 78.0)
