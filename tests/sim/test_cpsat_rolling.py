"""The cpsat-rolling simulation policy: exactness, validity, online information."""

from __future__ import annotations

import subprocess
import sys
from dataclasses import asdict

import pytest

from bilevel_kit import Kit, Plan, check, evaluate, solve
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


@pytest.mark.parametrize(("trays", "busy"), [(1, 50.0), ("unlimited", 50.0 - 4.0)])
def test_expected_waits_are_releases_and_the_human_token(table, trays, busy):
    # one tray: the dummy kit holds it for the human's whole remaining time; unlimited trays:
    # it only shifts time, its o_H is added back by the sub-instance's kit overhead
    table = table.with_overrides(trays=trays)
    policy = make_policy("cpsat-rolling", table, params=SimParams())
    assert asdict(policy.options) == {
        "window": 12,
        "supply_window": 8,
        "deterministic_time": 0.1,
        "time_limit": 10.0,
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
    waits = policy._waits(window, state)
    # the first leg is in stock; the second arrives in 20 s expected: a release, counted from
    # the model's "now" (after the dummy kit; with one tray after its tray came back)
    assert waits == {"foot1": 0.0, "conn1": 0.0, "foot2": pytest.approx(20.0), "top1": 0.0}
    tray = table.kit_overhead_human if trays == 1 else 0.0
    now = table.kit_overhead_robot + table.delivery_time + tray
    assert policy._now(50.0) == pytest.approx(now)
    assert policy._now(0.0) == 0.0
    times = {t: table.robot_time(t) for t in window}
    sub = policy._sub_instance(window, times, 50.0)
    assert sub.tasks[0].id == "__human_busy__"
    assert sub.task_by_id["__human_busy__"].human_mean == pytest.approx(busy)
    assert all(("__human_busy__", t) in set(sub.precedence) for t in window)


def test_unknown_option_is_a_usage_error(table):
    from bilevel_kit import UsageError

    with pytest.raises(UsageError, match="unknown option"):
        make_policy("cpsat-rolling", table, params=SimParams(policy_options={"speed": 2}))


def test_one_tray_token_holds_the_tray(table):
    """With one tray the dummy kit carries the human's whole remaining work h0 and the tray:
    its tray is back exactly when the robot may start (o_R + d + o_H), the human is busy h0
    after that, and the sub-instance has the instance's tray limit."""
    one = table.with_overrides(trays=1)
    policy = make_policy("cpsat-rolling", one, params=SimParams())
    window = ["foot1", "conn1", "top1"]
    times = {t: one.robot_time(t) for t in window}
    sub = policy._sub_instance(window, times, 50.0)
    assert sub.tray_limit == 1
    assert sub.task_by_id["__human_busy__"].human_mean == pytest.approx(50.0)
    plan = Plan((Kit(("__human_busy__",)), Kit(("foot1",)), Kit(("conn1", "top1"))))
    tl = evaluate(sub, plan)
    shift = one.kit_overhead_robot + one.delivery_time + one.kit_overhead_human
    assert tl.kits[1].robot_start == pytest.approx(shift)
    assert tl.kits[0].human_end == pytest.approx(shift + 50.0)
    # no remaining work: no token (the tray is back, the human idle)
    assert "__human_busy__" not in policy._sub_instance(window, times, 0.0).task_by_id
    # unlimited trays: the token only shifts time, as before
    unlimited = table.with_overrides(trays="unlimited")
    free = make_policy("cpsat-rolling", unlimited, params=SimParams())._sub_instance(
        window, times, 50.0
    )
    assert free.tray_limit is None
    assert free.task_by_id["__human_busy__"].human_mean == pytest.approx(50.0 - 4.0)


def test_warm_start_hint_is_the_previous_plan_on_the_window(table):
    policy = make_policy("cpsat-rolling", table, params=SimParams())
    policy._rest = (("conn1", "top1"), ("foot2", "conn2"))
    assert policy._warm_kits(["conn1", "top1", "foot2", "foot3"]) == (
        ("conn1", "top1"),
        ("foot2",),
        ("foot3",),
    )
    policy.reset()
    assert policy._warm_kits(["foot1", "conn1"]) == (("foot1",), ("conn1",))


def _burn(seconds: float) -> subprocess.Popen:
    """A CPU-burning child process (machine load) for ``seconds``."""
    code = f"import time\nt = time.time() + {seconds}\nwhile time.time() < t: pass\n"
    return subprocess.Popen([sys.executable, "-c", code])


def test_runs_are_identical_under_machine_load(table):
    """Decisions are limited in deterministic units (one worker): the same run twice, once
    with CPU-burning processes beside it, gives identical records."""
    params = SimParams(units=2)
    quiet = run(table, "cpsat-rolling", params=params, seed=3)
    burners = [_burn(60.0) for _ in range(3)]
    try:
        loaded = run(table, "cpsat-rolling", params=params, seed=3)
    finally:
        for p in burners:
            p.kill()
            p.wait()
    assert loaded == quiet


def _supply_state(arrival: float) -> SimState:
    """One leg in stock, the next expected in ``arrival`` s, the human idle."""
    from bilevel_kit.instance import Supply

    return SimState(
        time=0.0,
        done=frozenset(),
        human_remaining=0.0,
        available={"leg": 1, "foot": 4, "connector": 4, "screw_short": 8, "screw_long": 8},
        expected_arrival={"leg": arrival},
        supply={"leg": Supply(mat=60.0)},
    )


def test_releases_enter_the_memo_key_and_order_the_committed_kit(table):
    """Missing legs become releases of the later foot tasks (and, raised, of their chains):
    the decision depends on them (memo key) and the committed kit lists its tasks in release
    order (the robot picks in kit order)."""
    policy = make_policy("cpsat-rolling", table, params=SimParams())
    kits = {}
    for arrival in (5.0, 400.0, 400.0):
        policy.reset()
        kits[arrival] = policy.decide(_supply_state(arrival))
    assert len(policy._memo) == 2  # the repeated state is a memo hit
    for arrival, kit in kits.items():
        waits = policy._waits(policy._order[:12], _supply_state(arrival))
        assert waits["foot1"] == 0.0 and waits["foot2"] == pytest.approx(arrival)
        raised = [
            max([waits[t]] + [waits[a] for a in table.ancestors[t] if a in waits])
            for t in kit.tasks
        ]
        assert raised == sorted(raised), kit.tasks
    # with the next leg 400 s away the robot does not start with a kit that waits for it
    assert set(kits[400.0].tasks) <= {"foot1", "conn1", "top1"}
    assert kits[400.0].tasks[0] == "foot1"


def test_without_supply_the_window_model_is_solved_without_releases(table):
    """No supply: no release reaches the sub-model, and zero releases decide exactly as no
    releases (the no-delay decisions are the model's plan without releases, unchanged)."""
    policy = make_policy("cpsat-rolling", table, params=SimParams())
    state = SimState(time=0.0, done=frozenset(), human_remaining=30.0, available={})
    window = policy._order[:12]
    assert policy._waits(window, state) == dict.fromkeys(window, 0.0)
    times = {t: table.robot_time(t) for t in window}
    warm = policy._warm_kits(window)
    none = policy._solve(window, times, 30.0, warm, {})
    zeros = policy._solve(window, times, 30.0, warm, dict.fromkeys(window, 0.0))
    assert none == zeros
    kit = policy.decide(state)
    assert (kit.tasks, policy._rest) == (none[0].tasks, none[1])


def _first_decision(instance) -> tuple[tuple[str, ...], tuple[tuple[str, ...], ...]]:
    """A fresh policy's first kit and the rest of its plan, from a cold packing cache."""
    from bilevel_kit.models import packing_oracle

    packing_oracle.clear_cache()
    policy = make_policy("cpsat-rolling", instance, params=SimParams())
    kit = policy.decide(SimState(time=0.0, done=frozenset(), human_remaining=0.0, available={}))
    assert kit is not None
    return kit.tasks, policy._rest


def test_decisions_do_not_depend_on_the_packing_clock(monkeypatch):
    """The window's packing calls are limited by deterministic time (docs/simulation.md,
    "Determinism"): with a clock under which every wall-clock packing limit has passed before
    CP-SAT starts, the decision is the same; the wall-limited solve (the ``cpsat`` method's)
    would take the kit b + c, which only CP-SAT packs, for one that does not fit."""
    from slowclock import hard_instance, slow_packing_clock

    import bilevel_kit.models.cpsat as exact
    from bilevel_kit.models import packing_oracle

    inst = hard_instance()
    quiet = _first_decision(inst)
    assert quiet == (("a",), (("b", "c"),))
    slow_packing_clock(monkeypatch)
    assert _first_decision(inst) == quiet
    wall_solve = exact.solve

    def wall(*args, **kw):
        kw["deterministic"] = False
        kw["fallback"] = "none"  # the model alone (the LNS first runs in wall-clock runs)
        return wall_solve(*args, **kw)

    monkeypatch.setattr(exact, "solve", wall)
    assert _first_decision(inst) == (("a", "b"), (("c",),))
    packing_oracle.clear_cache()


def _reproducible_solve() -> dict:
    """A reproducible solve of the hard kit's instance (as a ``cpsat-rolling`` window solves)
    from a cold packing cache: its plan, cuts, iterations and safety-net record."""
    from slowclock import hard_instance

    import bilevel_kit.models.cpsat as exact
    from bilevel_kit.models import packing_oracle

    packing_oracle.clear_cache()
    out = exact.solve(
        hard_instance(),
        time_limit=60.0,  # a safety net only: far above what the solve needs on a busy machine
        workers=1,
        tray="benders",
        cpsat_params={"max_deterministic_time": 0.1},
        deterministic=True,
    )
    assert out.plan is not None
    keys = ("makespan", "n_kits", "cuts", "master_solves", "bound_lp_kits", "safety_net")
    return {"kits": [k.tasks for k in out.plan.kits]} | {k: out.extra.get(k) for k in keys}


def test_reproducible_solve_reads_no_clock(monkeypatch):
    """docs/simulation.md#determinism: the seed cuts, the cut shrinking, the quick plans and
    the packing calls of a reproducible solve are limited by work, not by the clock; with
    every wall-clock limit of theirs passed, the solve is the same. Its safety nets (the
    run's budget, the kit-count LP's) record that they fired."""
    from slowclock import NET_CLOCKS, STEP_CLOCKS, slow_clock

    from bilevel_kit.models import packing_oracle

    # the packing calls' own nets (10 x their limit) can fire on a machine many times
    # oversubscribed (measured: 0.0125 deterministic units took 0.5 s at load 12 on 2 cores);
    # this test is about the steps' clocks, so those nets are set out of reach
    monkeypatch.setattr(packing_oracle, "SAFETY_NET", 1000.0)
    quiet = _reproducible_solve()
    assert quiet == {
        "kits": [("a",), ("b", "c")],
        "makespan": 170.0,
        "n_kits": 2,
        "cuts": quiet["cuts"],
        "master_solves": quiet["master_solves"],
        "bound_lp_kits": quiet["bound_lp_kits"],
        "safety_net": False,
    }
    assert quiet["bound_lp_kits"]  # the kit-count LP bound was computed
    with monkeypatch.context() as mp:
        slow_clock(mp, STEP_CLOCKS)
        assert _reproducible_solve() == quiet
    with monkeypatch.context() as mp:
        slow_clock(mp, STEP_CLOCKS + NET_CLOCKS)
        assert _reproducible_solve()["safety_net"] is True
