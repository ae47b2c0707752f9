"""CP-SAT tray packing: known feasible and infeasible packings, rotation, the fitness
surrogate, and the memoised oracle."""

from __future__ import annotations

import pytest
from brute import fits_on_grid

from bilevel_kit import geometry
from bilevel_kit.instance import PartType, Tray
from bilevel_kit.models import packing as pk
from bilevel_kit.models import packing_oracle as po

pytest.importorskip("ortools")


def _items(*specs: tuple[str, float, float, int, bool]) -> list[tuple[str, PartType]]:
    out = []
    for tid, w, h, n, rot in specs:
        pt = PartType(id=tid, width=w, height=h, pick_time=1.0, rotatable=rot)
        out += [(f"{tid}{j}", pt) for j in range(n)]
    return out


def _assert_valid(layout, tray: Tray, items) -> None:
    """Every item placed once, inside the tray, no two overlapping (exact geometry)."""
    assert sorted(p.part for p in layout) == sorted(pid for pid, _ in items)
    polys = [geometry.corners(p.x, p.y, p.w, p.h, p.theta) for p in layout]
    for c in polys:
        assert geometry.inside_tray(c, tray.width, tray.height)
    for a in range(len(polys)):
        for b in range(a + 1, len(polys)):
            assert not geometry.rects_overlap(polys[a], polys[b])
    for p, (_, pt) in zip(sorted(layout, key=lambda q: q.part), sorted(items), strict=True):
        assert (p.w, p.h) == (pt.width, pt.height)
        if not pt.rotatable:
            assert p.theta == 0.0


def test_four_squares_fill_the_tray_exactly():
    tray = Tray(100.0, 100.0)
    items = _items(("sq", 50.0, 50.0, 4, False))
    res = pk.pack(tray, items, time_limit=5.0)
    assert res.status == "feasible"
    _assert_valid(res.layout, tray, items)
    assert sorted((p.x, p.y) for p in res.layout) == [(25, 25), (25, 75), (75, 25), (75, 75)]


def test_one_grid_unit_smaller_is_infeasible():
    res = pk.pack(Tray(99.0, 100.0), _items(("sq", 50.0, 50.0, 4, False)), time_limit=5.0)
    assert res.status == "infeasible"
    assert res.layout is None


@pytest.fixture
def no_prechecks(monkeypatch):
    """CP-SAT alone: the pre-search tests of packing_bounds never answer."""
    from bilevel_kit.models import packing_bounds

    monkeypatch.setattr(packing_bounds, "infeasibility_reason", lambda sizes, W, H: None)


def test_pinwheel_needs_cpsat_and_is_tight(no_prechecks):
    """Four 30x20 parts fit a 50x50 tray only as a pinwheel (the shelf heuristic fails);
    49 x 50 is proven infeasible by CP-SAT although the area (2400 <= 2450) allows it."""
    items = _items(("p", 30.0, 20.0, 4, True))
    res = pk.pack(Tray(50.0, 50.0), items, time_limit=10.0)
    assert res.status == "feasible"
    assert res.extra.get("reason") != "shelf heuristic"
    assert sorted(p.theta for p in res.layout) == [0.0, 0.0, 90.0, 90.0]
    _assert_valid(res.layout, Tray(50.0, 50.0), items)
    small = pk.pack(Tray(49.0, 50.0), items, time_limit=10.0)
    assert small.status == "infeasible"
    assert small.extra["cpsat_status"] == "INFEASIBLE"


def test_two_60mm_squares_do_not_fit_although_area_does(no_prechecks):
    res = pk.pack(Tray(100.0, 100.0), _items(("s", 60.0, 60.0, 2, True)), time_limit=10.0)
    assert res.status == "infeasible"
    assert res.extra["cpsat_status"] == "INFEASIBLE"


def test_prechecks_answer_the_same_without_search():
    """The pinwheel's 49 x 50 tray (a dual-feasible-function bound) and the two 60 mm squares
    (both cross the midline) are proven infeasible before CP-SAT, as proofs."""
    small = pk.pack(Tray(49.0, 50.0), _items(("p", 30.0, 20.0, 4, True)), time_limit=10.0)
    assert small.status == "infeasible"
    assert small.extra["reason"] == "dual-feasible function bound"
    assert small.extra["proof"] is True
    assert "cpsat_status" not in small.extra
    two = pk.pack(Tray(100.0, 100.0), _items(("s", 60.0, 60.0, 2, True)), time_limit=10.0)
    assert two.status == "infeasible"
    assert two.extra["reason"] == "tall or wide parts"
    assert two.extra["proof"] is True


