"""``bilevel-kit repro robust-sim`` (docs/robust.md#in-the-shop-floor-simulation-the-method):
the committed CSV's consistency, its rows from a cell record, and the page's drift test."""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest

from bilevel_kit.errors import UsageError
from bilevel_kit.repro.report import read_rows
from bilevel_kit.repro.robust import CVS, INSTANCES, TRAYS
from bilevel_kit.repro.robust_sim import (
    CELLS,
    COLUMNS,
    FIXED,
    LAWS,
    ONLINE,
    REPS,
    ROBUST_SIM_TABLES,
    rows_of,
    run_robust_sim,
    select_cells,
    sim_detail_markdown,
    sim_summary_markdown,
    sim_vss_markdown,
)
from bilevel_kit.repro.template import ROOT, check

CSV = ROOT / "paper_repro" / "results" / "robust_sim.csv"
ROBUST = ROOT / "paper_repro" / "results" / "robust.csv"


def _by_cell(rows):
    out: dict[tuple[str, str, str, str], dict[str, dict]] = {}
    for r in rows:
        key = (r["instance"], r["trays"], r["cv"], r["law"])
        out.setdefault(key, {})[r["policy"]] = r
    return out


def test_committed_rows_are_paired_and_complete() -> None:
    rows = read_rows(CSV)
    cells = _by_cell(rows)
    assert {k[3] for k in cells} == set(LAWS) and len(cells) >= 4
    for key, pols in cells.items():
        assert list(pols) == [*FIXED, *ONLINE], key
        base = float(pols["mean-plan"]["makespan"])
        assert float(pols["mean-plan"]["gain"]) == 0.0
        for name, r in pols.items():
            assert int(r["reps"]) == REPS
            if r["error"]:  # only an online policy may fail in a cell, and has no numbers
                assert name in ONLINE and r["makespan"] == r["gain"] == "", (key, name)
                continue
            assert float(r["gain_low"]) <= float(r["gain"]) <= float(r["gain_high"])
            # the gain is the difference of the means on the same seeds (paired)
            assert float(r["gain"]) == pytest.approx(base - float(r["makespan"]), abs=0.02)
            assert float(r["makespan_low"]) <= float(r["makespan"]) <= float(r["makespan_high"])
        # the SAA solve is hinted with the mean-value plan: never worse on its own scenarios
        assert float(pols["saa-plan"]["in_sample"]) <= float(pols["mean-plan"]["in_sample"])
        assert float(pols["saa-plan"]["committed_in_sample"]) > 0
    # a fixed plan runs its own kits under either law (never re-planned)
    for key, pols in cells.items():
        other = cells[(*key[:3], LAWS[1] if key[3] == LAWS[0] else LAWS[0])]
        for name in FIXED:
            assert pols[name]["n_kits"] == other[name]["n_kits"], (key, name)


def test_the_default_cells_are_the_whole_study_and_the_committed_csv_has_them() -> None:
    assert len(CELLS) == len(set(CELLS)) == len(INSTANCES) * len(TRAYS) * len(CVS) == 24
    assert select_cells() == CELLS
    labels = {"1": 1, "2": 2, "unlimited": None}
    done = {(r["instance"], labels[r["trays"]], float(r["cv"])) for r in read_rows(CSV)}
    assert done == set(CELLS)


def test_the_recomputed_plans_give_the_committed_study_in_every_cell() -> None:
    """docs/robust.md: the study is a pure function of its cells (no safety net fired), so
    the recomputed mean-value and SAA plans give robust.csv's numbers in all 24 cells."""
    committed = {(r["instance"], r["trays"], r["cv"]): r for r in read_rows(ROBUST)}
    rows = [r for r in read_rows(CSV) if r["law"] == "task"]
    for r in rows:
        old = committed[(r["instance"], r["trays"], r["cv"])]
        if r["policy"] == "mean-plan":
            assert float(r["timeline_makespan"]) == float(old["mean_plan"]), r
        if r["policy"] == "saa-plan" and r["reproduced"] != "True":
            assert float(r["in_sample"]) < float(r["committed_in_sample"]), r
    saa = [r for r in rows if r["policy"] == "saa-plan"]
    assert sum(r["reproduced"] == "True" for r in saa) == 24
    for r in saa:  # the same plans: the same sample average on the scenarios optimised on
        assert float(r["in_sample"]) == float(r["committed_in_sample"]), r


