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
    assert names == {"table_u2", "table_u2_d5", "table_u2_d2.5"}  # 2 s is the table's own d
    assert generate("stool", 1, delivery_time=0)["name"] == "stool_u1_d0"
    assert generate("table", 2, delivery_time=5, name="mine")["name"] == "mine"  # --name wins
    assert generate("intree", 8, seed=0)["name"] == "intree_n8_s0"  # committed names kept


def test_seed_stations_and_delivery_time_have_their_own_tokens() -> None:
    """``_s`` was both the seed and the stations: ``intree_n8_s2`` could be either (issue 40,
    item 10); the random families' ``--d`` variants shared one name."""
    from bilevel_kit.generate import generate

    names = {
        "seed 2": generate("intree", 8, seed=2)["name"],
        "seed 0, 2 stations": generate("intree", 8, seed=0, stations=2)["name"],
        "seed 2, d 10": generate("intree", 8, seed=2, delivery_time=10)["name"],
        "seed 2, d 5 (the default)": generate("intree", 8, seed=2, delivery_time=5)["name"],
        "seed 2, d 10, 3 stations": generate("intree", 8, 2, None, 10, stations=3)["name"],
        "table, 2 stations": generate("table", 1, stations=2)["name"],
        "table, d 5, 3 stations": generate("table", 2, delivery_time=5, stations=3)["name"],
        "mixed, d 0": generate("mixed", 1, delivery_time=0)["name"],
    }
    assert names == {
        "seed 2": "intree_n8_s2",
        "seed 0, 2 stations": "intree_n8_s0_st2",
        "seed 2, d 10": "intree_n8_s2_d10",
        "seed 2, d 5 (the default)": "intree_n8_s2",
        "seed 2, d 10, 3 stations": "intree_n8_s2_d10_st3",
        "table, 2 stations": "table_u1_st2",
        "table, d 5, 3 stations": "table_u2_d5_st3",
        "mixed, d 0": "mixed_u1_d0",
    }
    with_d = {generate("sparse", 12, seed=1, delivery_time=d)["name"] for d in (0, 10, 30)}
    assert with_d == {"sparse_n12_s1_d0", "sparse_n12_s1_d10", "sparse_n12_s1_d30"}
