"""The exact models against lns at the same limit
(docs/kitbench.md#exact-models-against-lns-at-the-same-limit): the excess and the goal's
count on hand-made rows, and the committed pass (bench/results/kitbench_cmp_10s.*) rendered
into the pages, with metadata naming what ran."""

from __future__ import annotations

import json
import math

import pytest
from paths import RESULTS, ROOT

from bilevel_kit.experiments.kitbench import Library
from bilevel_kit.experiments.kitbench.profiles import read_rows
from bilevel_kit.experiments.kitbench.versus import (
    excess,
    number,
    pass_proofs,
    proofs_text,
    render_versus_blocks,
    run_text,
    versus_blocks_in,
    versus_markdown,
    versus_rows,
    versus_summary,
    versus_text,
)

LABEL = "cmp_10s"


def _row(instance, method, makespan, status="feasible", bound=None, valid=True):
    return {
        "instance": instance,
        "tasks": "10",
        "method": method,
        "makespan": makespan,
        "valid": valid,
        "status": status,
        "bound": "" if bound is None else str(bound),
    }


ROWS = [
    _row("a", "lns", 1000.0, bound=990.0),
    _row("a", "cpsat", 1001.0, bound=995.0),  # +0.1 %: exactly the goal, within
    _row("a", "milp", 1001.5, bound=980.0),  # +0.15 %: a miss
    _row("b", "lns", 500.0),
    _row("b", "cpsat", 495.0, status="optimal", bound=495.0),  # better than lns
    _row("b", "milp", None, status="refused", valid=None),  # no plan: never within
    _row("c", "lns", None, status="error", valid=None),  # no reference: no excess
    _row("c", "cpsat", 70.0),
    _row("c", "milp", 80.0),
]


def test_excess_is_relative_to_the_reference_and_no_plan_is_infinite() -> None:
    assert excess(1001.0, 1000.0) == pytest.approx(0.001, rel=1e-9)
    assert excess(495.0, 500.0) == pytest.approx(-0.01, rel=1e-9)
    assert excess(None, 500.0) == math.inf
    assert excess(70.0, None) is None


def test_number_reads_a_csv_field_and_an_empty_one_is_none() -> None:
    """The one parser of the rows' and cells' numbers (bench/kitbench_docs.py's cells too)."""
    assert number("995.5") == 995.5 and number(7) == 7.0 and number("0") == 0.0
    assert number("") is None and number(None) is None


def test_rows_and_summary_count_the_goal_with_misses_worst_first() -> None:
    table = versus_rows(ROWS, ["cpsat", "milp"])
    assert [r["instance"] for r in table] == ["a", "b", "c"]
    a = table[0]
    assert a["lns"] == 1000.0 and a["best_bound"] == 995.0 and a["milp_bound"] == 980.0
    assert a["milp_excess"] == pytest.approx(0.0015, rel=1e-9)
    assert table[2]["cpsat_excess"] is None and table[2]["best_bound"] is None
    s = versus_summary(table, ["cpsat", "milp"])
    assert s["cpsat"]["instances"] == 2 and s["cpsat"]["within"] == 2
    assert s["cpsat"]["better"] == 1 and s["cpsat"]["optimal"] == 1
    assert s["cpsat"]["median"] == pytest.approx(-0.0045, rel=1e-9)
    assert s["cpsat"]["worst"] == pytest.approx(0.001, rel=1e-9) and s["cpsat"]["misses"] == []
    assert s["milp"]["within"] == 0 and s["milp"]["worst"] == math.inf
    assert [n for n, _ in s["milp"]["misses"]] == ["b", "a"]


def test_text_and_table_state_the_counts_and_each_miss() -> None:
    text = versus_text(ROWS)
    assert text.startswith("3 instances;")
    assert "**cpsat** within 0.1 % of lns (or better) on 2 of 2 instances, better on 1" in text
    assert "median -0.450 %, worst +0.100 %; missing the goal: none." in text
    assert "median no plan, worst no plan; missing the goal: `b` no plan, `a` +0.150 %." in text
    table = versus_markdown(ROWS)
    assert "| `a` | 10 | 1,000.00 | 1,001.00 | +0.100 | feasible | 995.00 |" in table
    assert "| `b` | 10 | 500.00 | 495.00 | -1.000 | optimal | 495.00 | - | no plan | refused |" in (
        table
    )


