"""KitBench before and after a change (bench/kitbench_before_after.py): the cell-by-cell and
per-record comparison on hand-made rows, and the committed side-by-side run's pages rendered
from its rows (docs/kitbench.md#before-and-after-a-change)."""

from __future__ import annotations

import importlib.util
import json
import math
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
_spec = importlib.util.spec_from_file_location(
    "kitbench_before_after", ROOT / "bench" / "kitbench_before_after.py"
)
ba = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(ba)


def row(instance, method, makespan, status, bound, time):
    return {
        "instance": instance,
        "tasks": "12",
        "method": method,
        "makespan": makespan,
        "valid": makespan is not None,
        "status": status,
        "bound": "" if bound is None else str(bound),
        "wall_time_s": str(time),
    }


BEFORE = [
    row("a", "cpsat", 100.0, "optimal", 100.0, 2.0),
    row("a", "lns", 100.0, "feasible", 99.0, 60.0),
    row("b", "cpsat", 200.0, "feasible", 190.0, 60.0),
    row("b", "lns", 201.0, "feasible", 190.0, 60.0),
]
AFTER = [
    row("a", "cpsat", 100.0 + 1e-11, "optimal", 100.0, 1.0),
    row("a", "lns", 100.0, "optimal", 100.0, 30.0),
    row("b", "cpsat", None, "unknown", 195.0, 60.0),
    row("b", "lns", 202.0, "feasible", 195.0, 60.0),
]


def test_change_is_relative_and_equal_plans_in_the_last_bits_are_the_same() -> None:
    assert ba.change(101.0, 100.0) == pytest.approx(0.01, rel=1e-12)
    assert ba.change(100.0 + 1e-8, 100.0) == 0.0
    assert ba.change(None, 100.0) == math.inf and ba.change(100.0, None) == -math.inf
    assert ba.change(None, None) is None


def test_methods_count_better_same_worse_optimal_and_time() -> None:
    table = ba.cells(BEFORE, AFTER)
    assert [(c["instance"], c["method"]) for c in table] == [
        ("a", "cpsat"),
        ("a", "lns"),
        ("b", "cpsat"),
        ("b", "lns"),
    ]
    cp = ba.method_summary(table, "cpsat")
    assert (cp["cells"], cp["better"], cp["same"]) == (2, 0, 1)
    assert cp["worse"] == [("b", math.inf)]
    assert (cp["optimal_before"], cp["optimal_after"]) == (1, 1)
    assert (cp["time_before"], cp["time_after"]) == (62.0, 61.0)
    assert cp["median_ratio"] == pytest.approx(0.75)
    ln = ba.method_summary(table, "lns")
    assert ln["worse"] == [("b", pytest.approx(1 / 201))]
    assert (ln["same"], ln["optimal_before"], ln["optimal_after"]) == (1, 0, 1)


def test_records_compare_each_pass_best_plan_and_bound() -> None:
    rec = ba.record_summary(ba.cells(BEFORE, AFTER))
    assert rec["records"] == 2 and rec["better"] == 0
    assert rec["worse"] == [("b", pytest.approx(0.01))]  # 200 (cpsat) -> 202 (lns)
    assert rec["bound_higher"] == 1 and rec["bound_lower"] == []


def test_the_text_says_what_ran_and_lists_every_worse_cell() -> None:
    runs = [
        {"command": "bilevel-kit bench run", "commit": c, "started": "2026-01-01T00:00:00Z"}
        for c in ("old", "new")
    ]
    text = ba.before_after_text(BEFORE, AFTER, runs)
    assert "Before: `bilevel-kit bench run` (commit `old`" in text
    assert "After: `bilevel-kit bench run` (commit `new`" in text
    assert "worse on 1 (`b` +1.000 %)" in text
    assert "**cpsat** (2 cells): better on 0, the same on 1, worse on 1 (`b` plan lost)" in text
    assert "median ratio after / before 0.75" in text


def test_wall_seconds_reads_time_v(tmp_path) -> None:
    log = tmp_path / "time.log"
    log.write_text("\tElapsed (wall clock) time (h:mm:ss or m:ss): 1:02:03.5\n")
    assert ba.wall_seconds(log) == 3723.5
    log.write_text("\tElapsed (wall clock) time (h:mm:ss or m:ss): 2:03.25\n")
    assert ba.wall_seconds(log) == 123.25


#: The committed side-by-side runs: issue 36's refactors, the 60 s pass up to 130 tasks.
LABELS = ("i36_60s",)


def test_the_committed_runs_are_listed() -> None:
    assert set(LABELS) <= set(ba.labels())


@pytest.mark.parametrize(
    "page", ["docs/kitbench.md", *(f"bench/results/kitbench_{x}.md" for x in LABELS)]
)
def test_the_pages_are_rendered_from_the_committed_rows(page) -> None:
    text = (ROOT / page).read_text(encoding="utf-8")
    for label in LABELS:
        assert f"<!-- kitbench-before-after:{label} -->" in text or not page.startswith("docs")
    assert ba.render(text) == text, (
        f"{page} disagrees with its rows: run python bench/kitbench_before_after.py"
    )


def test_the_changelog_numbers_of_the_issue_36_run():
    """CHANGELOG (Added, KitBench before and after): the counts it quotes."""
    from bilevel_kit.experiments.kitbench.profiles import read_rows

    results = ROOT / "bench" / "results"
    table = ba.cells(
        read_rows(results / "kitbench_i36_60s_before.csv"),
        read_rows(results / "kitbench_i36_60s_after.csv"),
    )
    rec = ba.record_summary(table)
    assert (rec["records"], rec["better"], len(rec["worse"])) == (50, 4, 3)
    assert rec["worse"][0][0] == "sparse_n25_s1_tu_tight_d10"
    assert round(100 * rec["worse"][0][1], 3) == 0.161
    counts = {m: ba.method_summary(table, m) for m in ("cpsat", "milp", "lns", "greedy-ce")}
    assert [(counts[m]["better"], len(counts[m]["worse"])) for m in counts] == [
        (20, 2),
        (18, 2),
        (3, 4),
        (0, 0),
    ]
    assert all(s["optimal_before"] == s["optimal_after"] for s in counts.values())
    assert [round(counts[m]["median_ratio"], 2) for m in ("cpsat", "milp", "lns")] == [
        1.0,
        1.0,
        1.01,
    ]
    bm = ba.method_summary(table, "bilevel-milp")["median_ratio"]
    assert round(bm, 2) == 1.0
    walls = [
        round(json.loads((results / f"kitbench_i36_60s_{s}_run.json").read_text())["wall_s"])
        for s in ("before", "after")
    ]
    assert walls == [5239, 5311]