def test_select_cells_is_the_product_of_the_lists_given() -> None:
    assert select_cells(["sp12"], None, [0.3]) == (
        ("sp12", 1, 0.3),
        ("sp12", 2, 0.3),
        ("sp12", None, 0.3),
    )
    assert select_cells(None, [None], [0.5]) == (("table", None, 0.5), ("sp12", None, 0.5))
    with pytest.raises(UsageError, match="unknown instance 'chair'; the study's are table, sp12"):
        select_cells(["chair"])


def test_the_cli_selects_cells(monkeypatch, capsys, tmp_path: Path) -> None:
    import bilevel_kit.repro.robust_sim as mod
    from bilevel_kit.cli import main

    seen: dict = {}
    monkeypatch.setattr(mod, "run_robust_sim", lambda out, **kw: seen.update(kw) or {})
    out = ["--out", str(tmp_path / "o")]
    argv = ["repro", "robust-sim", "--instances", "sp12", "--trays", "1,unlimited"]
    assert main([*argv, "--cvs", "0.3", *out]) == 0
    assert seen["cells"] == (("sp12", 1, 0.3), ("sp12", None, 0.3))
    assert main(["repro", "robust-sim", "--reps", "3", *out]) == 0
    assert seen["cells"] is None and seen["reps"] == 3  # the default cells
    assert main(["repro", "robust-sim", "--trays", "0", *out]) == 2
    assert "expected an integer >= 1 or 'unlimited', got '0'" in capsys.readouterr().err


def test_the_task_law_agrees_with_the_timeline() -> None:
    """Under the timeline's own law the simulated VSS interval meets the timeline's."""
    for (_, _, _, law), pols in _by_cell(read_rows(CSV)).items():
        if law != "task":
            continue
        saa = pols["saa-plan"]
        assert float(saa["gain_low"]) <= float(saa["timeline_vss_high"])
        assert float(saa["gain_high"]) >= float(saa["timeline_vss_low"])


def test_rows_of_a_record_say_whether_the_committed_plans_were_reproduced() -> None:
    committed = next(r for r in read_rows(ROBUST) if r["instance"] == "table")
    est = {
        "mean-plan": {"mean": float(committed["mean_plan"]), "half": 1.0, "n": 1000},
        "saa-plan": {"mean": float(committed["saa_plan"]), "half": 1.0, "n": 1000},
        "vss": {"mean": float(committed["vss"]), "half": 0.5, "n": 1000},
    }
    runs = {name: {"makespan": [400.0, 410.0, 420.0], "n_kits": [5, 5, 6]} for name in FIXED}
    runs["saa-plan"]["makespan"] = [398.0, 409.0, 417.0]
    cell = {"instance": "table", "trays": int(committed["trays"]), "cv": float(committed["cv"])}
    rec = {"cell": {**cell, "seed": 0, "reps": 3}, "timeline": est, "runs": {"task": runs}}
    rows = rows_of([rec], ROBUST)
    assert [r["policy"] for r in rows] == list(FIXED)
    assert rows[1]["gain"] == pytest.approx(2.0) and rows[0]["n_kits"] == pytest.approx(5.33)
    assert all(r["reproduced"] is True for r in rows)
    assert rows[0]["committed_vss"] == float(committed["vss"])
    est["vss"]["mean"] += 0.5
    assert rows_of([rec], ROBUST)[0]["reproduced"] is False
    assert "| table | 1 |" in sim_vss_markdown(rows)
    assert set(ROBUST_SIM_TABLES) == {"robust_sim_summary", "robust_sim_vss", "robust_sim_detail"}


