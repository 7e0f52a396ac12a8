"""A porous point beside the Hugoniot at its slab's own distention (``CSPHBackend.
point_references``): the reference is ``analysis.porous.partial_compaction_from_up`` at the
slab's u_p and α with half the deviator's range (0 to (2/3) Y/α), and its error combines
the α and u_p errors with that half-range. Checked against direct calls of the solver (the
same function, so the tolerance is rounding: 1e-12), and a solid scene is left unchanged."""

from __future__ import annotations

import numpy as np
import pytest
import xarray as xr

from hugomap.analysis.porous import MGSolid, partial_compaction_from_up
from hugomap.sph.backend import CSPHBackend

EOS = {"rho0": 8930.0, "c0": 3940.0, "s": 1.49, "gamma0": 2.0, "source": "test"}
Y = 1.2e8
SCENE = {
    "dim": 2,
    "material": {"eos": EOS, "strength": {"model": "von_mises", "yield_stress": Y}},
    "sample": {"porous": {"distention": 1.35}},
}


def _points(alpha, alpha_err, u, u_err):
    n = len(alpha)
    dims = ("scheme", "u_p")
    return xr.Dataset(
        {
            "alpha": (dims, [alpha]), "alpha_err": (dims, [alpha_err]),
            "u_p_jump": (dims, [u]), "u_p_jump_err": (dims, [u_err]),
            "u_p_measured": (dims, [[np.nan] * n]), "u_p_measured_err": (dims, [[np.nan] * n]),
            "rho0": ((), 8930.0 / 1.35),
        },
        coords={"scheme": ["amw"], "u_p": [100.0 * (i + 1) for i in range(n)]},
    )  # fmt: skip


def test_reference_at_the_slab_distention_and_its_error():
    ds = _points([1.02, 1.005], [0.003, 0.0], [95.0, 190.0], [0.5, 0.0])
    out = CSPHBackend().point_references(ds, SCENE)
    solid = MGSolid(EOS["rho0"], EOS["c0"], EOS["s"], EOS["gamma0"])
    for i, (a, ae, u, ue) in enumerate([(1.02, 0.003, 95.0, 0.5), (1.005, 0.0, 190.0, 0.0)]):
        half = Y / 3.0 / a
        mid = partial_compaction_from_up(u, 1.35, a, solid, deviator=half)
        got = out["D_compaction_ref"].values[0, i]
        assert got == pytest.approx(float(mid.D), rel=1e-12)
        assert out["P_compaction_ref"].values[0, i] == pytest.approx(float(mid.P), rel=1e-12)

        def d(uu, aa, t):
            return float(partial_compaction_from_up(uu, 1.35, aa, solid, deviator=t).D)

        parts = [0.5 * abs(d(u, a, 2 * half) - d(u, a, 0.0))]
        if ae:
            parts.append(0.5 * abs(d(u, a + ae, half) - d(u, a - ae, half)))
        if ue:
            parts.append(0.5 * abs(d(u + ue, a, half) - d(u - ue, a, half)))
        err = np.sqrt(np.sum(np.square(parts)))
        assert out["D_compaction_ref_err"].values[0, i] == pytest.approx(err, rel=1e-9)
        assert out["D_compaction_ref"].attrs["units"] == "m s-1"
    # α's error dominates: 0.003 of distention is ~1 % of D at 100 m/s
    rel = out["D_compaction_ref_err"].values[0, 0] / out["D_compaction_ref"].values[0, 0]
    assert 0.005 < rel < 0.02


def test_solid_scene_and_missing_values_are_left_alone():
    ds = _points([1.02], [0.003], [np.nan], [np.nan])
    solid_scene = {**SCENE, "dim": 1}
    assert "D_compaction_ref" not in CSPHBackend().point_references(ds, solid_scene)
    out = CSPHBackend().point_references(ds, SCENE)
    assert np.isnan(out["D_compaction_ref"].values).all()
