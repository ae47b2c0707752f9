"""The smaller confusions of a research workflow (issue 40, item 10), each held by a test.

The others of the item have their tests beside the code they touch: ``compare --figures``
announcing its drawing (tests/cli/test_cli.py, the figures test).
"""

from __future__ import annotations

from pathlib import Path

import pytest

from bilevel_kit.experiments.tables import bound_down, table_rows

ROOT = Path(__file__).resolve().parents[2]


@pytest.mark.parametrize(
    ("makespan", "bound"),
    [(936.47, 936.47), (936.474999999, 936.4750000001), (0.1 + 0.2, 0.3), (435.085, 435.08)],
)
def test_a_bound_never_shows_above_its_makespan(makespan: float, bound: float) -> None:
    """A bound within the checker's tolerance of 936.475 showed as 936.48 beside 936.47."""
    row = {"instance": "t", "method": "m", "makespan": makespan, "bound": bound,
           "best_bound": bound, "status": "optimal"}  # fmt: skip
    header, cells = table_rows([row])
    shown = dict(zip(header, cells[0], strict=True))
    shown_makespan = float(shown["makespan (s)"])
    shown_bound, shown_best = float(shown["own bound (s)"]), float(shown["best bound (s)"])
    assert shown_bound <= shown_makespan and shown_best <= shown_makespan
    assert shown_bound >= round(bound, 2) - 0.01


def test_bounds_round_down_but_equal_numbers_stay_equal() -> None:
    assert bound_down(936.4750000001) == 936.47
    assert bound_down(936.47) == 936.47  # 936.47 * 100 is 93646.99999999999
    assert bound_down(430.379) == 430.37 and bound_down(0.0) == 0.0


def test_readme_does_not_call_single_task_a_floor() -> None:
    """greedy-ce can be worse than single-task (README's honest notes): no floor."""
    text = (ROOT / "README.md").read_text(encoding="utf-8")
    row = next(line for line in text.splitlines() if line.startswith("| `single-task` |"))
    assert "floor" not in row.replace("not a floor", "")
    assert "not a floor" in row
    assert "worse than single-task" in text  # the honest note the row points to


def test_two_delivery_time_variants_of_a_product_get_two_names() -> None:
    from bilevel_kit.generate import generate

    assert generate("table", 2)["name"] == "table_u2"
    names = {generate("table", 2, delivery_time=d)["name"] for d in (2, 5, 2.5)}
    assert names == {"table_u2_d2", "table_u2_d5", "table_u2_d2.5"}
    assert generate("stool", 1, delivery_time=0)["name"] == "stool_u1_d0"
    assert generate("table", 2, delivery_time=5, name="mine")["name"] == "mine"  # --name wins
    assert generate("intree", 8, seed=0)["name"] == "intree_n8_s0"  # committed names kept
