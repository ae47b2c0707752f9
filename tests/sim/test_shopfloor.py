"""The shop-floor simulation: equivalence with the evaluator, valid kits, determinism, delays."""

from __future__ import annotations

import json
import math
from dataclasses import replace

import pytest
from simcheck import assert_matches_evaluator

from bilevel_kit import Plan, check, evaluate
from bilevel_kit.errors import UsageError
from bilevel_kit.heuristics.cross_entropy import CEParams
from bilevel_kit.heuristics.greedy_ce import GreedyCEPolicy, GreedyParams
from bilevel_kit.heuristics.greedy_ce import plan as greedy_plan
from bilevel_kit.plan import Kit, next_robot_start, tray_back
from bilevel_kit.sim import (
    POLICIES,
    UNLIMITED,
    SimParams,
    SimState,
    SimulationError,
    SingleTaskPolicy,
    TimingModel,
    effective_instance,
    make_policy,
    replicate,
    run,
    simulate,
)

CE = CEParams(samples=60, elite=10, max_iter=30)
DET = SimParams(timing=TimingModel.deterministic(), ce=CE)
DELAYS = SimParams(ce=CE, mat={"leg": 60.0, "foot": 60.0}, mttf=90.0)


@pytest.mark.parametrize("policy", sorted(POLICIES))
@pytest.mark.parametrize("name", ["table", "stool"])
@pytest.mark.parametrize("units", [1, 2])
def test_deterministic_run_equals_the_evaluator(request, policy, name, units) -> None:
    """No supply, deterministic times: simulated per-kit times == plan.evaluate (1e-9)."""
    inst = request.getfixturevalue(name)
    res = simulate(inst, policy, params=replace(DET, units=units), seed=7)
    assert res.robot_wait == 0 and res.n_waits == 0 and not res.feeders
    expanded = inst.with_overrides(units=units)
    assert res.n_kits >= 1 and sorted(res.plan.task_order) == sorted(t.id for t in expanded.tasks)
    assert_matches_evaluator(res, evaluate(expanded, res.plan))


@pytest.mark.parametrize("policy", sorted(POLICIES))
def test_sampled_times_without_supply_equal_the_evaluator(table, policy) -> None:
    """With sampled (not mean) times the evaluator, fed the same times, still agrees."""
    timing = TimingModel(task_cv=0.1, robot_cv=0.1)
    res = simulate(table, policy, params=SimParams(units=2, ce=CE, timing=timing), seed=3)
    tl = evaluate(
        res.instance,
        res.plan,
        robot_times=res.times.robot_times(),
        human_times=res.times.human,
    )
    assert_matches_evaluator(res, tl)
    assert res.human_work != pytest.approx(
        evaluate(res.instance, res.plan).human_work
    )  # times really were sampled


def test_calibration_knobs_reach_evaluator_and_policy(table) -> None:
    timing = TimingModel.deterministic(
        robot_scale=1.5, human_scale=0.8, kit_overhead_robot=3.0, kit_overhead_human=7.0
    )
    params = SimParams(units=2, delivery_time=10.0, timing=timing)
    res = simulate(table, "single-task", params=params, seed=0)
    eff = res.instance
    assert eff.kit_overhead_human == 7.0 and eff.kit_overhead_robot == 3.0
    assert eff.delivery_time == 10.0
    assert eff.robot_time("foot1@1") == pytest.approx(1.5 * table.robot_time("foot1"))
    assert eff.human_time("foot1@2") == pytest.approx(0.8 * table.human_time("foot1"))
    assert_matches_evaluator(res, evaluate(eff, res.plan))


@pytest.mark.parametrize(
    "trays",
    [
        "unlimited",
        pytest.param(
            1,
            marks=pytest.mark.xfail(
                reason="the simulated robot decides once its tray is back; greedy-ce's offline "
                "plan still decides at arrive_{k-1} (issue 11, the greedy-ce part)",
                strict=False,
            ),
        ),
    ],
)
def test_optimized_deterministic_matches_offline_greedy_plan(table, trays) -> None:
    """Online, deterministic and without supply, the policy sees exactly the offline state."""
    inst = table.with_overrides(units=2, trays=trays)
    res = simulate(table, "optimized", params=replace(DET, units=2, trays=trays), seed=0)
    offline = greedy_plan(inst, policy=GreedyCEPolicy(inst, GreedyParams(ce=CE), seed=0))
    assert [k.tasks for k in res.plan.kits] == [k.tasks for k in offline.kits]


