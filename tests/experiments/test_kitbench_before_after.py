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
RESULTS = ROOT / "bench" / "results"


def _summaries(label: str, methods: tuple[str, ...]) -> dict[str, dict]:
    """Each method's summary of the committed side-by-side pass ``label``."""
    from bilevel_kit.experiments.kitbench.profiles import read_rows

    before, after = (read_rows(RESULTS / f"kitbench_{label}_{s}.csv") for s in ("before", "after"))
    table = ba.cells(before, after)
    return {m: ba.method_summary(table, m) for m in methods}


def _moves(counts: dict[str, dict]) -> list[tuple[int, int, int]]:
    """(cells, better, worse) of each method, in the order of ``counts``."""
    return [(s["cells"], s["better"], len(s["worse"])) for s in counts.values()]


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


def test_the_exact_models_are_held_to_lns_of_the_same_pass() -> None:
    table = ba.cells(BEFORE, AFTER)
    v = ba.versus_reference(table, "cpsat")
    assert (v["records"], v["before"], v["after"]) == (2, 2, 1)  # b: 200 <= 201; lost after
    assert v["misses_before"] == [] and v["misses_after"] == [("b", math.inf)]
    close = ba.cells(
        [
            row("c", "cpsat", 100.1, "feasible", 90.0, 9.0),
            row("c", "lns", 100.0, "feasible", 90, 9),
        ],
        [
            row("c", "cpsat", 100.11, "feasible", 90.0, 9.0),
            row("c", "lns", 100.0, "feasible", 90, 9),
        ],
    )
    w = ba.versus_reference(close, "cpsat")  # 0.1 % above: within; 0.11 %: not
    assert (w["before"], w["after"]) == (1, 0) and w["misses_after"][0][0] == "c"
    runs = [{"command": "x", "commit": c, "started": "t"} for c in ("old", "new")]
    text = ba.before_after_text(BEFORE, AFTER, runs)
    assert "**Against lns in the same pass**" in text
    assert "cpsat 2 before, 1 after (missing it after: `b` plan lost)" in text


def test_wall_seconds_reads_time_v(tmp_path) -> None:
    log = tmp_path / "time.log"
    log.write_text("\tElapsed (wall clock) time (h:mm:ss or m:ss): 1:02:03.5\n")
    assert ba.wall_seconds(log) == 3723.5
    log.write_text("\tElapsed (wall clock) time (h:mm:ss or m:ss): 2:03.25\n")
    assert ba.wall_seconds(log) == 123.25


#: The committed side-by-side runs: issue 36's refactors, the 60 s pass up to 130 tasks; the
#: LNS after the model (docs/formulations.md): 10 s up to 130 tasks, 60 s on 11 records, and
#: the rule's first version at 10 s; the LNS first's cut share at 10 s and its stall of a sweep
#: at 10 s (up to 130 tasks, 131 to 250) and 60 s (9 records); the windows' dual-feasible-function
#: inequalities at 10 s (tight trays up to 130 tasks); the maximal-rectangles packer in the
#: packing oracle at 10 s (up to 130 tasks), and its cap on attempts against it; issue 37's
#: changes together at 10 s (up to 250 tasks) and 60 s (the exact models up to 60 tasks).
LABELS = (
    "i36_60s",
    "lnsafter_10s",
    "lnsafter_60s",
    "lnsafter_uncond_10s",
    "cutshare_10s",
    "sweepstall_10s",
    "sweepstall_250_10s",
    "sweepstall_60s",
    "dffrows_10s",
    "sweepcap_10s",
    "sweepcap_60s",
    "maxrects_10s",
    "maxcap_10s",
    "johnson_10s",
    "i37_10s",
    "i37_60s",
)


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


