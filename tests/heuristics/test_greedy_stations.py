"""greedy-ce with several assembly stations (docs/timeline.md#several-stations): one station
gives today's plans, several give plans the checker accepts, never below the brute force, near
the baselines, with the next kit for the station of earliest need."""

from __future__ import annotations

import contextlib
import json

import pytest
import strategies
from brute import best_makespan

from bilevel_kit import check, load, solve
from bilevel_kit.errors import KitDoesNotFit
from bilevel_kit.heuristics.greedy_ce import greedy_ce
from bilevel_kit.instance import from_dict
from bilevel_kit.plan import evaluate

pytest.importorskip("ortools")

CASES = [(seed, s) for seed in range(12) for s in (2, 3)]


@pytest.mark.parametrize(
    ("path", "makespan"),
    [("hrc_table.json", 463.78), ("generated/table_u2.json", 862.56)],
)
def test_one_station_gives_todays_plans(root, path, makespan):
    """Without ``stations`` the plan is today's; a declared station holding every task (the
    per-station path) gives the same plan."""
    inst = load(root / "instances" / path)
    res = solve(inst, "greedy-ce", seed=0)
    assert res.objective == pytest.approx(makespan)
    doc = json.loads((root / "instances" / path).read_text())
    doc["stations"] = [{"id": "A"}]
    for task in doc["tasks"]:
        task["station"] = "A"
    one = solve(from_dict(doc), "greedy-ce", seed=0, check=True)
    assert one.extra["violations"] == []
    assert one.plan == res.plan
    assert one.objective == res.objective


def _best_baseline(inst) -> float:
    best = solve(inst, "single-task").objective
    with contextlib.suppress(KitDoesNotFit):
        best = min(best, solve(inst, "whole-assembly").objective)
    return best


def test_random_stations_valid_above_brute_force_near_baselines():
    """24 random two- and three-station instances (the cpsat test's generator): every plan
    valid, never below the optimum; measured at most 18 % above the better baseline on one
    instance and below it in total."""
    total_greedy = total_base = 0.0
    for seed, n_stations in CASES:
        inst = from_dict(strategies.stations_doc(seed, n_stations, n=5 + seed % 2))
        out = greedy_ce(inst, seed=0)
        assert check(inst, out.plan) == [], (seed, n_stations)
        makespan = evaluate(inst, out.plan).makespan
        opt, _ = best_makespan(inst)
        base = _best_baseline(inst)
        assert makespan >= opt - 1e-9
        assert makespan <= 1.25 * base, (seed, n_stations, makespan, base)
        total_greedy += makespan
        total_base += base
    assert total_greedy <= total_base


def test_next_kit_goes_to_the_station_of_earliest_need():
    doc = strategies.stations_doc(5, 3, n=6)
    doc["units"] = 2
    inst = from_dict(doc)
    res = solve(inst, "greedy-ce", seed=0, check=True)
    assert res.extra["violations"] == []
    assert len(res.extra["kit_terms"]) == len(res.plan.kits) == res.extra["epochs"]
    tl = evaluate(inst, res.plan)
    ends = dict.fromkeys(inst.station_ids, 0.0)
    for k, (kit, kt) in enumerate(zip(res.plan.kits, tl.kits, strict=True)):
        s = inst.station_of(kit.tasks[0])
        left = {inst.station_of(x.tasks[0]) for x in res.plan.kits[k:]}
        assert ends[s] == min(ends[x] for x in left)
        ends[s] = kt.human_end
    metrics = res.extra["station_metrics"]
    assert max(m["completion"] for m in metrics.values()) == res.objective


def test_past_the_time_limit_single_task_kits_stay_valid():
    """A deadline already past (greedy-ce refuses a time limit shorter than its set-up, so
    the planner is called directly): every station's tasks alone, interleaved, valid."""
    from bilevel_kit.heuristics.greedy_ce import GreedyCEPolicy, PolicyState, plan
    from bilevel_kit.heuristics.greedy_stations import plan_greedy

    inst = from_dict(strategies.stations_doc(3, 3, n=6))
    result, stats = plan_greedy(inst, GreedyCEPolicy, PolicyState, plan, deadline=0.0)
    assert stats.time_limit_hit and stats.epochs == inst.n_tasks
    assert check(inst, result) == []
    assert all(len(k.tasks) == 1 for k in result.kits)


def test_simulation_without_delays_kits_the_offline_plan(root):
    """The simulation's ``optimized`` (a greedy-ce policy per station, earliest need first:
    docs/simulation.md#several-stations) with deterministic times and every part in stock
    kits what offline greedy-ce plans."""
    from bilevel_kit.sim import simulate
    from bilevel_kit.sim.params import SimParams, TimingModel

    inst = load(root / "instances" / "stations" / "table_u1_s2.json")
    offline = solve(inst, "greedy-ce", seed=0)
    params = SimParams(timing=TimingModel.deterministic())
    online = simulate(inst, "optimized", params=params, seed=0)
    assert [k.tasks for k in online.plan.kits] == [k.tasks for k in offline.plan.kits]
    assert online.timeline.makespan == pytest.approx(offline.objective)
