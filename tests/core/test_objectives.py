"""The objective registry (bilevel_kit/objectives.py) is the one list of objectives: the
checker's known names, the exact models' ``-p objective=`` choices and the evaluation from a
timeline all come from it; and the checker holds every registered objective's claims
(issue 35, "Make the next objective safe by construction")."""

from __future__ import annotations

import dataclasses
import json
import typing

import pytest
from solution_v1 import to_format_1
from stations_example import worked_example_doc

from bilevel_kit import solution
from bilevel_kit.instance import from_dict
from bilevel_kit.methods import MethodOutput, Result, Status
from bilevel_kit.objectives import MODEL_OBJECTIVES, OBJECTIVES, evaluated, get
from bilevel_kit.plan import Kit, Plan, evaluate
from bilevel_kit.stations import objective_of
from bilevel_kit.validate import timeline_params


def test_every_list_of_objective_names_is_the_registry():
    from bilevel_kit.models.cpsat import OBJECTIVES as CPSAT
    from bilevel_kit.models.cpsat import CpsatOptions
    from bilevel_kit.models.milp import OBJECTIVES as MILP
    from bilevel_kit.models.milp import MilpOptions
    from bilevel_kit.objectives import model_objectives
    from bilevel_kit.options import allowed_choices
    from bilevel_kit.registry import Registry

    assert isinstance(OBJECTIVES, Registry)  # plugins add to it (docs/extending.md)
    builtin = ("makespan", "sum_completion", "human_idle", "expected_makespan", "J")
    assert tuple(OBJECTIVES)[: len(builtin)] == builtin
    assert CPSAT == MILP == MODEL_OBJECTIVES == ("makespan", "sum_completion", "human_idle")
    assert model_objectives()[:3] == MODEL_OBJECTIVES
    for options in (CpsatOptions, MilpOptions):  # the option's choices: read from the registry
        field = next(f for f in dataclasses.fields(options) if f.name == "objective")
        assert allowed_choices(field.metadata) == model_objectives()


def _option_choices(options: type) -> tuple[str, ...] | None:
    """The values an options class's ``objective`` field takes: its ``Literal`` or its
    ``choices`` (None: it has no such field)."""
    from bilevel_kit.options import allowed_choices

    field = next((f for f in dataclasses.fields(options) if f.name == "objective"), None)
    if field is None:
        return None
    literal = typing.get_args(typing.get_type_hints(options)["objective"])
    return literal or allowed_choices(field.metadata)


def test_each_method_declares_the_objectives_of_its_option():
    """The method spec's objectives (docs/extending.md) are its ``objective`` option's
    choices, default first, and registered objectives; the exact models take every modelled
    one (:func:`~bilevel_kit.objectives.model_objectives`, a plugin's too)."""
    from bilevel_kit.methods import REGISTRY, get_method
    from bilevel_kit.objectives import model_objectives

    for name, spec in REGISTRY.items():
        names = spec.objective_names()
        assert names and set(names) <= set(OBJECTIVES), name
        options = spec.options_class()
        choices = _option_choices(options)
        if choices is not None:
            assert choices == names, name
            field = next(f for f in dataclasses.fields(options) if f.name == "objective")
            assert field.default == names[0], name
    for method in ("cpsat", "milp"):
        assert get_method(method).objective_names() == model_objectives()
        assert get_method(method).objectives == MODEL_OBJECTIVES


def test_the_worked_example_values():
    """docs/timeline.md#several-stations: [a1] [a2] [b1] ends A at 19 s, B at 23.5 s, with
    4 + 17.5 = 21.5 s of idle."""
    inst = from_dict(worked_example_doc())
    tl = evaluate(inst, Plan((Kit(("a1",)), Kit(("a2",)), Kit(("b1",)))))
    want = {"makespan": 23.5, "sum_completion": 42.5, "human_idle": 21.5}
    assert {o.name: o.value(tl) for o in evaluated()} == want
    assert {name: objective_of(tl, name) for name in want} == want
    assert OBJECTIVES["J"].value(tl) is None
    with pytest.raises(ValueError, match="not a function of the timeline"):
        objective_of(tl, "J")
    with pytest.raises(KeyError, match="unknown objective 'idle'"):
        get("idle")


