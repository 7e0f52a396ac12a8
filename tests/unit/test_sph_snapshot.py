"""Snapshots: extended XYZ read back by a parser written to the extxyz spec (and by ASE when it
is installed), and PNG pictures with plastic particles in green (hugomap.sph.snapshot, the
CSPH backend's extras).

Reference for the format: the extxyz specification (github.com/libAtoms/extxyz; ASE's
``ase.io.extxyz``): a count line, a comment line of key=value pairs (values with spaces in double
quotes) whose ``Properties`` key lists name:type:columns triplets, then one row per particle.
Values are written with 17 significant digits, so float64 round-trips exactly; positions written
in Å come back within a few ulp (one multiplication by 1e10 and one by 1e-10), velocities in
Å/fs likewise (1e-5).
"""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest

from hugomap.io.extxyz import SnapshotError, write_extxyz
from hugomap.sph.sample import porous_2d
from hugomap.sph.snapshot import PLASTIC_GREEN, sph_frame, write_png

_KV = re.compile(r'([A-Za-z_][A-Za-z0-9_]*)=("[^"]*"|\S+)')
_TYPES = {"S": str, "R": float, "I": int, "L": lambda v: v == "T"}


def read_extxyz(path: Path) -> list[tuple[dict, dict]]:
    """Frames as (info, arrays) parsed per the extxyz spec: info holds the comment-line pairs
    (quotes removed), arrays holds one array per ``Properties`` entry, shape (n,) or (n, k)."""
    lines = path.read_text().splitlines()
    frames, i = [], 0
    while i < len(lines):
        n = int(lines[i])
        info = {k: v.strip('"') for k, v in _KV.findall(lines[i + 1])}
        assert (
            "".join(f"{k}={v} " for k, v in _KV.findall(lines[i + 1])).strip()
            == lines[i + 1].strip()
        ), "the comment line must consist of key=value pairs only"
        rows = [ln.split() for ln in lines[i + 2 : i + 2 + n]]
        spec = info["Properties"].split(":")
        arrays, c = {}, 0
        for name, typ, ncol in zip(spec[0::3], spec[1::3], spec[2::3], strict=True):
            k = int(ncol)
            conv = _TYPES[typ]
            col = np.array([[conv(r[c + j]) for j in range(k)] for r in rows])
            arrays[name] = col[:, 0] if k == 1 else col
            c += k
        assert all(len(r) == c for r in rows), "every row has one value per Properties column"
        frames.append((info, arrays))
        i += 2 + n
    return frames


@pytest.fixture(scope="module")
def sample():
    return porous_2d(0.2e-3, 0.1e-3, 2e-6, 8930.0, pore_radius=(6e-6, 10e-6), seed=5)


def _fields(n: int):
    rng = np.random.default_rng(1)
    return {
        "pressure": rng.normal(1e9, 3e8, n),
        "plastic_strain": rng.uniform(0, 0.1, n),
        "id": np.arange(n, dtype=np.int64),
        "v": rng.normal(0, 50, (n, 2)),
        "boundary": np.arange(n) % 7 == 0,
    }


def test_extxyz_round_trip_per_spec(tmp_path, sample):
    f = _fields(sample.n)
    v = f.pop("v")
    text = sph_frame(
        sample.x, v, f, sample.box, masses=sample.m, mass_unit="kg/m", time=2.5e-9,
        units={"pressure": "Pa"}, periodic=(False, True, False),
        info={"scene": "cu-porous", "u_p": 100.0, "note": "two words", "step": 12,
              "window": True},
    )  # fmt: skip
    path = write_extxyz(tmp_path / "snap.extxyz", text)
    ((info, arr),) = read_extxyz(path)
    assert len(arr["species"]) == sample.n and set(arr["species"]) == {"Cu"}
    # Å and Å/fs; z padded with 0 for 2D; momenta = masses × velo
    np.testing.assert_allclose(arr["pos"][:, :2] * 1e-10, sample.x, rtol=4e-16, atol=0)
    assert np.all(arr["pos"][:, 2] == 0.0) and np.all(arr["velo"][:, 2] == 0.0)
    np.testing.assert_allclose(arr["velo"][:, :2] * 1e5, v, rtol=4e-16, atol=0)
    np.testing.assert_allclose(arr["momenta"], arr["masses"][:, None] * arr["velo"], rtol=1e-15)
    for name in ("pressure", "plastic_strain", "id", "boundary"):
        assert np.array_equal(arr[name], f[name]), name
    assert arr["id"].dtype.kind == "i" and arr["boundary"].dtype == bool
    lx, ly = sample.x_hi - sample.x_lo, sample.y_hi - sample.y_lo
    cell = np.array(info["Lattice"].split(), dtype=float).reshape(3, 3)
    np.testing.assert_allclose(np.diag(cell) * 1e-10, [lx, ly, max(lx, ly)], rtol=4e-16)
    assert np.count_nonzero(cell - np.diag(np.diag(cell))) == 0
    assert info["pbc"] == "F T F" and float(info["Time"]) == pytest.approx(2.5e6, rel=1e-15)
    assert info["units"] == (
        "pos:Angstrom velo:Angstrom/fs masses:kg/m momenta:kg/m*Angstrom/fs pressure:Pa"
    )
    assert info["length_unit"] == "Angstrom" and info["time_unit"] == "fs"
    assert info["note"] == "two words" and info["step"] == "12" and info["window"] == "T"
    assert list(tmp_path.iterdir()) == [path]  # no temporary file left behind


