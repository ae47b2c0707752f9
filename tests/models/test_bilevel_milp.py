"""The paper's whole-plan objective and its exact optimum over enumerated kits."""

from __future__ import annotations

import importlib.util
import time
from pathlib import Path

import pytest
from brute import segmentations
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from strategies import binding_parts, binding_types
from timing import allowed

from bilevel_kit.errors import UsageError
from bilevel_kit.instance import from_dict, load
from bilevel_kit.models import bilevel_milp as kc
from bilevel_kit.plan import Kit, Plan
from bilevel_kit.validate import check

pytest.importorskip("pyomo")
if importlib.util.find_spec("highspy") is None:  # never import it here: see solvers/milp/solver.py
    pytest.skip("highspy is not installed", allow_module_level=True)

TABLE = Path(__file__).resolve().parents[2] / "instances" / "hrc_table.json"
TYPES = binding_types()
FAST_CE = {"samples": 60, "elite": 10, "max_iter": 25}


def two_task_doc() -> dict:
    return {
        "format": "bilevel-kit/1",
        "name": "two",
        "tray": {"width": 100.0, "height": 60.0},
        "delivery_time": 1.0,
        "kit_overhead": {"robot": 1.0, "human": 0.5},
        "part_types": TYPES,
        "tasks": [
            {
                "id": "t0",
                "parts": [{"type": "sq", "count": 1}],
                "robot_time": 2.0,
                "human_time": {"mean": 5.0},
            },
            {
                "id": "t1",
                "parts": [{"type": "sq", "count": 1}],
                "robot_time": 3.0,
                "human_time": {"mean": 1.0},
            },
        ],
    }


def plan_of(*kits: tuple[str, ...]) -> Plan:
    return Plan(tuple(Kit(k) for k in kits))


# ---------------------------------------------------------------------------------------------
# the objective, by hand
# ---------------------------------------------------------------------------------------------


def test_paper_objective_by_hand():
    """d = 1, o_R = 1, o_H = 0.5, W2 = W3 = W4 = 1, W5 = 0.001, f = 1000 per task.

    [t0], [t1]: R = 3, 4; H = 5.5, 1.5; kit 1 arrives at 4 and ends at 9.5, so B_1 = 5.5.
    kit 1: -1 + |1 + 3 - 0| + |1 + 4 - 5.5| - 1 = 2.5; kit 2: -1 + |1 + 4 - 5.5| + |1 - 1.5| - 1
    = -1; J = 1.5. Signed: 1.5 and -3, J = -1.5. [t0, t1]: -2 + |1 + 6| + |1 - 6.5| - 2 = 8.5.
    [t1], [t0]: B_1 = 6.5 - 5 = 1.5; 5.5 + 5 = 10.5.
    """
    inst = from_dict(two_task_doc())

    def per_task(kit: Kit) -> float:
        return 1000.0 * len(kit.tasks)

    assert kc.paper_objective(inst, plan_of(("t0",), ("t1",)), per_task) == pytest.approx(1.5)
    assert kc.paper_objective(
        inst, plan_of(("t0",), ("t1",)), per_task, signed=True
    ) == pytest.approx(-1.5)
    assert kc.paper_objective(inst, plan_of(("t0", "t1")), per_task) == pytest.approx(8.5)
    assert kc.paper_objective(inst, plan_of(("t1",), ("t0",)), per_task) == pytest.approx(10.5)
    terms = kc.paper_terms(inst, plan_of(("t0",), ("t1",)), per_task)
    assert [t["diff5"] for t in terms] == pytest.approx([4.0, 0.5])
    assert [t["diff6"] for t in terms] == pytest.approx([0.5, 0.5])
    heavier = kc.paper_objective(inst, plan_of(("t0",), ("t1",)), per_task, weights={"W3": 3.0})
    assert heavier == pytest.approx(1.5 + 2 * (4.0 + 0.5))


def test_convex_kit_enumeration_of_the_table():
    """Four chains foot -> conn -> top: per chain an interval or nothing, 7^4 - 1 sets."""
    inst = load(TABLE)
    kits = kc.enumerate_kits(inst)
    assert len(kits) == 2400
    assert frozenset({"foot1", "top1"}) not in kits  # not convex: conn1 lies between
    assert frozenset({"foot1", "conn1", "foot2"}) in kits
    with pytest.raises(UsageError, match="more than 100 candidate kits"):
        kc.enumerate_kits(inst, max_columns=100)


def test_size_limit_is_a_usage_error():
    inst = load(TABLE).with_overrides(units=2)  # 24 tasks
    with pytest.raises(UsageError, match="at most 16"):
        kc.solve(inst, time_limit=5.0)
    with pytest.raises(UsageError, match="at most 10"):
        kc.solve(load(TABLE), time_limit=5.0, max_tasks=10)


