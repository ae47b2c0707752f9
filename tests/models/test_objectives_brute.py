"""No false claim on any objective (issue 35): every exact method x every registered objective
(bilevel_kit/objectives.py) x trays 1, 2, unlimited x one to three stations, against the brute
force of tests/brute.py (:func:`brute.station_optima`, a timeline of its own written from
docs/timeline.md, not the package's evaluator). An objective added to the registry is tested
here without a new line.

A claim is false when the plan is better than the optimum (the evaluator and the brute force
disagree), when a bound on the status objective lies above the optimum, or when "optimal" (for
every plan, or for 0/90-degree plans: the brute force's exact 1 mm grid holds both) comes
with a value above it. The full comparison on 200+ instances is bench/objectives_brute.py."""

from __future__ import annotations

import random

import pytest
import strategies
from brute import station_optima

from bilevel_kit.instance import from_dict
from bilevel_kit.methods import solve
from bilevel_kit.objectives import MODEL_OBJECTIVES, OBJECTIVES
from bilevel_kit.plan import evaluate

pytest.importorskip("ortools")
pytest.importorskip("pyomo")

#: Values agree to the solvers' relative tolerance (1e-6 on real seconds, MILP) on objectives
#: of at most a few hundred seconds.
TOL = 1e-4


#: The trays of :func:`instance_doc`: ``binding`` (:func:`strategies.random_doc`'s 100 x 60 mm
#: tray, up to four parts a task) or ``two`` (one part a task, at most two a kit).
TRAYS = ("binding", "two")


def instance_doc(
    seed: int,
    n_stations: int,
    trays: int | None,
    n: int = 5,
    tray: str = "binding",
    long_overhead: bool = False,
) -> dict:
    """A random ``n``-task instance on ``n_stations`` stations (none declared for one), every
    station with ``trays`` trays; ``tray="two"``: :func:`two_per_kit`; ``long_overhead``:
    :func:`fast_robot`."""
    if n_stations == 1:
        doc = strategies.random_doc(seed, n)
        if trays is not None:
            doc["trays"] = trays
    else:
        doc = strategies.stations_doc(seed, n_stations, n=n)
        for st in doc["stations"]:
            st.pop("trays", None)
            if trays is not None:
                st["trays"] = trays
    doc = two_per_kit(doc, seed) if tray == "two" else doc
    return fast_robot(doc, seed) if long_overhead else doc


def fast_robot(doc: dict, seed: int) -> dict:
    """Every robot time 0.5 s, ``o_R = 0.5``, no delivery time and a human overhead of 2-8 s
    on every station: a kit arrives long before a tray comes back, the regime in which the
    first kit of a one-tray station waiting for a tray changed the optimum (issue 35, item 1;
    tests/stations_example.py's ``first_tray_doc`` is one such instance)."""
    rng = random.Random(seed * 17 + 3)
    doc["kit_overhead"] = {"robot": 0.5, "human": float(rng.randint(2, 8))}
    doc["delivery_time"] = 0.0
    for task in doc["tasks"]:
        task["robot_time"] = 0.5
    for st in doc.get("stations", ()):
        st["delivery_time"] = 0.0
        st["kit_overhead_human"] = float(rng.randint(2, 8))
    return doc


def two_per_kit(doc: dict, seed: int) -> dict:
    """Each task one part of three fixed-orientation types (40 x 40, 45 x 35, 48 x 30 mm) on a
    100 x 50 mm tray: any two fit side by side, no three (three widths need >= 120 mm, two
    rows >= 60 mm), so every kit holds one or two tasks (the setting of issue 35, item 1)."""
    rng = random.Random(seed * 31 + 5)
    doc["part_types"] = [
        {"id": k, "width": w, "height": h, "pick_time": p, "rotatable": False}
        for k, w, h, p in (("a", 40.0, 40.0, 1.0), ("b", 45.0, 35.0, 2.0), ("c", 48.0, 30.0, 1.5))
    ]
    doc["tray"] = {"width": 100.0, "height": 50.0}
    for task in doc["tasks"]:
        task["parts"] = [{"type": rng.choice("abc"), "count": 1}]
    return doc


def false_claims(inst, res, opt: dict[str, float]) -> list[str]:
    """What ``res`` claims about its status objective that the brute force ``opt`` refutes."""
    obj = OBJECTIVES[res.status_objective]
    value = obj.value(evaluate(inst, res.plan))
    bound = res.bound  # the minimised objective's
    best = opt[obj.name]
    out = []
    if value < best - TOL:
        out.append(f"value {value} below the optimum {best}")
    if bound is not None and bound > best + TOL:
        out.append(f"bound {bound} above the optimum {best}")
    proven = res.status == "optimal" or res.extra.get("optimal_axis_aligned")
    if proven and value > best + TOL:
        out.append(f"optimal at {value}, the optimum is {best}")
    return out


CASES = [
    (method, objective, trays, n_stations)
    for method in ("cpsat", "milp")
    for objective in MODEL_OBJECTIVES
    for trays in (1, 2, None)
    for n_stations in (1, 2, 3)
]


@pytest.mark.slow
@pytest.mark.parametrize(("method", "objective", "trays", "n_stations"), CASES)
def test_no_false_claim_on_any_objective(method, objective, trays, n_stations):
    seed = random.Random(f"{method}{objective}{trays}{n_stations}").randrange(10_000)
    inst = from_dict(instance_doc(seed, n_stations, trays))
    opt = station_optima(inst)
    res = solve(inst, method, time_limit=60, objective=objective)
    assert res.plan is not None
    assert false_claims(inst, res, opt) == [], (seed, res.status, res.extra)
    assert res.status == "optimal" or res.extra.get("optimal_axis_aligned"), res.extra


def test_the_brute_force_on_the_worked_example():
    """docs/timeline.md#several-stations (o_R = 1; A: d = 1, one tray, o_H = 0.5; B: d = 2,
    o_H = 0). [a1] [b1] [a2]: a1 arrives at 4, A works 4-14.5; b1 robot 4-8, arrives 10, B
    10-16; a2 robot from max(10, 4 + 0.5) = 10 to 16, arrives 17, A 17-21.5: makespan 21.5 s.
    [b1] [a1] [a2]: B 6-12; a1 arrives 10, A 10-20.5; a2 robot 10.5-16.5, arrives 17.5, A
    20.5-25: completions 12 + 25 = 37 s, idle (12 - 6) + (25 - 15) = 16 s. The brute force
    finds these optima, and its plans have them under the package's evaluator too."""
    from stations_example import worked_example_doc

    from bilevel_kit.plan import Kit, Plan

    inst = from_dict(worked_example_doc())
    plans: dict = {}
    assert station_optima(inst, plans) == {
        "makespan": 21.5,
        "sum_completion": 37.0,
        "human_idle": 16.0,
    }
    assert plans["makespan"] == [("a1",), ("b1",), ("a2",)]
    assert plans["sum_completion"] == [("b1",), ("a1",), ("a2",)]
    for name, kits in plans.items():
        tl = evaluate(inst, Plan(tuple(Kit(k) for k in kits)))
        assert OBJECTIVES[name].value(tl) == station_optima(inst)[name]
