"""``bilevel-kit repro robust`` (docs/robust.md): a one-cell run, the committed CSV's
honesty (independent evaluation sample, paired VSS, intervals) and the page's drift test."""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest

from bilevel_kit.repro.report import read_rows
from bilevel_kit.repro.robust import (
    EVALUATION,
    plot_robust_panel,
    run_robust,
    vss_markdown,
)
from bilevel_kit.repro.robust_facts import ROBUST_TABLES
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
        # no solve of the committed study was cut by the wall clock: every row reproducible
        assert int(r["safety_net_fired"]) == 0
        if r["saa_proven"] == "True":  # a proof: the bound meets the plan (0.01 s rounding)
            assert float(r["saa_bound"]) == pytest.approx(float(r["saa_in_sample"]), abs=0.02)


def test_the_committed_study_is_the_rerun_with_the_net_recorded() -> None:
    """The rerun of 2026-12-06 (docs/robust.md#the-study): its SAA solves ran to their
    deterministic limits, 23 of 24 to a proof, and no VSS interval lies below 0."""
    rows = read_rows(CSV)
    assert len(rows) == 24
    assert sum(r["saa_proven"] == "True" for r in rows) == 23
    (open_,) = [r for r in rows if r["saa_proven"] != "True"]
    assert (open_["instance"], open_["trays"], open_["cv"]) == ("table", "1", "0.5")
    assert sum(float(r["vss_low"]) > 0 for r in rows) == 21
    assert min(float(r["vss_low"]) for r in rows) == 0.0
    assert max(float(r["vss"]) for r in rows) == 6.34
    by = {(r["instance"], r["trays"], r["cv"]): r for r in rows}
    # the cells whose committed VSS the first run's cut solves had understated
    two = by["table", "2", "0.5"]
    assert (float(two["vss"]), float(two["vss_low"]), two["saa_proven"]) == (4.6, 3.69, "True")
    assert float(by["sp12", "1", "0.5"]["vss"]) == 0.81


def test_plot_panel_returns_its_axes_and_the_table_renders() -> None:
    import matplotlib

    matplotlib.use("Agg")
    rows = read_rows(CSV)
    name = rows[0]["instance"]
    ax = plot_robust_panel(rows, name)
    assert ax.get_title() == name and ax.get_ylabel() == "VSS (s)"
    assert name in vss_markdown(rows)
    assert set(ROBUST_TABLES) == {"robust_vss", "robust_detail", "robust_advice", "robust_solves"}


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
    assert row["safety_net_fired"] == 0 and res["cut"] == res["retried"] == []
    assert (tmp_path / "robust.png").stat().st_size > 0
    assert "VSS" in (tmp_path / "robust.md").read_text()
    again = run_robust(tmp_path, **opts)
    assert again["computed"] == 0 and again["rows"] == res["rows"]