# ---------------------------------------------------------------------------------------------
# exactness and the comparison with greedy-ce
# ---------------------------------------------------------------------------------------------


@st.composite
def small_instances(draw, max_n: int = 5):
    n = draw(st.integers(2, max_n))
    half = st.integers(1, 40).map(lambda v: v / 2)
    tasks = []
    for i in range(n):
        task = {
            "id": f"t{i}",
            "parts": [{"type": k, "count": c} for k, c in binding_parts(draw)],
            "human_time": {"mean": draw(half)},
        }
        if draw(st.booleans()):
            task["robot_time"] = draw(half)
        tasks.append(task)
    pairs = [(a, b) for a in range(n) for b in range(a + 1, n)]
    edges = draw(st.lists(st.sampled_from(pairs), max_size=n, unique=True))
    doc = {
        "format": "bilevel-kit/1",
        "name": "kc_rand",
        "tray": {"width": 100.0, "height": 60.0},
        "delivery_time": draw(st.integers(1, 16)) / 2,
        "kit_overhead": {
            "robot": draw(st.integers(1, 6)) / 2,
            "human": draw(st.integers(1, 6)) / 2,
        },
        "part_types": TYPES,
        "tasks": tasks,
        "precedence": [[f"t{a}", f"t{b}"] for a, b in edges],
        "weights": {"W5": draw(st.sampled_from([0.001, 0.01]))},
        "horizon": draw(st.integers(1, 3)),
    }
    return from_dict(doc)


def brute_force(inst, lower) -> float:
    """Every precedence-feasible order x every cut pattern whose kits fit: the least J."""
    return min(
        (
            kc.paper_objective(inst, plan_of(*kits), lower)
            for kits in segmentations(inst)
            if all(lower.value(inst.kit_parts(k)).fits for k in kits)
        ),
        default=float("inf"),
    )


@settings(
    max_examples=5, deadline=None, derandomize=True, suppress_health_check=[HealthCheck.too_slow]
)
@given(small_instances())
def test_bilevel_optimum_is_exact_and_never_above_greedy(inst):
    from bilevel_kit.heuristics.cross_entropy import CEParams
    from bilevel_kit.heuristics.greedy_ce import GreedyCEOptions, greedy_ce

    ce = CEParams(**FAST_CE)
    t0 = time.perf_counter()
    out = kc.solve(inst, time_limit=30.0, lower="ce", ce_params=ce)
    wall = time.perf_counter() - t0
    assert wall <= allowed(30.0)
    assert out.extra["optimal_over_columns"], out.extra  # "optimal" needs every exclusion
    proven = out.extra["excluded_axis_aligned"] + out.extra["excluded_unproven"] == 0
    assert (out.status == "optimal") == proven, out.extra  # proven at any angle
    assert check(inst, out.plan) == []
    lower = kc.LowerLevel(inst, lower="ce", ce_params=ce)
    value = out.extra["objective_value"]
    assert value == pytest.approx(kc.paper_objective(inst, out.plan, lower), abs=1e-9)
    assert value == pytest.approx(out.extra["plan_objective_J_milp"], abs=1e-5)
    assert out.extra["objective_bound"] <= value + 1e-9
    assert value == pytest.approx(brute_force(inst, lower), abs=1e-5)
    assert out.bound is not None and out.bound <= out.extra["makespan"] + 1e-9

    greedy = greedy_ce(inst, GreedyCEOptions(**FAST_CE), seed=0)
    assert check(inst, greedy.plan) == []
    j_greedy = kc.paper_objective(inst, greedy.plan, lower)
    j_greedy_own = kc.paper_objective(inst, greedy.plan, kc.layout_fitness(inst))
    assert value <= j_greedy + 1e-6
    assert j_greedy <= j_greedy_own + 1e-6  # the lower level is never worse than greedy's CE


def test_stool_optimum_equals_greedy_and_its_number():
    """The 3-task stool (a1 -> a2, a1 -> a3): one kit per task is both optimal and greedy-ce's
    plan, and a2, a3 are interchangeable (symmetry constraint)."""
    from bilevel_kit.heuristics.greedy_ce import greedy_ce

    inst = load(TABLE.parent / "stool.json")
    out = kc.solve(inst, time_limit=30.0, lower="ce")
    assert out.status == "optimal"
    assert out.extra["columns"] == 7  # every subset but {} is convex here, and all fit
    assert [k.tasks for k in out.plan.kits] == [("a1",), ("a2",), ("a3",)]
    assert out.extra["objective_value"] == pytest.approx(54.0581203987, abs=1e-6)
    greedy = greedy_ce(inst, seed=0)
    lower = kc.LowerLevel(inst, lower="ce")
    assert kc.paper_objective(inst, greedy.plan, lower) == pytest.approx(
        out.extra["objective_value"], abs=1e-6
    )


