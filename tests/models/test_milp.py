"""The Pyomo/HiGHS MILP schedule against brute force, against CP-SAT, and its result contract."""

from __future__ import annotations

import importlib.util
import time
from pathlib import Path

import pytest
from brute import assert_model_optimal, best_makespan, model_verdict
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from strategies import binding_parts, binding_types
from timing import PROOF_LIMIT, allowed

from bilevel_kit.errors import UsageError
from bilevel_kit.instance import from_dict, load
from bilevel_kit.models import milp as ms
from bilevel_kit.plan import evaluate
from bilevel_kit.validate import check

pytest.importorskip("pyomo")
if importlib.util.find_spec("highspy") is None:  # never import it here: see solvers/milp/solver.py
    pytest.skip("highspy is not installed", allow_module_level=True)

TABLE = Path(__file__).resolve().parents[2] / "instances" / "hrc_table.json"
TYPES = binding_types()


# ---------------------------------------------------------------------------------------------
# helpers
# ---------------------------------------------------------------------------------------------


def make_doc(n, parts, human, robot, edges, d, o_r, o_h, tray=(100.0, 60.0)) -> dict:
    """An instance document; the 100 x 60 tray binds geometrically (big + bar fit one way)."""
    tasks = []
    for i in range(n):
        task = {
            "id": f"t{i}",
            "parts": [{"type": k, "count": c} for k, c in parts[i]],
            "human_time": {"mean": human[i]},
        }
        if robot[i] is not None:
            task["robot_time"] = robot[i]
        tasks.append(task)
    return {
        "format": "bilevel-kit/1",
        "name": "milp_rand",
        "tray": {"width": tray[0], "height": tray[1]},
        "delivery_time": d,
        "kit_overhead": {"robot": o_r, "human": o_h},
        "part_types": TYPES,
        "tasks": tasks,
        "precedence": [[f"t{a}", f"t{b}"] for a, b in edges],
    }


@st.composite
def small_instances(draw, max_n: int = 6):
    """Random instances: <= max_n tasks, a DAG (edges i -> j, i < j), d > 0, overheads > 0."""
    n = draw(st.integers(3, max_n))
    half = st.integers(1, 40).map(lambda v: v / 2)
    parts = [binding_parts(draw) for _ in range(n)]
    human = [draw(half) for _ in range(n)]
    robot = [draw(st.one_of(st.none(), half)) for _ in range(n)]
    pairs = [(a, b) for a in range(n) for b in range(a + 1, n)]
    edges = draw(st.lists(st.sampled_from(pairs), max_size=n, unique=True)) if pairs else []
    d = draw(st.integers(1, 16)) / 2
    o_r = draw(st.integers(1, 6)) / 2
    o_h = draw(st.integers(1, 6)) / 2
    return from_dict(make_doc(n, parts, human, robot, edges, d, o_r, o_h))


def brute_force(inst) -> float:
    return best_makespan(inst)[0]


def assert_contract(inst, out, time_limit=None, wall=None) -> float:
    """Valid plan, honest numbers, bound <= objective; returns the makespan."""
    assert out.status in ("optimal", "feasible")
    assert out.plan is not None
    assert check(inst, out.plan) == []
    makespan = evaluate(inst, out.plan).makespan
    assert out.extra["makespan"] == pytest.approx(makespan, abs=1e-9)
    assert out.bound is not None and out.bound <= makespan + 1e-9
    assert 0.0 <= out.extra["gap"] <= 1.0
    for kit in out.plan.kits:  # human order is topological inside each kit
        pos = {t: j for j, t in enumerate(kit.tasks)}
        for a, b in inst.precedence:
            if a in pos and b in pos:
                assert pos[a] < pos[b]
    if time_limit is not None:
        assert wall <= allowed(time_limit)
    return makespan


# ---------------------------------------------------------------------------------------------
# agreement: brute force, CP-SAT
# ---------------------------------------------------------------------------------------------


