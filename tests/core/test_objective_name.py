"""One name for the paper's objective (issue 40, item 2): J, explained where it is printed.

The paper scores kits with F (Section IV-A, Eqs. 3-7); ``bilevel-milp`` minimises F summed over
a plan's kits, which every output and page calls J
(docs/guide.md#exact-baselines-bilevel_kitmodels).
"""

from __future__ import annotations

import argparse
import re
from pathlib import Path

import pytest

from bilevel_kit.cli import main
from bilevel_kit.cli.compare import _report
from bilevel_kit.objectives import J_MEANING

ROOT = Path(__file__).resolve().parents[2]
PAGES = ["README.md", "docs/guide.md", "docs/tutorial.md", "docs/cli.md", "docs/index.md"]


def test_methods_names_j_and_explains_it(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["methods"]) == 0
    out = capsys.readouterr().out
    row = next(line for line in out.splitlines() if line.startswith("bilevel-milp"))
    assert "the paper's objective J " in row
    assert out.rstrip().endswith(f"{J_MEANING}.")
    assert "kit score F (Eqs. 3-7" in J_MEANING and "not the makespan" in J_MEANING
    assert "objective F" not in out


@pytest.mark.parametrize("page", PAGES)
def test_pages_call_bilevel_milps_objective_j(page: str) -> None:
    text = (ROOT / page).read_text(encoding="utf-8")
    assert not re.search(r"objective F\b|optimum of F\b", text), page
    rows = [line for line in text.splitlines() if line.startswith("| `bilevel-milp`")]
    assert all("objective J" in row for row in rows), (page, rows)


def test_compare_explains_a_status_for_j(capsys: pytest.CaptureFixture[str]) -> None:
    record = {
        "instance": "t",
        "method": "bilevel-milp",
        "makespan": 451.78,
        "status": "feasible (for J)",
        "valid": True,
    }
    args = argparse.Namespace(figures=None, csv=None, md=None)
    assert _report(args, [record]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert "feasible (for J)" in lines[2]
    assert lines[3] == f"(for J): the status is about J, not the makespan. {J_MEANING}."
    _report(args, [{**record, "status": "optimal"}])
    assert "for J" not in capsys.readouterr().out