def test_the_changelog_numbers_of_the_lns_after_runs():
    """CHANGELOG (Changed, the LNS after the model): the counts it quotes."""

    def summary(label):
        return _summaries(label, ("cpsat", "milp"))

    ten = summary("lnsafter_10s")
    assert _moves(ten) == [
        (50, 9, 0),
        (50, 6, 1),
    ]
    assert round(100 * ten["milp"]["worse"][0][1], 3) == 0.039
    assert [(ten[m]["optimal_before"], ten[m]["optimal_after"]) for m in ten] == [
        (20, 20),
        (20, 19),
    ]
    sixty = summary("lnsafter_60s")
    assert (
        sum(sixty[m]["same"] for m in sixty) == 19 and sum(s["cells"] for s in sixty.values()) == 22
    )
    assert all(s["optimal_before"] == s["optimal_after"] == 4 for s in sixty.values())
    first = summary("lnsafter_uncond_10s")
    assert [(first[m]["optimal_before"], first[m]["optimal_after"]) for m in first] == [
        (19, 17),
        (18, 17),
    ]
    text = (ROOT / "CHANGELOG.md").read_text(encoding="utf-8")
    for quoted in (
        "`cpsat` better on 9 records, worse on 0",
        "`milp` better on 6, worse on 1",
        "20 -> 20 (`cpsat`) and 20 -> 19 (`milp`)",
        "the same on 19 of\n  22 cells",
        "(`cpsat` 19 -> 17, `milp` 18 -> 17)",
    ):
        assert quoted in text, quoted


def test_the_changelog_numbers_of_the_cut_share_run():
    """CHANGELOG (Changed, the LNS first's start plans): the counts it quotes."""
    from bilevel_kit.experiments.kitbench.profiles import read_rows

    results = ROOT / "bench" / "results"
    counts = _summaries("cutshare_10s", ("cpsat", "milp", "lns"))
    assert _moves(counts) == [
        (50, 4, 1),
        (50, 1, 3),
        (50, 1, 3),
    ]
    text = (ROOT / "CHANGELOG.md").read_text(encoding="utf-8")
    for quoted in (
        "`cpsat` better on 4 cells, worse on 1, within 0.1 % of `lns` on 43 -> 47",
        "`milp` better on 1, worse on 3, within 0.1 % of `lns` on 48 -> 48",
        "`lns`, whose\n  code did not change, better on 1, worse on 3",
    ):
        assert quoted in text, quoted
    page = (ROOT / "bench" / "results" / "kitbench_cutshare_10s.md").read_text(encoding="utf-8")
    assert "cpsat 43 before, 47 after" in page and "milp 48 before, 48 after" in page
    case = [
        float(row["makespan"])
        for side in ("before", "after")
        for row in read_rows(results / f"kitbench_cutshare_10s_{side}.csv")
        if (row["instance"], row["method"]) == ("sp_n100_s2_t1_loose_d10", "cpsat")
    ]
    assert case == [2449.0, 2423.0] and "(`cpsat` 2,449 -> 2,423 s)" in text


