"""The exact CP-SAT schedule against Johnson's rule and against brute-force enumeration."""

from __future__ import annotations

import random
import time
from collections import Counter

import pytest
from brute import assert_model_optimal, best_makespan, fits, model_verdict
from flowshop import jobs_doc
from strategies import random_doc
from timing import PROOF_LIMIT, allowed

from bilevel_kit import bounds
from bilevel_kit.instance import InstanceBuilder, from_dict
from bilevel_kit.models import cpsat as cs
from bilevel_kit.plan import Kit, Plan, evaluate

pytest.importorskip("ortools")

FAST = {"workers": 2, "time_limit": PROOF_LIMIT}


# ---------------------------------------------------------------------------------------------
# helpers
# ---------------------------------------------------------------------------------------------


def brute_force(inst) -> tuple[float, Plan]:
    return best_makespan(inst)


def assert_valid_plan(inst, out) -> None:
    """Every task once, precedence across and inside kits, honest makespan, checker clean."""
    plan = out.plan
    assert plan is not None
    order = plan.task_order
    assert Counter(order) == Counter(t.id for t in inst.tasks)
    pos = {t: k for k, t in enumerate(order)}
    for a, b in inst.precedence:
        assert pos[a] < pos[b]
    for kit in plan.kits:
        assert Counter(p.type for p in kit.layout) == inst.kit_parts(kit.tasks)
    assert out.extra["makespan"] == pytest.approx(evaluate(inst, plan).makespan, abs=1e-9)
    assert out.bound is not None
    assert out.bound <= out.extra["makespan"] + 1e-9
    try:
        from bilevel_kit.validate import check
    except ImportError:  # pragma: no cover - the checker is written elsewhere
        return
    assert check(inst, plan) == []


# ---------------------------------------------------------------------------------------------
# special case: F2||Cmax
# ---------------------------------------------------------------------------------------------


@pytest.mark.parametrize("seed", range(4))
def test_no_delivery_no_overheads_equals_johnson(seed):
    """d = 0, no overheads, a roomy tray, no precedence: splitting never hurts, so the
    optimum is Johnson's makespan on (robot, human) times."""
    rng = random.Random(seed)
    n = 5 + seed % 3
    r = [float(rng.randint(1, 20)) for _ in range(n)]
    h = [float(rng.randint(1, 20)) for _ in range(n)]
    doc = jobs_doc(f"f2_{seed}", r, h, part=("s", 10.0), tray=1000.0)
    inst = from_dict(doc)
    out = cs.solve(inst, **FAST)
    assert out.status == "optimal"
    assert out.extra["makespan"] == pytest.approx(bounds.johnson_makespan(r, h))
    assert out.bound == pytest.approx(bounds.johnson_makespan(r, h))
    assert_valid_plan(inst, out)


# ---------------------------------------------------------------------------------------------
# brute force on small random instances
# ---------------------------------------------------------------------------------------------


@pytest.mark.parametrize("seed", range(12))
def test_matches_brute_force_in_both_tray_modes(seed):
    inst = from_dict(random_doc(seed, n=7 if seed in (5, 11) else None))
    opt, _ = brute_force(inst)
    for mode in ("embedded", "benders"):
        out = cs.solve(inst, tray=mode, **FAST)
        assert out.extra["tray_mode"] == mode
        assert_model_optimal(out, opt)  # the brute force is the optimum of 0/90-degree plans
        assert (out.extra["gap"] == 0.0) == (out.status == "optimal")
        assert_valid_plan(inst, out)
    lb = bounds.best_bound(inst)
    assert lb <= opt + 1e-9


def test_known_optimum_of_one_random_instance():
    """Pinned by hand. Tasks (r, h): t0 (2, 20) bar; t1 (4, 16) sq; t2 (3, 18) 2 sq;
    t3 (5, 8) bar + big; t1 -> t3; d = 1, o_R = 1.5, o_H = 0.5. Kits [t0], [t1], [t2, t3]:
    arrivals 4.5, 11, 21.5; human ends 25, 41.5, 68 = the human bound with 3 kits
    (2 + 1.5 + 1 + 62 + 3 x 0.5). Two kits [t0], [t1, t2, t3] would give 67.5, but a 50 x 40,
    a 70 x 15 and three 30 x 30 parts do not fit the 100 x 60 tray together."""
    inst = from_dict(random_doc(3))
    opt, plan = brute_force(inst)
    assert opt == pytest.approx(68.0)
    assert len(plan.kits) == 3
    assert not fits(inst, ["t1", "t2", "t3"])
    assert evaluate(inst, Plan((Kit(("t0",)), Kit(("t1", "t2", "t3"))))).makespan == 67.5
    for mode in ("embedded", "benders"):
        out = cs.solve(inst, tray=mode, **FAST)
        assert_model_optimal(out, 68.0)
        assert out.extra["n_kits"] == 3
        # the misfit of [t1, t2, t3] is proven for 0/90-degree layouts only: parts at other
        # angles might fit, so "optimal" is claimed among 0/90-degree plans only
        assert out.status == "feasible" and out.extra["proof_scope"] == "0/90 degrees"
        assert out.bound < 68.0


