"""The reproduction's documents (paper_repro/README.md, docs/reproduction.md and the adaptive
section of docs/simulation.md; the top-level README carries no reproduction number) are
rendered from templates and the committed CSVs in paper_repro/results/
(bilevel_kit.repro.template): the tests fail when a number in them drifts from the CSVs, and
when a template types a number instead of taking it from a CSV."""

from __future__ import annotations

import re
import shutil
from pathlib import Path

import pytest

from bilevel_kit.repro.report import read_rows, tables
from bilevel_kit.repro.template import PLACEHOLDER, ROOT, TARGETS, check, typed_numbers

RESULTS = ROOT / "paper_repro" / "results"


def test_documents_match_their_templates_and_the_csvs() -> None:
    diffs = check(ROOT)
    assert not diffs, (
        "a rendered document disagrees with paper_repro/results/ (run python "
        "paper_repro/render_readme.py):\n\n" + "\n\n".join(diffs)
    )


@pytest.mark.parametrize("target", TARGETS, ids=lambda t: t.template)
def test_templates_type_no_result(target) -> None:
    text = (ROOT / target.template).read_text()
    assert typed_numbers(text) == [], f"{target.template} types numbers: take them from a CSV"


def test_every_result_file_is_small_and_used() -> None:
    used = {
        m.group(1) for t in TARGETS for m in PLACEHOLDER.finditer((ROOT / t.template).read_text())
    }
    files = {p.name for p in RESULTS.glob("*.csv")}
    wanted = {tables()[name[len("table:") :]] for name in used if name.startswith("table:")}
    assert wanted <= files, wanted - files
    for name in files:
        assert (RESULTS / name).stat().st_size < 50_000, name
        assert read_rows(RESULTS / name), name


def _copy_repo(dst: Path) -> None:
    """The files the rendering reads: templates, results and the rendered documents."""
    shutil.copytree(ROOT / "paper_repro" / "templates", dst / "paper_repro" / "templates")
    shutil.copytree(RESULTS, dst / "paper_repro" / "results")
    for t in TARGETS:
        (dst / t.output).parent.mkdir(parents=True, exist_ok=True)
        shutil.copyfile(ROOT / t.output, dst / t.output)


def test_an_edited_number_is_caught(tmp_path: Path) -> None:
    _copy_repo(tmp_path)
    readme = tmp_path / "paper_repro" / "README.md"
    text = readme.read_text()
    m = re.search(r"\*\*(\d+) of (\d+) predicted paper numbers", text)
    assert m is not None
    edited = f"**{int(m.group(1)) - 1} of {m.group(2)} predicted paper numbers"
    readme.write_text(text.replace(m.group(0), edited, 1))
    (diff,) = check(tmp_path)
    assert f"-{edited}" in diff and f"+{m.group(0)}" in diff
    assert "README.md (rendered from the CSVs)" in diff


def test_a_changed_csv_is_caught(tmp_path: Path) -> None:
    _copy_repo(tmp_path)
    summary = tmp_path / "paper_repro" / "results" / "user_study_summary.csv"
    lines = summary.read_text().splitlines()
    i = next(k for k, line in enumerate(lines) if line.startswith("predicted_inside,"))
    lines[i] = "predicted_inside,0"
    summary.write_text("\n".join(lines) + "\n")
    (diff,) = check(tmp_path)  # the count is quoted in paper_repro/README.md
    assert "0 of" in diff and "README.md (rendered from the CSVs)" in diff


def test_every_result_file_comes_from_a_rerun_step() -> None:
    """paper_repro/rerun.py copies every committed CSV (none is made by hand) and the timing
    table names only its steps."""
    import importlib.util

    spec = importlib.util.spec_from_file_location("rerun", ROOT / "paper_repro" / "rerun.py")
    assert spec is not None and spec.loader is not None
    rerun = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(rerun)
    copied = {dst for _, _, copies in rerun.STEPS.values() for dst in copies.values()}
    csvs = {d for d in copied if not d.startswith("figures/")}
    assert csvs | {"timing.csv"} == {p.name for p in RESULTS.glob("*.csv")}
    for dst in copied - csvs:
        assert (ROOT / "docs" / dst).exists(), dst
    assert {r["run"] for r in read_rows(RESULTS / "timing.csv")} <= set(rerun.STEPS)
