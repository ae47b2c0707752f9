"""The numbers docs/stations.md and the CHANGELOG quote from the committed side-by-side run of
``lns`` at scale (``python bench/bench_lns_scale.py --baseline DIR``,
bench/results/lns_scale.csv): a rerun that changes them fails here until the pages follow."""

from __future__ import annotations

import csv
import math

import pytest

from tests.paths import RESULTS, ROOT

PAGES = ("docs/stations.md", "CHANGELOG.md")


def _rows() -> dict[tuple[str, int, str], float]:
    with (RESULTS / "lns_scale.csv").open(newline="") as f:
        return {
            (r["instance"], int(r["seed"]), r["side"]): float(r["makespan"])
            for r in csv.DictReader(f)
        }


def _s(x: float) -> str:
    return f"{x:,.0f} s"


def _flat(path: str) -> str:
    return " ".join((ROOT / path).read_text(encoding="utf-8").split())


@pytest.mark.parametrize("page", PAGES)
def test_the_1800_task_numbers_are_the_runs(page: str) -> None:
    rows, text = _rows(), _flat(page)
    big = "sparse_n600_st3"
    new = {rows[big, s, "new"] for s in (0, 1)}
    assert len(new) == 1  # "for both seeds"
    assert f"{_s(new.pop())} for both seeds" in text
    assert f"{_s(rows[big, 0, 'old'])} and {_s(rows[big, 1, 'old'])}" in text  # before
    assert f"{_s(rows[big, 0, 'greedy-ce'])} and {_s(rows[big, 1, 'greedy-ce'])}" in text


def test_the_stations_page_numbers_are_the_runs() -> None:
    rows, text = _rows(), _flat("docs/stations.md")
    big = "sparse_n600_st3"
    gain = 1 - rows[big, 0, "new"] / rows[big, 0, "old"]
    assert f"({100 * gain:.1f} % better than before this change" in text
    mid = ("intree_n100_st3", "wide_n150_st3", "sparse_n200_st3")
    worst = max(rows[m, s, "new"] / rows[m, s, "old"] - 1 for m in mid for s in (0, 1))
    assert f"within {math.ceil(worst * 1e4) / 100:.2f} % of what it returned before" in text
    lns, greedy = ([_s(rows[m, 0, side]) for m in mid] for side in ("new", "greedy-ce"))
    assert f"{lns[0]}, {lns[1]} and {lns[2]} at seed 0" in text
    assert f"greedy-ce's {greedy[0]}, {greedy[1]} and {greedy[2]}" in text
