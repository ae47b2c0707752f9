"""Golden backtests of ``bilevel-kit repro user-study --quick`` and ``repro fig6 --quick``:
their CSV outputs (and Figure 6's cell file names, i.e. the resume keys) must not change
(tests/golden.py)."""

from __future__ import annotations

from pathlib import Path

import pytest
from golden import assert_matches_golden, assert_names_match_golden

from bilevel_kit.cli import main


def test_user_study_quick_matches_golden(tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
    assert main(["repro", "user-study", "--quick", "--out", str(tmp_path)]) == 0
    capsys.readouterr()
    for name in ("user_study_runs.csv", "user_study_predictions.csv"):
        assert_matches_golden(tmp_path / name, name)


def test_fig6_quick_matches_golden(tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
    assert main(["repro", "fig6", "--quick", "--reps", "2", "--out", str(tmp_path)]) == 0
    capsys.readouterr()
    assert_matches_golden(tmp_path / "fig6_cells.csv", "fig6_cells.csv")
    names = [p.name for p in (tmp_path / "cells").glob("*.json")]
    assert_names_match_golden(names, "fig6_cell_files.txt")