def test_the_changelog_numbers_of_the_sweep_stall_run():
    """CHANGELOG (Changed, the LNS first's stall of a sweep): the counts it quotes."""
    from bilevel_kit.experiments.kitbench.profiles import read_rows

    results = ROOT / "bench" / "results"
    rows = {
        side: read_rows(results / f"kitbench_sweepstall_10s_{side}.csv")
        for side in ("before", "after")
    }
    counts = _summaries("sweepstall_10s", ("cpsat", "milp", "lns"))
    assert _moves(counts) == [
        (50, 8, 4),
        (50, 4, 5),
        (50, 2, 2),
    ]
    assert [(counts[m]["optimal_before"], counts[m]["optimal_after"]) for m in counts] == [
        (21, 25),
        (21, 24),
        (8, 9),
    ]
    text = (ROOT / "CHANGELOG.md").read_text(encoding="utf-8")
    for quoted in (
        "`cpsat` better on 8 cells, worse on 4, within 0.1 % of\n  `lns` on 45 -> 47 records, "
        "proven optimal 21 -> 25",
        "`milp` better on 4, worse on 5, within\n  0.1 % of `lns` on 47 -> 48, proven optimal "
        "21 -> 24",
        "`lns`, whose code did not change, better\n  on 2, worse on 2",
    ):
        assert quoted in text, quoted
    page = (ROOT / "bench" / "results" / "kitbench_sweepstall_10s.md").read_text(encoding="utf-8")
    assert "cpsat 45 before, 47 after" in page and "milp 47 before, 48 after" in page
    page = (ROOT / "bench" / "results" / "kitbench_sweepstall_250_10s.md").read_text(
        encoding="utf-8"
    )
    assert "cpsat 12 before, 12 after" in page and "milp 11 before, 12 after" in page
    assert "within 0.1 % of `lns` on 12 -> 12 (`cpsat`) and\n  11 -> 12 (`milp`)" in text
    # the misses up to 250 tasks after: the two passes' after rows, every record once
    misses = {}
    for label, records in (("sweepstall_10s", 50), ("sweepstall_250_10s", 12)):
        after = read_rows(results / f"kitbench_{label}_after.csv")
        best = {r["instance"]: float(r["makespan"]) for r in after if r["method"] == "lns"}
        assert len(best) == records
        for m in ("cpsat", "milp"):
            misses[m] = misses.get(m, 0) + sum(
                float(r["makespan"]) > best[r["instance"]] * (1 + 1e-3)
                for r in after
                if r["method"] == m
            )
    assert misses == {"cpsat": 3, "milp": 2}
    at60 = _summaries("sweepstall_60s", ("cpsat", "milp"))
    assert _moves(at60) == [
        (9, 4, 0),
        (9, 3, 0),
    ]
    assert [(at60[m]["optimal_before"], at60[m]["optimal_after"]) for m in at60] == [
        (2, 2),
        (3, 2),
    ]
    page = (ROOT / "bench" / "results" / "kitbench_sweepstall_60s.md").read_text(encoding="utf-8")
    assert "cpsat 4 before, 8 after" in page and "milp 5 before, 8 after" in page
    for quoted in (
        "`cpsat`\n  better on 4 cells, worse on 0, `milp` better on 3, worse on 0",
        "within 0.1 % of `lns` on 4 ->\n  8 and 5 -> 8 of the 9",
        "(proven optimal 3 ->\n  2)",
    ):
        assert quoted in text, quoted
    assert (
        "`cpsat` now misses that goal on 3 of the 62 records up to 250\n  tasks, `milp` on 2"
        in text
    )
    case = [
        float(row["makespan"])
        for side in ("before", "after")
        for row in rows[side]
        if (row["instance"], row["method"]) == ("table_u5_tu_loose_d30", "cpsat")
    ]
    assert case == pytest.approx([2018.9, 2003.815], abs=1e-6)
    assert "(`cpsat` 2,018.9 -> 2,003.815 s at 10 s)" in text


def test_the_changelog_numbers_of_the_dff_rows_run():
    """CHANGELOG (Changed, the LNS windows' dual-feasible-function inequalities)."""
    counts = _summaries("dffrows_10s", ("lns", "cpsat", "milp"))
    assert _moves(counts) == [
        (24, 5, 1),
        (24, 3, 2),
        (24, 3, 1),
    ]
    assert (counts["lns"]["optimal_before"], counts["lns"]["optimal_after"]) == (1, 3)
    text = (ROOT / "CHANGELOG.md").read_text(encoding="utf-8")
    for quoted in (
        "`lns` better on 5\n  cells, worse on 1, proven optimal 1 -> 3",
        "`cpsat` better on 3, worse on 2; `milp` better on\n  3, worse on 1",
    ):
        assert quoted in text, quoted
    page = (ROOT / "bench" / "results" / "kitbench_dffrows_10s.md").read_text(encoding="utf-8")
    assert "the best plan better on 6, worse on 0" in page
    assert "of the pass better on 6 records, worse on none" in text