def test_run_text_states_the_wall_time_and_the_load() -> None:
    run = {
        "command": "bilevel-kit bench run --methods cpsat,lns",
        "commit": "abc",
        "started": "2026-01-01T00:00:00Z",
        "instances": ["a", "b"],
        "methods": ["cpsat", "lns"],
        "wall_s": 1234.4,
        "load_average_before": [3.5, 4.0, 4.75],
        "load_average_after": [6.0, 5.5, 5.0],
    }
    assert run_text(run) == (
        "`bilevel-kit bench run --methods cpsat,lns` (commit `abc`, started "
        "2026-01-01T00:00:00Z): 4 cells in 1,234 s of wall time, load average (1 / 5 / 15 min) "
        "3.50 / 4.00 / 4.75 before and 6.00 / 5.50 / 5.00 after."
    )


#: The committed passes: before and after issue 37's budget split (docs/kitbench.md).
#: The passes over every record up to 250 tasks in one run; the 60 s passes split it in two.
FULL = (LABEL, "cmp2_10s")
LABELS = (*FULL, "cmp_60s", "cmp250_60s")


@pytest.mark.parametrize(
    ("page", "label"),
    [("docs/kitbench.md", x) for x in LABELS]
    + [(f"bench/results/kitbench_{x}.md", x) for x in LABELS],
)
def test_the_pages_are_rendered_from_the_committed_pass(page, label) -> None:
    text = (ROOT / page).read_text(encoding="utf-8")
    assert label in versus_blocks_in(text), f"{page} has no kitbench-versus block of {label}"
    assert render_versus_blocks(text, RESULTS) == text, (
        f"{page} disagrees with bench/results/kitbench_{label}.csv: "
        "run python bench/kitbench_docs.py"
    )


@pytest.mark.parametrize("label", FULL)
def test_the_pass_is_one_run_of_the_three_methods_on_every_record_up_to_250_tasks(label) -> None:
    run = json.loads((RESULTS / f"kitbench_{label}_run.json").read_text())
    rows = read_rows(RESULTS / f"kitbench_{label}.csv")
    assert sorted(run["methods"]) == ["cpsat", "lns", "milp"] and run["time_limit"] == 10.0
    assert run["params"] == {"cpsat": {}, "milp": {}, "lns": {}}  # default options
    assert "--time-limit 10" in run["command"] and run["filter"] == "tasks<=250"
    records = Library.at(ROOT / "instances" / "kitbench").read()
    assert sorted(run["instances"]) == sorted(r.instance for r in records if r.tasks <= 250)
    assert sorted({(r["instance"], r["method"]) for r in rows}) == sorted(
        (i, m) for i in run["instances"] for m in run["methods"]
    )
    assert len(rows) == len(run["instances"]) * len(run["methods"])
    assert all(r["valid"] for r in rows), "every plan of the pass passes the checker"


def test_the_records_name_the_bounds_the_pass_raised() -> None:
    """docs/kitbench.md#the-records says the pass raised 8 bounds and set no plan: the index's
    provenance columns name its commit on 4 of them, the 4 others raised again since (steps 10,
    12 and 13, tests/experiments/test_kitbench_library.py and below)."""
    run = json.loads((RESULTS / f"kitbench_{LABEL}_run.json").read_text())
    records = Library.at(ROOT / "instances" / "kitbench").read()
    bounds = [r for r in records if r.bound is not None and r.bound.commit == run["commit"]]
    assert len(bounds) == 4 and {r.bound.method for r in bounds} == {"cpsat", "lns"}
    assert all(r.bound.time_limit == 10.0 and r.instance in run["instances"] for r in bounds)
    assert not [r for r in records if r.plan is not None and r.plan.commit == run["commit"]]
    docs = " ".join((ROOT / "docs" / "kitbench.md").read_text().split())
    assert "raised 8 bounds by 1 to 2 s" in docs and f"commit `{run['commit']}`, 4 of them" in docs


