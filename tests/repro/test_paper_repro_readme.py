"""paper_repro/README.md's result tables are rendered from the committed CSVs in
paper_repro/results/ (bilevel_kit.repro.report): the test fails when they disagree."""

from __future__ import annotations

from pathlib import Path

from bilevel_kit.repro.report import BLOCKS, blocks_in, read_rows, render_readme

ROOT = Path(__file__).resolve().parents[2] / "paper_repro"


def test_readme_tables_match_the_result_files() -> None:
    text = (ROOT / "README.md").read_text()
    assert set(blocks_in(text)) == set(BLOCKS)
    assert render_readme(text, ROOT / "results") == text, (
        "paper_repro/README.md disagrees with paper_repro/results/: "
        "run python paper_repro/render_readme.py"
    )


def test_every_result_file_is_small_and_used() -> None:
    files = {p.name for p in (ROOT / "results").glob("*.csv")}
    assert {f for f, _ in BLOCKS.values()} <= files
    for name in files:
        assert (ROOT / "results" / name).stat().st_size < 50_000, name
        assert read_rows(ROOT / "results" / name), name