def test_the_changelog_numbers_of_the_sweepcap_runs():
    """CHANGELOG (Changed, KitBench records) and docs/formulations.md ("The LNS after the
    model"): the counts of the two passes of the change measured and not adopted."""
    at10 = _summaries("sweepcap_10s", ("cpsat", "milp", "lns"))
    assert _moves(at10) == [(50, 3, 3), (50, 2, 2), (50, 4, 2)]
    assert [(at10[m]["optimal_before"], at10[m]["optimal_after"]) for m in ("cpsat", "milp")] == [
        (24, 22),
        (24, 24),
    ]
    at60 = _summaries("sweepcap_60s", ("cpsat", "milp"))
    assert _moves(at60) == [(13, 1, 1), (13, 1, 1)]
    assert (at60["milp"]["optimal_before"], at60["milp"]["optimal_after"]) == (2, 3)
    text = " ".join((ROOT / "CHANGELOG.md").read_text(encoding="utf-8").split())
    for quoted in (
        "At 10 s `cpsat` was better on 3 cells and worse on 3, `milp` better on 2 and worse on "
        "2, and `lns`, whose code did not change, better on 4 and worse on 2",
        "at 60 s on 13 records `cpsat` and `milp` were better on 1 and worse on 1 each",
    ):
        assert quoted in text, quoted
    docs = " ".join((ROOT / "docs" / "formulations.md").read_text(encoding="utf-8").split())
    for quoted in (
        "`cpsat` was better on 3 cells and worse on 3, `milp` better on 2 and worse on 2, `lns` "
        "(the same code in both checkouts) better on 4 and worse on 2; `cpsat` proved 24 -> 22, "
        "`milp` 24 -> 24",
        "`cpsat` and `milp` were better on 1 cell and worse on 1 each, and `milp` proved 2 -> 3",
    ):
        assert quoted in docs, quoted


@pytest.mark.parametrize(
    ("label", "moves", "optimal", "within_after"),
    [
        ("maxrects_10s", [(6, 1), (6, 1), (7, 2)], [(25, 25), (23, 24), (9, 9)], (48, 48)),
        ("maxcap_10s", [(4, 0), (4, 0), (5, 2)], [(23, 23), (21, 21), (8, 8)], (50, 50)),
        ("johnson_10s", [(6, 1), (4, 3), (3, 1)], [(24, 24), (22, 22), (9, 9)], (50, 50)),
        ("i37_10s", [(38, 0), (21, 1), (17, 2)], [(21, 25), (24, 23), (5, 11)], (59, 58)),
    ],
)
def test_the_changelog_numbers_of_the_packer_runs(label, moves, optimal, within_after):
    """CHANGELOG (Changed, the packing oracle's second fast packer) and docs/kitbench.md: each
    method's better / worse cells, proven optima before and after, and the records within
    0.1 % of ``lns`` after, for the packer's run and its cap's."""
    from bilevel_kit.experiments.kitbench.profiles import read_rows

    results = ROOT / "bench" / "results"
    table = ba.cells(
        read_rows(results / f"kitbench_{label}_before.csv"),
        read_rows(results / f"kitbench_{label}_after.csv"),
    )
    counts = [ba.method_summary(table, m) for m in ("cpsat", "milp", "lns")]
    assert [(c["better"], len(c["worse"])) for c in counts] == moves
    assert [(c["optimal_before"], c["optimal_after"]) for c in counts] == optimal
    assert tuple(ba.versus_reference(table, m)["after"] for m in ("cpsat", "milp")) == within_after
    text = " ".join((ROOT / "CHANGELOG.md").read_text(encoding="utf-8").split())
    if label == "maxrects_10s":
        assert "`cpsat` better on 6 cells and worse on 1, `milp` 6 and 1, `lns` 7 and 2" in text
        assert "proven optimal `cpsat` 25 and 25, `milp` 23 and 24" in text
    elif label == "johnson_10s":  # (the Johnson-order incumbent, issue 37)
        assert "`cpsat` better on 6 cells and worse on 1, `milp` 4 and 3 (`lns`, unchanged" in text
        assert "within 0.1 % of `lns` on 48 records before and 50 after" in text
    elif label == "i37_10s":  # (issue 37's closing measurement, up to 250 tasks)
        assert "`cpsat` better on 38 cells and worse on none, `milp` 21 and 1 (`lns` 17 and 2)" in (
            text
        )
        assert "proven optimal `cpsat` 21 -> 25, `milp` 24 -> 23, `lns` 5 -> 11" in text
        assert "`cpsat` 33 -> 59 and `milp` 55 -> 58 of the 62 records" in text
    else:
        assert "better on 4 cells and worse on none, `milp` 4 and none, `lns` 5 and 2" in text
        assert "within 0.1 % of `lns` on all 50 records" in text


