"""The committed KitBench library (instances/kitbench/, docs/kitbench.md): every record holds
(what ``bench verify`` checks, run by CI), every instance is what its command makes, the design
covers what the library promises, and the published tables are the index's."""

from __future__ import annotations

import shlex
from pathlib import Path

import pytest

from bilevel_kit.cli import main
from bilevel_kit.experiments.kitbench import Library, verify
from bilevel_kit.experiments.kitbench.report import blocks_in, render_blocks, size_step

ROOT = Path(__file__).resolve().parents[2]
FOLDER = ROOT / "instances" / "kitbench"


@pytest.fixture(scope="module")
def library() -> Library:
    return Library.at(FOLDER)


def test_every_record_holds(library):
    records, problems = verify(library)
    assert [p.line() for p in problems] == []
    assert all(r.best_known is not None and r.best_bound is not None for r in records)


def test_the_design(library):
    records = library.read()
    assert len(records) >= 60
    assert {r.family for r in records} == {
        "table",
        "mixed",
        "stool",
        "intree",
        "series-parallel",
        "wide",
        "sparse",
    }
    assert len({size_step(r.tasks) for r in records}) >= 7
    assert min(r.tasks for r in records) <= 12 and max(r.tasks for r in records) >= 990
    assert sum(25 <= r.tasks <= 250 for r in records) > len(records) / 2
    assert {r.trays for r in records} == {1, None}
    assert {0.0, 10.0, 30.0} <= {r.delivery_time for r in records}
    assert {r.tray for r in records} == {"tight", "loose"}
    for family in {r.family for r in records}:  # every family has both tray settings
        assert {r.trays for r in records if r.family == family} == {1, None}, family


def test_every_instance_is_what_its_command_makes(library, tmp_path, capsys):
    from bilevel_kit.instance import load

    for rec in library.read():
        path = library.instance_path(rec.instance)
        command = load(path).generated_by
        assert command.startswith("bilevel-kit generate "), rec.instance
        again = tmp_path / f"{rec.instance}.json"
        assert main([*shlex.split(command)[1:], "--out", str(again)]) == 0
        assert again.read_bytes() == path.read_bytes(), rec.instance
    capsys.readouterr()


@pytest.mark.parametrize("page", ["docs/kitbench.md", "instances/kitbench/README.md", "README.md"])
def test_published_tables_are_the_index(library, page):
    text = (ROOT / page).read_text(encoding="utf-8")
    assert blocks_in(text), f"{page} has no kitbench block"
    assert render_blocks(text, library.read()) == text, (
        f"{page} disagrees with instances/kitbench/index.csv: run python bench/kitbench_docs.py"
    )


def _pass_in_the_records(library, stem: str):
    """A committed pass (``bench/results/kitbench_STEM``'s rows and run) and what the index's
    provenance columns name its commit on: {record: best-known} and {record: best bound}."""
    import json

    from bilevel_kit.experiments.kitbench.profiles import read_rows

    results = ROOT / "bench" / "results"
    run = json.loads((results / f"kitbench_{stem}_run.json").read_text())
    rows = {(r["instance"], r["method"]): r for r in read_rows(results / f"kitbench_{stem}.csv")}
    records = library.read()
    commit = run["commit"]
    plans = {r.instance: r for r in records if r.plan is not None and r.plan.commit == commit}
    bounds = {r.instance: r for r in records if r.bound is not None and r.bound.commit == commit}
    return run, rows, plans, bounds


def _quoted_in_the_records_page(*quoted: str) -> None:
    docs = " ".join((ROOT / "docs" / "kitbench.md").read_text(encoding="utf-8").split())
    for text in quoted:
        assert text in docs, text


def test_the_records_name_the_bounds_the_sweepcap_pass_raised(library):
    """docs/kitbench.md#the-records, step 10: ``bench update`` from the ``before`` side of the
    committed pass ``sweepcap_10s`` raised 3 bounds to the 1 s grid and set no plan; the index's
    provenance columns name that pass's commit exactly there, with the values its rows hold."""
    run, rows, plans, bounds = _pass_in_the_records(library, "sweepcap_10s_before")
    assert {name: r.best_bound for name, r in bounds.items()} == {
        "intree_n100_s1_t1_tight_d30": 2550.0,
        "wide_n100_s2_tu_tight_d30": 2626.0,
        "sparse_n100_s1_tu_tight_d30": 2449.0,
    }
    for name, r in bounds.items():
        assert (r.bound.method, r.bound.time_limit, r.status) == ("cpsat", 10.0, "open")
        assert float(rows[(name, "cpsat")]["bound"]) == r.best_bound
    assert not plans
    _quoted_in_the_records_page(
        "`intree_n100_s1_t1_tight_d30` 2,549.6 -> 2,550 s",
        "`wide_n100_s2_tu_tight_d30` 2,625.3 -> 2,626 s",
        "`sparse_n100_s1_tu_tight_d30` 2,448.4 -> 2,449 s",
        f"commit `{run['commit']}`",
        "(957 s of wall time, 677 MB peak",
    )
    assert run["wall_s"] == pytest.approx(957.4, abs=0.1)


def test_the_records_name_the_plans_the_maxrects_pass_set(library):
    """docs/kitbench.md#the-records, step 11: ``bench update`` from the ``after`` side of the
    committed pass ``maxrects_10s`` set 2 plans (``lns``'s) and no bound; the index's provenance
    names that pass's commit on the one step 13 did not improve again, with the makespan its
    rows hold."""
    run, rows, plans, bounds = _pass_in_the_records(library, "maxrects_10s_after")
    assert {name: r.best_known for name, r in plans.items()} == {"mixed_u5_t1_loose_d0": 3926.9}
    for name, r in plans.items():
        assert (r.plan.method, r.plan.time_limit) == ("lns", 10.0)
        assert float(rows[(name, "lns")]["makespan"]) == pytest.approx(r.best_known, abs=1e-6)
    assert not bounds
    _quoted_in_the_records_page(
        "`mixed_u5_t1_loose_d0` 3,930.9 -> 3,926.9 s",
        "`mixed_u5_tu_loose_d30` 4,003.9 -> 3,998.9 s",
        f"commit `{run['commit']}`",
        "(921 s of wall time, 651 MB peak",
    )
    assert run["wall_s"] == pytest.approx(921.1, abs=0.1)
