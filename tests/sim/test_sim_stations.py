"""The simulation with several assembly stations: one human per station, shared robot and
feeders (docs/simulation.md#several-stations)."""

from __future__ import annotations

from dataclasses import replace

import pytest
from simcheck import assert_matches_evaluator

from bilevel_kit import check, evaluate, load
from bilevel_kit.errors import UsageError
from bilevel_kit.generate import generate
from bilevel_kit.instance import from_dict
from bilevel_kit.methods import solve
from bilevel_kit.sim import SimParams, TimingModel, make_policy, simulate
from bilevel_kit.sim.stations import STATION_POLICIES, station_policies

DET = SimParams(timing=TimingModel.deterministic())
FAST_CPSAT = {"window": 6, "deterministic_time": 0.05}


def _assert_timeline(res, tl) -> None:
    assert_matches_evaluator(res, tl, tasks=False)
    assert res.timeline.kit_stations == tl.kit_stations
    for t, start in tl.task_start.items():
        assert res.task_start[t] == pytest.approx(start, abs=1e-9, rel=0)


def _instances():
    return [
        load("instances/stations/table_stool_s2.json"),
        load("instances/stations/stool_u1_s3.json"),
        load("instances/stations/table_u1_s2.json"),
        from_dict(generate("table", 2, stations=2)),
        from_dict(generate("stool", 2, stations=3, trays=1)),
    ]


@pytest.mark.parametrize("policy", ["single-task", "whole-assembly"])
@pytest.mark.parametrize("index", range(5))
def test_deterministic_baselines_kit_the_offline_plan(policy, index) -> None:
    """Without supply and with mean times the simulated baselines choose the stations by the
    offline rule (earliest need): the same kits, and the sim's times are the evaluator's."""
    inst = _instances()[index]
    res = simulate(inst, policy, params=DET, seed=3)
    offline = solve(inst, policy).plan
    assert [k.tasks for k in res.plan.kits] == [k.tasks for k in offline.kits]
    _assert_timeline(res, evaluate(inst, res.plan))
    assert check(inst, res.plan) == []


def test_cpsat_rolling_with_stations_is_valid_and_timed_by_the_evaluator() -> None:
    inst = load("instances/stations/table_stool_s2.json")
    params = replace(DET, policy_options=FAST_CPSAT)
    res = simulate(inst, "cpsat-rolling", params=params, seed=0)
    assert check(inst, res.plan) == []
    _assert_timeline(res, evaluate(inst, res.plan))
    rec = res.record()
    assert set(rec["stations"]) == {"table", "stool"}
    assert max(m["completion"] for m in rec["stations"].values()) == pytest.approx(res.makespan)


@pytest.mark.parametrize("policy", ["single-task", "cpsat-rolling"])
def test_sampled_times_and_supply_delays_keep_the_rules(policy) -> None:
    """Sampled times and feeders: every kit holds one station's tasks in precedence order,
    the evaluator fed the sampled times agrees without supply, and delays only add waits."""
    inst = from_dict(generate("mixed", 1, stations=3))
    timing = TimingModel(task_cv=0.2, robot_cv=0.1)
    base = SimParams(timing=timing, policy_options=FAST_CPSAT if policy != "single-task" else {})
    res = simulate(inst, policy, params=base, seed=5)
    tl = evaluate(inst, res.plan, robot_times=res.times.robot_times(), human_times=res.times.human)
    _assert_timeline(res, tl)
    delayed = replace(base, mat={"leg": 40.0, "screw_long": 20.0}, mttf=90.0)
    late = simulate(inst, policy, params=delayed, seed=5)
    assert check(inst, late.plan) == []
    assert late.robot_wait > 0 and late.makespan > res.makespan
    per = late.record()["stations"]
    assert sum(m["n_kits"] for m in per.values()) == late.n_kits
    assert sum(m["human_idle"] for m in per.values()) == pytest.approx(late.human_idle)


def test_one_station_declared_gives_the_same_run_as_none() -> None:
    """A declared single station serving everything is the instance without stations."""
    plain = load("instances/hrc_table.json")
    doc = plain.to_dict()
    doc["stations"] = [{"id": "A", "serves": [t.product for t in plain.tasks][:1]}]
    one = from_dict(doc)
    params = SimParams(mat={"leg": 60.0}, mttf=90.0, units=1)
    a = simulate(plain, "single-task", params=params, seed=2)
    b = simulate(one, "single-task", params=params, seed=2)
    assert a.makespan == pytest.approx(b.makespan, abs=1e-9)
    assert [k.tasks for k in a.plan.kits] == [k.tasks for k in b.plan.kits]


def test_policies_without_stations_refuse_and_the_list_follows_the_methods(monkeypatch) -> None:
    inst = load("instances/stations/table_u1_s2.json")
    with pytest.raises(UsageError, match="does not model several assembly stations"):
        simulate(inst, "optimized-adaptive")
    with pytest.raises(UsageError, match="make_policy"):
        from bilevel_kit.sim.policies import SingleTaskPolicy

        simulate(inst, SingleTaskPolicy(inst))
    assert station_policies()[: len(STATION_POLICIES)] == STATION_POLICIES
    from bilevel_kit.methods import REGISTRY

    spec = REGISTRY["greedy-ce"]
    monkeypatch.setitem(REGISTRY, "greedy-ce", replace(spec, supports_stations=True))
    assert "optimized" in station_policies()
    monkeypatch.setitem(REGISTRY, "greedy-ce", replace(spec, supports_stations=False))
    assert "optimized" not in station_policies()


def test_a_policy_object_serves_several_runs() -> None:
    inst = load("instances/stations/stool_u1_s3.json")
    pol = make_policy("single-task", inst)
    a = simulate(inst, pol, params=DET, seed=1)
    b = simulate(inst, pol, params=DET, seed=1)
    assert a.record() == b.record()


def test_cli_simulates_stations_and_refuses_other_policies_before_any_run(capsys) -> None:
    from bilevel_kit.cli import main

    path = "instances/stations/table_stool_s2.json"
    assert main(["simulate", path, "--policy", "single-task", "--reps", "2", "-q"]) == 0
    assert "table_stool_s2: policy single-task" in capsys.readouterr().out
    assert main(["simulate", path, "--policy", "optimized-oracle", "-q"]) == 2
    assert "does not model several assembly stations" in capsys.readouterr().err


def test_optimized_runs_per_station_once_greedy_ce_plans_stations(monkeypatch) -> None:
    """The study picks ``optimized`` up when greedy-ce plans stations; the wrapper already
    runs it (a greedy-ce policy per station) and its run is timed by the evaluator."""
    from bilevel_kit.heuristics.cross_entropy import CEParams
    from bilevel_kit.methods import REGISTRY

    spec = REGISTRY["greedy-ce"]
    monkeypatch.setitem(REGISTRY, "greedy-ce", replace(spec, supports_stations=True))
    inst = load("instances/stations/table_u1_s2.json")
    ce = CEParams(samples=30, elite=6, max_iter=8)
    res = simulate(inst, "optimized", params=replace(DET, ce=ce), seed=0)
    assert check(inst, res.plan) == []
    _assert_timeline(res, evaluate(inst, res.plan))
