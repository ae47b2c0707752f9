"""Closed-form lower bounds and Johnson's rule."""

from __future__ import annotations

import itertools
import random

import pytest

from bilevel_kit import bounds
from bilevel_kit.instance import document, from_dict
from bilevel_kit.plan import Kit, Plan, evaluate


def test_johnson_on_a_textbook_case():
    a = [3, 5, 1, 6, 7]
    b = [6, 2, 2, 6, 5]
    assert bounds.johnson_order(a, b) == [2, 0, 3, 4, 1]
    assert bounds.johnson_makespan(a, b) == 24
    assert bounds.flow_shop_makespan([0, 1, 2, 3, 4], a, b) == 27


@pytest.mark.parametrize("seed", range(5))
def test_johnson_is_optimal_for_f2_cmax(seed):
    rng = random.Random(seed)
    n = rng.randint(3, 7)
    a = [rng.randint(1, 20) for _ in range(n)]
    b = [rng.randint(1, 20) for _ in range(n)]
    brute = min(bounds.flow_shop_makespan(p, a, b) for p in itertools.permutations(range(n)))
    assert bounds.johnson_makespan(a, b) == brute


def test_bounds_of_the_table(table):
    lb = bounds.lower_bounds(table)
    # human: foot r = 27 + o_R 8 + d 2 + sum h 374.78 + 1 kit x o_H 4
    assert lb["human"] == pytest.approx(415.78)
    # robot: sum r 208 + 1 x (8 + 2) + o_H 4 + shortest sink (top) 34.695
    assert lb["robot"] == pytest.approx(256.695)
    assert lb["min_kits"] == 1
    assert bounds.best_bound(table) == pytest.approx(415.78)
    ten = table.with_overrides(units=10)
    # 10 x 22,917.92 mm^2 of parts on a 60,000 mm^2 tray -> at least 4 kits
    assert bounds.min_kits(ten) == 4
    assert bounds.lower_bounds(ten)["human"] == pytest.approx(37 + 3747.8 + 4 * 4)


def _doc(seed: int) -> dict:
    rng = random.Random(1000 + seed)
    n = rng.randint(3, 6)
    types = [
        {"id": "p", "width": 40.0, "height": 30.0, "pick_time": 2.0},
        {"id": "q", "width": 25.0, "height": 25.0, "pick_time": 1.5},
    ]
    tasks = [
        {
            "id": f"t{i}",
            "parts": [{"type": rng.choice("pq"), "count": rng.randint(1, 2)}],
            "human_time": {"mean": float(rng.randint(2, 20))},
            **({"robot_time": float(rng.randint(1, 12))} if rng.random() < 0.5 else {}),
        }
        for i in range(n)
    ]
    prec = [[f"t{i}", f"t{j}"] for i in range(n) for j in range(i + 1, n) if rng.random() < 0.3]
    return document(
        f"b{seed}",
        types,
        tasks,
        tray=(80.0, 60.0),
        delivery_time=float(rng.randint(0, 6)),
        overhead=(float(rng.randint(0, 3)), float(rng.randint(0, 3))),
        precedence=prec,
    )


def _brute_force(inst) -> float:
    """Best makespan over ordered partitions into precedence-closed kits whose part area fits
    (area only: a relaxation of the tray, so this is <= the true optimum and every bound must
    stay below it)."""
    ids = [t.id for t in inst.tasks]
    anc = inst.ancestors
    best = float("inf")

    def area(kit):
        return sum(inst.part_types[p].area * c for p, c in inst.kit_parts(kit).items())

    def rec(done: frozenset, kits: list):
        nonlocal best
        if len(done) == len(ids):
            best = min(best, evaluate(inst, Plan(tuple(Kit(tuple(k)) for k in kits))).makespan)
            return
        rest = [t for t in ids if t not in done]
        for r in range(1, len(rest) + 1):
            for kit in itertools.combinations(rest, r):
                s = set(kit)
                if (
                    all(a in done or a in s for t in kit for a in anc[t])
                    and area(kit) <= inst.tray.area
                ):
                    rec(done | s, [*kits, kit])

    rec(frozenset(), [])
    return best


@pytest.mark.parametrize("seed", range(8))
def test_bounds_never_exceed_the_optimum(seed):
    inst = from_dict(_doc(seed))
    opt = _brute_force(inst)
    lb = bounds.lower_bounds(inst)
    assert lb["human"] <= opt + 1e-9
    assert lb["robot"] <= opt + 1e-9
    assert bounds.best_bound(inst) <= opt + 1e-9
