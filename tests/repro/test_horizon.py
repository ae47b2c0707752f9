"""The horizon study (bilevel_kit.repro.horizon): greedy-ce's horizon N against the exact
optimum, cpsat-rolling's window in the simulator, resumable cells, the CLI."""

from __future__ import annotations

import csv

import pytest

from bilevel_kit.cli import main
from bilevel_kit.experiments.compare import CompareCell
from bilevel_kit.instance import load
from bilevel_kit.repro import horizon
from bilevel_kit.repro.common import DEFAULT_INSTANCE
from bilevel_kit.repro.plots import plot_horizon, plot_horizon_gap, plot_horizon_time
from bilevel_kit.sim import TimingModel

TABLE = str(DEFAULT_INSTANCE)
#: The table's proven optimum (cpsat, one tray) and greedy-ce's plans at N = 1 and 5.
OPTIMUM = 435.085
N1 = (466.695, 12)
N5 = (463.78, 8)


def _rows(path):
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


@pytest.fixture(scope="module")
def study(tmp_path_factory):
    out = tmp_path_factory.mktemp("horizon")
    res = horizon.run_horizon(
        out, quick=True, horizons=(1, 5), instances=[TABLE], simulation=False, progress=False
    )
    return out, res


@pytest.mark.parametrize(("n", "expected"), [(1, N1), (5, N5)])
def test_cell_on_the_table_gives_the_known_plan(n, expected):
    cell = CompareCell(TABLE, "greedy-ce", time_limit=60.0, params={"horizon": n})
    rec = horizon.horizon_cell(cell)
    assert rec["makespan"] == pytest.approx(expected[0], abs=1e-6)
    assert rec["n_kits"] == expected[1]
    assert rec["valid"] is True and rec["violations"] == 0
    assert rec["time_limit_hit"] is False and rec["beam_epochs"] == 0
    tasks = [t for k in rec["kits"] for t in k]
    assert sorted(tasks) == sorted(t.id for t in load(TABLE).tasks)  # each task in one kit
    assert "solution" not in rec  # the layouts stay out of the cell file


def test_gap_is_against_the_proven_optimum_and_never_negative(study):
    out, res = study
    rows = _rows(out / "horizon.csv")
    assert [int(r["horizon"]) for r in rows] == [1, 5]
    for r in rows:
        assert r["reference"] == "optimum" and r["cpsat_status"] == "optimal"
        assert float(r["reference_makespan"]) == pytest.approx(OPTIMUM, abs=1e-6)
        assert float(r["gap_pct"]) >= 0.0
        assert r["valid"] == "True" and r["quick"] == "True"
    by_n = {int(r["horizon"]): r for r in rows}
    assert float(by_n[1]["gap_pct"]) == pytest.approx(100 * (N1[0] - OPTIMUM) / N1[0], abs=1e-6)
    assert float(by_n[5]["gap_pct"]) == pytest.approx(100 * (N5[0] - OPTIMUM) / N5[0], abs=1e-6)
    (s,) = res["summary"]
    assert (s["best_n"], s["reference"]) == (5, "optimum")
    g1, g5 = float(by_n[1]["gap_pct"]), float(by_n[5]["gap_pct"])
    assert s["closed_pct"] == pytest.approx(100 * (g1 - g5) / g1)


def test_second_run_skips_every_cell(study):
    out, res = study
    assert (res["cells"], res["computed"], res["failed"]) == (3, 3, [])
    again = horizon.run_horizon(
        out, quick=True, horizons=(1, 5), instances=[TABLE], simulation=False, progress=False
    )
    assert (again["computed"], again["reused"]) == (0, 3)
    assert again["summary"] == res["summary"]


def test_cli_quick_writes_the_csv_with_its_columns(study, capsys):
    out, _ = study  # the cells of N = 1 and 5 are reused; N = 2 is computed now
    args = ["--quick", "--horizons", "1,2,5", "--instances", TABLE, "--no-simulation", "-q"]
    code = main(["repro", "horizon", *args, "--out", str(out)])
    text = capsys.readouterr()
    assert code == 0, text.err
    assert "1 done, 3 skipped" in text.err
    assert "QUICK" in text.out and "| hrc_table | optimum |" in text.out
    rows = _rows(out / "horizon.csv")
    assert tuple(rows[0]) == horizon.PLANNING_COLUMNS
    assert [int(r["horizon"]) for r in rows] == [1, 2, 5]
    assert all(r["valid"] == "True" and r["violations"] == "0" for r in rows)
    assert (out / "horizon.png").stat().st_size > 0