def test_warm_start_and_cpsat_lower_level_keep_the_contract():
    """``lower="best"`` adds CP-SAT fitness layouts (never lowers f); a greedy warm start is
    accepted; J* can only improve over the CE-only value."""
    from bilevel_kit.heuristics.cross_entropy import CEParams
    from bilevel_kit.heuristics.greedy_ce import GreedyCEOptions, greedy_ce

    doc = two_task_doc()
    doc["tasks"].append(
        {
            "id": "t2",
            "parts": [{"type": "bar", "count": 1}, {"type": "sq", "count": 1}],
            "human_time": {"mean": 4.0},
        }
    )
    doc["precedence"] = [["t0", "t2"]]
    inst = from_dict(doc)
    ce = CEParams(**FAST_CE)
    greedy = greedy_ce(inst, GreedyCEOptions(**FAST_CE), seed=0)
    a = kc.solve(inst, time_limit=30.0, lower="ce", ce_params=ce, warm_plan=greedy.plan)
    b = kc.solve(inst, time_limit=30.0, lower="best", ce_params=ce, pack_time_limit=0.5)
    assert a.status == b.status == "optimal"
    assert b.extra["objective_value"] <= a.extra["objective_value"] + 1e-9
    for out in (a, b):
        assert check(inst, out.plan) == []


def test_registered_method_reports_a_makespan_bound(monkeypatch):
    """Through methods.solve: 'optimal' refers to J, so the bound must stay a makespan bound
    (the closed-form one), never the plan's own makespan."""
    from bilevel_kit.bounds import best_bound
    from bilevel_kit.methods import REGISTRY, MethodSpec, solve

    if "bilevel-milp" not in REGISTRY:  # until methods.py registers it
        spec = MethodSpec("bilevel-milp", "bilevel_kit.models.bilevel_milp:solve", "bilevel")
        monkeypatch.setitem(REGISTRY, "bilevel-milp", spec)
    inst = load(TABLE.parent / "stool.json")
    res = solve(inst, "bilevel-milp", time_limit=30.0, check=True, lower="ce")
    assert res.status == "optimal"
    assert res.extra["violations"] == []
    assert res.makespan_bound == pytest.approx(best_bound(inst))
    assert res.makespan_bound <= res.makespan
    # the result reports J, the objective it minimised, with its bound and gap
    assert res.objective_name == "J" and "objective_value" not in res.extra
    assert res.objective == pytest.approx(54.0581203987, abs=1e-6)
    assert res.bound <= res.objective + 1e-9
    assert res.gap == pytest.approx(abs(res.objective - res.bound) / max(1.0, abs(res.objective)))


def test_options_of_the_registered_method():
    from bilevel_kit.methods import get_method
    from bilevel_kit.options import describe

    assert get_method("bilevel-milp").options_class() is kc.BilevelMilpOptions
    names = [o.name for o in describe(kc.BilevelMilpOptions)]
    assert "warm_plan" not in names and "ce_params" not in names  # Python-only arguments
    with pytest.raises(UsageError, match="lower"):
        kc.solve(load(TABLE.parent / "stool.json"), lower="magic", time_limit=5.0)


def test_a_solver_stopped_without_a_solution_leaves_the_warm_start(monkeypatch):
    """When HiGHS returns no solution (killed past the time limit), the result is the plan the
    MILP was started from, checked and labelled, not 'unknown' without a plan."""
    from bilevel_kit.models.bilevel_milp import method
    from bilevel_kit.models.milp.solver import SolveInfo

    def killed(*args, **kwargs):
        return SolveInfo("killed", False, False, False, None, None, 0.0)

    monkeypatch.setattr(method, "run_solver", killed)
    inst = load(TABLE.parent / "stool.json")
    out = kc.solve(inst, time_limit=30.0, lower="ce")
    assert out.status == "feasible" and out.extra["incumbent"] == "warm start"
    assert out.extra["termination"] == "killed" and out.extra["objective_bound"] is None
    assert check(inst, out.plan) == []
    assert [k.tasks for k in out.plan.kits] == [("a1",), ("a2",), ("a3",)]
    assert out.extra["objective_value"] == pytest.approx(out.extra["local_search_objective"])
    assert kc.solve(inst, time_limit=30.0, lower="ce", warm_plan=None).status == "unknown"
