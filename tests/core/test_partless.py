"""Part-less tasks need no kit of their own (docs/timeline.md#part-less-tasks, issue 40 item 6).

A task with no parts and no robot time rides in a neighbouring kit of its station: the checker
refuses a kit of such tasks alone (``kit_without_parts``), every method's plan is folded by
``solve`` (``plan.fold_kitless``) and ``bilevel-milp`` enumerates no such kit, and a file whose
every task is part-less is refused on load.
"""

from __future__ import annotations

import copy
import json
import random

import pytest
from brute import best_makespan

from bilevel_kit import check, evaluate, solve
from bilevel_kit.cli import main
from bilevel_kit.errors import InstanceError
from bilevel_kit.heuristics.baselines import packed_kit
from bilevel_kit.instance import document, from_dict
from bilevel_kit.plan import Plan, fold_kitless, kitless

#: Two tasks with parts and two part-less ones ("glue" after "x", "check" at the end); one
#: tray, a 4 s delivery and 3 s / 1 s of overheads per kit, as the issue's example.
DOC = document(
    "partless",
    [
        {"id": "a", "width": 10.0, "height": 10.0, "pick_time": 1.0},
        {"id": "b", "width": 40.0, "height": 5.0, "pick_time": 2.0},
    ],
    [
        {"id": "x", "parts": [{"type": "a", "count": 2}], "human_time": {"mean": 5.0}},
        {"id": "glue", "parts": [], "human_time": {"mean": 6.0}},
        {"id": "y", "parts": [{"type": "b", "count": 1}], "human_time": {"mean": 3.0}},
        {"id": "check", "parts": [], "human_time": {"mean": 2.0}},
    ],
    precedence=[["x", "glue"], ["glue", "y"], ["y", "check"]],
    tray=(60.0, 40.0),
    delivery_time=4.0,
    overhead=(3.0, 1.0),
    trays=1,
)


@pytest.fixture(scope="module")
def inst():
    return from_dict(copy.deepcopy(DOC), "partless.json")


def _plan(inst, *kits: tuple[str, ...]) -> Plan:
    """Kits of these tasks, laid out by the baselines' shelf packer."""
    return Plan(tuple(packed_kit(inst, k, "kit") for k in kits))


def test_part_less_means_no_parts_and_no_robot_time(inst) -> None:
    assert [t for t in ("x", "glue", "y", "check") if not inst.needs_kit(t)] == ["glue", "check"]
    doc = copy.deepcopy(DOC)
    doc["tasks"][1]["robot_time"] = 2.0  # robot work without parts still needs a kit
    assert from_dict(doc, "m.json").needs_kit("glue")


def test_checker_refuses_a_kit_of_part_less_tasks_and_the_fold_fixes_it(inst) -> None:
    single = _plan(inst, ("x",), ("glue",), ("y",), ("check",))
    found = [v.kind for v in check(inst, single)]
    assert found.count("kit_without_parts") == 2 and set(found) == {"kit_without_parts"}
    folded = fold_kitless(inst, single)
    assert [k.tasks for k in folded.kits] == [("x", "glue"), ("y", "check")]
    assert check(inst, folded) == []
    # by hand (docs/timeline.md): kits (R, H) = x (5, 6), glue (3, 7), y (5, 4), check (3, 3)
    # end at 15, 24, 31, 38 (one tray: each robot start waits for the last kit's human start
    # + 1 s); folded, (5, 12) and (5, 6) end at 21 and 27
    assert evaluate(inst, single).makespan == pytest.approx(38.0)
    assert evaluate(inst, folded).makespan == pytest.approx(27.0)
    assert fold_kitless(inst, folded) is folded
    # no kit before them: part-less kits join the next one, first and in the plan's order
    # (the hypothesis example that found the order reversed: t0 -> t1, both part-less, first)
    first = fold_kitless(inst, _plan(inst, ("check",), ("glue",), ("x",), ("y",)))
    assert [k.tasks for k in first.kits] == [("check", "glue", "x"), ("y",)]
    assert not kitless(inst, first.kits[0])


@pytest.mark.parametrize(
    "method", ["single-task", "whole-assembly", "greedy-ce", "cpsat", "milp", "lns", "bilevel-milp"]
)
def test_every_method_gives_plans_without_part_less_kits(inst, method: str) -> None:
    res = solve(inst, method, time_limit=20.0, check=True)
    assert res.plan is not None and res.extra["violations"] == []
    assert not any(kitless(inst, k) for k in res.plan.kits)
    if method in ("cpsat", "milp"):
        assert res.status == "optimal" and res.objective == pytest.approx(27.0)
    if method == "single-task":  # one kit per task, the part-less ones merged: 4 -> 2 kits
        assert res.extra["kitless_folded"] == 2 and res.objective == pytest.approx(27.0)


def test_the_optimum_is_the_old_rules_optimum(inst) -> None:
    """On one station the fold never delays, so forbidding part-less kits keeps the optimum."""
    new, plan = best_makespan(inst)
    old, old_plan = best_makespan(inst, kitless=True)
    assert new == pytest.approx(old) == pytest.approx(27.0)
    assert plan is not None and old_plan is not None
    assert [k.tasks for k in plan.kits] == [("x", "glue"), ("y", "check")]


@pytest.mark.parametrize("trays", [1, 2, None])
def test_the_fold_never_delays_on_one_station(trays: int | None) -> None:
    rng = random.Random(trays or 0)
    for _ in range(60):
        doc = copy.deepcopy(DOC)
        doc["trays"] = trays
        for t in doc["tasks"]:
            t["human_time"]["mean"] = float(rng.randint(1, 9))
        doc["delivery_time"] = float(rng.randint(0, 5))
        doc["kit_overhead"] = {"robot": float(rng.randint(0, 3)), "human": float(rng.randint(0, 3))}
        inst = from_dict(doc, "r.json")
        order = ["x", "glue", "y", "check"]
        cuts = [i for i in range(1, 4) if rng.random() < 0.6]
        kits = [tuple(order[a:b]) for a, b in zip([0, *cuts], [*cuts, 4], strict=True)]
        plan = _plan(inst, *kits)
        folded = fold_kitless(inst, plan)
        assert check(inst, folded) == []
        assert evaluate(inst, folded).makespan <= evaluate(inst, plan).makespan + 1e-9


def test_stations_fold_within_their_station() -> None:
    from stations_example import worked_example_doc

    doc = worked_example_doc()
    # single-task's order a1, b1, a3, a2: a3's kit joins a1's, the previous kit of station A
    doc["tasks"].insert(2, {"id": "a3", "parts": [], "human_time": {"mean": 3}, "station": "A"})
    inst = from_dict(doc, "s.json")
    res = solve(inst, "single-task", check=True)
    assert res.extra["violations"] == [] and res.extra["kitless_folded"] == 1
    assert res.plan is not None
    assert [k.tasks for k in res.plan.kits] == [("a1", "a3"), ("b1",), ("a2",)]


def test_a_file_of_part_less_tasks_only_is_refused(tmp_path, capsys) -> None:
    doc = copy.deepcopy(DOC)
    for t in doc["tasks"]:
        t["parts"] = []
    path = tmp_path / "empty.json"
    path.write_text(json.dumps(doc))
    with pytest.raises(InstanceError, match=r"\$\.tasks.*every task has no parts"):
        from_dict(doc, str(path))
    assert main(["solve", str(path), "-m", "single-task"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "empty.json" in err and "$.tasks" in err
