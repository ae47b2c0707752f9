"""KitBench's performance profiles and the numbers the pages state about the passes
(docs/kitbench.md#performance-profiles): each reference kept apart, the prose rendered from the
committed CSVs, the run metadata what ran, and the typed claims of the CHANGELOG and the
tutorial checked against their CSVs."""

from __future__ import annotations

import csv
import json
import math
import re

import pytest
from paths import RESULTS, ROOT

from bilevel_kit.experiments.kitbench import Library
from bilevel_kit.experiments.kitbench.profiles import (
    pass_best,
    profile_blocks_in,
    ratios,
    read_rows,
    records_best,
    render_profile_blocks,
    shares,
)


@pytest.fixture(scope="module")
def records():
    return Library.at(ROOT / "instances" / "kitbench").read()


def _row(instance, method, makespan, valid=True):
    return {"instance": instance, "method": method, "makespan": makespan, "valid": valid}


def test_same_pass_reference_is_the_best_of_the_pass_and_no_plan_is_never_within() -> None:
    rows = [
        _row("a", "x", 100.0),
        _row("a", "y", 104.0),
        _row("b", "x", None, False),
        _row("b", "y", 50.0),
        _row("c", "x", 10.0, False),  # an invalid plan is no plan
        _row("c", "y", None, False),
    ]
    assert pass_best(rows) == {"a": 100.0, "b": 50.0}
    r = ratios(rows, ["x", "y"], pass_best(rows))
    assert r["x"] == [1.0, math.inf, math.inf] and r["y"] == [1.04, 1.0, math.inf]
    assert shares(r) == {"x": (1 / 3, 1 / 3), "y": (1 / 3, 2 / 3)}


@pytest.mark.parametrize("label", ["60s", "10s"])
def test_a_pass_is_one_run_and_its_metadata_names_what_ran(label) -> None:
    """The rows of a pass come from the methods and instances its run.json lists (one code
    version: the 10 s pass has no lns, which ran apart, ``kitbench_10s_lns.csv``)."""
    run = json.loads((RESULTS / f"kitbench_{label}_run.json").read_text())
    rows = read_rows(RESULTS / f"kitbench_{label}.csv")
    assert sorted({r["method"] for r in rows}) == sorted(run["methods"])
    assert sorted({r["instance"] for r in rows}) == sorted(run["instances"])
    assert len(rows) == len(run["methods"]) * len(run["instances"])


def test_the_60s_metadata_says_it_is_the_last_invocation_not_the_three_passes() -> None:
    """docs/kitbench.md describes three filtered --jobs 2 invocations; the file records an
    unfiltered --jobs 1 one, so it must say so."""
    run = json.loads((RESULTS / "kitbench_60s_run.json").read_text())
    assert "--jobs 1" in run["command"] and run["filter"] is None
    assert "last invocation" in run["note"] and "tasks<=60" in run["note"]
    docs = (ROOT / "docs" / "kitbench.md").read_text()
    assert "kitbench_60s_run.json" in docs and "`note` says so" in docs


@pytest.mark.parametrize("page", ["docs/kitbench.md", "README.md"])
def test_profile_prose_is_rendered_from_the_passes_csvs(records, page) -> None:
    text = (ROOT / page).read_text(encoding="utf-8")
    assert profile_blocks_in(text), f"{page} has no kitbench-profile block"
    assert render_profile_blocks(text, records, RESULTS) == text, (
        f"{page} disagrees with bench/results/kitbench_*.csv: run python bench/kitbench_docs.py"
    )


def test_the_60s_pass_grades_lns_partly_against_itself(records) -> None:
    """The records' reference includes the plans lns set in the same pass: against the best
    of the pass its share within 1 % is at least its share against the records."""
    rows = read_rows(RESULTS / "kitbench_60s.csv")
    own = shares(ratios(rows, ["lns"], pass_best(rows)))["lns"]
    rec = shares(ratios(rows, ["lns"], records_best(records)))["lns"]
    assert own[0] >= rec[0]


def _issue27_counts(records) -> tuple[int, int, int]:
    """lns at 10 s in bench/results/issue27_kitbench.csv: instances within 0.5 % of the best plan
    of that run (both codes), within 0.5 % of today's records, and instances run."""
    with open(RESULTS / "issue27_kitbench.csv", newline="") as fh:
        rows = list(csv.DictReader(fh))
    best: dict[str, float] = {}
    for r in rows:
        if r["makespan"] and r["valid"] == "True":
            best[r["instance"]] = min(best.get(r["instance"], math.inf), float(r["makespan"]))
    lns = [r for r in rows if r["method"] == "lns" and r["code"] == "after"]
    rec = records_best(records)
    ms = [float(r["makespan"]) if r["makespan"] else math.inf for r in lns]
    run = sum(m <= 1.005 * best[r["instance"]] for m, r in zip(ms, lns, strict=True))
    lib = sum(m <= 1.005 * rec[r["instance"]] for m, r in zip(ms, lns, strict=True))
    return run, lib, len(lns)


@pytest.mark.parametrize("page", ["CHANGELOG.md", "docs/tutorial.md"])
def test_lns_issue27_claim_is_its_csv(records, page) -> None:
    run, lib, n = _issue27_counts(records)
    text = " ".join((ROOT / page).read_text().split())
    assert f"{run} of the {n} instances it ran" in text
    assert f"{lib} of {n} against the library's records" in text


def test_changelog_records_count_is_the_index(records) -> None:
    text = " ".join((ROOT / "CHANGELOG.md").read_text().split())
    optimal = sum(r.status == "optimal" for r in records)
    claims = re.findall(r"(\d+) of (\d+) optimal", text)
    assert claims and all((int(a), int(b)) == (optimal, len(records)) for a, b in claims)
