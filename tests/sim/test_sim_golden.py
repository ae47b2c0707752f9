"""Golden backtests of ``bilevel-kit simulate``: per-replication CSVs of several policies on
the paper's table with supply delays must not change (tests/golden.py). The table has one tray
(the study's protocol); ``sim_optimized_trays_unlimited.csv`` keeps the unlimited-tray run."""

from __future__ import annotations

from pathlib import Path

import pytest
from golden import assert_matches_golden

from bilevel_kit.cli import main

ROOT = Path(__file__).resolve().parents[2]
TABLE = str(ROOT / "instances" / "hrc_table.json")

#: golden file -> simulate arguments (after the instance)
CASES = {
    f"sim_{p}.csv": [
        "--policy",
        p,
        "--reps",
        "3",
        "--seed",
        "5",
        "--mat",
        "leg=60,foot=45",
        "--mttf",
        "90",
    ]
    for p in ("single-task", "whole-assembly", "optimized")
}
CASES["sim_optimized_units2_trays2.csv"] = [
    "--policy",
    "optimized",
    "--reps",
    "2",
    "--seed",
    "3",
    "--units",
    "2",
    "--trays",
    "2",
    "--mat",
    "leg=50",
]


CASES["sim_optimized_trays_unlimited.csv"] = [*CASES["sim_optimized.csv"], "--trays", "unlimited"]


@pytest.mark.parametrize("name", sorted(CASES))
def test_simulate_matches_golden(name: str, tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
    out = tmp_path / name
    assert main(["simulate", TABLE, *CASES[name], "--csv", str(out)]) == 0
    capsys.readouterr()
    assert_matches_golden(out, name)
