"""``compare`` holds every registered objective's claims against the other methods' valid plans
(issue 35, item 2): a claimed optimum, or a bound, on the status objective above another
method's valid plan's value of it is exit 1 naming both methods."""

from __future__ import annotations

import json
import sys
from dataclasses import dataclass, field

import pytest

from bilevel_kit.experiments.compare import inconsistencies, objective_conflicts
from bilevel_kit.methods import MethodOutput, Status


def _row(method, claim, values, valid=True):
    return {
        "instance": "a",
        "method": method,
        "valid": valid,
        "objective_claim": claim,
        "objective_values": values,
    }


def test_a_claimed_optimum_above_another_valid_plan_names_both():
    rows = [
        _row(
            "milp", {"name": "human_idle", "optimal": True, "bound": 33.38}, {"human_idle": 33.38}
        ),
        _row(
            "cpsat", {"name": "human_idle", "optimal": True, "bound": 28.62}, {"human_idle": 28.62}
        ),
    ]
    assert objective_conflicts(rows) == [
        "a: milp claims the optimum 33.38 on human_idle, above the human_idle 28.62 of a valid "
        "plan of cpsat",
        "a: milp states the bound 33.38 on human_idle, above the human_idle 28.62 of a valid "
        "plan of cpsat",
    ]
    assert inconsistencies(rows) == objective_conflicts(rows)


@pytest.mark.parametrize("name", ["sum_completion", "human_idle"])
def test_a_bound_alone_above_another_valid_plan_is_a_conflict(name):
    rows = [
        _row("x", {"name": name, "optimal": False, "bound": 30.0}, {name: 35.0}),
        _row("y", {"name": "makespan", "optimal": False, "bound": 1.0}, {name: 29.0}),
    ]
    assert objective_conflicts(rows) == [
        f"a: x states the bound 30 on {name}, above the {name} 29 of a valid plan of y"
    ]


def test_consistent_claims_and_invalid_plans_are_no_conflict():
    rows = [
        _row(
            "x",
            {"name": "sum_completion", "optimal": True, "bound": 30.0},
            {"sum_completion": 30.0},
        ),
        _row("y", {"name": "makespan", "optimal": False, "bound": 1.0}, {"sum_completion": 31.0}),
        # an invalid plan refutes nothing
        _row(
            "z",
            {"name": "makespan", "optimal": False, "bound": 1.0},
            {"sum_completion": 2.0},
            False,
        ),
        # an older cell without these keys claims nothing
        {"instance": "a", "method": "w", "valid": True},
    ]
    assert objective_conflicts(rows) == []


def test_j_is_not_a_function_of_the_timeline_so_it_is_not_compared():
    rows = [_row("bilevel-milp", {"name": "J", "optimal": True, "bound": -3.0}, {"makespan": 20})]
    assert objective_conflicts(rows) == []


def idle_boaster(instance, options, *, seed=0, time_limit=None):
    """Whole-assembly's plan on the tiny instance (human idle 12 s), claimed optimal for the
    human idle with a bound equal to its value; single-task's valid plan idles 4 s."""
    from bilevel_kit.heuristics.baselines import whole_assembly
    from bilevel_kit.plan import evaluate

    plan = whole_assembly(instance).plan
    idle = evaluate(instance, plan).human_idle
    extra = {"objective_value": idle, "objective_bound": idle, "objective_gap": 0.0}
    return MethodOutput(plan, Status.OPTIMAL, None, extra, status_objective="human_idle")


@dataclass(frozen=True)
class IdleOptions:
    status: str = field(default="optimal", metadata={"help": "unused"})


def _register_once(name: str, function: str, summary: str) -> None:
    """Register this module's ``function`` as method ``name`` (with :class:`IdleOptions`)
    unless an earlier test did: the registry is process-wide."""
    from bilevel_kit import methods

    module = sys.modules[__name__].__name__
    if name not in methods.REGISTRY:
        methods.register(name, f"{module}:{function}", summary, f"{module}:IdleOptions")


def test_compare_exits_1_on_a_false_optimum_of_another_objective(tiny, capsys):
    from bilevel_kit.cli import main

    _register_once("idle-boaster-test", "idle_boaster", "claims an idle optimum")
    code = main(["compare", str(tiny.source), "--methods", "single-task,idle-boaster-test"])
    out, err = capsys.readouterr()
    assert code == 1
    assert (
        "INCONSISTENT: tiny: idle-boaster-test claims the optimum 12 on human_idle, above the "
        "human_idle 4 of a valid plan of single-task" in err
    )
    assert "Traceback" not in out + err


def idle_optimum(instance, options, *, seed=0, time_limit=None):
    """Single-task's plan on the tiny instance, claimed optimal for the human idle (4 s, the
    optimum cpsat proves, tests/models/test_result_objective.py) with that bound."""
    from bilevel_kit.heuristics.baselines import single_task

    extra = {"objective_value": 4.0, "objective_bound": 4.0, "objective_gap": 0.0}
    return MethodOutput(single_task(instance).plan, Status.OPTIMAL, None, extra, "human_idle")


def test_compare_reports_the_makespan_by_name_whatever_was_minimised(tiny, tmp_path, capsys):
    """A row of a method that minimised the human idle: its makespan, bound and gap columns
    are the makespan's (25.5 s over the bound 24.5 s), its status names the idle (issue 36)."""
    import csv

    from bilevel_kit.cli import main

    _register_once("idle-optimum-test", "idle_optimum", "claims the idle optimum")
    out = tmp_path / "c.csv"
    code = main(
        [
            "compare",
            str(tiny.source),
            "--methods",
            "single-task,idle-optimum-test",
            "--csv",
            str(out),
        ]
    )
    printed = capsys.readouterr().out
    assert code == 0
    rows = {r["method"]: r for r in csv.DictReader(out.open())}
    idle, plain = rows["idle-optimum-test"], rows["single-task"]
    assert idle["status"] == "optimal (for human_idle)" and plain["status"] == "feasible"
    for r in (idle, plain):
        assert (float(r["makespan"]), float(r["bound"])) == (25.5, 24.5)
        assert float(r["gap_own"]) == pytest.approx(1 / 25.5)
    assert json.loads(idle["objective_claim"]) == {
        "name": "human_idle",
        "optimal": True,
        "bound": 4.0,
    }
    assert "makespan (s)" in next(line for line in printed.splitlines() if "method" in line)