def test_tray_geometry_forces_cuts_and_both_modes_agree():
    """Each task carries one 60 x 60 part: two of them pass the area test on a 100 x 100
    tray but cannot be placed together, at any angle (their inscribed disks, 60 mm wide,
    have no room to lie apart), so the tray allows one task per kit. Benders cuts with that
    proof: optimal. The embedded tray proves it for 0/90-degree plans only. (Task a takes
    3.1 s: on whole seconds the kit-count LP's bound, rounded up to the makespan's grid, meets
    the LNS's plan and no model runs.)"""
    inst = (
        InstanceBuilder("squares", tray=(100.0, 100.0), delivery_time=1.0, kit_overhead=(1.0, 1.0))
        .part_type("s", 60.0, 60.0, pick_time=4.0)
        .part_type("k", 20.0, 20.0, pick_time=1.0)
        .task("a", {"s": 1}, human_time=3.1)
        .task("b", {"s": 1}, human_time=9.0)
        .task("c", {"k": 2}, human_time=2.0)
        .task("e", {"s": 1}, human_time=1.0)
        .precede("a", "e")
        .build()
    )
    opt, _ = brute_force(inst)
    emb = cs.solve(inst, tray="embedded", **FAST)
    ben = cs.solve(inst, tray="benders", **FAST)
    for out in (emb, ben):
        assert_model_optimal(out, opt)
        assert_valid_plan(inst, out)
        for kit in out.plan.kits:
            assert inst.kit_parts(kit.tasks)["s"] <= 1
    assert ben.extra["cuts"] >= 1
    assert ben.status == "optimal" and ben.extra["proof_scope"] == "any angle"
    assert emb.extra["proof_scope"] == "0/90 degrees" and emb.extra["optimal_axis_aligned"]


def test_interchangeable_chains_keep_the_optimum():
    """Three identical chains (the legs of a small table) trigger the lexicographic symmetry
    breaking; two units add cross-unit precedence. Still equal to brute force."""
    doc = {
        "format": "bilevel-kit/1",
        "name": "legs",
        "tray": {"width": 100.0, "height": 60.0},
        "delivery_time": 2.0,
        "kit_overhead": {"robot": 1.5, "human": 1.0},
        "part_types": [
            {"id": "leg", "width": 90.0, "height": 10.0, "pick_time": 3.0},
            {"id": "b", "width": 30.0, "height": 30.0, "pick_time": 2.0},
        ],
        "tasks": [
            {
                "id": f"{kind}{leg}",
                "parts": [{"type": part, "count": 1}],
                "human_time": {"mean": ht},
            }
            for leg in range(3)
            for kind, part, ht in (("f", "leg", 6.0), ("c", "b", 4.5))
        ],
        "precedence": [[f"f{leg}", f"c{leg}"] for leg in range(3)],
    }
    inst = from_dict(doc)
    opt, _ = brute_force(inst)
    for mode in ("embedded", "benders"):
        out = cs.solve(inst, tray=mode, **FAST)
        assert out.extra["symmetric_chains"] == 3
        assert_model_optimal(out, opt)
        assert_valid_plan(inst, out)
    two = from_dict(
        {**doc, "tasks": doc["tasks"][:4], "precedence": [["f0", "c0"], ["f1", "c1"]], "units": 2}
    )
    opt2, _ = brute_force(two)
    out = cs.solve(two, tray="benders", **FAST)
    assert_model_optimal(out, opt2)
    assert_valid_plan(two, out)