def test_a_failed_online_policy_is_a_row_with_its_error_not_a_failed_cell() -> None:
    runs = {name: {"makespan": [400.0, 410.0, 420.0], "n_kits": [5, 5, 6]} for name in FIXED}
    runs["saa-plan"]["makespan"] = [398.0, 409.0, 417.0]
    runs["cpsat-rolling"] = {"makespan": [399.0, 408.0, 421.0], "n_kits": [5, 5, 5]}
    runs["optimized-adaptive"] = {"error": "KitDoesNotFit: t4, t5 do not fit"}
    est = {k: {"mean": 1.0, "half": 0.5, "n": 1000} for k in ("mean-plan", "saa-plan", "vss")}
    cell = {"instance": "sp12", "trays": 1, "cv": 0.3, "seed": 0, "reps": 3}
    in_sample = {"mean-plan": 376.36, "saa-plan": 376.36}  # the committed cell's
    rec = {"cell": cell, "timeline": est, "runs": {"task": runs}, "in_sample": in_sample}
    rows = rows_of([rec], ROBUST)
    assert [r["policy"] for r in rows] == [*FIXED, *ONLINE] and list(rows[-1]) == list(COLUMNS)
    failed = rows[-1]
    assert failed["error"] == "KitDoesNotFit: t4, t5 do not fit"
    assert failed["makespan"] == failed["gain_low"] == "" and failed["law"] == "task"
    assert all(r["error"] == "" for r in rows[:-1]) and rows[2]["gain"] == pytest.approx(0.67)
    assert sim_detail_markdown(rows).splitlines()[-1].endswith("| failed | - | - |")
    summary = sim_summary_markdown(rows)
    assert (
        "`optimized-adaptive` failed in 1 cell x law pairs (every cell of sp12): "
        "KitDoesNotFit: t4, t5 do not fit." in summary
    )
    assert "`cpsat-rolling` gains 0.67 s over the mean-value plan" in summary
    assert "`optimized-adaptive` gains" not in summary  # it ran in no cell
    assert summary.startswith(
        "The recomputed plans reproduce the committed study in 0 of 1 cells; in the other 1 "
        "the recomputed SAA plan is better in sample than the committed one in 0, equal in 1 "
        "and worse in 0. Recomputed, the timeline VSS is 1.00 s, its interval above 0 in 1 "
        "cells and below 0 in 0."
    )


def test_the_page_is_rendered_from_the_csv(tmp_path: Path) -> None:
    """docs/robust.md's simulation tables match robust_sim.csv; an edited number is caught."""
    assert not [d for d in check(ROOT) if "robust.md" in d]
    shutil.copytree(ROOT / "paper_repro", tmp_path / "paper_repro")
    (tmp_path / "docs").mkdir()
    for name in ("robust.md", "simulation.md", "stations.md", "reproduction.md"):
        shutil.copyfile(ROOT / "docs" / name, tmp_path / "docs" / name)
    csv = tmp_path / "paper_repro" / "results" / "robust_sim.csv"
    lines = csv.read_text().splitlines()
    head = lines[0].split(",")
    i = next(k for k, line in enumerate(lines) if ",saa-plan," in line)
    cells = lines[i].split(",")
    cells[head.index("gain")] = "98.76"
    lines[i] = ",".join(cells)
    csv.write_text("\n".join(lines) + "\n")
    diffs = [d for d in check(tmp_path) if "robust.md (committed)" in d]
    assert diffs and "98.76" in diffs[0]


@pytest.mark.slow
def test_a_two_replication_cell_writes_its_outputs_and_resumes(tmp_path: Path) -> None:
    pytest.importorskip("ortools")
    res = run_robust_sim(tmp_path, quick=True, reps=2)
    assert res["failed"] == [] and res["computed"] == res["cells"] == 1
    assert len(res["rows"]) == len(LAWS) * (len(FIXED) + len(ONLINE))
    assert "simulated VSS" in (tmp_path / "robust_sim.md").read_text()
    again = run_robust_sim(tmp_path, quick=True, reps=2)
    assert again["computed"] == 0 and again["rows"] == res["rows"]
