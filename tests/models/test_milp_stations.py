"""milp with several assembly stations (docs/timeline.md#several-stations): hints, the registry,
the first kit's tray and the master's price of a plan (its brute-force cases are cpsat's,
parametrised over both backends in tests/models/test_cpsat_stations.py)."""

from __future__ import annotations

import pytest
import strategies
from brute import assert_model_optimal, assert_objective_optimal, best_makespan

from bilevel_kit.instance import from_dict
from bilevel_kit.plan import evaluate
from bilevel_kit.stations import objective_of
from bilevel_kit.validate import check

pytest.importorskip("ortools")
pytest.importorskip("pyomo")


def test_milp_stations_honours_a_hint_that_models_stations():
    """``hint`` with stations: a method that models them joins the warm start (the best plan
    is the incumbent, ``hint_method`` names it); one that does not is refused in one line."""
    from bilevel_kit.errors import UsageError
    from bilevel_kit.models.milp import MilpOptions, milp

    inst = from_dict(strategies.stations_doc(1, 2, n=4))
    out = milp(inst, MilpOptions(hint="single-task", fallback="none"), time_limit=20)
    assert out.plan is not None and check(inst, out.plan) == []
    assert out.extra["hint_method"] in ("single-task", "whole-assembly", "greedy-ce")
    with pytest.raises(UsageError, match="hint=bilevel-milp") as exc:
        milp(inst, MilpOptions(hint="bilevel-milp"), time_limit=5)
    assert "\n" not in str(exc.value) and "bilevel-milp does not model them" in str(exc.value)


def test_milp_sum_completion_on_one_station_is_the_makespan(table):
    """Without stations the sum of the completions is the makespan: solved as such."""
    from bilevel_kit.models.milp import solve

    out = solve(table, objective="sum_completion", time_limit=60)
    assert out.status_objective == "makespan"
    assert out.extra["objective"] == "makespan"


@pytest.mark.parametrize("objective", ["makespan", "sum_completion", "human_idle"])
def test_milp_stations_through_solve(objective):
    """The registry lets milp take stations; the result reports each station, and the chosen
    objective's value is the stations' completions or idles summed; the checker accepts it."""
    from bilevel_kit.methods import solve

    inst = from_dict(strategies.stations_doc(4, 3, n=5))
    res = solve(inst, "milp", time_limit=60, check=True, objective=objective)
    assert res.extra["violations"] == []
    metrics = res.extra["station_metrics"]
    assert max(m["completion"] for m in metrics.values()) == res.makespan
    if objective != "makespan":
        key = "completion" if objective == "sum_completion" else "human_idle"
        want = sum(m[key] for m in metrics.values())
        assert res.objective == pytest.approx(want, abs=1e-9)
        assert res.status_text == f"optimal (for {objective})"


#: tests/stations_example.py: first_tray_doc's optima (the brute force's).
FIRST_TRAY = {"makespan": 31.0, "sum_completion": 62.0, "human_idle": 3.0}


@pytest.mark.parametrize("objective", list(FIRST_TRAY))
def test_milp_stations_a_first_kit_waits_for_no_tray(objective):
    """Issue 35, item 1. [a1] [b1 b2] [a2 a3] of tests/stations_example.py: a1 arrives at 1
    and A works until 13; B has no tray out, so its robot starts at 1 (docs/timeline.md
    #several-stations), the kit arrives at 2.5 and B ends at 2.5 + 6 + 22.5 = 31; a1's tray is
    back at 4, [a2 a3] arrives at 5.5 and A ends at 13 + 3 + 15 = 31: makespan 31 s and 62 s
    of completions, both optimal. The stations master made the first kit of a one-tray station
    at a position k >= 1 wait ``o_H`` for a tray (B's robot until 6, B's end 36), and milp
    proved a plan of 62.5 s of completions and one of makespan 32.5 s optimal."""
    from stations_example import first_tray_doc

    from bilevel_kit.models.milp import MilpOptions, milp

    inst = from_dict(first_tray_doc())
    optimum = FIRST_TRAY[objective]
    assert best_makespan(inst, objective)[0] == optimum
    out = milp(inst, MilpOptions(objective=objective), seed=0, time_limit=60)
    assert out.plan is not None and check(inst, out.plan) == []
    assert objective_of(evaluate(inst, out.plan), objective) == pytest.approx(optimum, abs=1e-6)
    assert out.status == "optimal"
    if objective == "makespan":
        assert_model_optimal(out, optimum, tol=1e-5)
    else:
        assert_objective_optimal(out, optimum)


@pytest.mark.parametrize("objective", ["sum_completion", "human_idle"])
@pytest.mark.parametrize(
    "kits", [[["a1"], ["b1", "b2"], ["a2", "a3"]], [["a1"], ["b1"], ["a2"], ["a3"], ["b2"]]]
)
def test_milp_stations_master_prices_a_plan_at_its_timeline(kits, objective):
    """The stations master with a plan's binaries fixed is the plan's objective
    (:func:`bilevel_kit.models.milp.model.model_objective`, docs/formulations.md): b1 comes
    second and its robot starts when a1 has arrived, not ``o_H`` later (the optimal plans of
    the sum of completions and of the total idle)."""
    import pyomo.environ as pyo
    from stations_example import first_tray_doc

    from bilevel_kit.models.budget import Budget
    from bilevel_kit.models.milp import run_solver
    from bilevel_kit.models.milp.model import build, model_objective, set_start
    from bilevel_kit.plan import Kit, Plan

    inst = from_dict(first_tray_doc())
    value = model_objective(
        inst, evaluate(inst, Plan(tuple(Kit(tuple(k)) for k in kits))), objective
    )
    master = build(inst, inst.n_tasks, 100.0, objective, 0.0)
    set_start(master, inst, kits)
    m = master.model
    for var in m.component_data_objects(pyo.Var):
        if var.is_binary():
            var.fix(round(var.value))
    info = run_solver(m, None, "highs", budget=Budget(30), objective=m.obj)
    assert info.optimal
    assert info.objective == pytest.approx(value, abs=1e-6)