def test_human_idle_objective():
    """With o_H = 0 human idle is makespan minus a constant: same optimum. With o_H > 0 the
    idle-optimal plan never idles more than the makespan-optimal one."""
    doc = random_doc(7)
    doc["kit_overhead"]["human"] = 0.0
    inst = from_dict(doc)
    ms = cs.solve(inst, **FAST)
    idle = cs.solve(inst, objective="human_idle", **FAST)
    assert model_verdict(idle)[0] and model_verdict(ms)[0]
    assert idle.extra["makespan"] == pytest.approx(ms.extra["makespan"])
    idle_bound = idle.extra["objective_bound"]
    if idle.extra["proof_scope"] != "any angle":
        idle_bound = idle.extra["objective_bound_axis_aligned"]
    assert idle_bound == pytest.approx(idle.extra["human_idle"])
    assert idle.extra["objective_value"] == pytest.approx(idle.extra["human_idle"])
    inst2 = from_dict(random_doc(8))
    ms2 = cs.solve(inst2, **FAST)
    idle2 = cs.solve(inst2, objective="human_idle", **FAST)
    assert model_verdict(idle2)[0]
    assert idle2.extra["human_idle"] <= ms2.extra["human_idle"] + 1e-9
    assert idle2.bound <= ms2.extra["makespan"] + 1e-9


def test_inexact_times_are_floored_and_the_bound_stays_valid():
    doc = random_doc(2)
    for t in doc["tasks"]:
        t["human_time"]["mean"] += 0.037
    inst = from_dict(doc)
    opt, _ = brute_force(inst)
    out = cs.solve(inst, time_resolution=0.1, refine_times=False, **FAST)
    assert out.extra["times_exact"] is False
    assert out.bound <= opt + 1e-9 <= out.extra["makespan"] + 2e-9
    assert_valid_plan(inst, out)
    # refining the grid to 0.001 s makes the times exact again, hence a proof
    exact = cs.solve(inst, time_resolution=0.1, **FAST)
    assert exact.extra["times_exact"] is True
    assert exact.extra["time_resolution"] == pytest.approx(0.001)
    assert_model_optimal(exact, opt)


# ---------------------------------------------------------------------------------------------
# the table: hint, time limit, infeasibility
# ---------------------------------------------------------------------------------------------


def test_hint_and_embedded_equals_benders_on_the_table(table):
    inst = table.with_overrides(delivery_time=10.0)
    single = Plan(
        tuple(
            Kit((t,))
            for t in [
                "foot1",
                "conn1",
                "top1",
                "foot2",
                "conn2",
                "top2",
                "foot3",
                "conn3",
                "top3",
                "foot4",
                "conn4",
                "top4",
            ]
        )
    )
    a = cs.solve(inst, tray="embedded", hint=single, **FAST)
    b = cs.solve(inst, tray="benders", **FAST)
    # the single-task plan packs but the quick plan is better: that is the incumbent
    assert a.extra["hint_used"] is False and a.extra["hint_method"] is None
    assert a.extra["upper_start"] < evaluate(inst, single).makespan
    assert a.status == b.status == "optimal"
    assert a.extra["makespan"] == pytest.approx(b.extra["makespan"])
    assert a.extra["makespan"] <= evaluate(inst, single).makespan
    assert_valid_plan(inst, a)
    assert_valid_plan(inst, b)


def test_time_limit_is_honoured(table):
    inst = table.with_overrides(units=10)
    t0 = time.perf_counter()
    out = cs.solve(inst, time_limit=3.0, workers=2)
    wall = time.perf_counter() - t0
    assert wall <= allowed(3.0)
    assert out.status in ("optimal", "feasible")
    assert_valid_plan(inst, out)
    assert out.extra["tray_mode"] == "benders"


def test_a_task_that_cannot_fit_makes_the_instance_infeasible():
    doc = random_doc(0)
    doc["part_types"].append({"id": "huge", "width": 60.0, "height": 60.0, "pick_time": 1.0})
    doc["tasks"][0]["parts"] = [{"type": "huge", "count": 2}]
    out = cs.solve(from_dict(doc), **FAST)
    assert out.status == "infeasible"
    assert out.plan is None


