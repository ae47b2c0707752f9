"""Convex layout polish (models/convex_layout.py): never worse, never invalid, clearly better on
poor layouts, exact on a case with a known optimum, deterministic, and its guard works."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest
from hypothesis import HealthCheck, assume, given, settings
from hypothesis import strategies as st
from strategies import one_task_doc

from bilevel_kit import geometry
from bilevel_kit.errors import UsageError
from bilevel_kit.fitness import layout_fitness, layout_terms
from bilevel_kit.heuristics import convex as cl
from bilevel_kit.heuristics.convex import polish, polish_arrangement, polish_plan
from bilevel_kit.heuristics.cross_entropy import CEParams, arrange
from bilevel_kit.heuristics.shelf import kit_items, shelf_pack
from bilevel_kit.instance import Instance, from_dict
from bilevel_kit.plan import Kit, Placement, Plan
from bilevel_kit.validate import check

P = Placement
FAST_CE = CEParams(samples=40, elite=8, max_iter=20, patience=5)
TABLE_PARTS = {"leg": 4, "foot": 4, "connector": 4, "screw_long": 8, "screw_short": 8}


def one_kit_instance(
    width: float, height: float, types: dict[str, tuple[float, float, bool]], counts: dict
) -> Instance:
    """An instance with one task ``all`` needing ``counts`` parts, so that a one-kit plan
    holding a layout of exactly those parts can go through the checker."""
    kinds = [(t, w, h, r) for t, (w, h, r) in types.items()]
    parts = {t: n for t, n in counts.items() if n}
    return from_dict(one_task_doc("polish-test", width, height, kinds, parts, task="all"))


def assert_valid(inst: Instance, before: tuple[Placement, ...], after: tuple[Placement, ...]):
    """The checker accepts the polished kit and only positions changed."""
    assert check(inst, Plan((Kit(("all",), after),))) == []
    assert [(p.part, p.type, p.theta, p.w, p.h) for p in after] == [
        (p.part, p.type, p.theta, p.w, p.h) for p in before
    ]


@st.composite
def small_kits(draw):
    """2-3 part types (some rotatable), 1-4 parts each, on a random tray."""
    n_types = draw(st.integers(2, 3))
    types = {}
    counts = {}
    for k in range(n_types):
        w = draw(st.floats(4.0, 50.0))
        h = draw(st.floats(4.0, 50.0))
        types[f"t{k}"] = (w, h, draw(st.booleans()))
        counts[f"t{k}"] = draw(st.integers(1, 4))
    width = draw(st.floats(120.0, 300.0))
    height = draw(st.floats(100.0, 220.0))
    return one_kit_instance(width, height, types, counts), counts


@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(small_kits(), st.sampled_from([0.0, 10.0]))
def test_never_worse_and_valid_from_shelf_packer(kit, w6):
    # Shelf layouts are all touching: every separation constraint starts tight.
    inst, counts = kit
    layout = shelf_pack(inst.tray, kit_items(inst.part_types, counts))
    assume(layout is not None)
    res = polish(inst, layout, w6=w6)
    assert res.fitness_before == pytest.approx(layout_fitness(layout, w6), abs=1e-9)
    assert res.fitness_after == layout_fitness(res.layout, w6)
    assert res.fitness_after >= res.fitness_before
    assert all(b >= a for a, b in zip(res.trace, res.trace[1:], strict=False))
    assert res.status in ("converged", "max_rounds")
    assert_valid(inst, layout, res.layout)


@settings(max_examples=30, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(small_kits(), st.integers(0, 1000))
def test_never_worse_and_valid_from_ce(kit, seed):
    # CE layouts have arbitrary angles on rotatable parts.
    inst, counts = kit
    arr = arrange(inst, counts, rng=seed, params=FAST_CE)
    assume(arr.fits)
    res = polish(inst, arr.layout)
    assert res.status in ("converged", "max_rounds")
    assert res.fitness_after >= arr.fitness - 1e-9
    assert res.fitness_before == pytest.approx(arr.fitness, abs=1e-6)
    assert_valid(inst, arr.layout, res.layout)


# A deliberately poor layout: the four a's at the tray corners, different types touching in
# the middle (a-5 sits on b-1 and c-1, b-2 under them).
POOR = (
    P("a-1", "a", 10, 10, 0, 20, 20),
    P("a-2", "a", 290, 10, 0, 20, 20),
    P("a-3", "a", 10, 190, 0, 20, 20),
    P("a-4", "a", 290, 190, 0, 20, 20),
    P("b-1", "b", 140, 100, 0, 20, 20),
    P("c-1", "c", 160, 100, 0, 20, 20),
    P("a-5", "a", 150, 120, 0, 20, 20),
    P("b-2", "b", 150, 80, 0, 20, 20),
)
SQUARES = {"a": (20.0, 20.0, True), "b": (20.0, 20.0, True), "c": (20.0, 20.0, True)}


def test_poor_layout_improves_by_a_clear_margin():
    inst = one_kit_instance(300, 200, SQUARES, {"a": 5, "b": 2, "c": 1})
    assert check(inst, Plan((Kit(("all",), POOR),))) == []
    d_same0, d_diff0, _, _ = layout_terms(POOR)
    res = polish(inst, POOR, w6=10.0)
    d_same1, d_diff1, _, z1 = layout_terms(res.layout)
    # Measured: fitness -148.8 -> 4172.3, D_same 2277 -> 326, D_diff 2128 -> 4498, 3 rounds.
    assert res.fitness_before == pytest.approx(-148.84, abs=0.01)
    assert res.fitness_after - res.fitness_before > 4000.0
    assert d_same1 < 0.2 * d_same0
    assert d_diff1 > 2.0 * d_diff0
    assert z1 == pytest.approx(0.0, abs=1e-9)
    assert res.status == "converged"
    assert_valid(inst, POOR, res.layout)


def test_same_type_pair_reaches_the_known_optimum():
    # Two same-type 10 x 10 squares: min |c1 - c2| subject to non-overlap is 10 (touching).
    lay = (P("a-1", "a", 20, 50, 0, 10, 10), P("a-2", "a", 80, 50, 0, 10, 10))
    res = polish((100.0, 100.0), lay, w6=10.0)
    assert res.fitness_before == pytest.approx(-60.0)
    assert res.fitness_after == pytest.approx(-10.0, abs=1e-5)
    assert res.fitness_after <= -10.0 + 1e-6  # never closer than touching
    c = [geometry.corners(p.x, p.y, p.w, p.h, p.theta) for p in res.layout]
    assert geometry.penetration(c[0], c[1]) <= geometry.TOL


def test_rotated_parts_stay_valid():
    # Three legs at 30 degrees side by side, two feet at 30 degrees, one screw at 0.
    t = math.radians(30.0)
    normal = np.array([-math.sin(t), math.cos(t)])
    legs = tuple(
        P(
            f"leg-{k + 1}",
            "leg",
            *(np.array([150.0, 100.0]) + (k - 1) * 20.0 * normal),
            30.0,
            152.4,
            12.7,
        )
        for k in range(3)
    )
    lay = (
        *legs,
        P("foot-1", "foot", 40.0, 40.0, 30.0, 43.0, 43.0),
        P("foot-2", "foot", 260.0, 160.0, 30.0, 43.0, 43.0),
        P("screw-1", "screw", 150.0, 180.0, 0.0, 14.0, 6.0),
    )
    types = {"leg": (152.4, 12.7, True), "foot": (43.0, 43.0, True), "screw": (14.0, 6.0, True)}
    inst = one_kit_instance(300, 200, types, {"leg": 3, "foot": 2, "screw": 1})
    assert check(inst, Plan((Kit(("all",), lay),))) == []
    res = polish(inst, lay, w6=10.0)
    assert_valid(inst, lay, res.layout)
    assert [p.theta for p in res.layout] == [30.0] * 5 + [0.0]
    # Measured: fitness 958.7 -> 1856.5 in 5 rounds (the feet and the screw move apart).
    assert res.fitness_after - res.fitness_before > 800.0
    assert res.status == "converged"


def test_whole_table_kit_from_ce(table):
    # The 28-part kit: with Clarabel's default tolerances separations crept past TOL within 3
    # rounds here; with CLARABEL_OPTS every pair keeps a positive gap.
    from bilevel_kit.instance import topological_order

    arr = arrange(table, TABLE_PARTS, rng=0)
    res = polish(table, arr.layout)
    assert check(table, Plan((Kit(tuple(topological_order(table)), res.layout),))) == []
    c = [geometry.corners(p.x, p.y, p.w, p.h, p.theta) for p in res.layout]
    worst = max(geometry.penetration(c[a], c[b]) for a in range(28) for b in range(a + 1, 28))
    assert worst <= 1e-8
    # Measured: 38615.9 -> 45127.5 (+16.9 %) in 8 rounds.
    assert res.fitness_after > 1.1 * res.fitness_before
    assert res.status == "converged"


def test_deterministic():
    inst = one_kit_instance(300, 200, SQUARES, {"a": 5, "b": 2, "c": 1})
    a = polish(inst, POOR, w6=10.0)
    b = polish(inst, POOR, w6=10.0)
    assert a.layout == b.layout
    assert (a.fitness_after, a.rounds, a.status, a.trace) == (
        b.fitness_after,
        b.rounds,
        b.status,
        b.trace,
    )


# -- the guard ---------------------------------------------------------------------------------


def test_overlapping_solver_answer_is_rolled_back(monkeypatch):
    def bad(self, xy):  # a-5 dropped onto a-1
        out = xy.copy()
        out[6] = out[0] + 5.0
        return out, "optimal"

    monkeypatch.setattr(cl._RoundProblem, "solve", bad)
    res = polish((300.0, 200.0), POOR, w6=10.0)
    assert res.status == "rejected"
    assert res.layout == POOR
    assert res.fitness_after == res.fitness_before
    assert res.rounds == 1


def test_worse_solver_answer_is_rolled_back(monkeypatch):
    # From the polished layout, a "solver" that answers with the poor layout (valid, worse).
    good = polish((300.0, 200.0), POOR, w6=10.0).layout
    poor_xy = np.array([[p.x, p.y] for p in POOR])
    monkeypatch.setattr(cl._RoundProblem, "solve", lambda self, xy: (poor_xy, "optimal"))
    res = polish((300.0, 200.0), good, w6=10.0)
    assert res.status == "converged"
    assert res.layout == good
    assert res.fitness_after == layout_fitness(good, 10.0) > layout_fitness(POOR, 10.0)


def test_solver_failure_keeps_the_layout(monkeypatch):
    monkeypatch.setattr(cl._RoundProblem, "solve", lambda self, xy: (None, "infeasible"))
    res = polish((300.0, 200.0), POOR, w6=10.0)
    assert res.status == "solver_failed"
    assert res.layout == POOR


def test_outside_tray_answer_is_rolled_back(monkeypatch):
    def out(self, xy):
        new = xy.copy()
        new[0, 0] = 9.99  # a-1 sticks out by 0.01 mm
        return new, "optimal"

    monkeypatch.setattr(cl._RoundProblem, "solve", out)
    res = polish((300.0, 200.0), POOR, w6=10.0)
    assert res.status == "rejected"
    assert res.layout == POOR


def test_invalid_input_and_trivial_cases():
    with pytest.raises(UsageError):
        polish((300.0, 200.0), (*POOR[:-1], replace(POOR[-1], y=90.0)), w6=10.0)
    with pytest.raises(UsageError):
        polish((300.0, 200.0), POOR)  # no instance: w6 required
    one = polish((300.0, 200.0), POOR[:1], w6=10.0)
    assert (one.status, one.rounds, one.layout) == ("trivial", 0, POOR[:1])


# -- arrangement and plan wrappers -------------------------------------------------------------


def test_polish_arrangement_recomputes_terms(table):
    parts = {"leg": 2, "foot": 2, "connector": 2, "screw_long": 4, "screw_short": 2}
    arr = arrange(table, parts, rng=0, params=FAST_CE)
    assert arr.fits
    pol = polish_arrangement(table, arr, w6=10.0)
    assert pol.source == arr.source + "+polish"
    assert pol.fits and pol.fitness >= arr.fitness
    d_same, d_diff, z_bbox, z = layout_terms(pol.layout)
    assert (pol.d_same, pol.d_diff, pol.z, pol.z_bbox) == (d_same, d_diff, z, z_bbox)
    assert pol.fitness == pytest.approx(-(d_same - d_diff + 10.0 * z), abs=1e-9)
    assert pol.fitness > arr.fitness + 1.0  # CE does not end at a local optimum
    none = replace(arr, layout=(), fits=False, fitness=-math.inf, source="area-bound")
    assert polish_arrangement(table, none, w6=10.0) is none


def test_polish_plan_of_greedy_ce(table):
    from bilevel_kit.heuristics.greedy_ce import GreedyParams, plan

    params = GreedyParams(ce=FAST_CE)
    original = plan(table, params, seed=0)
    new, stats = polish_plan(table, original)
    assert check(table, new) == []
    assert [k.tasks for k in new.kits] == [k.tasks for k in original.kits]
    assert len(stats["kits"]) == len(original.kits)
    w6 = table.weights["W6"]
    for k_old, k_new, s in zip(original.kits, new.kits, stats["kits"], strict=True):
        assert s["fitness_before"] == pytest.approx(layout_fitness(k_old.layout, w6), abs=1e-6)
        assert s["fitness_after"] == layout_fitness(k_new.layout, w6)
        assert s["fitness_after"] >= s["fitness_before"]
    assert stats["fitness_after"] > stats["fitness_before"]
