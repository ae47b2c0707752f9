"""The one implementation of the upper-level F (Eqs. 3-7, W7) against bilevel-milp's J terms."""

from __future__ import annotations

import numpy as np
import pytest

from bilevel_kit import solve
from bilevel_kit.heuristics import upper_level
from bilevel_kit.models.bilevel_milp import layout_fitness, paper_terms
from bilevel_kit.plan import Kit, Plan, evaluate, kit_durations


def plan_terms(instance, plan, fitness_of, *, weights=None, signed=False):
    """What ``bilevel_milp.paper_terms`` computes, through :mod:`upper_level` (per kit:
    diff5, diff6, fitness, score)."""
    w = {**instance.weights, **(weights or {})}
    tl = evaluate(instance, plan)
    r, h = np.array([kit_durations(instance, k.tasks) for k in plan.kits]).T
    # H_rem when the robot starts kit k (the tray rule decides when that is)
    backlog = [0.0] + [
        a.human_end - b.robot_start for a, b in zip(tl.kits, tl.kits[1:], strict=False)
    ]
    diff5, diff6 = upper_level.plan_balance(
        r, h, backlog, delivery=instance.delivery_time, signed=signed
    )
    fit = np.array([float(fitness_of(k)) for k in plan.kits])
    score = upper_level.objective(
        w,
        n_tasks=np.array([len(k.tasks) for k in plan.kits]),
        diff5=diff5,
        diff6=diff6,
        fitness=fit,
    )
    return diff5, diff6, fit, score


@pytest.fixture(scope="module")
def table_plans(table):
    plans = [solve(table, m).plan for m in ("greedy-ce", "single-task", "whole-assembly")]
    greedy = plans[0]
    # a few kits of the table: the greedy's first three and its last two, merged differently
    kits = greedy.kits
    mixed = Plan(
        (
            Kit(kits[0].tasks + kits[1].tasks, kits[0].layout + kits[1].layout),
            *kits[2:6],
            Kit(kits[6].tasks + kits[7].tasks, kits[6].layout + kits[7].layout),
        )
    )
    return [*plans, mixed]


@pytest.mark.parametrize(
    ("weights", "signed"),
    [(None, False), (None, True), ({"W2": 3.0, "W3": 0.5, "W4": 2.0, "W5": 0.01}, False)],
)
def test_same_terms_as_bilevel_milp_paper_terms(table, table_plans, weights, signed):
    fitness_of = layout_fitness(table)
    for plan in table_plans:
        want = paper_terms(table, plan, fitness_of, weights=weights, signed=signed)
        diff5, diff6, fit, score = plan_terms(
            table, plan, fitness_of, weights=weights, signed=signed
        )
        # bitwise: the same operations in the same order
        assert diff5.tolist() == [t["diff5"] for t in want]
        assert diff6.tolist() == [t["diff6"] for t in want]
        assert fit.tolist() == [t["fitness"] for t in want]
        assert score.tolist() == [t["score"] for t in want]


def test_task_sums_with_overheads_give_the_same_terms(table, table_plans):
    """Sums of task times plus the overheads added by balance_terms (greedy's way) agree with
    kit durations that include them (up to rounding)."""
    inst = table.with_overrides(delivery_time=3.0)
    plan = table_plans[0]
    tl = evaluate(inst, plan)
    backlog = np.array(
        [0.0] + [a.human_end - b.robot_start for a, b in zip(tl.kits, tl.kits[1:], strict=False)]
    )
    r = np.array([sum(inst.robot_time(t) for t in k.tasks) for k in plan.kits])
    h = np.array([sum(inst.human_time(t) for t in k.tasks) for k in plan.kits])
    m = len(plan.kits)
    got = upper_level.balance_terms(
        r,
        h,
        np.append(r[1:], 0.0),
        np.arange(m) < m - 1,
        delivery=inst.delivery_time,
        human_remaining=backlog,
        overhead_robot=inst.kit_overhead_robot,
        overhead_human=inst.kit_overhead_human,
    )
    want = paper_terms(inst, plan, layout_fitness(inst))
    assert got[0] == pytest.approx([t["diff5"] for t in want], abs=1e-9)
    assert got[1] == pytest.approx([t["diff6"] for t in want], abs=1e-9)


def test_window_balance_by_hand():
    # two sequences of 3 tasks; d = 2, o_R = 1, o_H = 0.5, H_rem = 4
    robot = np.array([[3.0, 5.0, 7.0], [1.0, 1.0, 1.0]])
    human = np.array([[10.0, 20.0, 30.0], [2.0, 2.0, 2.0]])
    shop = {"delivery": 2.0, "human_remaining": 4.0, "overhead_robot": 1.0, "overhead_human": 0.5}
    d5, d6 = upper_level.window_balance(robot, human, **shop, signed=True)
    # (5): d + o_R + R(prefix) - H_rem
    assert d5.tolist() == [[2.0, 7.0, 14.0], [0.0, 1.0, 2.0]]
    # (6): d + (o_R + R(rest) if the rest is not empty) - (o_H + H(prefix))
    assert d6.tolist() == [[15.0 - 10.5, 10.0 - 30.5, 2.0 - 60.5], [5.0 - 2.5, 4.0 - 4.5, -4.5]]
    a5, a6 = upper_level.window_balance(robot, human, **shop)
    assert (a5 == np.abs(d5)).all() and (a6 == np.abs(d6)).all()


def test_objective_terms_by_hand():
    w = {f"W{k}": float(k) for k in range(1, 8)}
    score = upper_level.objective(
        w,
        n_tasks=np.array([1, 2]),
        diff5=np.array([10.0, 0.0]),
        diff6=np.array([0.0, 5.0]),
        fitness=np.array([1.0, -1.0]),
        violations=np.array([1.0, 0.0]),
        unavailable=np.array([0.0, 2.0]),
    )
    # W1 v - W2 i + W3 d5 + W4 d6 - W5 f + W7 U
    assert score.tolist() == [1 - 2 + 30 - 5, -4 + 20 + 5 + 14]
    hard = upper_level.objective(
        w, n_tasks=1, diff5=np.array([1.0]), diff6=np.array([1.0]), fitness=np.array([0.0])
    )
    assert hard.tolist() == [-2 + 3 + 4]


def test_precedence_violations_and_unavailable_parts():
    # 0 -> 1 -> 2; task 0 done
    pred = [frozenset(), frozenset({0}), frozenset({1})]
    seqs = np.array([[1, 2], [2, 1]])
    assert upper_level.precedence_violations(seqs, {0}, pred).tolist() == [0.0, 1.0]
    counts = np.array([[2, 0, 1], [0, 0, 0]])
    assert upper_level.unavailable_parts(counts, np.array([1, 0, 5])).tolist() == [1.0, 0.0]