def test_what_the_exact_drivers_ask_of_an_objective(tiny):
    """The exact drivers (models/cpsat, models/milp) branch on what an objective says, not on
    its name: only the makespan is the makespan (the result's own numbers); with one station
    it and sum_completion equal the makespan, which a one-station run minimises instead."""
    assert [o.name for o in OBJECTIVES.values() if o.is_makespan] == ["makespan"]
    assert all(o.top_level == o.is_makespan for o in OBJECTIVES.values())
    same = [o.name for o in OBJECTIVES.values() if o.makespan_with_one_station]
    assert same == ["makespan", "sum_completion"]
    tl = evaluate(tiny, Plan(tuple(Kit((t.id,)) for t in tiny.tasks)))
    assert all(get(name).value(tl) == tl.makespan for name in same)
    assert get("human_idle").value(tl) != tl.makespan


def _doc(inst, plan, name, status, stated, fmt):
    """A solution file (format ``fmt``) of ``plan`` whose status refers to objective
    ``name``, stating ``stated`` (value, bound, gap) on it."""
    tl = evaluate(inst, plan)
    value, bound, gap = stated
    res = Result(
        method="x",
        status=Status(status),
        plan=plan,
        timeline=tl,
        objective=value,
        bound=bound,
        gap=gap,
        wall_time_s=0.0,
        seed=0,
        params={},
        instance=inst.name,
        objective_name=name,
        timeline_params=timeline_params(inst),
    )
    doc = json.loads(json.dumps(solution.result_to_dict(res)))
    return to_format_1(doc) if fmt == 1 else doc


@pytest.mark.parametrize("fmt", [1, 2])
@pytest.mark.parametrize("obj", [o for o in OBJECTIVES.values() if not o.top_level])
def test_every_stated_objective_is_held_to_its_numbers(obj, fmt):
    """For each registered objective besides the makespan, in the ``objective`` block of a
    format-2 file and in ``extra`` of a format-1 one: its true numbers pass; a tampered value,
    a bound above the value, a wrong gap and "optimal" without a bound are each named."""
    inst = from_dict(worked_example_doc())
    plan = Plan((Kit(("a1",)), Kit(("a2",)), Kit(("b1",))))
    real = obj.value(evaluate(inst, plan))
    # not a function of the timeline: its stated value stands in (J may be negative, a
    # sample-average makespan is a time)
    value = real if real is not None else (-3.0 if obj.name == "J" else 30.0)
    good = (value, value, 0.0)

    def kinds(status, value=value, bound=value, gap=0.0):
        doc = _doc(inst, plan, obj.name, status, (value, bound, gap), fmt)
        return sorted(v.kind for v in solution.from_dict(doc).check(inst))

    assert kinds("optimal") == []
    v1 = solution.from_dict(to_format_1(_doc(inst, plan, obj.name, "optimal", good, 2)))
    assert v1.claims.objective_claims == (value, value, 0.0, True)
    if real is not None:
        for tampered in (1.0, 1e9, 0.0):
            assert "objective_mismatch" in kinds("feasible", value=tampered)
        # the gap clips at 0, as the stated one: only the bound is named
        assert kinds("feasible", bound=value + 1) == ["bound_above_objective"]
    assert kinds("feasible", gap=0.5) == ["gap_mismatch"]
    assert kinds("optimal", bound=None, gap=None) == ["status_mismatch"]
    assert kinds("optimal", bound=value - 2, gap=obj.gap(value, value - 2)) == ["status_mismatch"]


def test_solve_check_holds_a_fresh_result_to_its_objective(tiny):
    """``solve --check``: an optimal human-idle claim without a bound is named at once."""
    from bilevel_kit.methods import REGISTRY, register
    from bilevel_kit.methods import solve as run

    if "idle-nobound-test" not in REGISTRY:
        register(
            "idle-nobound-test",
            f"{__name__}:no_bound",
            "claims an idle optimum without a bound",
            "bilevel_kit.options:NoOptions",
        )
    res = run(tiny, "idle-nobound-test", check=True)
    assert [v["kind"] for v in res.extra["violations"]] == ["status_mismatch"]


def no_bound(instance, options, *, seed=0, time_limit=None):
    """Single-task's plan claimed optimal for the human idle, with no bound."""
    from bilevel_kit.heuristics.baselines import single_task

    plan = single_task(instance).plan
    return MethodOutput(plan, Status.OPTIMAL, None, {}, status_objective="human_idle")