@settings(
    max_examples=6, deadline=None, derandomize=True, suppress_health_check=[HealthCheck.too_slow]
)
@given(small_instances())
def test_milp_equals_brute_force_and_cpsat(inst):
    from bilevel_kit.models import cpsat as cs

    opt = brute_force(inst)
    t0 = time.perf_counter()
    out = ms.solve(inst, time_limit=PROOF_LIMIT)
    wall = time.perf_counter() - t0
    makespan = assert_contract(inst, out, 20.0, wall)
    assert_model_optimal(out, opt, tol=1e-5)  # among 0/90-degree plans, like the brute force
    ref = cs.solve(inst, time_limit=PROOF_LIMIT, workers=2)
    assert model_verdict(ref)[0]
    assert evaluate(inst, ref.plan).makespan == pytest.approx(makespan, abs=1e-6)


def test_table_optimum_agrees_with_cpsat():
    """The paper's 12-task table with unlimited trays: 431.78 s (5 kits) for both models."""
    from bilevel_kit.models import cpsat as cs

    inst = load(TABLE).with_overrides(trays="unlimited")
    out = ms.solve(inst, time_limit=PROOF_LIMIT)
    assert out.status == "optimal"
    assert assert_contract(inst, out) == pytest.approx(431.78, abs=1e-6)
    assert out.bound == pytest.approx(431.78, abs=1e-5)
    assert out.extra["solver"] == "highs"
    ref = cs.solve(inst, time_limit=PROOF_LIMIT)
    assert ref.status == "optimal"
    assert evaluate(inst, ref.plan).makespan == pytest.approx(431.78, abs=1e-6)


# ---------------------------------------------------------------------------------------------
# Benders cuts, big-M from the data, objectives
# ---------------------------------------------------------------------------------------------


def geometry_doc() -> dict:
    """t0 and t1 each hold a fixed 60 x 35 part: together they pass the area relaxation of the
    100 x 60 tray (4200 <= 6000 mm^2) but cannot be packed (side by side 120 mm wide, stacked
    70 mm high). The robot is the bottleneck and the last kit's human time is what remains, so
    the area-only master asks for [t0, t1], [t2, t3] (last human time 2 + o_H)."""
    parts = [[("big", 1)], [("big", 1)], [("sq", 2)], [("sq", 1)]]
    doc = make_doc(
        4, parts, [5.0, 5.0, 1.0, 1.0], [10.0, 10.0, 5.0, 5.0], [(0, 2), (1, 3)], 2.0, 6.0, 0.5
    )
    doc["part_types"][0] = {**TYPES[0], "width": 60.0, "height": 35.0, "rotatable": False}
    return doc


@pytest.mark.parametrize("seeded", [True, False])
def test_benders_cuts_reach_the_brute_force_optimum(seeded, monkeypatch):
    """``tray=benders`` (and ``auto``, the same in milp) seeds the pair cuts; without them the
    loop's own cuts reach the optimum after a second master solve."""
    from bilevel_kit.models.common import NoGoodCuts

    if not seeded:
        monkeypatch.setattr(NoGoodCuts, "seed_pairs", lambda self: None)
    inst = from_dict(geometry_doc())
    opt = brute_force(inst)
    out = ms.solve(inst, time_limit=PROOF_LIMIT, tray="benders")
    assert out.status == "optimal" and out.extra["tray_mode"] == "benders"
    assert assert_contract(inst, out) == pytest.approx(opt, abs=1e-6)
    assert out.extra["cuts"] >= 1  # the area relaxation alone would accept a non-fitting kit
    assert out.extra["master_solves"] >= (1 if seeded else 2)


def test_big_m_scales_with_the_data():
    """Times x 1000 give makespan x 1000: no constant big-M caps the horizon."""
    base = geometry_doc()
    scaled = geometry_doc()
    for task in scaled["tasks"]:
        task["human_time"]["mean"] *= 1000
        if "robot_time" in task:
            task["robot_time"] *= 1000
    for p in scaled["part_types"]:
        p["pick_time"] *= 1000
    scaled["delivery_time"] *= 1000
    scaled["kit_overhead"] = {k: v * 1000 for k, v in scaled["kit_overhead"].items()}
    a = ms.solve(from_dict(base), time_limit=PROOF_LIMIT)
    b = ms.solve(from_dict(scaled), time_limit=PROOF_LIMIT)
    assert a.status == b.status == "optimal"
    assert b.extra["makespan"] == pytest.approx(1000 * a.extra["makespan"], rel=1e-9)