def test_the_reading_of_the_issue_37_run() -> None:
    """docs/kitbench.md, after block ``i37_10s``: the record whose proofs the exact models gave up
    for the LNS first, and ``lns``'s spread on its worse record over every committed 10 s pass."""
    from bilevel_kit.experiments.kitbench.profiles import plan_makespan, read_rows

    results = ROOT / "bench" / "results"
    table = ba.cells(
        read_rows(results / "kitbench_i37_10s_before.csv"),
        read_rows(results / "kitbench_i37_10s_after.csv"),
    )
    lost = [c for c in table if c["instance"] == "mixed_u1_tu_loose_d10" and c["method"] != "lns"]
    assert [(c["status_before"], c["status_after"]) for c in lost] == [("optimal", "feasible")] * 2
    assert {round(c["before"], 2) for c in lost} == {round(c["after"], 2) for c in lost} == {847.78}
    assert [round(c["time_before"], 1) for c in lost] == [9.4, 4.7]
    spread = [
        plan_makespan(r)
        for f in sorted(results.glob("kitbench_*_10s_*.csv"))
        for r in read_rows(f)
        if r["instance"] == "wide_n50_s1_t1_tight_d30" and r["method"] == "lns"
    ]
    assert (min(spread), max(spread)) == (1273.0, 1306.0)
    docs = " ".join((ROOT / "docs" / "kitbench.md").read_text(encoding="utf-8").split())
    assert "both models proved 847.78 s before (in 9.4 s and 4.7 s)" in docs
    assert "give it between 1,273 s and 1,306 s" in docs


def test_the_proofs_of_the_issue_37_run_at_60_s() -> None:
    """docs/kitbench.md, after block ``i37_60s`` (and the CHANGELOG): the records up to 60 tasks
    that ``cpsat`` or ``milp`` proved within the minute, before and after, and which stay open."""
    from bilevel_kit.experiments.kitbench.library import Library
    from bilevel_kit.experiments.kitbench.profiles import read_rows

    results = ROOT / "bench" / "results"
    proven = {}
    for side in ("before", "after"):
        rows = read_rows(results / f"kitbench_i37_60s_{side}.csv")
        records = {r["instance"] for r in rows}
        assert len(records) == 37
        proven[side] = {r["instance"] for r in rows if r["status"] == "optimal"}
        assert {r["method"] for r in rows} == {"cpsat", "milp"}
    assert (len(proven["before"]), len(proven["after"])) == (23, 26)
    unproven = sorted(records - proven["after"])
    assert len(unproven) == 11
    library = Library.at(ROOT / "instances" / "kitbench").read()
    status = {r.instance: r.status for r in library}
    assert sum(status[x] != "optimal" for x in unproven) == 7
    docs = " ".join((ROOT / "docs" / "kitbench.md").read_text(encoding="utf-8").split())
    listed = ", ".join(f"`{x}`" for x in unproven[:-1]) + f" and `{unproven[-1]}`"
    assert (
        f"23 of the 37 records before, 26 after. The 11 that neither proves after: {listed}; 7 "
        in docs
    )
    text = " ".join((ROOT / "CHANGELOG.md").read_text(encoding="utf-8").split())
    assert "proven by `cpsat` or `milp` within the minute on 23 -> 26 of the 37" in text
    table = ba.cells(
        read_rows(results / "kitbench_i37_60s_before.csv"),
        read_rows(results / "kitbench_i37_60s_after.csv"),
    )
    counts = [ba.method_summary(table, m) for m in ("cpsat", "milp")]
    assert [(c["better"], len(c["worse"])) for c in counts] == [(12, 1), (11, 1)]
    assert [(c["optimal_before"], c["optimal_after"]) for c in counts] == [(21, 25), (23, 26)]
    assert "`cpsat` 21 -> 25, `milp` 23 -> 26), plans better on 12 and 11 cells, worse on 1" in text