def test_state_seen_by_the_policy(table) -> None:
    """Epochs at t = 0 and each arrival, once a tray is back (the table has one); the state's
    human_remaining is the evaluator's backlog then."""
    seen: list[SimState] = []

    class Spy(SingleTaskPolicy):
        def decide(self, state: SimState):
            seen.append(state)
            return super().decide(state)

    params = replace(DET, units=1)
    spy = Spy(effective_instance(table, params), params=params)
    res = simulate(table, spy, params=params, seed=0)
    tl = evaluate(table, res.plan)
    assert len(seen) == res.n_kits + 1  # the last call returns None
    assert seen[0].time == 0 and seen[0].human_remaining == 0 and not seen[0].done
    for k, st in enumerate(seen[1:], start=1):
        prev = tl.kits[k - 1]
        # the last call (all tasks kitted, it returns None) does not wait for a tray
        now = next_robot_start(table, tl.kits[:k]) if k < res.n_kits else prev.arrive
        assert now >= prev.arrive
        assert st.time == pytest.approx(now)
        assert st.human_remaining == pytest.approx(max(0.0, prev.human_end - now))
        assert st.done == frozenset(res.plan.task_order[:k])
        assert all(v == UNLIMITED for v in st.available.values())
        assert st.policy_state().available is None  # W7 inactive without supply
    assert sum(s.human_remaining > 0 for s in seen) > 5  # the backlog is not trivially zero


@pytest.mark.parametrize("policy", sorted(POLICIES))
@pytest.mark.parametrize("pick_order", ["kit", "available-first"])
def test_simulated_kits_pass_the_checker(table, stool, policy, pick_order) -> None:
    """Kits (with the policy's layouts) executed under delays and sampled times are valid,
    on the expanded instance and unit by unit (kits spanning two units are only checked on the
    expanded instance)."""
    per_unit = 0
    for inst, mat in ((table, {"leg": 60.0, "foot": 60.0}), (stool, {"leg": 20.0})):
        params = replace(DELAYS, units=2, mat=mat, pick_order=pick_order)
        res = simulate(inst, policy, params=params, seed=1)
        assert check(inst.with_overrides(units=2), res.plan) == []
        for u in (1, 2):
            mine = [k for k in res.plan.kits if any(t.endswith(f"@{u}") for t in k.tasks)]
            if all(t.endswith(f"@{u}") for k in mine for t in k.tasks):
                base = [Kit(tuple(t.split("@")[0] for t in k.tasks), k.layout) for k in mine]
                assert check(inst, Plan(tuple(base))) == []
                per_unit += 1
    if policy in ("single-task", "whole-assembly"):
        assert per_unit == 4


@pytest.mark.parametrize("policy", sorted(POLICIES))
def test_same_seed_same_record_other_seed_other_record(table, policy) -> None:
    params = replace(DELAYS, units=3)
    a = run(table, policy, params=params, seed=5)
    b = run(table, policy, params=params, seed=5)
    assert a == b
    json.dumps(a)  # a plain JSON record
    spans = {run(table, policy, params=params, seed=s)["makespan"] for s in (1, 2, 3)}
    assert len(spans) == 3
    # replicate shares one policy object between runs and gives the same records
    reps = replicate(table, policy, params, seeds=[5, 1])
    assert reps[0] == a
    assert reps[1] == run(table, policy, params=params, seed=1)


@pytest.mark.parametrize("policy", sorted(POLICIES))
def test_supply_delays_make_the_robot_wait(table, policy) -> None:
    """MAT leg = foot = 60 s, MTTF 90 s: waits happen and the makespan grows."""
    grew = 0
    for seed in range(3):
        base = run(table, policy, params=replace(DELAYS, units=3, mat={}, mttf=None), seed=seed)
        slow = run(table, policy, params=replace(DELAYS, units=3), seed=seed)
        assert base["robot_wait"] == 0 and base["n_waits"] == 0
        assert slow["robot_wait"] > 0 and slow["n_waits"] > 0
        assert (
            slow["feeders"]["leg"]["consumed"] == 12 and slow["feeders"]["foot"]["consumed"] == 12
        )
        assert "connector" not in slow["feeders"]
        # same participants (common random numbers), only the supply differs
        assert slow["speed"] == base["speed"]
        grew += slow["makespan"] > base["makespan"]
        if policy in ("single-task", "whole-assembly"):  # fixed kits: delays only make it later
            assert slow["kits"] == base["kits"]
            assert slow["makespan"] >= base["makespan"] - 1e-9
    assert grew == 3


