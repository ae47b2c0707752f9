"""The tray rule in every exact model, against references written independently of them.

* One task per kit, d = 0, no overheads: with one tray the schedule is F2|block|Cmax
  (Gilmore-Gomory, tests/flowshop.py), with unlimited trays F2||Cmax (Johnson).
* Brute force over every segmentation (tests/brute.py, the one evaluator) with d, overheads,
  precedence and trays in {1, 2, unlimited}.
"""

from __future__ import annotations

import importlib.util
import random
import time

import pytest
import strategies
from brute import assert_model_optimal, best_makespan, segmentations
from flowshop import (
    blocking_makespan,
    flow_makespan,
    gilmore_gomory_order,
    jobs_doc,
    johnson_order,
)
from timing import PROOF_LIMIT

from bilevel_kit import bounds
from bilevel_kit.instance import Instance, from_dict
from bilevel_kit.plan import Kit, Plan, evaluate
from bilevel_kit.validate import check

pytest.importorskip("ortools")
HAVE_MILP = all(importlib.util.find_spec(m) is not None for m in ("pyomo", "highspy"))
needs_milp = pytest.mark.skipif(not HAVE_MILP, reason="pyomo or highspy is not installed")
TRAYS = (1, 2, None)


def flow_doc(a: list[float], b: list[float], trays: int | None) -> dict:
    """Jobs with robot time a_i and human time b_i; every task's part covers more than half
    of the tray, so no two tasks share a kit; d = 0, no overheads, no precedence."""
    return jobs_doc("flow", a, b, part=("plate", 80.0), trays=trays)


def random_jobs(seed: int, n: int) -> tuple[list[float], list[float]]:
    rng = random.Random(seed)
    return [float(rng.randint(1, 30)) for _ in range(n)], [
        float(rng.randint(1, 30)) for _ in range(n)
    ]


def random_doc(seed: int, trays: int | None, n: int | None = None) -> dict:
    """The exact tests' random instance (tests/strategies.py) with a busy robot, so that the
    tray rule binds, and ``trays`` kit trays."""
    doc = strategies.random_doc(seed, n, robot_share=0.6, robot_halves=(10, 50))
    doc["weights"] = {"W5": 0.01}
    if trays is not None:
        doc["trays"] = trays
    return doc


def assert_exact(inst: Instance, out, opt: float) -> None:
    """Optimal among the plans the model covers (the brute force: 0/90-degree plans, tests/
    brute.py), the brute-force makespan, a valid plan, and a bound that proves it there."""
    assert out.plan is not None and check(inst, out.plan) == []
    assert evaluate(inst, out.plan).makespan == pytest.approx(opt, abs=1e-6)
    assert_model_optimal(out, opt, tol=1e-5)


# ---------------------------------------------------------------------------------------------
# flow-shop references
# ---------------------------------------------------------------------------------------------


@pytest.mark.parametrize(("seed", "n"), [(0, 6), (1, 7), (2, 8), (3, 8)])
def test_one_tray_one_task_per_kit_is_the_blocking_flow_shop(seed, n):
    from bilevel_kit.models import cpsat as cs

    a, b = random_jobs(seed, n)
    ref = blocking_makespan(a, b, gilmore_gomory_order(a, b))
    inst = from_dict(flow_doc(a, b, 1))
    out = cs.solve(inst, time_limit=PROOF_LIMIT, tray="benders")
    assert_exact(inst, out, ref)
    assert all(len(k.tasks) == 1 for k in out.plan.kits)
    assert bounds.best_bound(inst) <= ref + 1e-9
    assert ref >= flow_makespan(a, b, johnson_order(a, b))


@pytest.mark.parametrize(("seed", "n"), [(2, 10), (0, 12), (1, 12)])
def test_cpsat_bound_and_plan_bracket_the_blocking_optimum(seed, n):
    """10-12 jobs are beyond a quick proof for the CP-SAT model (the MILP proves them below);
    within 5 s its bound and its plan must still bracket the Gilmore-Gomory optimum."""
    from bilevel_kit.models import cpsat as cs

    a, b = random_jobs(seed, n)
    ref = blocking_makespan(a, b, gilmore_gomory_order(a, b))
    inst = from_dict(flow_doc(a, b, 1))
    out = cs.solve(inst, time_limit=5.0, tray="benders")
    assert out.plan is not None and check(inst, out.plan) == []
    assert out.bound <= ref + 1e-9 <= out.extra["makespan"] + 2e-9


