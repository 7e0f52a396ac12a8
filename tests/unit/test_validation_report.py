"""The validation report is written from the data in docs/figures, and its numbers are theirs.

``hugomap.validation_report`` turns the committed data files into ``docs/validation.md``.
Checked here: the committed report is what the generator writes from the committed data
(so nobody edited a number by hand, and nobody changed the data without regenerating it);
its tables hold the numbers computed straight from the CSV and JSON-lines files, by
separate code (a replica group's mean and sd, the pooled χ², a setting's mean CPU, a point
extended by the longer average, the cost exponent); ``--check`` tells a stale report.
"""

from __future__ import annotations

import json
import re
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from hugomap import validation_report as vr
from hugomap.analysis.replicas import replica_summary

ROOT = Path(__file__).resolve().parents[2]
FIGURES = ROOT / "docs" / "figures"
REPORT = ROOT / "docs" / "validation.md"


@pytest.fixture(scope="module")
def text() -> str:
    return vr.build_report(FIGURES, REPORT)


def _section(text: str, heading: str) -> str:
    """The report's section under ``## heading``, to the next one."""
    return text.split(f"\n## {heading}\n", 1)[1].split("\n## ", 1)[0]


def _row(text: str, *cells: str) -> list[str]:
    """The cells of the one table row of ``text`` that starts with ``cells``."""
    start = "| " + " | ".join(cells) + " |"
    rows = [ln for ln in text.splitlines() if ln.startswith(start)]
    assert len(rows) == 1, (start, rows)
    return [c.strip() for c in rows[0].strip("|").split("|")]


def _percent(x: float) -> str:
    return f"{100 * x:+.2f}".replace("-", "\u2212")


def test_the_committed_report_is_current(text: str) -> None:
    assert REPORT.read_text() == text, "run: python -m hugomap.validation_report"


def test_replica_rows_are_the_csv_s(text: str) -> None:
    df = pd.read_csv(FIGURES / "replicas_points.csv")
    sel = df[(df["scheme"] == "amw") & np.isclose(df["u_p_over_c0"], 0.140184, atol=1e-5)]
    usable = sel[sel["status"].isin(["ok", "not_converged"])]
    e = usable["err_D"].to_numpy(float)
    row = _row(_section(text, "The replica study").split("Window points against")[0], "AMW",
               "0.140")  # fmt: skip
    assert row[2] == f"{_percent(e.mean())} ± {100 * e.std(ddof=1):.2f} %"
    assert row[8] == f"{(sel['status'] == 'ok').sum()}/{len(sel)}"
    # the pooled reduced chi-square and RMS pull, from analysis.replicas on the raw columns
    use = df[df["status"].isin(["ok", "not_converged"])]
    groups = [(s, round(u, 6)) for s, u in zip(use["scheme"], use["u_p_over_c0"], strict=True)]
    summ = replica_summary(groups, {q: (use[f"err_{q}"], use[f"err_{q}_err"]) for q in "DP"})
    line = next(ln for ln in text.splitlines() if ln.startswith("- Pooled over the"))
    assert f"over the {summ['D_n']} points with values" in line
    assert f"D χ² {summ['D_chi2_red']:.2f}, RMS pull {summ['D_pull_rms']:.2f}" in line
    assert f"P χ² {summ['P_chi2_red']:.2f}, RMS pull {summ['P_pull_rms']:.2f}" in line


def test_settings_are_computed_from_the_points(text: str) -> None:
    pts = pd.read_csv(FIGURES / "campaign_points.csv")
    sel = pts[(pts["study"] == "resolution") & (pts["case"] == "lj_liquid")]
    sel = sel[(sel["scheme"] == "amw") & (sel["variant"] == "high")]
    row = _row(_section(text, "The validation campaign"), "LJ liquid", "AMW", "high")
    assert row[4] == f"{sel['cpu_s'].mean():.3g}"
    rms = np.sqrt(np.mean(sel["err_D"].to_numpy(float) ** 2))
    assert row[5].startswith(f"{100 * rms:.2f} ± ")
    # and the stored settings file says the same
    assert "agrees with the recomputation" in text


def test_the_longer_average_counts_the_points_it_extended(text: str) -> None:
    longer = pd.read_csv(FIGURES / "max_average_points.csv")
    base = pd.read_csv(FIGURES / "replicas_points.csv")
    base = base.assign(seed=base["variant"].str[1:].astype(int))
    m = longer.merge(base, on=["seed", "scheme"], suffixes=("", "_b"))
    m = m[np.isclose(m["u_p_over_c0"], m["u_p_over_c0_b"]) & (m["scheme"] == "amw")]
    m = m[np.isclose(m["u_p_over_c0"], 0.140184, atol=1e-5)]
    extended = int((~np.isclose(m["err_D"], m["err_D_b"], rtol=1e-9, atol=0)).sum())
    row = _row(_section(text, "A longer average while a point is unresolved"), "AMW", "0.140",
               f"{(m['status_b'] == 'ok').sum()} → "
               f"{(m['status'] == 'ok').sum()} of {len(m)}")  # fmt: skip
    assert row[3] == str(extended)
    assert 0 < extended < len(m)


def test_the_cost_exponent_is_the_rows_fit(text: str) -> None:
    rows = [json.loads(ln) for ln in (FIGURES / "window_cost.jsonl").read_text().splitlines()]
    piston = [r for r in rows if r.get("scheme") == "piston" and r["status"] != "too_noisy"]
    p = np.polyfit(np.log([r["sim_time"] for r in piston]),
                   np.log([r["cpu_s"] for r in piston]), 1)[0]  # fmt: skip
    assert _row(_section(text, "What a point costs"), "piston", f"{p:.2f}")
    assert f"machine `{rows[0]['machine']}`" in text  # the file's own header


def test_figures_linked_exist(text: str) -> None:
    links = re.findall(r"\]\((figures/[^)]+)\)", text)
    assert {Path(x).name for x in links} == set(vr.FIGURES)
    assert all((REPORT.parent / x).is_file() for x in links)


def test_check_tells_a_stale_report(tmp_path: Path) -> None:
    out = tmp_path / "validation.md"
    args = ["--figures", str(FIGURES), "--out", str(out)]
    assert vr.main([*args, "--check"]) == 1  # not there yet
    assert vr.main(args) == 0
    assert vr.main([*args, "--check"]) == 0
    out.write_text(out.read_text().replace("49 of 64", "50 of 64"))
    assert vr.main([*args, "--check"]) == 1
