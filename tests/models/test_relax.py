"""The stronger lower bounds of bilevel_kit.models.relax against brute force: never above the
optimum (overall, and the kit-count LP for every kit count against the best plan of exactly
that many kits), with one, two and unlimited trays, delivery, overheads and precedence."""

from __future__ import annotations

import math

import pytest
from brute import fits, segmentations
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from test_exact_trays import random_doc

from bilevel_kit import load
from bilevel_kit.bounds import best_bound
from bilevel_kit.instance import from_dict
from bilevel_kit.models.relax import closed_at, proven_bound, time_grid
from bilevel_kit.models.relax.precedence import head_tail_bounds
from bilevel_kit.plan import Kit, Plan, evaluate


def best_by_kits(inst) -> dict[int, float]:
    """The least makespan of the plans of exactly m kits whose kits fit, for every m."""
    best: dict[int, float] = {}
    for kits in segmentations(inst):
        if all(fits(inst, k) for k in kits):
            ms = evaluate(inst, Plan(tuple(Kit(k) for k in kits))).makespan
            best[len(kits)] = min(best.get(len(kits), math.inf), ms)
    return best


def check_bounds(inst) -> None:
    per_m = best_by_kits(inst)
    opt = min(per_m.values())
    bound = proven_bound(inst, time_limit=30.0)
    assert bound.value <= opt + 1e-6, (bound, opt)
    for m, value in bound.per_kits.items():
        if m in per_m:
            assert value <= per_m[m] + 1e-6, (m, value, per_m[m])
    closed = closed_at(inst)
    for m, value in per_m.items():
        assert bound.at(m, closed) <= value + 1e-6, (m, bound.at(m, closed), value)
    for m, value in per_m.items():  # the kit cap never excludes a plan as good as the optimum
        cap = bound.kit_cap(opt, closed)
        assert cap is None or value > opt + 1e-9 or m <= cap
    ht = head_tail_bounds(inst)
    assert ht["head"] <= opt + 1e-6 and ht["tail"] <= opt + 1e-6
    assert bound.value >= best_bound(inst) - 1e-6


@pytest.mark.parametrize("trays", [1, 2, None])
@pytest.mark.parametrize("seed", range(6))
def test_bounds_never_exceed_the_brute_force_optimum(seed, trays):
    check_bounds(from_dict(random_doc(seed, trays)))


@settings(max_examples=25, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(st.integers(100, 10_000), st.sampled_from([1, 2, None]), st.integers(2, 6))
def test_bounds_hold_on_random_instances(seed, trays, n):
    check_bounds(from_dict(random_doc(seed, trays, n)))


@settings(max_examples=15, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(st.integers(0, 10_000), st.sampled_from([1, None]))
def test_robot_heavy_instances(seed, trays):
    """A busy robot (long picks, short assembly): the tail bound's side."""
    doc = random_doc(seed, trays, 5)
    for task in doc["tasks"]:
        task["robot_time"] = 5.0 + (seed % 7) + len(task["id"])
        task["human_time"] = {"mean": 1.0 + (seed % 3)}
    check_bounds(from_dict(doc))


def test_kit_lp_beats_the_closed_forms_on_the_table():
    """One tray: 430.37 s against 415.78 s (the optimum is 435.085 s)."""
    inst = load("instances/hrc_table.json")
    bound = proven_bound(inst, time_limit=30.0)
    assert bound.source == "kit_lp"
    assert bound.value == pytest.approx(430.37, abs=0.01)
    assert best_bound(inst) == pytest.approx(415.78)
    assert time_grid(inst) == pytest.approx(0.005)
