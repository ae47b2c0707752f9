"""The work cell a plan was solved in, recorded in its solution file (``solve --work-cell``)
and used by ``execute``, which warns when given another one (docs/formats.md,
docs/execution.md#the-work-cell)."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from bilevel_kit import solution as solution_io
from bilevel_kit.cli import main
from bilevel_kit.errors import SolutionError
from bilevel_kit.sawyer import workcell as wc

ROOT = Path(__file__).resolve().parents[2]
TABLE = ROOT / "instances" / "hrc_table.json"
CELL = ROOT / "examples" / "hrc_table_cell.json"


def test_the_record_round_trips_and_its_digest_ignores_layout(tmp_path):
    cell = wc.load_work_cell(CELL)
    doc = json.loads(CELL.read_text())
    shuffled = tmp_path / "shuffled.json"
    shuffled.write_text(json.dumps(dict(reversed(list(doc.items())))))  # one line, keys reversed
    assert wc.cell_digest(wc.load_work_cell(shuffled)) == wc.cell_digest(cell)
    record = wc.cell_record(cell)
    assert record["path"] == str(CELL) and len(record["sha256"]) == 64
    assert record["cell"] == doc
    again = wc.recorded_cell(record, "sol.json")
    assert (again.geometry, again.grasp_widths) == (cell.geometry, cell.grasp_widths)
    other = wc.parse_work_cell({**doc, "grasp_widths": {"foot": 4.0}})
    assert wc.cell_digest(other) != record["sha256"]
    with pytest.raises(
        wc.WorkCellFileError, match=r"sol.json: \$.work_cell.sha256: does not match"
    ):
        wc.recorded_cell({**record, "cell": {**doc, "grasp_widths": {"foot": 4.0}}}, "sol.json")


@pytest.fixture(scope="module")
def solved(tmp_path_factory):
    """Single Task's plan of the table solved in the example cell, and without a cell."""
    out = tmp_path_factory.mktemp("cellsol")
    with_cell, without = out / "with.json", out / "without.json"
    argv = ["solve", str(TABLE), "-m", "single-task", "-q"]
    assert main([*argv, "--work-cell", str(CELL), "--out", str(with_cell)]) == 0
    assert main([*argv, "--out", str(without)]) == 0
    return with_cell, without


def test_solve_records_the_cell_and_old_files_have_none(solved):
    with_cell, without = solved
    record = solution_io.read(with_cell).work_cell
    assert record == wc.cell_record(wc.load_work_cell(CELL))
    assert solution_io.read(without).work_cell is None
    assert "work_cell" not in json.loads(without.read_text())


def _execute(capsys, sol: Path, out: Path, *extra: str) -> tuple[int, str, str]:
    """Kit 1 of the plan, reported (``warn``: the plan was solved without finger room, so the
    default ``auto`` check would refuse it in its declared cell)."""
    argv = ["execute", str(TABLE), str(sol), "--kit", "1", "--format", "ros1", "--bag", str(out)]
    argv += ["--grasp-check", "warn"]
    code = main([*argv, *extra])
    text, err = capsys.readouterr()
    return code, text, err


def _grip(text: str) -> str:
    (line,) = [s for s in text.splitlines() if s.startswith("gripper:")]
    return line


def test_execute_uses_the_recorded_cell(capsys, solved, tmp_path):
    """Without --work-cell the recorded cell applies: the same gripper verdicts as with the
    cell given explicitly, none of the no-cell hint, and a line saying so."""
    with_cell, without = solved
    capsys.readouterr()
    code, text, err = _execute(capsys, with_cell, tmp_path / "a")
    assert code == 0 and err == ""
    assert f"work cell: {CELL}, as recorded in {with_cell}" in text.splitlines()
    code, explicit, err = _execute(capsys, with_cell, tmp_path / "b", "--work-cell", str(CELL))
    assert code == 0 and err == "" and "work cell:" not in explicit
    assert _grip(text) == _grip(explicit)
    code, bare, _ = _execute(capsys, without, tmp_path / "c")
    assert code == 0 and "work cell:" not in bare
    assert "with --work-cell" in _grip(bare) and "with --work-cell" not in _grip(text)


def test_execute_warns_on_another_cell(capsys, solved, tmp_path):
    with_cell, _ = solved
    other = tmp_path / "other.json"
    doc = json.loads(CELL.read_text())
    other.write_text(json.dumps({**doc, "gripper": {**doc["gripper"], "clearance": 1.0}}))
    capsys.readouterr()
    code, _, err = _execute(capsys, with_cell, tmp_path / "a", "--work-cell", str(other))
    assert code == 0
    assert err.strip() == (
        f"warning: --work-cell {other} is not the work cell {with_cell} was solved in "
        f"({CELL}, recorded in the file); executing in {other}"
    )


def test_a_malformed_record_is_refused(solved, tmp_path):
    with_cell, _ = solved
    doc = json.loads(with_cell.read_text())
    doc["work_cell"]["sha256"] = "not a digest"
    bad = tmp_path / "bad.json"
    bad.write_text(json.dumps(doc))
    with pytest.raises(SolutionError, match="work_cell"):
        solution_io.read(bad)
