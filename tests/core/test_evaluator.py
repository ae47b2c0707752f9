"""The timeline (docs/timeline.md) on hand-computed cases."""

from __future__ import annotations

import pytest

from bilevel_kit import Kit, Plan, evaluate


def _plan(*kits):
    return Plan(tuple(Kit(tuple(k)) for k in kits))


def test_stool_single_task_with_delivery(stool):
    # robot times a1 = 22, a2 = a3 = 16 (+2 overhead); human 20, 15, 15 (+1); d = 5
    tl = evaluate(stool, _plan(["a1"], ["a2"], ["a3"]))
    got = [(k.robot_start, k.robot_end, k.arrive, k.human_start, k.human_end) for k in tl.kits]
    assert got == [(0, 24, 29, 29, 50), (29, 47, 52, 52, 68), (52, 70, 75, 75, 91)]
    assert tl.makespan == 91
    assert tl.human_idle == 91 - 53
    assert tl.robot_idle == 91 - (24 + 18 + 18 + 3 * 5)
    assert tl.n_kits == 3
    assert tl.task_start["a2"] == 53 and tl.task_end["a2"] == 68


def test_stool_single_task_without_delivery(stool):
    tl = evaluate(stool.with_overrides(delivery_time=0), _plan(["a1"], ["a2"], ["a3"]))
    got = [(k.robot_start, k.arrive, k.human_start, k.human_end) for k in tl.kits]
    assert got == [(0, 24, 24, 45), (24, 42, 45, 61), (42, 60, 61, 77)]
    assert tl.makespan == 77 and tl.human_idle == 24


def test_stool_two_kits(stool):
    # kit 1 {a1, a2}: R = 2 + 22 + 16 = 40, arrives 45, H = 1 + 35 -> 81
    # kit 2 {a3}: robot 45..63, arrives 68, human waits for kit 1: 81..97
    tl = evaluate(stool, _plan(["a1", "a2"], ["a3"]))
    assert [(k.robot_end, k.arrive, k.human_start, k.human_end) for k in tl.kits] == [
        (40, 45, 45, 81),
        (63, 68, 81, 97),
    ]
    assert tl.makespan == 97 and tl.human_idle == 97 - 52


def test_whole_assembly_overheads(stool):
    tl = evaluate(stool, _plan(["a1", "a2", "a3"]))
    assert tl.makespan == 2 + 54 + 5 + 1 + 50
    assert tl.robot_idle == tl.makespan - (56 + 5)


def test_tiny_by_hand(tiny):
    # robot: t1 = 2, t2 = 3, t3 = 5, overhead 1, d = 1; human 10, 6, 4 (+0.5)
    tl = evaluate(tiny, _plan(["t2", "t1"], ["t3"]))
    assert (tl.kits[0].arrive, tl.kits[0].human_end) == (7, 23.5)
    assert (tl.kits[1].robot_start, tl.kits[1].arrive, tl.kits[1].human_end) == (7, 14, 28)
    assert tl.makespan == 28


def test_sampled_times_replace_expected(stool):
    h = {"a1": 10.0, "a2": 10.0, "a3": 10.0}
    r = {"a1": 1.0, "a2": 1.0, "a3": 1.0}
    tl = evaluate(stool, _plan(["a1"], ["a2", "a3"]), human_times=h, robot_times=r)
    # kit 1: robot 0..3, arrive 8, human 8..19; kit 2: robot 8..12, arrive 17, human 19..40
    assert tl.makespan == pytest.approx(40)


def test_builder_gives_each_prefix_the_timeline_of_evaluate(table):
    """The incremental evaluator is the evaluator: after every kit, its timeline equals
    ``evaluate`` of the plan so far (one tray, so the tray rule is exercised)."""
    from bilevel_kit.plan import TimelineBuilder

    order = [t.id for t in table.tasks]
    kits = [Kit(tuple(order[i : i + 3])) for i in range(0, len(order), 3)]
    builder = TimelineBuilder(table)
    assert builder.human_free == 0.0
    for k, kit in enumerate(kits, start=1):
        times = builder.append(kit)
        full = evaluate(table, Plan(tuple(kits[:k])))
        assert builder.timeline() == full
        assert times == full.kits[-1] and builder.human_free == full.makespan


def test_overrides_that_keep_the_tasks_share_the_expanded_graph():
    """A method's copy with its own horizon or weights (greedy-ce makes one) must not expand
    the units again: at 60,000 tasks that took seconds of its time limit."""
    from dataclasses import replace
    from pathlib import Path

    from bilevel_kit import load

    inst = replace(load(Path(__file__).parents[2] / "instances" / "hrc_table.json"), units=3)
    views = (inst.tasks, inst.index, inst.predecessors, inst.precedence)
    copy = inst.with_overrides(horizon=2, weights={"W1": 2.0}, trays="unlimited")
    assert (copy.tasks, copy.index, copy.predecessors, copy.precedence) == views
    assert copy.tasks is inst.tasks and copy.predecessors is inst.predecessors
    assert copy.trays is None and copy.station_params[""].tray_limit is None  # not shared
    assert inst.station_params[""].tray_limit == 1
    more = inst.with_overrides(units=4)
    assert more.n_tasks == 48 and more.tasks is not inst.tasks
