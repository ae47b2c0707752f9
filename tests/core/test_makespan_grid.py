"""The makespan's grid (docs/formulations.md#what-optimal-means): every makespan is a sum of
the instance's times, so it lies on their greatest common divisor, and a lower bound rounded up
onto that grid still holds; ``solve`` rounds every method's bound so and calls a plan the
bound reaches optimal."""

from __future__ import annotations

import math

import pytest
from hypothesis import HealthCheck, given, settings
from strategies import timeline_cases

from bilevel_kit import load
from bilevel_kit.bounds import makespan_grid, on_grid
from bilevel_kit.instance import from_dict
from bilevel_kit.plan import Kit, Plan, evaluate


def test_the_grid_of_whole_seconds_and_of_the_table():
    assert makespan_grid(load("instances/kitbench/sp_n12_s1_t1_tight_d10.json")) == 1.0
    assert makespan_grid(load("instances/hrc_table.json")) == pytest.approx(0.005)


def test_on_grid_rounds_up_past_float_noise_only():
    assert on_grid(2549.6, 1.0) == 2550.0
    assert on_grid(2549.0000000000005, 1.0) == 2549.0  # 25490 x 0.1 in floats
    assert on_grid(430.3712, 0.005) == 430.375
    assert on_grid(7.3, None) == 7.3 and on_grid(math.inf, 1.0) == math.inf


@settings(max_examples=300, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(timeline_cases(grid=True))
def test_every_time_of_a_plan_lies_on_the_grid(case):
    """Times on 1/8 s (their divisor often coarser): each kit's and task's end, each station's
    completion and the makespan are multiples of the grid, 1-3 stations, trays 1, 2 or
    unlimited."""
    doc, kits = case
    inst = from_dict(doc)
    grid = makespan_grid(inst)
    if grid is None:  # every time zero
        return
    tl = evaluate(inst, Plan(tuple(Kit(tuple(k)) for k in kits)))
    ends = [tl.makespan, *(k.human_end for k in tl.kits), *(k.robot_end for k in tl.kits)]
    for value in ends:
        steps = value / grid
        assert abs(steps - round(steps)) < 1e-6, (value, grid)


NEAR = """
from dataclasses import dataclass

from bilevel_kit import MethodOutput
from bilevel_kit.methods import Status, solve
from bilevel_kit.plan import evaluate


@dataclass(frozen=True)
class NearOptions:
    pass


def near(instance, options, *, seed=0, time_limit=None):
    plan = solve(instance, "single-task").plan
    return MethodOutput(plan, Status.FEASIBLE, evaluate(instance, plan).makespan - 0.5)
"""


@pytest.fixture
def near(tmp_path, monkeypatch):
    """A method whose bound is 0.5 s below its plan (status feasible)."""
    from bilevel_kit.methods import REGISTRY, register

    (tmp_path / "bk_near.py").write_text(NEAR)
    monkeypatch.syspath_prepend(str(tmp_path))
    register("near", "bk_near:near", "a bound half a second below", "bk_near:NearOptions")
    yield "near"
    REGISTRY.remove("near")


def test_solve_calls_a_plan_within_one_step_of_its_bound_optimal(near):
    from bilevel_kit.methods import solve

    inst = load("instances/kitbench/sp_n12_s1_t1_tight_d10.json")  # whole seconds
    res = solve(inst, near, check=True)
    assert res.status == "optimal" and res.extra["optimal_by_grid"] == 1.0
    assert res.bound == res.objective == res.makespan and res.gap == 0.0
    assert res.extra["violations"] == []


def test_solve_keeps_feasible_on_a_finer_grid(near):
    from bilevel_kit.methods import solve

    inst = load("instances/hrc_table.json")  # 0.005 s
    res = solve(inst, near, check=True)
    assert res.status == "feasible" and "optimal_by_grid" not in res.extra
    assert res.bound == pytest.approx(res.makespan - 0.5, abs=1e-9)
    assert res.gap == pytest.approx(0.5 / res.makespan) and res.extra["violations"] == []


def test_the_changelog_count_of_the_60s_pass():
    """CHANGELOG: on the committed 60 s pass's rows the grid makes 4 lns cells optimal."""
    from bilevel_kit.experiments.kitbench.profiles import read_rows

    grids: dict[str, float | None] = {}
    reached = []
    for r in read_rows("bench/results/kitbench_60s.csv"):
        if r["status"] == "optimal" or not r["valid"] or not r["bound"]:
            continue
        name = r["instance"]
        if name not in grids:
            grids[name] = makespan_grid(load(f"instances/kitbench/{name}.json"))
        if on_grid(float(r["bound"]), grids[name]) >= r["makespan"] - 1e-9:
            reached.append((name, r["method"]))
    assert len(reached) == 4 and {m for _, m in reached} == {"lns"}
    assert ("sp_n25_s2_t1_loose_d0", "lns") in reached