def _guillotine(W: int, H: int, n: int, rng) -> list[tuple[int, int]]:
    pieces = [(W, H)]
    while len(pieces) < n:
        pieces.sort(key=lambda p: p[0] * p[1])
        w, h = pieces.pop()
        if w >= h:
            c = rng.randint(1, w - 1)
            pieces += [(c, h), (w - c, h)]
        else:
            c = rng.randint(1, h - 1)
            pieces += [(w, c), (w, h - c)]
    return pieces


def test_zero_waste_kit_of_25_parts_is_decided():
    """A 40 x 15 tray cut into 25 pieces (zero waste; bench P00 of bench/data/packing): the
    plain no-overlap-2D model does not decide it in 10 s; the redundant cumulatives do."""
    import random

    pieces = _guillotine(40, 15, 25, random.Random(1000))
    items = [
        (f"q{j}", PartType(id=f"q{j}", width=w, height=h, pick_time=1.0, rotatable=False))
        for j, (w, h) in enumerate(pieces)
    ]
    res = pk.pack(Tray(40.0, 15.0), items, time_limit=30.0)
    assert res.status == "feasible"
    _assert_valid(res.layout, Tray(40.0, 15.0), items)


def test_clautiaux_infeasible_instance_is_proven():
    """CJCM E07N15 (20 x 20, 15 parts, no rotation; known infeasible): no pre-check sees it,
    the cumulative relaxation proves it quickly."""
    spec = [
        (5, 7, 1),
        (4, 11, 1),
        (1, 13, 2),
        (11, 6, 1),
        (2, 20, 1),
        (3, 17, 1),
        (1, 15, 1),
        (13, 4, 1),
        (3, 3, 1),
        (1, 11, 1),
        (1, 8, 1),
        (1, 7, 1),
        (1, 3, 1),
        (1, 9, 1),
    ]
    items = _items(*[(f"e{k}", w, h, n, False) for k, (w, h, n) in enumerate(spec)])
    res = pk.pack(Tray(20.0, 20.0), items, time_limit=30.0)
    assert res.status == "infeasible"
    assert res.extra["cpsat_status"] == "INFEASIBLE"
    assert res.extra["proof"] is True


@pytest.mark.parametrize("seed", range(12))
def test_decisions_match_brute_force(seed):
    """Random tiny kits (rotation allowed or not): pack's answer equals exhaustive search."""
    import random

    rng = random.Random(seed)
    W, H = rng.randint(3, 6), rng.randint(3, 6)
    n = rng.randint(2, 5)
    sizes = [(rng.randint(1, W), rng.randint(1, H), rng.random() < 0.5) for _ in range(n)]
    items = [
        (f"b{j}", PartType(id=f"b{j}", width=w, height=h, pick_time=1.0, rotatable=r))
        for j, (w, h, r) in enumerate(sizes)
    ]
    res = pk.pack(Tray(float(W), float(H)), items, time_limit=10.0)
    assert res.status == ("feasible" if fits_on_grid(sizes, W, H) else "infeasible")


def test_rotation_makes_a_long_part_fit():
    tray = Tray(20.0, 100.0)
    rot = _items(("long", 90.0, 10.0, 1, True))
    res = pk.pack(tray, rot, time_limit=5.0)
    assert res.status == "feasible"
    assert res.layout[0].theta == 90.0
    _assert_valid(res.layout, tray, rot)
    fixed = pk.pack(tray, _items(("long", 90.0, 10.0, 1, False)), time_limit=5.0)
    assert fixed.status == "infeasible"
    # two long parts side by side need the rotation and CP-SAT's answer agrees
    two = _items(("long", 90.0, 10.0, 2, True))
    res2 = pk.pack(tray, two, time_limit=5.0)
    assert res2.status == "feasible"
    _assert_valid(res2.layout, tray, two)


def test_grid_rounds_sizes_up_so_layouts_stay_valid():
    """12.7 mm parts occupy 13 grid cells at 1 mm: 7 fit in 91 mm but not in 90 mm."""
    items = _items(("t", 12.7, 12.7, 7, True))
    ok = pk.pack(Tray(91.0, 12.7), items, time_limit=5.0)
    assert ok.status == "infeasible"  # 12.7 mm tray height rounds down to 12 < 13
    ok = pk.pack(Tray(91.0, 13.0), items, time_limit=5.0)
    assert ok.status == "feasible"
    _assert_valid(ok.layout, Tray(91.0, 13.0), items)
    assert ok.extra["grid_exact"] is False
    assert pk.pack(Tray(90.0, 13.0), items, time_limit=5.0).status == "infeasible"