def test_window_study_against_optimized_in_the_same_runs(study):
    out, _ = study
    res = horizon.run_horizon(
        out,
        quick=True,
        horizons=(1,),
        instances=[TABLE],
        windows=(4,),
        mats=(60.0,),
        reps=2,
        units=1,
        timing=TimingModel(),
        progress=False,
    )
    assert res["failed"] == [] and res["computed"] == 4  # the planning cell is reused
    rows = _rows(out / "horizon_window.csv")
    assert tuple(rows[0]) == horizon.WINDOW_COLUMNS
    assert [(r["label"], r["policy"], r["window"]) for r in rows] == [
        ("no delay", "optimized", ""),
        ("no delay", "cpsat-rolling", "4"),
        ("MAT 60, MTTF 60", "optimized", ""),
        ("MAT 60, MTTF 60", "cpsat-rolling", "4"),
    ]
    for r in rows:
        assert int(r["reps"]) == 2 and int(r["units"]) == 1
        assert int(r["decisions"]) == round(2 * float(r["kits_mean"]))
        assert float(r["plan_s_per_decision"]) > 0
        if r["policy"] == "optimized":
            assert float(r["total_pct_over_optimized"]) == 0.0
            assert r["p_paired_total"] == ""
        mean = float(r["total_mean"])
        assert 300 < mean < 1000  # one table: about 375 s of human work plus idle


def test_plot_draws_into_given_axes_with_units():
    import matplotlib.pyplot as plt

    rows = [
        {"instance": "a", "instance_file": "a.json", "horizon": n, "gap_pct": g, "plan_time_s": t,
         "reference": ref}
        for n, g, t, ref in ((1, 5.0, 0.01, "optimum"), (2, 3.0, 0.5, "optimum"))
    ]  # fmt: skip
    fig, ax = plt.subplots()
    assert plot_horizon_gap(rows, ax=ax) is ax
    assert ax.get_ylabel() == "gap to the exact reference (%)"
    assert "(tasks" in ax.get_xlabel()
    assert fig.axes == [ax]  # one y axis per panel: the plan times are a panel of their own
    assert [line.get_gid() for line in ax.lines] == ["gap:a.json"]
    assert "exact reference: CP-SAT's proven optimum (filled), else its lower bound" in (
        ax.get_title()
    )
    plt.close(fig)
    # eight series: dodged along N (at most +-0.2) so that they do not sit on one another
    many = [
        {**r, "instance": f"i{k}", "instance_file": f"i{k}.json"} for k in range(8) for r in rows
    ]
    fig, ax = plt.subplots()
    plot_horizon_gap(many, ax=ax)
    xs = sorted(line.get_xdata()[0] for line in ax.lines)
    assert len(set(xs)) == 8 and xs[0] == pytest.approx(0.8) and xs[-1] == pytest.approx(1.2)
    fig.canvas.draw()  # the legend beside the axes, not over the lines
    assert ax.get_legend().get_window_extent().x0 >= ax.get_window_extent().x1
    plt.close(fig)
    fig, ax = plt.subplots()
    assert plot_horizon_time(rows, ax=ax) is ax
    assert ax.get_yscale() == "log" and ax.get_ylabel() == "plan time (s)"
    plt.close(fig)


def test_figure_panels_have_one_y_axis_each():
    import matplotlib.pyplot as plt

    plan = [
        {"instance": "a", "instance_file": "a.json", "horizon": n, "gap_pct": g, "plan_time_s": t,
         "reference": "optimum"}
        for n, g, t in ((1, 5.0, 0.01), (2, 3.0, 0.5))
    ]  # fmt: skip
    window = [
        {"label": "no delay", "window": w, "total_pct_over_optimized": g,
         "total_pct_ci_low": g - 1, "total_pct_ci_high": g + 1, "plan_s_per_decision": t}
        for w, g, t in ((None, 0.0, 0.002), (4, 1.0, 0.01), (8, 2.0, 0.1))
    ]  # fmt: skip
    fig = plot_horizon(plan, window)
    assert len(fig.axes) == 4  # gap, plan time, gain, time per decision: no twin axes
    assert {a.get_ylabel() for a in fig.axes} == {
        "gap to the exact reference (%)",
        "plan time (s)",
        "total time, gain over Optimized (%)",
        "planning time per decision (s)",
    }
    plt.close(fig)