def test_plans_respect_the_reach_map(root):
    """The table with its tray 900 mm ahead (44 % of the tray reachable): every centre of the
    exact plan lies in a reachable cell and the checker accepts the plan."""
    import json

    from bilevel_kit.reachability import reach_grid

    doc = json.loads((root / "instances/hrc_table.json").read_text())
    doc["work_cell"] = {"tray_pose": {"x": 900, "y": 150, "z": -150, "yaw": -90}}
    doc["reachability"] = True
    inst = from_dict(doc)
    grid = reach_grid(inst)
    out = cs.solve(inst, **FAST)
    assert out.extra["tray_mode"] == "benders"  # auto avoids embedding a reach map
    assert out.status == "optimal"
    assert_valid_plan(inst, out)
    assert all(grid.lookup(p.x, p.y) for kit in out.plan.kits for p in kit.layout)


def test_embedded_and_benders_agree_under_a_reach_map(monkeypatch):
    """A synthetic reach map (the tray's right 30 mm and top row out of reach) on a small
    random instance: both tray modes find the same plan, every centre is reachable. On a
    grid with a reach map no "does not fit" is a proof (a layout off the grid may reach other
    cells), so neither mode claims optimality, and the bound stays the closed-form one."""
    import numpy as np

    from bilevel_kit import reachability
    from bilevel_kit.reachability import ReachGrid

    doc = random_doc(10)
    doc["reachability"] = True
    inst = from_dict(doc)
    cells = np.ones((6, 10), dtype=bool)
    cells[:, 7:] = False
    cells[5, :] = False
    grid = ReachGrid(cells, 100.0, 60.0, None)
    free = cs.solve(from_dict(random_doc(10)), tray="benders", **FAST)
    monkeypatch.setattr(reachability, "reach_grid", lambda instance: grid)
    emb = cs.solve(inst, tray="embedded", **FAST)
    ben = cs.solve(inst, tray="benders", **FAST)
    for out in (emb, ben):
        assert out.status == "feasible" and out.extra["proof_scope"] is None
        assert out.bound <= out.extra["makespan"]
        assert_valid_plan(inst, out)
        assert all(grid.lookup(p.x, p.y) for kit in out.plan.kits for p in kit.layout)
    # the reach map costs 2 s here: 102 against 100 on the whole tray
    assert emb.extra["makespan"] == pytest.approx(102.0)
    assert ben.extra["makespan"] == pytest.approx(102.0)
    assert free.extra["makespan"] == pytest.approx(100.0)


# ---------------------------------------------------------------------------------------------
# the method contract
# ---------------------------------------------------------------------------------------------


def test_options_dataclass_and_hint_validation(stool):
    from bilevel_kit.errors import UsageError
    from bilevel_kit.methods import Status, get_method, solve
    from bilevel_kit.options import parse_options

    spec = get_method("cpsat")
    assert spec.options_class() is cs.CpsatOptions
    defaults = cs.CpsatOptions()
    assert (defaults.workers, defaults.tray, defaults.objective, defaults.hint) == (
        2,
        "auto",
        "makespan",
        "auto",
    )
    with pytest.raises(UsageError, match="'no-such-method'"):
        parse_options(cs.CpsatOptions, {"hint": "no-such-method"}, "method 'cpsat'")
    with pytest.raises(UsageError, match="time_resolution"):
        solve(stool, "cpsat", time_resolution=0)
    with pytest.raises(UsageError, match="workers"):
        solve(stool, "cpsat", workers=0)
    out = cs.cpsat(stool, cs.CpsatOptions(hint="single-task"), seed=0, time_limit=10.0)
    assert out.status is Status.OPTIMAL
    assert out.extra["hint_method"] == "single-task"


def test_a_time_limited_warm_start_skips_greedy_ce_while_its_kernels_would_compile(
    table, monkeypatch
):
    """A direct call of the method before the kernels are compiled in this process (solve()
    compiles them first, outside the clock): under a time limit the warm start keeps a
    baseline's plan instead of overrunning; once compiled greedy-ce runs."""
    from bilevel_kit.heuristics import _kernels, warmup
    from bilevel_kit.models.cpsat.warm import best_heuristic_plan

    if _kernels.njit() is None:
        pytest.skip("numba is disabled or missing: nothing compiles")
    monkeypatch.setattr(warmup, "_state", {})
    _, source = best_heuristic_plan(table, seed=0, time_limit=20.0)
    assert source == "single-task"  # 466.69 s; greedy-ce's 463.78 s would win
    _, source = best_heuristic_plan(table, seed=0, time_limit=None)
    assert source == "greedy-ce"  # without a limit nothing is skipped
    warmup.compile_kernels()
    _, source = best_heuristic_plan(table, seed=0, time_limit=20.0)
    assert source == "greedy-ce"
