"""The README's main job prints the same table on every run (issue: bilevel-milp, cut at its
60 s limit, made three runs print three tables): two runs of ``compare`` with the default
set of methods, each in a process of its own, write the same Markdown table apart from the
wall-time column, and every plan in it is valid and reached without a time limit."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
BIN = Path(sys.executable).parent


def _table(md: Path) -> list[list[str]]:
    """The Markdown table's cells without the wall-time column."""
    lines = [line for line in md.open() if not line.startswith("|---")]
    rows = [[c.strip() for c in line.strip("|\n").split("|")] for line in lines]
    drop = rows[0].index("time (s)")
    return [r[:drop] + r[drop + 1 :] for r in rows]


@pytest.mark.slow
def test_two_runs_of_the_main_job_print_the_same_table(tmp_path):
    tables = []
    for run in ("a", "b"):
        md = tmp_path / run / "compare.md"
        done = subprocess.run(
            [
                *(str(BIN / "bilevel-kit"), "compare", str(ROOT / "instances" / "hrc_table.json")),
                *("--methods", "default", "--md", str(md), "-q"),
            ],
            capture_output=True,
            text=True,
            timeout=600,
        )
        assert done.returncode == 0, done.stderr
        tables.append(_table(md))
    assert tables[0] == tables[1]
    header, *rows = tables[0]
    col = {name: header.index(name) for name in ("method", "makespan (s)", "status", "valid")}
    assert [r[col["method"]] for r in rows] == [
        "single-task",
        "whole-assembly",
        "greedy-ce",
        "cpsat",
        "milp",
        "lns",
    ]
    assert {r[col["valid"]] for r in rows} == {"True"}
    assert {r[header.index("limit hit")] for r in rows} == {"no"}
    by = {r[col["method"]]: r for r in rows}
    assert by["cpsat"][col["makespan (s)"]] == by["milp"][col["makespan (s)"]] == "435.08"
    assert by["cpsat"][col["status"]] == by["milp"][col["status"]] == "optimal"
    assert by["greedy-ce"][col["makespan (s)"]] == "463.78"