def test_extxyz_1d_radius_and_trajectory(tmp_path):
    x = np.array([[1e-6], [3e-6], [5.5e-6]])
    p = tmp_path / "line.xyz"
    write_extxyz(p, sph_frame(x, np.zeros(3), {"rho": np.array([8930.0, 8931.0, 8932.5])},
                              (0.0, 6e-6)))  # fmt: skip
    r = tmp_path / "r.xyz"
    write_extxyz(r, sph_frame(x, np.zeros(3), {}, (0.0, 6e-6), radius=np.full(3, 1e-6)))
    ((ir, ar),) = read_extxyz(r)
    np.testing.assert_allclose(ar["radius"], 1e4, rtol=1e-15)  # 1 μm written in Å
    assert ir["units"].endswith("radius:Angstrom")
    frame = sph_frame(x * 2, np.ones(3), {"rho": np.zeros(3)}, (0.0, 12e-6), time=1e-9,
                      species=["Cu", "Al", "Cu"])  # fmt: skip
    write_extxyz(p, frame, append=True)
    (i0, a0), (i1, a1) = read_extxyz(p)
    assert i0["Properties"] == "species:S:1:pos:R:3:velo:R:3:masses:R:1:momenta:R:3:rho:R:1"
    np.testing.assert_allclose(a0["pos"][:, 0] * 1e-10, x[:, 0], rtol=4e-16)
    assert np.all(a0["pos"][:, 1:] == 0.0)  # 1D: y and z padded with zeros
    np.testing.assert_allclose(np.diag(np.array(i0["Lattice"].split(), float).reshape(3, 3)), 6e4)
    np.testing.assert_allclose(a1["pos"][:, 0] * 1e-10, 2 * x[:, 0], rtol=4e-16)
    assert float(i1["Time"]) == pytest.approx(1e6) and a1["velo"][0, 0] == pytest.approx(1e-5)
    assert list(a1["species"]) == ["Cu", "Al", "Cu"] and np.all(a1["rho"] == 0.0)


def test_extxyz_read_by_ase(tmp_path, sample):
    ase_io = pytest.importorskip("ase.io")
    f = _fields(sample.n)
    v = f.pop("v")
    text = sph_frame(sample.x, v, f, sample.box, masses=sample.m, time=1e-9,
                     radius=sample.l / 2, periodic=(False, True, False))  # fmt: skip
    path = write_extxyz(tmp_path / "a.extxyz", [text, text])
    frames = ase_io.read(path, index=":", format="extxyz")
    assert len(frames) == 2
    atoms = frames[0]
    np.testing.assert_allclose(atoms.arrays["radius"] * 1e-10, sample.l / 2, rtol=4e-16)
    np.testing.assert_allclose(atoms.positions[:, :2] * 1e-10, sample.x, rtol=4e-16, atol=0)
    # velocities: ASE's get_velocities (momenta / masses) is the velo column, Å/fs
    np.testing.assert_allclose(atoms.get_velocities()[:, :2] * 1e5, v, rtol=1e-15, atol=1e-20)
    assert np.array_equal(atoms.get_masses(), sample.m)
    assert np.array_equal(atoms.arrays["pressure"], f["pressure"])
    assert atoms.arrays["boundary"].dtype == bool and list(atoms.pbc) == [False, True, False]
    assert atoms.get_chemical_symbols()[0] == "Cu" and atoms.info["Time"] == pytest.approx(1e6)