@needs_milp
@pytest.mark.parametrize(("seed", "n"), [(0, 8), (1, 10), (0, 12)])
def test_milp_one_tray_equals_gilmore_gomory(seed, n):
    from bilevel_kit.models import milp as ms

    a, b = random_jobs(seed, n)
    ref = blocking_makespan(a, b, gilmore_gomory_order(a, b))
    inst = from_dict(flow_doc(a, b, 1))
    assert_exact(inst, ms.solve(inst, time_limit=PROOF_LIMIT), ref)


@pytest.mark.parametrize(("seed", "n"), [(0, 6), (2, 8), (3, 10)])
def test_unlimited_trays_one_task_per_kit_is_johnson(seed, n):
    from bilevel_kit.models import cpsat as cs

    a, b = random_jobs(seed, n)
    ref = flow_makespan(a, b, johnson_order(a, b))
    inst = from_dict(flow_doc(a, b, None))
    assert_exact(inst, cs.solve(inst, time_limit=PROOF_LIMIT, tray="benders"), ref)
    if HAVE_MILP:
        from bilevel_kit.models import milp as ms

        assert_exact(inst, ms.solve(inst, time_limit=PROOF_LIMIT), ref)


# ---------------------------------------------------------------------------------------------
# brute force with d, overheads, precedence and trays
# ---------------------------------------------------------------------------------------------

BRUTE_CASES = [(seed, trays) for seed in range(5) for trays in TRAYS] + [(5, 1), (6, 2)]


@pytest.mark.parametrize(("seed", "trays"), BRUTE_CASES)
def test_cpsat_both_modes_equal_brute_force(seed, trays):
    from bilevel_kit.models import cpsat as cs

    inst = from_dict(random_doc(seed, trays, n=7 if seed >= 5 else None))
    opt, _ = best_makespan(inst)
    for mode in ("embedded", "benders"):
        out = cs.solve(inst, tray=mode, time_limit=PROOF_LIMIT)
        assert out.extra["tray_mode"] == mode
        assert_exact(inst, out, opt)
    assert bounds.best_bound(inst) <= opt + 1e-9


@needs_milp
@pytest.mark.parametrize(("seed", "trays"), BRUTE_CASES[:12])
def test_milp_equals_brute_force(seed, trays):
    from bilevel_kit.models import milp as ms

    inst = from_dict(random_doc(seed, trays))
    opt, _ = best_makespan(inst)
    assert_exact(inst, ms.solve(inst, time_limit=PROOF_LIMIT), opt)


def test_the_tray_rule_binds_on_some_random_instance():
    """The brute-force optimum grows from unlimited to one tray on most instances, so the
    cases above test the rule and not only the old timeline."""
    grows = 0
    for seed in range(5):
        free = best_makespan(from_dict(random_doc(seed, None)))[0]
        one = best_makespan(from_dict(random_doc(seed, 1)))[0]
        assert one >= free - 1e-9
        grows += one > free + 1e-9
    assert grows >= 3


@needs_milp
@pytest.mark.parametrize(("seed", "trays"), [(0, 1), (1, 2), (2, 1), (3, 2), (4, None)])
def test_bilevel_milp_is_exact_for_its_objective_under_trays(seed, trays):
    """bilevel-milp's claim (its docstring): J of its plan, computed by the MILP, equals the
    evaluator-based J, and no segmentation (all of them are convex kits) has a smaller J."""
    from bilevel_kit.heuristics.cross_entropy import CEParams
    from bilevel_kit.models import bilevel_milp as kc

    inst = from_dict(random_doc(seed, trays))
    ce = CEParams(samples=60, elite=10, max_iter=25)
    t0 = time.perf_counter()
    out = kc.solve(inst, time_limit=30.0, lower="ce", ce_params=ce)
    assert time.perf_counter() - t0 <= 31.5
    assert out.extra["optimal_over_columns"], out.extra
    proven = out.extra["excluded_axis_aligned"] + out.extra["excluded_unproven"] == 0
    assert (out.status == "optimal") == proven, out.extra
    assert check(inst, out.plan) == []
    lower = kc.LowerLevel(inst, lower="ce", ce_params=ce)
    value = out.extra["objective_value"]
    assert value == pytest.approx(kc.paper_objective(inst, out.plan, lower), abs=1e-9)
    assert value == pytest.approx(out.extra["plan_objective_J_milp"], abs=1e-5)
    best = min(
        kc.paper_objective(inst, Plan(tuple(Kit(k) for k in kits)), lower)
        for kits in segmentations(inst)
        if all(lower.value(inst.kit_parts(k)).fits for k in kits)
    )
    assert value == pytest.approx(best, abs=1e-5)