def test_whole_assembly_waits_for_the_whole_unit(table) -> None:
    """A whole-assembly kit needs 4 legs; with MAT 60 s and an empty start the first
    delivery comes no earlier than the 4th leg's arrival (mean 240 s)."""
    res = simulate(table, "whole-assembly", params=replace(DELAYS, units=1, mttf=None), seed=0)
    leg = res.feeders["leg"]
    assert leg["consumed"] == 4 and leg["arrivals"] >= 4
    assert res.kit_times[0].robot_end >= res.robot_wait
    assert res.kit_waits[0] == res.robot_wait > 0


def test_large_initial_stock_equals_no_supply(table) -> None:
    """Enough parts in stock from t = 0: no wait, same run as without supply processes."""
    for policy in sorted(POLICIES):
        params = replace(DELAYS, units=2, initial_stock=10**6)
        full = run(table, policy, params=params, seed=4)
        free = run(table, policy, params=replace(params, mat={}, mttf=None), seed=4)
        assert full["robot_wait"] == 0
        for key in ("makespan", "human_idle", "robot_idle", "kits", "kit_times"):
            assert full[key] == free[key], (policy, key)


def test_one_tray_waits_until_the_human_has_taken_the_parts(table) -> None:
    """The table's one tray (the study): kit k + 1 starts once kit k's parts are off the tray,
    ``o_H`` after the human started it; unlimited trays let the robot stack kits."""
    assert table.trays == 1
    params = replace(DET, units=2)
    res = simulate(table, "single-task", params=params, seed=0)
    kt, oh = res.kit_times, table.kit_overhead_human
    assert all(kt[k + 1].robot_start >= kt[k].human_start + oh - 1e-9 for k in range(len(kt) - 1))
    assert res.max_queue == 1 and res.robot_blocked > 0
    unbounded = simulate(table, "single-task", params=replace(params, trays="unlimited"), seed=0)
    assert unbounded.max_queue > 1 and unbounded.robot_blocked == 0
    assert res.makespan >= unbounded.makespan - 1e-9


@pytest.mark.parametrize("policy", ["single-task", "whole-assembly", "optimized"])
@pytest.mark.parametrize("trays", [1, 2, 3, "unlimited"])
@pytest.mark.parametrize("units", [1, 2])
def test_tray_rule_equals_the_evaluator(table, stool, policy, trays, units) -> None:
    """The planner and the world are one model: with deterministic times and no supply, the
    simulated run under any number of trays is ``plan.evaluate`` of its plan (1e-9)."""
    for inst in (table, stool):
        params = replace(DET, units=units, trays=trays)
        res = simulate(inst, policy, params=params, seed=1)
        expanded = inst.with_overrides(units=units, trays=trays)
        assert res.instance.trays == expanded.trays
        assert_matches_evaluator(res, evaluate(expanded, res.plan))
        if trays == "unlimited":
            assert res.robot_blocked == 0


def test_tray_wait_is_robot_blocked(table) -> None:
    """``robot_blocked`` is exactly the time the robot waited for a tray: the evaluator's
    ``robot_start_k - arrive_{k-1}`` summed (no supply, so no other wait)."""
    res = simulate(table, "single-task", params=replace(DET, units=2), seed=0)
    kt = res.kit_times
    gaps = sum(kt[k].robot_start - kt[k - 1].arrive for k in range(1, len(kt)))
    assert res.robot_blocked == pytest.approx(gaps, abs=1e-9)


def test_trays_param_is_checked() -> None:
    for bad in (0, -1, 1.5, "two", float("nan"), True):
        with pytest.raises(UsageError, match="trays"):
            SimParams(trays=bad)
    assert SimParams(trays="unlimited").trays == "unlimited"


def test_oracle_estimate_equals_expected_when_deterministic(table) -> None:
    a = run(table, "optimized", params=replace(DET, units=2), seed=0)
    b = run(table, "optimized", params=replace(DET, units=2, human_estimate="oracle"), seed=0)
    assert a["kits"] == b["kits"] and a["makespan"] == b["makespan"]


def test_metrics_are_consistent(table) -> None:
    rec = run(table, "optimized", params=replace(DELAYS, units=2), seed=2)
    assert rec["human_idle"] == pytest.approx(rec["makespan"] - rec["human_work"])
    assert rec["robot_idle"] == pytest.approx(rec["makespan"] - rec["robot_work"])
    assert rec["robot_idle"] >= rec["robot_wait"] - 1e-9
    assert rec["n_kits"] == len(rec["kits"]) == len(rec["kit_times"])
    assert rec["robot_wait"] == pytest.approx(sum(k["wait"] for k in rec["kit_times"]))
    assert rec["unit_end"][-1] == rec["makespan"] and rec["unit_end"][0] < rec["makespan"]
    assert sum(rec["human_times"].values()) + 4.0 * rec["n_kits"] == pytest.approx(
        rec["human_work"]
    )
    for k in rec["kit_times"]:
        assert k["robot_start"] <= k["robot_end"] <= k["arrive"] <= k["human_start"]
        assert k["human_start"] < k["human_end"]


