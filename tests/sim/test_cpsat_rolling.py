"""The cpsat-rolling simulation policy: exactness, validity, online information."""

from __future__ import annotations

from dataclasses import asdict

import pytest

from bilevel_kit import check, evaluate, solve
from bilevel_kit.sim import POLICIES, SimParams, TimingModel, make_policy, run, simulate
from bilevel_kit.sim.cpsat_rolling import CPSATRollingPolicy
from bilevel_kit.sim.state import SimState


def test_registered_as_one_class():
    assert POLICIES["cpsat-rolling"] is CPSATRollingPolicy


def test_deterministic_run_equals_evaluator_and_reaches_the_optimum(table):
    # unlimited trays: the optimum below is the one without the tray rule (the table has one)
    params = SimParams(units=2, trays="unlimited", timing=TimingModel.deterministic())
    res = simulate(table, "cpsat-rolling", params=params, seed=0)
    assert check(res.instance, res.plan) == []
    tl = evaluate(res.instance, res.plan)
    assert res.makespan == pytest.approx(tl.makespan, abs=1e-9)
    assert [k.arrive for k in res.kit_times] == pytest.approx([k.arrive for k in tl.kits])
    # two tables: the exact whole-horizon optimum (proven by CP-SAT) is 810.56 s
    exact = solve(res.instance, "cpsat", time_limit=30)
    assert exact.status == "optimal" and exact.objective == pytest.approx(810.56)
    assert res.makespan == pytest.approx(810.56)
    assert res.makespan < simulate(table, "optimized", params=params, seed=0).makespan


def test_under_supply_delays_kits_are_valid_and_waits_happen(table):
    params = SimParams(units=2, mat={"leg": 60, "foot": 60}, mttf=90)
    res = simulate(table, "cpsat-rolling", params=params, seed=1)
    assert check(res.instance, res.plan) == []
    assert res.robot_wait > 0
    again = run(table, "cpsat-rolling", params=params, seed=1)
    assert again["makespan"] == pytest.approx(res.makespan)


def test_expected_waits_and_the_human_token(table):
    policy = make_policy("cpsat-rolling", table, params=SimParams())
    assert asdict(policy.options) == {
        "window": 12,
        "time_limit": 1.0,
        "workers": 1,
        "tray": "benders",
    }
    from bilevel_kit.instance import Supply

    state = SimState(
        time=0.0,
        done=frozenset(),
        human_remaining=50.0,
        available={"leg": 1, "foot": 4, "connector": 4, "screw_short": 8, "screw_long": 8},
        expected_arrival={"leg": 20.0},
        supply={"leg": Supply(mat=60.0)},
    )
    window = ["foot1", "conn1", "foot2", "top1"]
    times = policy._robot_times(window, state)
    # the first leg is in stock; the second arrives in 20 s expected
    assert times["foot1"] == pytest.approx(table.robot_time("foot1"))
    assert times["foot2"] == pytest.approx(table.robot_time("foot2") + 20.0)
    sub = policy._sub_instance(window, times, 50.0)
    assert sub.tasks[0].id == "__human_busy__"
    assert sub.task_by_id["__human_busy__"].human_mean == pytest.approx(50.0 - 4.0)
    assert all(("__human_busy__", t) in set(sub.precedence) for t in window)


def test_unknown_option_is_a_usage_error(table):
    from bilevel_kit import UsageError

    with pytest.raises(UsageError, match="unknown option"):
        make_policy("cpsat-rolling", table, params=SimParams(policy_options={"speed": 2}))
