"""``bilevel-kit repro robust-kitbench`` (docs/robust.md#kitbench-up-to-60-tasks): the records
it takes, the committed CSV's honesty, its sentences (verdicts from the intervals) and a cell
on a small record."""

from __future__ import annotations

from typing import Any

import pytest

from bilevel_kit.experiments.kitbench.library import Library
from bilevel_kit.repro.report import read_rows
from bilevel_kit.repro.robust import EVALUATION
from bilevel_kit.repro.robust_kitbench import (
    LIBRARY,
    QUICK_TASKS,
    KitBenchCell,
    heading,
    kitbench_cell,
    study_cells,
)
from bilevel_kit.repro.robust_kitbench_facts import kitbench_advice
from bilevel_kit.repro.template import ROOT

CSV = ROOT / "paper_repro" / "results" / "robust_kitbench.csv"


def test_the_cells_are_every_record_of_at_most_60_tasks() -> None:
    records = [r for r in Library.at(LIBRARY).read() if r.tasks <= 60]
    cells = study_cells()
    assert [c.instance for c in cells] == [r.instance for r in records]
    assert len(records) == 37 and len(cells) == 37
    assert {c.cv for c in cells} == {0.5} and max(c.tasks for c in cells) == 60
    assert {c.trays for c in cells} == {1, None}  # the library has no 2-tray record
    assert len({c.family for c in cells}) == len({r.family for r in records})
    assert all(len(c.digest) == 12 for c in cells)


def test_a_cell_is_keyed_by_its_hint_too(tmp_path, monkeypatch) -> None:
    """The mean-value solve is hinted with the record's best-known plan: a solutions file that
    ``bench update`` improved makes a new cell key, so a saved cell of the old hint is not
    reused (the instance file alone names the same cell)."""
    from shutil import copytree

    from bilevel_kit.repro import robust_kitbench

    (before,) = study_cells(max_tasks=12)[:1]
    library = tmp_path / "kitbench"
    copytree(LIBRARY, library)
    hint = library / "solutions" / f"{before.instance}.json"
    hint.write_text(hint.read_text() + "\n")  # another file, the same instance file
    monkeypatch.setattr(robust_kitbench, "LIBRARY", library)
    (after,) = study_cells(max_tasks=12)[:1]
    assert after.instance == before.instance and after.digest == before.digest
    assert after.hint_digest != before.hint_digest and after.key() != before.key()


def test_a_quick_run_names_its_own_records() -> None:
    # the --quick run takes the records of at most QUICK_TASKS tasks, not MAX_TASKS
    assert heading(QUICK_TASKS, True).startswith(
        "Robust planning on KitBench up to 12 tasks (QUICK: a reduced run): VSS (s) = "
    )
    assert heading(60, False).startswith("Robust planning on KitBench up to 60 tasks: VSS")
    assert max(c.tasks for c in study_cells(max_tasks=QUICK_TASKS)) == QUICK_TASKS


def test_committed_rows_are_the_cells_and_honest() -> None:
    rows = read_rows(CSV)
    assert [r["instance"] for r in rows] == [c.instance for c in study_cells()]
    best = {r.instance: r.best_known for r in Library.at(LIBRARY).read()}
    assert EVALUATION >= 1000
    for r in rows:
        v = {k: float(r[k]) for k in ("vss", "vss_low", "vss_high", "mean_plan", "saa_plan")}
        assert v["vss_low"] <= v["vss"] <= v["vss_high"]
        assert v["vss"] == pytest.approx(v["mean_plan"] - v["saa_plan"], abs=0.02)
        # hinted with the record's best-known plan: never worse than it (0.01 s rounding)
        assert float(r["mean_plan_deterministic"]) <= best[r["instance"]] + 0.01
        assert float(r["saa_in_sample"]) <= float(r["mean_plan_in_sample"]) + 0.01
        assert int(r["safety_net_fired"]) >= 0


def _row(tasks: int, trays: str, vss: float, half: float, **kw: Any) -> dict[str, Any]:
    base = {"instance": f"r{tasks}", "tasks": tasks, "trays": trays, "cv": 0.5, "vss": vss}
    base |= {"vss_low": vss - half, "vss_high": vss + half, "vss_pct": vss / 4.0}
    base |= {"same_plan": vss == 0.0, "saa_proven": "True", "mean_plan_proven": "True"}
    return base | {"safety_net_fired": 0} | kw