@pytest.mark.parametrize("label", LABELS)
def test_the_changelog_states_the_pass_counts(label) -> None:
    rows = read_rows(RESULTS / f"kitbench_{label}.csv")
    s = versus_summary(versus_rows(rows, ["cpsat", "milp"]), ["cpsat", "milp"])
    text = " ".join((ROOT / "CHANGELOG.md").read_text().split())
    n, cp, mi = s["cpsat"]["instances"], s["cpsat"], s["milp"]
    assert f"(or better) on {cp['within']} of {n}, `milp` on {mi['within']} of {n}" in text
    assert f"{len(cp['misses'])} of the {n} miss for `cpsat`, {len(mi['misses'])} for" in text
    assert f"worst +{100 * s['cpsat']['worst']:.1f} %" in text


def test_the_pass_of_131_to_250_tasks_and_the_records_it_set() -> None:
    """docs/kitbench.md: the pass ``cmp250_10s`` (the records of 131 to 250 tasks) has every
    plan valid, `cpsat` and `milp` within 0.1 % of `lns` on all 12 (worst +0.052 % and
    +0.016 %), and its ``bench update`` (the records, step 12) set 5 plans and 4 bounds; the
    index's provenance names its commit on the 3 plans and the bound step 13 did not improve
    again; `intree_n150_s1_t1_loose_d10` is proven optimal by them."""
    label = "cmp250_10s"
    run = json.loads((RESULTS / f"kitbench_{label}_run.json").read_text())
    rows = read_rows(RESULTS / f"kitbench_{label}.csv")
    records = Library.at(ROOT / "instances" / "kitbench").read()
    assert run["filter"] == "tasks>130,tasks<=250" and run["params"] == {
        "cpsat": {},
        "milp": {},
        "lns": {},
    }
    assert sorted(run["instances"]) == sorted(r.instance for r in records if 130 < r.tasks <= 250)
    assert len(rows) == 36 and all(r["valid"] for r in rows)
    s = versus_summary(versus_rows(rows, ["cpsat", "milp"]), ["cpsat", "milp"])
    assert (s["cpsat"]["within"], s["milp"]["within"]) == (12, 12)
    assert [round(100 * s[m]["worst"], 3) for m in ("cpsat", "milp")] == [0.052, 0.016]
    plans = {r.instance for r in records if r.plan is not None and r.plan.commit == run["commit"]}
    bounds = {
        r.instance for r in records if r.bound is not None and r.bound.commit == run["commit"]
    }
    assert plans == {
        "table_u20_tu_loose_d0",
        "intree_n150_s1_t1_loose_d10",
        "sparse_n250_s2_t1_loose_d30",
    }
    assert bounds == {"sparse_n250_s2_t1_loose_d30"}
    by_name = {r.instance: r for r in records}
    assert by_name["intree_n150_s1_t1_loose_d10"].status == "optimal"
    assert by_name["intree_n150_s1_t1_loose_d10"].best_known == 3578.0
    page = (RESULTS / f"kitbench_{label}.md").read_text(encoding="utf-8")
    assert label in versus_blocks_in(page) and render_versus_blocks(page, RESULTS) == page
    assert page.count("| `") == 12  # the per-instance table is rendered
    docs = " ".join((ROOT / "docs" / "kitbench.md").read_text().split())
    assert "set 5 plans and 4 bounds" in docs and "(327 s of wall time, 464 MB peak" in docs


def test_pass_proofs_count_proven_instances_by_size_and_list_the_wide_gaps() -> None:
    """Issue 37's record goals counted on one pass: an instance is proven when any method's
    cell (the reference's too) is optimal; the pass's gap is its best plan against its best
    bound, and one without a bound has no certified gap."""
    rows = [
        *ROWS,
        _row("d", "lns", 600.0, status="optimal", bound=600.0),
        _row("d", "cpsat", 601.0, bound=590.0),
        _row("d", "milp", 602.0),
        _row("e", "lns", 1000.0, bound=980.0),  # 2 % open: wide
        _row("e", "cpsat", 990.0, bound=970.0),  # best plan 990 against 980: 1.01 %
        _row("e", "milp", 995.0),
    ]
    for r in rows:
        r["tasks"] = "100" if r["instance"] == "e" else r["tasks"]
    table = versus_rows(rows, ["cpsat", "milp"])
    p = pass_proofs(table)
    assert p["proven"] == {60: (2, 4), 130: (2, 5)}  # b (cpsat) and d (lns)
    assert [n for n, _ in p["open"]] == ["c", "e"]  # a: 0.5 % open
    assert p["open"][0][1] is None and p["open"][1][1] == pytest.approx(10 / 990, rel=1e-9)
    text = proofs_text(table)
    assert "on 2 of the 4 up to 60 tasks, 2 of the 5 up to 130 tasks" in text
    assert "`c` no certified gap, `e` 1.01 %." in text
    for r in rows:
        r["tasks"] = "200"
    assert proofs_text(versus_rows(rows, ["cpsat", "milp"])) == ""  # beyond the goals' sizes


