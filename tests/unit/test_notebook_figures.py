"""The analysis notebook's figures (notebooks/hugoniot_analysis.py, run as a script on a
synthetic aggregate): each scheme in the colour of the package's figures
(``figures.SCHEME_COLORS``), not-converged points hollow, units written as the package's
figures write them (σ/τ, ε σ⁻³).
"""

from __future__ import annotations

import runpy
from pathlib import Path

import matplotlib.pyplot as plt
import pytest
from matplotlib.colors import to_rgba

from hugomap.figures import SCHEME_COLORS

from .test_cf_outputs import _md_aggregate, _md_config

ROOT = Path(__file__).resolve().parents[2]


@pytest.fixture
def notebook_figures(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> dict[str, plt.Figure]:
    """The notebook's Hugoniot and cost figures, drawn on scene ``tiny`` (schemes piston
    and amw; at each, the first u_p ok and the others not converged)."""
    agg = _md_aggregate(tmp_path / "work", _md_config(u_p=(1.0, 2.0, 3.0)), n_ref=5)
    (tmp_path / "hugoniot").mkdir()
    agg.rename(tmp_path / "hugoniot" / "tiny.nc")
    monkeypatch.setenv("HUGOMAP_RESULTS", str(tmp_path))
    monkeypatch.setenv("MPLBACKEND", "Agg")
    before = set(plt.get_fignums())
    runpy.run_path(str(ROOT / "notebooks" / "hugoniot_analysis.py"))
    figs = [plt.figure(n) for n in plt.get_fignums() if n not in before]
    try:
        yield {
            "hugoniot": next(f for f in figs if f.axes[0].get_title() == "tiny"),
            "cost": next(f for f in figs if f.axes[0].get_xlabel() == "CPU per point [s]"),
        }
    finally:
        for f in figs:
            plt.close(f)


def test_hugoniot_colours_hollow_markers_and_units(notebook_figures: dict) -> None:
    fig = notebook_figures["hugoniot"]
    ax1, ax2 = fig.axes
    assert (ax1.get_xlabel(), ax1.get_ylabel()) == ("u_p [σ/τ]", "D [σ/τ]")
    assert (ax2.get_xlabel(), ax2.get_ylabel()) == ("V [σ³]", "P [ε σ⁻³]")
    for ax in (ax1, ax2):
        seen = set()
        for c in ax.containers:
            scheme, _, rest = c.get_label().partition(", ")
            line = c.lines[0]
            assert to_rgba(line.get_color()) == to_rgba(SCHEME_COLORS[scheme]), c.get_label()
            hollow = line.get_markerfacecolor() == "none"
            assert hollow == (rest == "not converged"), c.get_label()
            seen.add(c.get_label())
        assert seen == {"piston", "piston, not converged", "amw", "amw, not converged"}


def test_cost_figure_uses_the_scheme_colours(notebook_figures: dict) -> None:
    for ax in notebook_figures["cost"].axes:
        lines = {ln.get_label(): ln for ln in ax.get_lines()}
        assert set(lines) == {"piston", "amw"}
        for scheme, ln in lines.items():
            assert to_rgba(ln.get_color()) == to_rgba(SCHEME_COLORS[scheme]), scheme