def test_human_idle_objective_with_no_human_overhead_has_the_same_optimum():
    doc = geometry_doc()
    doc["kit_overhead"]["human"] = 0.0
    inst = from_dict(doc)
    a = ms.solve(inst, time_limit=PROOF_LIMIT)
    b = ms.solve(inst, time_limit=PROOF_LIMIT, objective="human_idle")
    assert a.status == b.status == "optimal"
    assert b.extra["makespan"] == pytest.approx(a.extra["makespan"], abs=1e-6)
    assert_contract(inst, b)


def test_task_that_fits_nowhere_is_infeasible():
    parts = [[("big", 1), ("bar", 1)], [("sq", 1)]]
    doc = make_doc(2, parts, [1.0, 1.0], [None, None], [], 1.0, 1.0, 1.0)
    doc["part_types"][0] = {**TYPES[0], "width": 60.0, "height": 50.0, "rotatable": False}
    out = ms.solve(from_dict(doc), time_limit=10.0)
    assert out.status == "infeasible"
    assert out.plan is None


# ---------------------------------------------------------------------------------------------
# time limit, solver choice
# ---------------------------------------------------------------------------------------------


def test_time_limit_is_honoured_on_three_tables():
    inst = load(TABLE).with_overrides(units=3)  # 36 tasks: not solved to optimality in 4 s
    t0 = time.perf_counter()
    out = ms.solve(inst, time_limit=4.0)
    wall = time.perf_counter() - t0
    assert wall <= allowed(4.0)
    makespan = assert_contract(inst, out, 4.0, wall)
    assert makespan <= out.extra["upper_start"] + 1e-9  # never worse than the quick plan


def test_missing_solver_is_a_usage_error_naming_it():
    inst = from_dict(geometry_doc())
    with pytest.raises(UsageError, match="no_such_solver"):
        ms.solve(inst, solver="no_such_solver", time_limit=5.0)
    with pytest.raises(UsageError, match="tray"):
        ms.solve(inst, tray="embedded", time_limit=5.0)


def test_registered_method_goes_through_methods_solve(monkeypatch):
    from bilevel_kit.methods import REGISTRY, MethodSpec, solve

    if "milp" not in REGISTRY:  # until methods.py registers it
        spec = MethodSpec("milp", "bilevel_kit.models.milp:solve", "MILP")
        monkeypatch.setitem(REGISTRY, "milp", spec)
    inst = from_dict(geometry_doc())
    res = solve(inst, "milp", time_limit=PROOF_LIMIT, check=True)
    assert res.status == "optimal"
    assert res.extra["violations"] == []
    assert res.objective == pytest.approx(brute_force(inst), abs=1e-6)


def test_options_and_python_entry_share_the_validation():
    from bilevel_kit.methods import Status, get_method

    assert get_method("milp").options_class() is ms.MilpOptions
    with pytest.raises(UsageError, match="objective"):
        ms.solve(from_dict(geometry_doc()), objective="idle", time_limit=5.0)
    out = ms.milp(from_dict(geometry_doc()), ms.MilpOptions(), seed=0, time_limit=PROOF_LIMIT)
    assert out.status is Status.OPTIMAL


def test_the_highs_child_module_never_loads_ortools():
    """The child process must not load OR-Tools (both bundle libhighs.so.1)."""
    import subprocess
    import sys

    code = (
        "import sys, bilevel_kit.models.milp.highs_child; "
        "print(any(m.startswith('ortools') for m in sys.modules))"
    )
    out = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, check=True
    ).stdout
    assert out.strip() == "False"
