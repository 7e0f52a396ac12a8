"""The Hugoniot figures (``figures.hugoniot_figures``) on a synthetic aggregate: what each
kind of point looks like and what the legend says.

Reference: the aggregate layout (dims scheme × u_p, ``ref_point``; ``status`` per point,
``config_json`` naming an MD scene for the labels). A converged point is filled, a
not-converged one hollow, a failed one (no value) named with its status; a scheme with
nothing drawn has no legend entry; the reference carries a ±1 s.e. band where it has
``ref_*_err``; D–u_p marks the measured u_p with its error.
"""

from __future__ import annotations

import json
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np
import pytest
import xarray as xr
import yaml

from hugomap import figures
from hugomap.config import validate_config

ROOT = Path(__file__).resolve().parents[2]


def _aggregate(path: Path) -> Path:
    cfg = validate_config(yaml.safe_load((ROOT / "tests/workflow/tiny/config.yaml").read_text()))
    u = [1.0, 2.0, 3.0]
    status = [["ok", "not_converged", "ok"],  # piston
              ["ok", "oscillating", "too_noisy"],  # amw: two failed, no value
              ["bracket_not_found"] * 3]  # dichotomy: nothing to draw  # fmt: skip
    nan = np.nan
    D = [[8.6, 10.2, 12.0], [8.7, nan, nan], [nan, nan, nan]]
    V = [[1.14, 1.04, 0.96], [1.13, nan, nan], [nan, nan, nan]]
    P = [[11.0, 20.0, 34.0], [11.2, nan, nan], [nan, nan, nan]]
    um = [[0.97, 1.95, 2.9], [0.98, nan, nan], [nan, nan, nan]]
    dims = ("scheme", "u_p")
    data = {k: (dims, np.asarray(v, float)) for k, v in
            {"D": D, "V": V, "P": P, "u_p_measured": um}.items()}  # fmt: skip
    data |= {k + "_err": (dims, np.full((3, 3), 0.05)) for k in ("D", "V", "P", "u_p_measured")}
    data["u_p_set"] = (dims, np.asarray([[nan] * 3, [1.0, nan, nan], [nan] * 3]))
    # the jump's u_p: the piston's speed, the window's slab (its u_p_measured)
    data["u_p_jump"] = (dims, np.asarray([u, [0.98, nan, nan], [nan] * 3]))
    data["u_p_jump_err"] = (dims, np.asarray([[0.0] * 3, [0.05, nan, nan], [nan] * 3]))
    data["status"] = (dims, np.asarray(status))
    data["converged"] = (dims, np.asarray(status) == "ok")
    ref = {"ref_V": [1.25, 1.14, 1.04, 0.96], "ref_P": [6.0, 11.4, 19.9, 34.2],
           "ref_u_p": [0.0, 0.78, 1.70, 2.85], "ref_D": [nan, 8.6, 10.2, 12.4],
           "ref_P_err": [0.04, 0.13, 0.16, 0.32], "ref_D_err": [nan, 0.1, 0.1, 0.1],
           "ref_V_err": [0.0] * 4, "ref_u_p_err": [0.0, 0.01, 0.01, 0.02]}  # fmt: skip
    data |= {k: ("ref_point", np.asarray(v)) for k, v in ref.items()}
    ds = xr.Dataset(data, coords={"scheme": ["piston", "amw", "dichotomy"], "u_p": u})
    ds["rho0"], ds["P0"] = 0.8, 6.0
    ds.attrs.update(scene="tiny", config_json=json.dumps(cfg))
    ds.to_netcdf(path)
    return path


