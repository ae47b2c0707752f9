"""The exact one-tray cut of a fixed order (bilevel_kit.models.segment): its value is the
timeline's makespan of its plan, no cut of the order is better (brute force over every cut),
and on the paper's table it attains the proven one-tray optimum."""

from __future__ import annotations

import itertools
import random
from pathlib import Path

import pytest
from strategies import random_doc

from bilevel_kit.instance import from_dict, load, topological_order
from bilevel_kit.models.budget import Budget
from bilevel_kit.models.common import Packer, best_cut, quick_plan
from bilevel_kit.models.segment import fit_extents, one_tray_cut
from bilevel_kit.plan import Kit, Plan, evaluate
from bilevel_kit.validate import check

TABLE = Path(__file__).resolve().parents[2] / "instances" / "hrc_table.json"


def _plan(kits: list[list[str]]) -> Plan:
    return Plan(tuple(Kit(tuple(k)) for k in kits))


def _random_ext(rng: random.Random, n: int) -> list[int]:
    """A monotone fit extent: ext non-decreasing, ext[b] > b (every single task fits)."""
    ext, c = [], 0
    for b in range(n):
        c = max(c, b + 1, min(n, b + rng.randint(1, 4)))
        ext.append(c)
    return ext


def _cuts(n: int, ext: list[int]) -> list[list[tuple[int, int]]]:
    out = []
    for mask in range(2 ** (n - 1)):
        bounds = [0, *(i + 1 for i in range(n - 1) if mask >> i & 1), n]
        segs = list(itertools.pairwise(bounds))
        if all(c <= ext[b] for b, c in segs):
            out.append(segs)
    return out


@pytest.mark.parametrize("seed", range(30))
def test_cut_is_the_best_of_every_cut_under_one_tray(seed: int) -> None:
    rng = random.Random(seed)
    doc = random_doc(seed, rng.randint(2, 8))
    doc["trays"] = 1
    inst = from_dict(doc)
    order = topological_order(inst)
    ext = _random_ext(rng, len(order))
    value, kits = one_tray_cut(inst, order, ext)
    assert [t for k in kits for t in k] == order
    assert evaluate(inst, _plan(kits)).makespan == pytest.approx(value, abs=1e-9)
    brute = min(
        evaluate(inst, _plan([order[b:c] for b, c in segs])).makespan
        for segs in _cuts(len(order), ext)
    )
    assert value == pytest.approx(brute, abs=1e-9)
    assert all(len(k) <= ext[order.index(k[0])] - order.index(k[0]) for k in kits)


def test_fit_extents_two_pointers_equal_the_direct_scan() -> None:
    rng = random.Random(7)
    for _ in range(50):
        n = rng.randint(1, 12)
        limit = [rng.randint(1, 5) for _ in range(n)]

        # a monotone predicate: [b, c) fits iff every task in it allows the length c - b
        def fits(b: int, c: int, limit: list[int] = limit) -> bool:
            return all(c - b <= limit[i] for i in range(b, c))

        direct = [max(c for c in range(b + 1, n + 1) if fits(b, c)) for b in range(n)]
        assert fit_extents(n, fits) == direct
    assert fit_extents(3, lambda b, c: not b <= 1 < c) is None  # task 1 does not fit


def test_fit_extents_stop_growing_at_the_deadline() -> None:
    """Past the deadline only single tasks are asked (and segments inside a known fit are
    kept): a valid, coarser extent instead of none."""
    asked: list[tuple[int, int]] = []

    def fits(b: int, c: int) -> bool:
        asked.append((b, c))
        return True

    assert fit_extents(5, fits, until=0.0) == [1, 2, 3, 4, 5]
    assert asked == [(b, b + 1) for b in range(5)]
    assert fit_extents(4, lambda b, c: not b <= 2 < c, until=0.0) is None


@pytest.mark.parametrize(("units", "makespan", "kits"), [(1, 435.085, 5), (2, 813.865, 6)])
def test_table_cut_attains_the_proven_one_tray_optimum(
    units: int, makespan: float, kits: int
) -> None:
    """435.085 s and 813.865 s are the optima cpsat and milp prove (bench/results)."""
    inst = load(TABLE).with_overrides(units=units)
    cut = best_cut(inst, topological_order(inst), Packer(inst, 0.5, Budget(60.0)))
    assert cut is not None
    assert len(cut) == kits
    assert evaluate(inst, _plan(cut)).makespan == pytest.approx(makespan, abs=1e-6)


def test_quick_plan_on_ten_table_units_is_the_cut() -> None:
    """The ten-unit table, one tray: 3828.105 s in 10 kits of growing size (the quick plan
    before this cut was 3931.8 s in 20 kits; 3830.41 s in kits of 1, 2, 3, 4, 7, 11, 18, 24,
    26, 24 tasks before the maximal-rectangles packer answered the probes CP-SAT left open)."""
    inst = load(TABLE).with_overrides(units=10)
    kits = quick_plan(inst, Packer(inst, 0.5, Budget(60.0)))
    assert kits is not None
    assert [len(k) for k in kits] == [1, 2, 3, 4, 6, 10, 15, 26, 29, 24]
    packer = Packer(inst, 0.5, Budget(60.0))
    plan = Plan(tuple(Kit(tuple(k), packer.layout(k)) for k in kits))
    assert evaluate(inst, plan).makespan == pytest.approx(3828.105, abs=1e-6)
    assert check(inst, plan) == []