def test_errors(table) -> None:
    with pytest.raises(UsageError, match="unknown policy"):
        run(table, "no-such-policy")
    with pytest.raises(UsageError, match="unknown part type"):
        run(table, "single-task", params=SimParams(mat={"bolt": 10.0}))
    with pytest.raises(UsageError, match="MAT"):
        run(table, "single-task", params=SimParams(mat={"leg": 0.0}))
    with pytest.raises(UsageError):
        SimParams(pick_order="random")
    other = make_policy("single-task", table.with_overrides(units=3))
    with pytest.raises(UsageError, match="different instance"):
        run(table, other, params=SimParams(units=2))

    class Bad(SingleTaskPolicy):
        def decide(self, state):
            return Kit(("top1",))  # top1 needs foot1 and conn1 first

    with pytest.raises(SimulationError, match="predecessor"):
        run(table, Bad(table), params=SimParams())

    class Quitter(SingleTaskPolicy):
        def decide(self, state):
            return None

    with pytest.raises(SimulationError, match="not kitted"):
        run(table, Quitter(table), params=SimParams())


def test_expected_wait_from_state(table) -> None:
    from bilevel_kit.instance import Supply

    st = SimState(
        time=0.0,
        done=frozenset(),
        human_remaining=0.0,
        available={"leg": 1, "foot": UNLIMITED},
        expected_arrival={"leg": 50.0},
        supply={"leg": Supply(40.0, 120.0, 30.0)},
    )
    assert st.expected_wait("foot", 3) == 0.0
    assert st.expected_wait("leg", 1) == 0.0
    assert st.expected_wait("leg", 3) == pytest.approx(50.0 + 40.0 * (1 + 30 / 120))
    assert math.isfinite(st.expected_wait("leg", 10))


@pytest.mark.parametrize("policy", ["single-task", "whole-assembly"])
def test_robot_timeline_replayed_from_arrivals(table, policy) -> None:
    """An independent replay: the j-th part of a supplied type can be picked no earlier than
    its j-th arrival (after the initial stock); picks in kit order; o_R, pick times, d; each kit
    starts once the tray is back (the table has one)."""
    params = replace(DELAYS, units=2, initial_stock=1, timing=TimingModel.deterministic())
    res = simulate(table, policy, params=params, seed=9)
    inst = res.instance
    used = {t: 0 for t in res.arrival_times}
    t = 0.0
    waits = 0
    for k, (kit, kt) in enumerate(zip(res.plan.kits, res.kit_times, strict=True)):
        t = max(t, tray_back(inst, res.kit_times[:k]))
        assert kt.robot_start == pytest.approx(t, abs=1e-9)
        t += inst.kit_overhead_robot
        for task in kit.tasks:
            for ptype, n in inst.task_by_id[task].parts:
                for _ in range(n):
                    if ptype in used:
                        j = used[ptype] - 1  # the first part came from the initial stock
                        used[ptype] += 1
                        if j >= 0 and res.arrival_times[ptype][j] > t:
                            t = res.arrival_times[ptype][j]
                            waits += 1
                    t += inst.part_types[ptype].pick_time
        assert kt.robot_end == pytest.approx(t, abs=1e-9)
        t += inst.delivery_time
        assert kt.arrive == pytest.approx(t, abs=1e-9)
    assert waits == res.n_waits > 0


def test_optimized_sees_the_stock_and_w7_acts(table) -> None:
    """With supply the greedy gets the stock (W7 on); switching W7 off changes the kits."""
    seen: list[SimState] = []
    params = replace(DELAYS, units=2)
    pol = make_policy("optimized", effective_instance(table, params), params=params)
    inner = pol.decide

    def spy(state: SimState):
        seen.append(state)
        return inner(state)

    pol.decide = spy  # type: ignore[method-assign]
    with_w7 = run(table, pol, params=params, seed=1)
    ps = [s.policy_state() for s in seen]
    assert all(p.available is not None for p in ps)
    assert all(p.available["connector"] == UNLIMITED for p in ps)
    assert any(p.available["leg"] == 0 for p in ps) and any(p.available["leg"] > 0 for p in ps)
    no_w7 = run(table, "optimized", params=replace(params, weights={"W7": 0.0}), seed=1)
    assert with_w7["kits"] != no_w7["kits"]