@pytest.fixture
def drawn(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> dict[str, plt.Figure]:
    figs: list = []
    close = plt.close
    monkeypatch.setattr(figures.plt, "close", figs.append)  # keep the figures open
    agg = _aggregate(tmp_path / "tiny.nc")
    figures.hugoniot_figures(agg, tmp_path / "pv.png", tmp_path / "dup.png")
    assert (tmp_path / "pv.png").stat().st_size and (tmp_path / "dup.png").stat().st_size
    yield dict(zip(("PV", "D_up"), figs, strict=True))
    for f in list(figs):
        close(f)


def _legend(fig: plt.Figure) -> list[str]:
    return [t.get_text() for t in fig.axes[0].get_legend().get_texts()]


def test_failed_and_not_converged_are_told_apart(drawn: dict) -> None:
    for name, fig in drawn.items():
        labels = _legend(fig)
        assert "piston (MD)" in labels and "piston, not converged" in labels
        assert "amw (MD)" in labels and "amw, not converged" not in labels
        failed = [s for s in labels if s.startswith("amw failed")]
        assert failed == ["amw failed (no value): u_p 2 (oscillating), 3 (too_noisy)"], name
        assert not any(s.startswith("piston failed") for s in labels)


def test_no_entry_for_a_scheme_with_nothing_drawn(drawn: dict) -> None:
    """The dichotomy has no value anywhere: it is named only as failed, never as points."""
    for fig in drawn.values():
        labels = _legend(fig)
        assert not any(s.startswith("dichotomy (") or s == "dichotomy" for s in labels)
        assert any(s.startswith("dichotomy failed (no value): u_p 1 (bracket_not_found)")
                   for s in labels)  # fmt: skip


def test_reference_band_and_measured_u_p(drawn: dict) -> None:
    for fig in drawn.values():
        ax = fig.axes[0]
        assert "reference (equilibrium MD) ± 1 s.e." in _legend(fig)
        assert any(type(c).__name__ in ("PolyCollection", "FillBetweenPolyCollection")
                   for c in ax.collections)  # fmt: skip
    assert "u_p measured behind the front ± 1 s.e." in _legend(drawn["D_up"])
    assert "u_p measured behind the front ± 1 s.e." not in _legend(drawn["PV"])


def test_d_up_draws_each_point_at_its_jump_u_p(drawn: dict) -> None:
    """D–u_p: the piston at its speed (1, 2, 3) with its measured slab as a check bar, the
    window point at its slab's u_p (0.98 ± 0.05), with no second bar for the same slab."""
    ax = drawn["D_up"].axes[0]
    at: dict[str, list] = {}
    for c in ax.containers:
        if c.lines[0] is not None and len(c.lines[0].get_xdata()):
            x = tuple(np.round(np.asarray(c.lines[0].get_xdata(), float), 6))
            at.setdefault(c.get_label(), []).append(x)
    assert at["piston (MD)"] == [(1.0, 3.0)] and at["piston, not converged"] == [(2.0,)]
    assert at["amw (MD)"] == [(0.98,)]
    bars = sorted(x for k, v in at.items() if k.startswith("_") for x in v)
    assert bars == [(0.97, 1.95, 2.9)]


@pytest.mark.parametrize(
    ("units", "text"),
    [("sigma tau^-1", "σ/τ"), ("epsilon sigma^-3", "ε σ⁻³"), ("sigma^-3", "σ⁻³"),
     ("sigma^3", "σ³"), ("epsilon k_B^-1", "ε/k_B"), ("tau", "τ"), ("tau^-1", "τ⁻¹"),
     ("m s-1", "m/s"), ("kg m-3", "kg m⁻³"), ("1", "1"), ("g/mol", "g/mol")],
)  # fmt: skip
def test_unit_text(units: str, text: str) -> None:
    assert figures.unit_text(units) == text


def _profile() -> dict:
    """A front-frame profile as ``stages.profile.front_profile`` gives it (MD units)."""
    from hugomap.io.dataset import lj_units

    t = lj_units()
    x = np.linspace(-40.0, 20.0, 60)
    s = 0.5 * (1.0 - np.tanh(x / 2.0))
    fields = {"rho": 0.8 + 0.45 * s, "u": 2.0 * s, "P": 0.05 + 19.5 * s, "Pyy": 0.05 + 15 * s,
              "Pzz": 0.05 + 15.2 * s, "E": -5.0 + 3.0 * s, "T": 1.0 + 4.1 * s}  # fmt: skip
    units = {"x": t.axes["length"], "u": t.axes["velocity"]}
    units |= {k: t.point[k][0] for k in fields if k not in units}
    return {"x": x, **fields, "units": units, "scene": "lj", "t": 100.0, "samples": 10,
            "merge": 2}  # fmt: skip


def test_profile_labels_are_unicode_aligned_and_apart(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """The profile's four y labels: units written as the other figures write them, at one
    x, and no two of them overlapping once drawn."""
    figs: list = []
    close = plt.close
    monkeypatch.setattr(figures.plt, "close", figs.append)
    figures.profile_figure(_profile(), tmp_path / "profile.png")
    assert (tmp_path / "profile.png").stat().st_size
    (fig,) = figs
    try:
        labels = [ax.yaxis.label for ax in fig.axes]
        texts = [lb.get_text() for lb in labels] + [fig.axes[-1].get_xlabel()]
        for unit in ("[σ⁻³]", "[σ/τ]", "[ε σ⁻³]", "[ε/k_B]", "[σ]"):
            assert any(unit in t for t in texts), (unit, texts)
        assert not any(w in t for t in texts for w in ("sigma", "tau", "epsilon", "^")), texts
        fig.canvas.draw()
        boxes = [lb.get_window_extent() for lb in labels]
        assert max(b.x0 for b in boxes) - min(b.x0 for b in boxes) < 1.0  # aligned
        for i, a in enumerate(boxes):
            assert not any(a.overlaps(b) for b in boxes[i + 1 :]), texts
    finally:
        close(fig)