def test_fitness_objective_on_a_strip_has_known_optimum():
    """Centres 5, 15, 25, 35 on a 40 x 10 strip: D_same + D_diff = 100, so the fitness
    100 - 2 D_same is maximised by grouping types (a a b b): D_same = 20, fitness = 60."""
    items = _items(("a", 10.0, 10.0, 2, False), ("b", 10.0, 10.0, 2, False))
    res = pk.pack(Tray(40.0, 10.0), items, objective="fitness", time_limit=10.0)
    assert res.status == "optimal"
    assert res.surrogate_objective == pytest.approx(60.0)
    assert res.bound == pytest.approx(60.0)
    assert res.true_fitness == pytest.approx(60.0)
    order = "".join(p.type for p in sorted(res.layout, key=lambda p: p.x))
    assert order in ("aabb", "bbaa")


def test_fitness_reports_true_euclidean_next_to_l1_surrogate():
    items = _items(("a", 10.0, 10.0, 1, False), ("b", 10.0, 10.0, 1, False))
    res = pk.pack(Tray(40.0, 40.0), items, objective="fitness", time_limit=10.0)
    assert res.status == "optimal"
    # opposite corners: L1 = 30 + 30, Euclidean = 30 sqrt 2
    assert res.surrogate_objective == pytest.approx(60.0)
    assert res.true_fitness == pytest.approx(30.0 * 2**0.5)


def test_kit_fits_memoises_and_uses_monotonicity(table):
    po.clear_cache()
    parts = table.kit_parts([t.id for t in table.tasks])
    assert po.kit_fits(table, parts, 5.0) is True
    cache = next(iter(po._CACHES.values()))
    solves = cache.solves
    assert po.kit_fits(table, parts, 5.0) is True
    assert po.kit_fits(table, {"leg": 2, "foot": 1}, 5.0) is True  # a sub-multiset
    assert cache.solves == solves
    # 32 legs: 32 x 153 x 13 grid mm^2 = 63648 > 60000 mm^2 of tray, refused by area
    assert po.kit_fits(table, {"leg": 32}, 5.0) is False
    assert po.kit_fits(table, {"leg": 33, "foot": 1}, 5.0) is False  # a super-multiset
    assert cache.solves == solves + 1
    layout = po.kit_layout(table, ["foot1", "conn1"], time_limit=5.0)
    assert sorted(p.part for p in layout) == [
        "conn1:connector:1",
        "conn1:screw_short:1",
        "foot1:foot:1",
        "foot1:leg:1",
        "foot1:screw_short:1",
    ]


def _grid(pattern: list[str], width: float, height: float):
    """A reach grid from rows of '#' (reachable) and '.' (row 0 = bottom of the tray)."""
    import numpy as np

    from bilevel_kit.reachability import ReachGrid

    cells = np.array([[c == "#" for c in row] for row in pattern])
    return ReachGrid(cells, width, height, None)


@pytest.mark.parametrize("contiguous", [True, False])
def test_reachability_keeps_every_centre_in_a_reachable_cell(contiguous):
    """Left half reachable (one span per row) or a two-column-wide comb (not a span): four
    30 x 30 squares must all sit with their centres in '#' cells, as the checker sees it."""
    row = "#####....." if contiguous else "##..##..##"
    reach = _grid([row] * 10, 100.0, 100.0)
    tray = Tray(100.0, 100.0)
    items = _items(("sq", 30.0, 30.0, 4, False))
    res = pk.pack(tray, items, reach=reach, time_limit=10.0)
    assert res.status == "feasible"
    _assert_valid(res.layout, tray, items)
    assert all(reach.lookup(p.x, p.y) for p in res.layout)
    tables = pk.reach_tables(reach, 100, 100, 1.0)
    assert (tables.row_spans is not None) == contiguous
    assert tables.step_x == 20
    # centres below y = 20 mm: one line of squares (centre y = 15), so at most three of them
    low = _grid(["##########"] * 2 + [".........."] * 8, 100.0, 100.0)
    assert pk.pack(tray, _items(("sq", 30.0, 30.0, 3, False)), reach=low).status == "feasible"
    res4 = pk.pack(tray, items, reach=low, time_limit=10.0)
    assert res4.status == "infeasible"
