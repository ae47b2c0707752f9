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