def test_the_verdicts_follow_the_intervals() -> None:
    rows = [
        _row(12, "1", 0.05, 0.04),  # tiny, above 0: pays
        _row(25, "1", 3.0, 4.0),  # large, meets 0: no evidence
        _row(50, "unlimited", -1.0, 0.5),  # below 0
        _row(60, "unlimited", 0.0, 0.0, saa_proven="False"),  # kept, unproven
    ]
    text = kitbench_advice(rows)
    assert text.startswith(
        "Over the 4 records (CV 0.5), the VSS interval lies above 0 in 1 (records of 12 tasks), "
        "below 0 in 1 and meets 0 in 2; the VSS ranges from -1.00 s"
    )
    assert (
        "With 1 tray (2 records of 12 to 25 tasks), the VSS interval lies above 0 in 1 "
        "(records of 12 tasks), below 0 in 0 and meets 0 in 1" in text
    )
    assert (
        "With unlimited trays (2 records of 50 to 60 tasks), the VSS interval lies above 0 in 0, "
        "below 0 in 1 and meets 0 in 1" in text
    )
    assert (
        "In 1 of the 4 records the SAA solve kept the mean-value plan (VSS exactly 0), proven "
        "optimal on its scenarios in 0; in the other 1 (records of 60 tasks) zero says only" in text
    )
    assert "the SAA solve its plan on its scenarios in 3 (records of 12 to 50 tasks)." in text


def test_a_cut_cell_is_named() -> None:
    text = kitbench_advice([_row(12, "1", 1.0, 0.5, safety_net_fired=2), _row(25, "1", 1, 0.5)])
    assert (
        "The wall-clock safety net cut 2 solves in 1 of 2 cells, even computed again (r12: 12"
        in text
    )
    assert "pure function of their configuration and seed." in text


@pytest.mark.slow
def test_a_small_cell_runs_hinted_with_the_best_known_plan() -> None:
    pytest.importorskip("ortools")
    (rec,) = [r for r in Library.at(LIBRARY).read() if r.instance == "sp_n12_s1_t1_tight_d10"]
    cell = KitBenchCell(rec.instance, rec.trays, 0.3, 0, scenarios=2, evaluation=100,
                        wait_and_see=1, family=rec.family, tasks=rec.tasks)  # fmt: skip
    out = kitbench_cell(cell)
    assert out["mean_plan_deterministic"] <= rec.best_known + 1e-6
    assert out["vss_low"] <= out["vss"] <= out["vss_high"]
    assert out["saa_in_sample"] <= out["mean_plan_in_sample"] + 1e-6
    assert out["safety_net_fired"] == 0 and out["cell"]["tasks"] == 12


def test_the_hint_picks_another_optimal_mean_value_plan_on_sp12() -> None:
    """docs/robust.md#kitbench-up-to-60-tasks-the-method: the panel's sp_n12 cell is the
    study's sp12 cell (1 tray, CV 0.5) with the mean-value solve hinted: the same deterministic
    optimum and SAA plan, another mean-value plan, another VSS."""
    (ours,) = [r for r in read_rows(CSV) if r["instance"] == "sp_n12_s1_t1_tight_d10"]
    study = read_rows(ROOT / "paper_repro" / "results" / "robust.csv")
    (theirs,) = [r for r in study if (r["instance"], r["trays"], r["cv"]) == ("sp12", "1", "0.5")]
    for key in ("mean_plan_deterministic", "saa_plan", "saa_in_sample"):
        assert ours[key] == theirs[key], key
    assert ours["mean_plan"] != theirs["mean_plan"] and ours["vss"] != theirs["vss"]


def test_the_committed_advice_counts_the_intervals() -> None:
    """The run of 2026-12-06 (`python paper_repro/rerun.py --only robust_kitbench --jobs 2`)."""
    text = kitbench_advice(read_rows(CSV))
    assert text.startswith(
        "Over the 37 records (CV 0.5), the VSS interval lies above 0 in 5 (records of 12 to 25 "
        "tasks), below 0 in 3 and meets 0 in 29; the VSS ranges from -4.52 s (-0.55 %; "
        "table_u2_tu_tight_d0: 24 tasks, unlimited trays) to 9.44 s (1.35 % of the expected "
        "makespan; sp_n25_s1_tu_loose_d30: 25 tasks, unlimited trays)."
    )
    assert (
        "With 1 tray (19 records of 12 to 60 tasks), the VSS interval lies above 0 in 2 (records "
        "of 12 tasks), below 0 in 0 and meets 0 in 17" in text
    )
    assert (
        "With unlimited trays (18 records of 12 to 60 tasks), the VSS interval lies above 0 in 3 "
        "(records of 12 to 25 tasks), below 0 in 3 and meets 0 in 12" in text
    )
    assert (
        "In 25 of the 37 records the SAA solve kept the mean-value plan (VSS exactly 0), proven "
        "optimal on its scenarios in 2; in the other 23 (records of 24 to 60 tasks)" in text
    )
    assert "(`safety_net_fired` is 0 in all 37 cells)" in text
    assert "the SAA solve its plan on its scenarios in 9 (records of 12 to 27 tasks)." in text
