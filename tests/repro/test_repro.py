"""Paper reproductions (bilevel_kit.repro): user study and Figure 6, quick mode end to end."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import numpy as np
import pytest

from bilevel_kit import repro
from bilevel_kit.sim import SimParams, TimingModel, run

PNG_MAGIC = b"\x89PNG\r\n\x1a\n"


def _strip_wall(obj):
    """Drop wall-clock fields (the only ones allowed to differ between two runs)."""
    if isinstance(obj, dict):
        return {
            k: _strip_wall(v)
            for k, v in obj.items()
            if not k.startswith("wall") and k not in ("files", "simulation_wall_s")
        }
    if isinstance(obj, list):
        return [_strip_wall(v) for v in obj]
    return obj


# -- small pure helpers --------------------------------------------------------------------------


def test_paper_idle_counts_the_pickup_as_idle(table):
    params = SimParams(units=1, trays=1, timing=TimingModel(kit_overhead_human=3.0))
    rec = run(table, "single-task", params=params, seed=4)
    expected = rec["human_idle"] + rec["n_kits"] * 3.0
    assert repro.paper_idle(rec) == pytest.approx(expected, abs=1e-9)


def test_tukey_sign_convention_is_mean_a_minus_mean_b():
    rng = np.random.default_rng(1)
    vals = np.r_[rng.normal(100, 5, 18), rng.normal(60, 5, 18)]
    groups = ["whole-assembly"] * 18 + ["single-task"] * 18
    t = repro.tukey_pairs(vals, groups)
    st_wa = t[("single-task", "whole-assembly")]
    assert st_wa["diff"] == pytest.approx(vals[18:].mean() - vals[:18].mean())
    assert st_wa["lo"] < st_wa["diff"] < st_wa["hi"] < 0
    assert t[("whole-assembly", "single-task")]["diff"] == pytest.approx(-st_wa["diff"])


def test_stars_thresholds():
    assert [repro.stars(p) for p in (None, 0.2, 0.049, 0.0009)] == ["", "", "*", "**"]


def test_summarize_cell_percent_improvement_and_extra_policy_hook():
    n = 6
    runs = {
        p: {
            "total_time": list(base + np.arange(n)),
            "human_idle": list(idle + np.arange(n)),
            "n_kits": [1] * n,
        }
        for p, base, idle in (
            ("single-task", 200.0, 50.0),
            ("whole-assembly", 400.0, 100.0),
            ("optimized", 100.0, 25.0),
            ("cpsat-rolling", 50.0, 25.0),
        )
    }
    rec = {"cell": {"mat": 30.0, "mttf": 60.0, "units": 2, "seeds": list(range(n))}, "runs": runs}
    row = repro.summarize_cell(rec)
    assert row["pct_total:optimized_over_single-task"] == pytest.approx(
        100 * (202.5 - 102.5) / 202.5
    )
    assert row["pct_idle:optimized_over_whole-assembly"] == pytest.approx(
        100 * (102.5 - 27.5) / 102.5
    )
    assert row["stars_total:optimized_over_single-task"] == "**"
    assert row["pct_total:cpsat-rolling_over_optimized"] == pytest.approx(
        100 * (102.5 - 52.5) / 102.5
    )
    assert row["pct_idle:cpsat-rolling_over_optimized"] == pytest.approx(0.0)
    assert row["stars_idle:cpsat-rolling_over_optimized"] == ""
    assert repro.comparisons(list(runs)) == [
        ("optimized", "single-task"),
        ("optimized", "whole-assembly"),
        ("cpsat-rolling", "optimized"),
    ]


# -- user study ----------------------------------------------------------------------------------


@pytest.fixture(scope="module")
def study(tmp_path_factory):
    out = tmp_path_factory.mktemp("study")
    return out, repro.run_user_study(out, quick=True, seed=0)


def test_user_study_quick_summary_and_files(study):
    out, res = study
    table = res["table"]
    kinds = [r["kind"] for r in table]
    # 6 means, 2 F, 4 Tukey centres, 2 Tukey half-widths (one per metric: equal for every pair)
    assert len(table) == 14
    assert (kinds.count("fitted"), kinds.count("implied"), kinds.count("predicted")) == (3, 4, 7)
    fitted = {r["quantity"] for r in table if r["kind"] == "fitted"}
    assert fitted == {
        "mean human idle time, Whole Assembly (s)",
        "mean human idle time, Single Task (s)",
        "repeated-measures F(2, 34), total task time",
    }
    for r in table:
        assert r["pi_low"] <= r["median"] <= r["pi_high"]
        assert r["cal_low"] <= r["cal_high"]
        h = r["readoff"]
        lo, hi = r["cal_low"], r["cal_high"]
        assert r["inside"] == (lo - 0.01 <= r["paper"] + h and r["paper"] - h <= hi + 0.01)
        assert r["studies"] == res["n_studies"] and r["cal_studies"] == res["cal_studies"]
    assert res["inside"]["predicted"] == 7 and res["inside"]["independent"] == 2
    assert res["cal_studies"] >= res["n_studies"]
    assert res["delivery_time"] == 0.0 and res["trays"] == 1
    for name in ("runs_csv", "table", "parameters", "summary", "within", "markdown", "json"):
        assert Path(res["files"][name]).is_file(), name
    assert Path(res["files"]["figure"]).read_bytes()[:8] == PNG_MAGIC
    rows = (out / "user_study_runs.csv").read_text().splitlines()
    assert len(rows) == 1 + 3 * repro.PAPER_N * res["n_studies"]
    assert json.loads((out / "user_study.json").read_text())["table"] == res["table"]
    assert "quick" in (out / "user_study.md").read_text()


def test_user_study_uses_the_committed_calibration(study):
    _, res = study
    cal = repro.load_calibration()
    assert res["timing"]["robot_scale"] == cal.robot_scale
    assert res["timing"]["kit_overhead_human"] == cal.kit_overhead_human
    assert res["design"]["within_cv"] == cal.within_cv
    assert res["draws_used"] == min(3, len(cal.draws))


def test_within_rows_explain_the_model(study):
    _, res = study
    by = {(r["quantity"], r["metric"]): r for r in res["within"]}
    shares = [r["ours"] for r in res["within"] if r["quantity"].startswith("share of a")]
    assert sum(shares) == pytest.approx(1.0, abs=1e-3)
    for m in ("total", "idle"):
        f = by[("F from the medians", m)]
        assert f["paper"] == repro.PAPER_F[m]
        cond = by[("MS conditions (median over studies)", m)]["ours"]
        err = by[("MS residual (participant x condition)", m)]["ours"]
        assert f["ours"] == pytest.approx(cond / err, rel=1e-3)


def test_user_study_same_seed_same_results(study, tmp_path):
    _, first = study
    again = repro.run_user_study(tmp_path, quick=True, seed=0)
    assert _strip_wall(again) == _strip_wall(first)


def test_within_subject_model_counterbalances_and_keeps_the_papers_spread():
    from bilevel_kit.sim.timing import WithinSubjectModel, counterbalanced_orders

    assert len(counterbalanced_orders(3)) == 6
    rng = np.random.default_rng(0)
    n = 6 * 4000
    design = WithinSubjectModel(within_cv=0.1, learning=0.05)
    f = design.session_factors(rng.standard_normal(n), rng.standard_normal((n, 3)))
    assert f.mean() == pytest.approx(1.0, abs=0.005)
    assert f.std() == pytest.approx(repro.PAPER_ACTIVE[1] / repro.PAPER_ACTIVE[0], abs=0.005)
    # every condition sees every session position equally often: same mean per condition
    assert np.ptp(f.mean(axis=0)) < 0.01
    # the participant's own speed makes sessions correlate; within_cv near its maximum: hardly
    assert np.corrcoef(f[:, 0], f[:, 1])[0, 1] > 0.3
    with pytest.raises(Exception, match="between-participant"):
        WithinSubjectModel(within_cv=0.2)


def test_session_factor_scales_human_times_only(table):
    base = SimParams(units=1, trays=1, timing=TimingModel(participant_cv=0.0))
    slow = SimParams(units=1, trays=1, timing=TimingModel(participant_cv=0.0, session_factor=1.5))
    a = run(table, "single-task", params=base, seed=0)
    b = run(table, "single-task", params=slow, seed=0)
    for t, v in a["human_times"].items():
        assert b["human_times"][t] == pytest.approx(1.5 * v)


def test_plot_user_study_draws_into_given_axes(study):
    import matplotlib.pyplot as plt

    _, res = study
    fig, ax = plt.subplots()
    assert repro.plot_user_study(res["table"], ax=ax) is ax
    gids = {p.get_gid() for p in ax.patches}
    assert {"bar:total:optimized", "bar:idle:whole-assembly", "paper:idle:optimized"} <= gids
    ours = next(p for p in ax.patches if p.get_gid() == "bar:idle:optimized")
    paper = next(p for p in ax.patches if p.get_gid() == "paper:idle:optimized")
    assert ours.get_x() + ours.get_width() <= paper.get_x() + 1e-9  # beside, not on, our bar
    # issue 40 item 11: the paper's bar hatched in its condition's colour, one legend entry per
    # condition's hatch; the two intervals side by side and told apart in the legend; tags
    # explained
    assert paper.get_hatch() == "///"
    assert paper.get_edgecolor() == ours.get_facecolor() == paper.get_hatchcolor()
    legend = ax.get_legend()
    labels = [t.get_text() for t in legend.get_texts()]
    hatched = [h for h in legend.legend_handles if getattr(h, "get_hatch", lambda: None)()]
    assert len(hatched) == 3 and len({tuple(h.get_edgecolor()) for h in hatched}) == 3
    assert "95 % PI, participants only (thick)" in labels
    assert "95 % PI, with calibration uncertainty (thin, capped)" in labels
    assert legend.get_title().get_text().startswith("tags: fitted = a bar the calibration")
    thick = [c for c in ax.collections if str(c.get_gid()).startswith("pi:participants:")]
    thin = [c for c in ax.collections if str(c.get_gid()).startswith("pi:calibration:")]
    assert len(thick) == len(thin) == 6
    x_thick = thick[0].get_segments()[0][0][0]
    x_thin = thin[0].get_segments()[0][0][0]
    assert x_thin > x_thick  # side by side, not one hidden behind the other
    assert thick[0].get_linewidth()[0] > 3 * thin[0].get_linewidth()[0]
    plt.close(fig)


# -- Figure 6 ------------------------------------------------------------------------------------


@pytest.fixture(scope="module")
def fig6(tmp_path_factory):
    out = tmp_path_factory.mktemp("fig6")
    return out, repro.run_fig6(out, quick=True, seed=0, progress=False)


def test_fig6_quick_end_to_end(fig6):
    out, res = fig6
    n_cells = 1 + len(repro.QUICK_MATS) * len(repro.QUICK_MTTFS)
    assert res["cells"] == res["computed"] == n_cells
    assert len(list((out / "cells").glob("*.json"))) == n_cells
    assert Path(res["files"]["csv"]).read_text().count("\n") == 1 + n_cells
    assert Path(res["files"]["figure"]).read_bytes()[:8] == PNG_MAGIC
    assert "Optimized over Single Task" in Path(res["files"]["markdown"]).read_text()
    for row in res["rows"]:
        for base in ("single-task", "whole-assembly"):
            for m in ("total", "idle"):
                assert row[f"pct_{m}:optimized_over_{base}"] is not None
                assert row[f"stars_{m}:optimized_over_{base}"] in ("", "*", "**")
    ref = next(r for r in res["rows"] if r["mat"] is None)
    assert ref["reps"] == repro.QUICK_REPS and ref["units"] == repro.QUICK_UNITS == 10
    assert res["quick"] and all(r["quick"] for r in res["rows"])
    assert "QUICK" in Path(res["files"]["markdown"]).read_text()
    verdicts = (out / "fig6_verdicts.csv").read_text().splitlines()
    assert len(verdicts) == 1 + 4


def test_fig6_figure_shares_one_colour_scale(fig6):
    import matplotlib.pyplot as plt

    _, res = fig6
    fig = repro.plot_fig6(res["rows"], quick=True)
    norms = {(im.norm.vmin, im.norm.vmax) for ax in fig.axes for im in ax.images}
    assert len(norms) == 1
    texts = " ".join(t.get_text() for t in fig.texts)
    assert "Tukey" in texts and "R = 3" in texts and "QUICK" in texts
    # colour-blind safe (ColorBrewer RdBu, not red-green), the axes spelled out
    assert {im.get_cmap().name for ax in fig.axes for im in ax.images} == {"RdBu"}
    panel = fig.axes[0]
    assert panel.get_xlabel() == "MTTF: the feeders' mean time to failure (s)"
    assert panel.get_ylabel() == "MAT: mean time between part arrivals (s)"
    assert "MAT: mean time between part arrivals" in texts
    plt.close(fig)


def test_fig6_resumes_only_missing_cells_with_identical_results(fig6, tmp_path, monkeypatch):
    src, first = fig6
    out = tmp_path / "fig6"
    shutil.copytree(src, out)
    cells = sorted((out / "cells").glob("mat*.json"))
    victim = cells[0]
    before = json.loads(victim.read_text())
    victim.unlink()
    calls = []
    real = repro.fig6_cell

    def spy(cell):
        calls.append(cell.key())
        return real(cell)

    monkeypatch.setattr(repro.fig6, "fig6_cell", spy)
    again = repro.run_fig6(out, quick=True, seed=0, progress=False)
    assert calls == [victim.stem]
    assert (again["computed"], again["reused"]) == (1, first["cells"] - 1)
    after = json.loads(victim.read_text())
    assert _strip_wall(after) == _strip_wall(before)
    assert again["rows"] == first["rows"]
