"""notebooks/hugoniot_analysis.ipynb is the jupytext pair of its percent-format .py: the same
cells with the same sources (regenerate with `jupytext --sync notebooks/hugoniot_analysis.py`)."""

from __future__ import annotations

from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]


def test_notebook_pair_in_sync():
    import jupytext

    py = jupytext.read(ROOT / "notebooks" / "hugoniot_analysis.py")
    nb = jupytext.read(ROOT / "notebooks" / "hugoniot_analysis.ipynb")
    assert [(c.cell_type, c.source) for c in py.cells] == [
        (c.cell_type, c.source) for c in nb.cells
    ]