def test_csph_backend_snapshot_and_trajectory(tmp_path):
    ase_io = pytest.importorskip("ase.io")
    from hugomap.config import validate_config
    from hugomap.sph.backend import BACKEND

    sc = {"solver": "csph", "dim": 1, "schemes": ["piston"],
          "sample": {"length": 6e-4, "dx": 1e-5},
          "shock": {"u_p": [500.0], "snapshot_every": 2, "gap": 2e-5, "avg_length": 8e-5}}  # fmt: skip
    scene = validate_config({"scenes": {"cu": sc}})["scenes"]["cu"]
    scene["name"] = "cu"
    sim, _, info = BACKEND.prepare(scene)
    prof = BACKEND.profile(sim, scene, info)
    BACKEND.start_piston(sim, scene, 500.0)  # (marks a loading run: no trajectory after)
    assert not hasattr(BACKEND.profile(sim, scene, info), "_trajectory")
    for _ in range(4):
        sim.advance(3)
        prof.sums(sim)
    BACKEND.extras(sim, tmp_path / "piston.nc", scene, 500.0, info)
    assert (tmp_path / "piston_snapshot.extxyz").exists()
    frames = ase_io.read(tmp_path / "piston_trajectory.extxyz", index=":")
    (last,) = ase_io.read(tmp_path / "piston_snapshot.extxyz", index=":")
    assert len(frames) == 2 and last.info["run"] == "piston"
    st = sim.state
    np.testing.assert_allclose(last.positions[:, 0] * 1e-10, st.x[:, 0], rtol=4e-16)
    np.testing.assert_allclose(last.get_velocities()[:, 0] * 1e5, st.v[:, 0], rtol=1e-14)
    assert np.array_equal(last.arrays["plastic"], st.eps_p > 1e-4)
    assert np.array_equal(last.arrays["P_xx"], -sim.stress_xx())
    assert last.info["units"].startswith("pos:Angstrom velo:Angstrom/fs masses:kg/m^2")


@pytest.mark.parametrize(
    ("fields", "words"),
    [
        ({"bad name": np.zeros(3)}, "field name"),
        ({"velo": np.zeros(3)}, "field name"),
        ({"p": np.zeros(4)}, "shape"),
        ({"p": np.array(["a", "b", "c"])}, "dtype"),
    ],
)
def test_extxyz_bad_fields_are_refused(fields, words):
    with pytest.raises(SnapshotError, match=words):
        sph_frame(np.zeros((3, 2)), np.zeros((3, 2)), fields, (0, 1, 0, 1))


def _rgb_fraction(png: Path, colour: str, tol: float = 0.02) -> float:
    import matplotlib.colors as mcolors
    import matplotlib.image as mimage

    img = mimage.imread(png)[..., :3]
    target = np.array(mcolors.to_rgb(colour))
    return float(np.mean(np.all(np.abs(img - target) < tol, axis=-1)))


def test_png_plastic_particles_are_green(tmp_path, sample):
    n = sample.n
    eps = np.where(sample.x[:, 0] < 0.08e-3, 0.05, 0.0)  # a plastic band near the piston
    p = np.linspace(0.0, 2e9, n)
    out = write_png(tmp_path / "a.png", sample.x, eps, 0.01, p, box=sample.box, title="t")
    assert out.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    green = _rgb_fraction(out, PLASTIC_GREEN)
    # The band covers 40 % of the box (less the pores); the axes take about half of the image.
    assert 0.05 < green < 0.4
    none = write_png(tmp_path / "b.png", sample.x, np.zeros(n), 0.01, None, box=sample.box)
    # No plastic particle: only the legend's marker is green.
    assert _rgb_fraction(none, PLASTIC_GREEN) < 1e-3
    assert _rgb_fraction(none, "0.6") > 0.05  # the others are grey without a field
    with pytest.raises(SnapshotError, match="plastic_strain"):
        write_png(tmp_path / "c.png", sample.x, np.zeros(n - 1), 0.01)
