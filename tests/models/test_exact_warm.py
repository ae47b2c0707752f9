"""The exact methods' one warm-start loop (bilevel_kit.models.exact.warm): the best plan of the
methods, and the two rules (cpsat's default, milp's with several stations) where they differ."""

from __future__ import annotations

import pytest

from bilevel_kit.models.exact import warm
from bilevel_kit.models.exact.warm import DEFAULT, MIN_RUN, best_heuristic_plan
from bilevel_kit.models.milp.warm import RULE as MILP_STATIONS
from bilevel_kit.plan import evaluate


def test_the_best_baseline_is_the_warm_start(tiny):
    """single-task 25.5 s beats whole-assembly 32.5 s on tiny, whatever the order."""
    for methods in (("single-task", "whole-assembly"), ("whole-assembly", "single-task")):
        plan, name = best_heuristic_plan(tiny, methods)
        assert name == "single-task" and plan is not None
        assert evaluate(tiny, plan).makespan == 25.5
    assert best_heuristic_plan(tiny, ()) == (None, None)


def test_the_rules_share_time_differently(tiny):
    """cpsat's rule skips a method with at most 0.3 s left once a plan is known, milp's with
    stations gives it MIN_RUN; greedy-ce's overrun margin is 0.01 s per task against 0.002."""
    assert warm._time_for(tiny, "single-task", 0.2, DEFAULT, known=True) is None
    assert warm._time_for(tiny, "single-task", 0.2, DEFAULT, known=False) == 0.2
    assert warm._time_for(tiny, "single-task", 0.2, MILP_STATIONS, known=True) == 0.2
    assert warm._time_for(tiny, "single-task", -1.0, MILP_STATIONS, known=True) == MIN_RUN
    # 3 tasks: 2.0 - 3 x 0.002 (milp's rule has no kernel-load margin)
    assert warm._time_for(tiny, "greedy-ce", 2.0, MILP_STATIONS, known=True) == pytest.approx(
        2.0 - 3 * 0.002
    )


def test_a_near_tie_goes_to_the_later_plan_in_cpsat_and_the_earlier_in_milp(tiny, monkeypatch):
    """Values 100 and 100 - 1e-9: strictly less wins under cpsat's rule (tol 0), the first
    method keeps it under milp's (a plan is better only beyond the solver's 1e-6)."""
    values = {"single-task": 100.0, "whole-assembly": 100.0 - 1e-9}
    plans = {name: best_heuristic_plan(tiny, (name,))[0] for name in values}
    by_plan = {id(plans[name]): v for name, v in values.items()}
    monkeypatch.setattr(warm, "_heuristic_plan", lambda inst, name, seed, tl: (plans[name], False))
    monkeypatch.setattr(warm, "evaluate", lambda inst, plan: plan)
    monkeypatch.setattr(warm, "objective_of", lambda plan, objective: by_plan[id(plan)])
    methods = ("single-task", "whole-assembly")
    assert best_heuristic_plan(tiny, methods, time_limit=5.0)[1] == "whole-assembly"
    out = best_heuristic_plan(tiny, methods, time_limit=5.0, rule=MILP_STATIONS)
    assert out[1] == "single-task"


def test_milp_reports_greedy_ce_skipped_while_its_kernels_would_compile(tiny, monkeypatch):
    """With ``extra`` given, a skipped greedy-ce is said; the baseline's plan is kept."""
    monkeypatch.setattr(warm, "_kernels_would_compile", lambda: True)
    extra: dict[str, object] = {}
    methods = ("single-task", "greedy-ce")
    _, name = best_heuristic_plan(tiny, methods, 0, 5.0, "makespan", MILP_STATIONS, extra)
    assert name == "single-task"
    assert extra == {"warm_start_skipped": "greedy-ce: its kernels are not compiled"}


def test_a_warm_start_method_stopped_by_its_time_limit_is_listed(tiny, monkeypatch):
    """A method whose run its share of the time stopped is named in ``warm_start_cut``; its
    plan still competes (it is a valid plan), one that ran to its end is not named."""
    plans = {name: best_heuristic_plan(tiny, (name,))[0] for name in ("single-task", "greedy-ce")}
    cut = {"single-task": False, "greedy-ce": True}
    monkeypatch.setattr(
        warm, "_heuristic_plan", lambda inst, name, seed, tl: (plans[name], cut[name])
    )
    monkeypatch.setattr(warm, "_kernels_would_compile", lambda: False)
    extra: dict[str, object] = {}
    methods = ("single-task", "greedy-ce")
    plan, _ = best_heuristic_plan(tiny, methods, 0, 5.0, "makespan", MILP_STATIONS, extra)
    assert extra == {"warm_start_cut": ["greedy-ce"]}
    assert plan is not None
