"""``bilevel-kit repro robust`` (docs/robust.md): a one-cell run, the committed CSV's
honesty (independent evaluation sample, paired VSS, intervals) and the page's drift test."""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest

from bilevel_kit.repro.report import read_rows
from bilevel_kit.repro.robust import (
    EVALUATION,
    ROBUST_TABLES,
    plot_robust_panel,
    run_robust,
    vss_markdown,
)
from bilevel_kit.repro.template import ROOT, TARGETS, check

CSV = ROOT / "paper_repro" / "results" / "robust.csv"

pytest.importorskip("ortools")


def test_committed_rows_are_honest() -> None:
    rows = read_rows(CSV)
    assert rows and EVALUATION >= 1000
    for r in rows:
        v = {k: float(r[k]) for k in ("vss", "vss_low", "vss_high", "mean_plan", "saa_plan")}
        assert v["vss_low"] <= v["vss"] <= v["vss_high"]
        # VSS is the difference of the two plans' means on the same evaluation scenarios
        assert v["vss"] == pytest.approx(v["mean_plan"] - v["saa_plan"], abs=0.02)
        assert float(r["mean_plan_low"]) <= v["mean_plan"] <= float(r["mean_plan_high"])
        # Jensen: the mean-time optimum bounds every plan's expectation from below
        assert float(r["mean_plan_deterministic"]) <= v["saa_plan"] + float(r["saa_plan"]) * 0.01
        # the SAA plan is never worse in-sample (it is hinted with the mean-value plan)
        assert float(r["saa_in_sample"]) <= float(r["mean_plan_in_sample"]) + 1e-6


def test_plot_panel_returns_its_axes_and_the_table_renders() -> None:
    import matplotlib

    matplotlib.use("Agg")
    rows = read_rows(CSV)
    name = rows[0]["instance"]
    ax = plot_robust_panel(rows, name)
    assert ax.get_title() == name and ax.get_ylabel() == "VSS (s)"
    assert name in vss_markdown(rows)
    assert set(ROBUST_TABLES) == {"robust_vss", "robust_detail", "robust_advice"}


def test_the_page_is_rendered_from_the_csv(tmp_path: Path) -> None:
    """docs/robust.md's results section matches the CSV, and an edited CSV number is caught."""
    (target,) = [t for t in TARGETS if t.output == "docs/robust.md"]
    assert not [d for d in check(ROOT) if "robust.md" in d]
    shutil.copytree(ROOT / "paper_repro", tmp_path / "paper_repro")
    for t in TARGETS:
        (tmp_path / t.output).parent.mkdir(parents=True, exist_ok=True)
        shutil.copyfile(ROOT / t.output, tmp_path / t.output)
    csv = tmp_path / "paper_repro" / "results" / "robust.csv"
    lines = csv.read_text().splitlines()
    head = lines[0].split(",")
    cells = lines[1].split(",")
    cells[head.index("vss")] = "123.45"
    lines[1] = ",".join(cells)
    csv.write_text("\n".join(lines) + "\n")
    diffs = [d for d in check(tmp_path) if f"{Path(target.output).name} (committed)" in d]
    assert diffs and "123.45" in diffs[0]


@pytest.mark.slow
def test_one_cell_study_writes_its_outputs_and_resumes(tmp_path: Path) -> None:
    opts = dict(instances=("sp12",), cvs=(0.3,), trays=(None,))
    res = run_robust(tmp_path, **opts)
    assert res["failed"] == [] and res["computed"] == res["cells"] == 1
    (row,) = res["rows"]
    assert row["vss_low"] <= row["vss"] <= row["vss_high"]
    assert row["evpi"] >= -1e-6 or row["evpi_low"] < 0  # per-scenario optima found, or noise
    assert (tmp_path / "robust.png").stat().st_size > 0
    assert "VSS" in (tmp_path / "robust.md").read_text()
    again = run_robust(tmp_path, **opts)
    assert again["computed"] == 0 and again["rows"] == res["rows"]
