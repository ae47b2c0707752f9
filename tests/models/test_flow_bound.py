"""The flow-shop bound (d) of bilevel_kit.bounds: its two-line form against Johnson's rule on
the explicit jobs, its validity against brute force (d, overheads, precedence, trays) and its
exactness on the Johnson special case (both exact models prove it at once)."""

from __future__ import annotations

import importlib.util
import random
import time

import pytest
from brute import best_makespan
from flowshop import flow_makespan, jobs_doc, johnson_order
from test_exact_trays import random_doc
from timing import load_factor

from bilevel_kit import bounds, check, solve
from bilevel_kit.instance import from_dict

HAVE_MILP = all(importlib.util.find_spec(m) is not None for m in ("pyomo", "highspy"))


def johnson_doc(seed: int, n: int) -> dict:
    """The Johnson special case: one small part type, d = 0, no overheads, no precedence,
    unlimited trays, random integer robot and human times."""
    rng = random.Random(seed)
    times = [(float(rng.randint(1, 30)), float(rng.randint(1, 30))) for _ in range(n)]
    a, b = [r for r, _ in times], [h for _, h in times]
    return jobs_doc(f"johnson_n{n}_s{seed}", a, b, prefix="t")


def test_two_lines_equal_johnson_with_m_overhead_jobs():
    rng = random.Random(0)
    for _ in range(2000):
        n = rng.randint(0, 7)
        a = [rng.randint(0, 9) for _ in range(n)]
        b = [rng.randint(0, 9) for _ in range(n)]
        a0, b0 = rng.randint(0, 5), rng.randint(0, 5)
        lines = bounds.johnson_lines(a, b, a0, b0)
        assert all(isinstance(c, int) for c, _ in lines)  # exact on the scaled integer times
        for m in range(1, 6):
            aa, bb = a + [a0] * m, b + [b0] * m
            ref = flow_makespan(aa, bb, johnson_order(aa, bb))
            assert bounds.lines_value(lines, m) == ref


@pytest.mark.parametrize("trays", [1, 2, None])
@pytest.mark.parametrize("seed", range(8))
def test_flow_bound_never_exceeds_the_brute_force_optimum(seed, trays):
    inst = from_dict(random_doc(seed, trays))
    opt, _ = best_makespan(inst)
    assert bounds.flow_bound(inst) <= opt + 1e-9
    assert bounds.best_bound(inst) <= opt + 1e-9


def test_flow_bound_beats_the_human_and_robot_bounds_on_flow_shops():
    """(a) and (b) are each one split of Johnson's makespan; on random Johnson instances the
    best split is sometimes in between (2 of these 10)."""
    wins = 0
    for seed in range(10):
        lb = bounds.lower_bounds(from_dict(johnson_doc(seed, 12)))
        assert lb["flow"] >= max(lb["human"], lb["robot"]) - 1e-9
        wins += lb["flow"] > max(lb["human"], lb["robot"]) + 1e-9
    assert wins >= 2


@pytest.mark.parametrize("n", [6, 20, 50, 200])
def test_johnson_special_case_is_proven_by_both_models(n):
    inst = from_dict(johnson_doc(n, n))
    a = [inst.robot_time(t.id) for t in inst.tasks]
    b = [inst.human_time(t.id) for t in inst.tasks]
    ref = flow_makespan(a, b, johnson_order(a, b))
    assert bounds.best_bound(inst) == pytest.approx(ref)
    for method in ("cpsat", "milp") if HAVE_MILP else ("cpsat",):
        t0 = time.perf_counter()
        res = (
            solve(inst, method, time_limit=60.0, hint="none")
            if method == "cpsat"
            else solve(inst, method, time_limit=60.0)
        )
        assert time.perf_counter() - t0 < 5.0 * load_factor()  # proven at once, not by search
        assert res.status == "optimal"
        assert res.objective == pytest.approx(ref) and res.bound == pytest.approx(ref)
        assert check(inst, res.plan) == []


def test_the_models_carry_the_flow_bound_without_the_shortcut():
    """A 6-task Johnson instance solved by the CP-SAT model itself (no incumbent: hint none
    and the quick plan is not used as the proof): the model's bound is Johnson's makespan."""
    from bilevel_kit.models.cpsat import model as cm
    from bilevel_kit.models.cpsat.scaling import scale_times

    ortools = pytest.importorskip("ortools.sat.python.cp_model")
    inst = from_dict(johnson_doc(1, 6))
    sc = scale_times(inst, 0.1)
    mdl = cm.build(
        inst, sc, K=6, upper=None, embedded=False, objective="makespan", pack_res=1.0, groups=[]
    )
    solver = ortools.CpSolver()
    solver.parameters.max_time_in_seconds = 10
    assert solver.solve(mdl.model) == ortools.OPTIMAL
    a = [inst.robot_time(t.id) for t in inst.tasks]
    b = [inst.human_time(t.id) for t in inst.tasks]
    assert solver.objective_value * sc.res == pytest.approx(
        flow_makespan(a, b, johnson_order(a, b))
    )
