"""The independent reference timeline (tests/reference_timeline.py, written from
docs/timeline.md alone) on the page's worked examples, and the package's evaluator held to it
on random instances and plans: one to three stations, trays 1, 2 and unlimited."""

from __future__ import annotations

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from reference_timeline import disagreements, reference
from stations_example import worked_example_doc
from strategies import timeline_cases

from bilevel_kit.instance import from_dict
from bilevel_kit.plan import Kit, Plan, evaluate


def _rows(ref):
    return [(k.robot_start, k.robot_end, k.arrive, k.human_start, k.human_end) for k in ref.kits]


def test_worked_example_of_the_rule(tiny):
    """docs/timeline.md, "Worked example": [t1] [t2, t3] on the tiny instance."""
    ref = reference(tiny, [["t1"], ["t2", "t3"]])
    assert _rows(ref) == [(0, 3, 4, 4, 14.5), (4, 13, 14, 14.5, 25)]
    assert (ref.makespan, ref.human_idle, ref.robot_idle) == (25, 4, 11)
    assert (ref.task_start["t2"], ref.task_end["t2"]) == (15, 21)
    assert (ref.task_start["t3"], ref.task_end["t3"]) == (21, 25)


def test_worked_example_of_the_trays(tiny):
    """docs/timeline.md, "Trays in circulation": [t1] [t2] [t3] is 25.5 s with unlimited
    trays and 26.5 s with one (kit 2 starts at 4.5, kit 3 at 15 and arrives at 22)."""
    kits = [["t1"], ["t2"], ["t3"]]
    assert reference(tiny, kits).makespan == 25.5
    ref = reference(tiny.with_overrides(trays=1), kits)
    assert [k.robot_start for k in ref.kits] == [0, 4.5, 15]
    assert ref.kits[2].arrive == 22
    assert ref.makespan == 26.5


def test_worked_example_of_several_stations():
    """docs/timeline.md#several-stations: [a1] [a2] [b1]."""
    inst = from_dict(worked_example_doc())
    ref = reference(inst, [["a1"], ["a2"], ["b1"]])
    assert _rows(ref) == [
        (0, 3, 4, 4, 14.5),
        (4.5, 10.5, 11.5, 14.5, 19),
        (11.5, 15.5, 17.5, 17.5, 23.5),
    ]
    assert ref.completion == {"A": 19, "B": 23.5}
    assert ref.completion["A"] - ref.human_work_at["A"] == 4
    assert ref.completion["B"] - ref.human_work_at["B"] == 17.5
    assert (ref.makespan, ref.human_idle, ref.robot_idle) == (23.5, 21.5, 6.5)


@settings(max_examples=400, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(timeline_cases())
def test_the_evaluator_is_the_reference(case):
    """Every kit's times, every task's, the metrics, each station's completion and idle and
    the registry's objectives agree to 1e-9 relative (the two add the same numbers in other
    orders)."""
    doc, kits = case
    inst = from_dict(doc)
    tl = evaluate(inst, Plan(tuple(Kit(tuple(k)) for k in kits)))
    assert disagreements(reference(inst, kits), tl) == []


@settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(timeline_cases(), st.data())
def test_the_evaluator_is_the_reference_with_sampled_times(case, data):
    """``robot_times=`` and ``human_times=`` (the simulator's sampled durations) replace the
    tasks' times and nothing else, in both."""
    doc, kits = case
    inst = from_dict(doc)
    ids = [t.id for t in inst.tasks]
    sample = st.floats(0, 90, allow_nan=False)
    robot = {t: data.draw(sample) for t in ids}
    human = {t: data.draw(sample) for t in ids}
    plan = Plan(tuple(Kit(tuple(k)) for k in kits))
    tl = evaluate(inst, plan, robot_times=robot, human_times=human)
    ref = reference(inst, kits, robot_times=robot, human_times=human)
    assert disagreements(ref, tl) == []


@pytest.mark.parametrize("name", ["tiny", "stool", "table"])
def test_the_shipped_instances_in_file_order(name, request):
    """One kit per task and all tasks in one kit, in file order, on the shipped instances."""
    inst = request.getfixturevalue(name)
    ids = [t.id for t in inst.tasks]
    for kits in ([[t] for t in ids], [ids]):
        tl = evaluate(inst, Plan(tuple(Kit(tuple(k)) for k in kits)))
        assert disagreements(reference(inst, kits), tl) == []