def test_the_60_s_passes_their_proofs_and_the_records_they_set() -> None:
    """docs/kitbench.md: the passes ``cmp_60s`` (up to 130 tasks) and ``cmp250_60s`` (131 to
    250) of main's code, every plan valid; `cpsat` within 0.1 % of `lns` on 49 of 50 and 12 of
    12, `milp` on 47 and 12; the pass's own proofs (25 of 37 up to 60 tasks, 29 of 50 up to
    130, 5 more than 1 % open); their ``bench update`` (the records, step 13) set 7 plans and 8
    bounds, the index naming that commit at 60 s exactly there, and proved
    `sp_n100_s2_t1_loose_d10` optimal."""
    small, large = (
        json.loads((RESULTS / f"kitbench_{label}_run.json").read_text())
        for label in ("cmp_60s", "cmp250_60s")
    )
    assert (small["filter"], large["filter"]) == ("tasks<=130", "tasks>130,tasks<=250")
    assert small["commit"] == large["commit"] and small["time_limit"] == 60.0
    records = Library.at(ROOT / "instances" / "kitbench").read()
    assert sorted(small["instances"] + large["instances"]) == sorted(
        r.instance for r in records if r.tasks <= 250
    )
    tables = {}
    for label, n in (("cmp_60s", 50), ("cmp250_60s", 12)):
        rows = read_rows(RESULTS / f"kitbench_{label}.csv")
        assert len(rows) == 3 * n and all(r["valid"] for r in rows)
        tables[label] = versus_rows(rows, ["cpsat", "milp"])
    s = versus_summary(tables["cmp_60s"], ["cpsat", "milp"])
    assert (s["cpsat"]["within"], s["milp"]["within"]) == (49, 47)
    assert [n for n, _ in s["milp"]["misses"]] == [
        "intree_n100_s1_t1_tight_d30",
        "sparse_n25_s1_tu_tight_d10",
        "table_u10_tu_tight_d10",
    ]
    s = versus_summary(tables["cmp250_60s"], ["cpsat", "milp"])
    assert (s["cpsat"]["within"], s["milp"]["within"]) == (12, 12)
    proofs = pass_proofs(tables["cmp_60s"])
    assert proofs["proven"] == {60: (25, 37), 130: (29, 50)}
    assert [n for n, _ in proofs["open"]] == [
        "stool_u17_t1_loose_d0",
        "intree_n100_s1_t1_tight_d30",
        "mixed_u2_t1_tight_d10",
        "sp_n50_s2_t1_tight_d30",
        "table_u5_t1_tight_d10",
    ]
    mine = small["commit"]
    plans = [r for r in records if r.plan is not None and r.plan.commit == mine]
    bounds = [r for r in records if r.bound is not None and r.bound.commit == mine]
    assert (len(plans), len(bounds)) == (7, 8)
    assert all(r.plan.time_limit == 60.0 for r in plans)
    assert all(r.bound.time_limit == 60.0 for r in bounds)
    by_name = {r.instance: r for r in records}
    assert by_name["sp_n100_s2_t1_loose_d10"].status == "optimal"
    assert by_name["sp_n100_s2_t1_loose_d10"].best_bound == pytest.approx(2422.0, abs=1e-9)
    docs = " ".join((ROOT / "docs" / "kitbench.md").read_text().split())
    assert "it set 7 plans and 8 bounds" in docs and "(2,154 s of wall time, 164 MB peak" in docs
