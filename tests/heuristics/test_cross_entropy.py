"""Cross-entropy kit arrangement (paper Algorithm 1): behaviour, determinism, exactness."""

from __future__ import annotations

import math
from dataclasses import replace
from typing import Any

import numpy as np
import pytest
from strategies import one_task_doc

from bilevel_kit import geometry
from bilevel_kit.errors import UsageError
from bilevel_kit.fitness import layout_terms
from bilevel_kit.heuristics.ce.accept import push_apart
from bilevel_kit.heuristics.ce.kit import build_kit
from bilevel_kit.heuristics.ce.sampling import standard_normal
from bilevel_kit.heuristics.cross_entropy import Arrangement, CEParams, arrange
from bilevel_kit.instance import Instance, PartType, from_dict
from bilevel_kit.plan import Placement


def make(
    width: float, height: float, types: list[tuple[str, float, float, bool]], **extra: Any
) -> Instance:
    """A one-task instance in format bilevel-kit/1 holding the given part types."""
    doc = one_task_doc("ce-test", width, height, types, {types[0][0]: 1})
    return from_dict({**doc, **extra})


TRAY = make(300, 200, [("a", 20, 20, True), ("b", 20, 20, True)])
TABLE = make(
    300,
    200,
    [
        ("leg", 152.4, 12.7, True),
        ("foot", 43, 43, True),
        ("connector", 41, 41, True),
        ("screw_long", 14, 6, True),
        ("screw_short", 8, 6, True),
    ],
)
TABLE_PARTS = {"leg": 4, "foot": 4, "connector": 4, "screw_long": 8, "screw_short": 8}


def centre_dist(p: Placement, q: Placement) -> float:
    return math.hypot(p.x - q.x, p.y - q.y)


def assert_exactly_valid(res: Arrangement, inst: Instance) -> None:
    """Independent check with geometry: inside the tray, no pair penetrating."""
    assert res.fits
    tray = inst.tray
    corners = [geometry.corners(p.x, p.y, p.w, p.h, p.theta) for p in res.layout]
    for p, c in zip(res.layout, corners, strict=True):
        assert geometry.inside_tray(c, tray.width, tray.height), p
        pt = inst.part_types[p.type]
        assert (p.w, p.h) == (pt.width, pt.height)
        if not pt.rotatable:
            assert p.theta == 0.0
    for a in range(len(corners)):
        for b in range(a + 1, len(corners)):
            assert geometry.penetration(corners[a], corners[b]) <= geometry.TOL, (a, b)


def test_two_types_end_in_opposite_corners() -> None:
    res = arrange(TRAY, {"a": 1, "b": 1}, rng=0)
    assert_exactly_valid(res, TRAY)
    p, q = res.layout
    # the farthest two 20 x 20 squares can be: opposite corners, sqrt(280^2 + 180^2) = 332.9
    assert centre_dist(p, q) > 0.9 * math.hypot(300, 200)
    assert res.d_diff == pytest.approx(centre_dist(p, q))
    assert res.d_same == 0.0


def test_same_type_parts_end_adjacent() -> None:
    res = arrange(TRAY, {"a": 2, "b": 1}, rng=0)
    assert_exactly_valid(res, TRAY)
    a1, a2, b1 = res.layout
    assert [p.part for p in res.layout] == ["a-1", "a-2", "b-1"]
    # disjoint 20 x 20 squares are at least 20 apart (their inscribed discs are disjoint)
    assert 20.0 - 1e-6 <= centre_dist(a1, a2) < 1.5 * 20.0
    assert min(centre_dist(a1, b1), centre_dist(a2, b1)) > 0.8 * math.hypot(300, 200)


def test_same_seed_same_layout_other_seed_other_layout() -> None:
    parts = {"a": 3, "b": 2}
    first = arrange(TRAY, parts, rng=7)
    again = arrange(TRAY, parts, rng=np.random.default_rng(7))
    other = arrange(TRAY, parts, rng=8)
    assert first.layout == again.layout
    assert first.trace == again.trace
    assert first.layout != other.layout


def test_result_fields_are_consistent() -> None:
    res = arrange(TRAY, {"a": 3, "b": 2}, rng=1, w6=5.0)
    d_same, d_diff, z_bbox, z_exact = layout_terms(res.layout)
    assert (res.d_same, res.d_diff, res.z_bbox, res.z) == (d_same, d_diff, z_bbox, z_exact)
    assert res.fitness == pytest.approx(-(d_same - d_diff + 5.0 * z_exact))
    assert len(res.trace) == res.iterations
    assert all(b >= a for a, b in zip(res.trace, res.trace[1:], strict=False))
    assert res.source.startswith("ce")


def test_small_kit_converges_before_the_cap() -> None:
    res = arrange(TRAY, {"a": 1, "b": 1}, rng=0)
    assert res.converged
    assert CEParams().patience < res.iterations < CEParams().max_iter


def test_table_kit_fits_and_beats_the_shelf_packer() -> None:
    from bilevel_kit.fitness import layout_fitness
    from bilevel_kit.heuristics.shelf import shelf_pack

    res = arrange(TABLE, TABLE_PARTS, rng=0)
    assert_exactly_valid(res, TABLE)
    assert len(res.layout) == 28
    items = [(p.part, TABLE.part_types[p.type]) for p in res.layout]
    packed = shelf_pack(TABLE.tray, items)
    assert packed is not None
    assert res.fitness > layout_fitness(packed, TABLE.weights["W6"])


@pytest.mark.parametrize("precision", ["float32", "float64"])
def test_fixed_and_long_parts_are_valid(precision: str) -> None:
    inst = make(300, 200, [("bar", 150, 10, False), ("long", 250, 10, True), ("nut", 10, 10, True)])
    res = arrange(
        inst,
        {"bar": 2, "long": 1, "nut": 4},
        rng=3,
        params=CEParams(precision=precision, max_iter=60),
    )
    assert_exactly_valid(res, inst)
    assert all(-90.0 < p.theta <= 90.0 for p in res.layout)


def test_area_bound_reports_no_fit_immediately() -> None:
    inst = make(100, 100, [("sq", 60, 60, True)])
    res = arrange(inst, {"sq": 3}, rng=0)
    assert not res.fits
    assert res.layout == ()
    assert res.source == "area-bound"
    assert res.iterations == 0
    assert res.fitness == -math.inf


def test_part_wider_than_the_tray_in_every_direction() -> None:
    # 120 x 110 on a 300 x 100 tray: small area, but every width of it exceeds 100 mm
    # (from_dict would reject the type, so it is swapped in behind the loader's back)
    inst = make(300, 100, [("sq", 10, 10, True)])
    big = replace(inst, part_types={"sq": PartType("sq", 120, 110, 1.0)})
    res = arrange(big, {"sq": 1}, rng=0)
    assert not res.fits
    assert res.source == "too-large"


def test_impossible_kit_is_not_reported_as_fitting() -> None:
    # two 110 mm squares never fit in a 200 mm square (at most side 100 for two equal
    # squares), although their area is only 60 % of the tray
    inst = make(200, 200, [("sq", 110, 110, True)])
    res = arrange(inst, {"sq": 2}, rng=0, params=CEParams(max_iter=30))
    assert not res.fits
    assert len(res.layout) == 2  # returned for debugging
    c = [geometry.corners(p.x, p.y, p.w, p.h, p.theta) for p in res.layout]
    inside = all(geometry.inside_tray(k, 200, 200) for k in c)
    assert not inside or geometry.rects_overlap(c[0], c[1])


def test_packer_layout_when_ce_fails() -> None:
    # four 50 mm squares tile a 100 mm tray exactly: one CE iteration without repair cannot
    # find the tiling, the packer can
    inst = make(100, 100, [("sq", 50, 50, True)])
    res = arrange(inst, {"sq": 4}, rng=0, params=CEParams(max_iter=1, repair=False))
    assert res.source == "packer"
    assert_exactly_valid(res, inst)
    assert sorted((p.x, p.y) for p in res.layout) == [(25, 25), (25, 75), (75, 25), (75, 75)]


def test_no_valid_layout_without_packer(monkeypatch: pytest.MonkeyPatch) -> None:
    from bilevel_kit.heuristics import shelf as packing

    monkeypatch.setattr(packing, "shelf_pack", lambda tray, items: None)
    inst = make(100, 100, [("sq", 50, 50, True)])
    res = arrange(inst, {"sq": 4}, rng=0, params=CEParams(max_iter=1, repair=False))
    assert not res.fits
    assert res.z > 0.0


def test_start_layout_is_never_made_worse() -> None:
    from bilevel_kit.fitness import layout_fitness
    from bilevel_kit.heuristics.shelf import shelf_pack

    parts = {"a": 3, "b": 3}
    items = [(f"{t}-{k}", TRAY.part_types[t]) for t in "ab" for k in (1, 2, 3)]
    packed = shelf_pack(TRAY.tray, items)
    assert packed is not None
    res = arrange(TRAY, parts, rng=0, start=packed, params=CEParams(max_iter=20))
    assert res.source.startswith("ce+start")
    assert_exactly_valid(res, TRAY)
    assert res.fitness >= layout_fitness(packed, TRAY.weights["W6"]) - 1e-9


def test_push_apart_separates_boxes() -> None:
    kit = build_kit(TRAY, {"a": 2, "b": 1}, np.float64)
    x, y, th = np.array([100.0, 105.0, 0.0]), np.array([100.0, 103.0, 0.0]), np.zeros(3)
    moved = push_apart(kit, x, y, th)
    assert moved is not None
    mx, my = moved
    assert max(abs(mx[0] - mx[1]), abs(my[0] - my[1])) >= 20.0
    assert mx[2] >= 10.0 and my[2] >= 10.0  # clipped into the tray


def test_bad_arguments() -> None:
    with pytest.raises(UsageError):
        CEParams(elite=300)
    with pytest.raises(UsageError):
        CEParams(cov_smoothing=0.0)
    with pytest.raises(UsageError):
        arrange(TRAY, {"zz": 1})
    empty = arrange(TRAY, {})
    assert empty.fits and empty.layout == ()


def test_standard_normals_float32() -> None:
    z = standard_normal(np.random.default_rng(0), (400, 500), np.float32)
    assert z.dtype == np.float32
    assert abs(float(z.mean())) < 0.01
    assert abs(float(z.std()) - 1.0) < 0.01
    assert 0.0035 < float((np.abs(z) > 2.9).mean()) < 0.0040  # two-sided tail 0.00373


def _one_task_of_squares(n: int, tray: float):
    """One task of ``n`` 10 mm squares on a square tray of side ``tray`` mm: a kit as large
    as a test of CE's size limits wants."""
    from bilevel_kit import instance as inst_mod

    doc = inst_mod.document(
        "many",
        [{"id": "p", "width": 10.0, "height": 10.0, "pick_time": 1.0}],
        [{"id": "t", "parts": [{"type": "p", "count": n}], "human_time": {"mean": 2.0}}],
        tray=(tray, tray),
    )
    return inst_mod.from_dict(doc)


def test_a_kit_above_max_ce_parts_gets_the_shelf_layout_without_ce():
    """CE's covariance grows with the square of the parts (4,000 parts asked for 6 GiB):
    beyond MAX_CE_PARTS the kit gets the shelf packer's layout, checked like any other."""
    from bilevel_kit.heuristics import cross_entropy

    n = cross_entropy.MAX_CE_PARTS + 1
    arr = cross_entropy.arrange(_one_task_of_squares(n, 300.0), {"p": n})
    assert arr.fits and arr.source == "packer" and len(arr.layout) == n and arr.iterations == 0


def test_a_kit_too_large_for_ce_never_builds_the_pair_table(monkeypatch):
    """The pair table is quadratic (a 4,000-part task used 1.2 GB and 21 s at a 2 s limit):
    a kit above MAX_CE_PARTS is scored by blocks and the grid hash, with the same terms."""
    from bilevel_kit.fitness import layout_terms
    from bilevel_kit.heuristics import cross_entropy
    from bilevel_kit.heuristics.ce import kit as kit_mod

    built = []
    real = kit_mod.PairTable.build
    monkeypatch.setattr(kit_mod.PairTable, "build", lambda *a: built.append(1) or real(*a))
    n = 1500
    arr = cross_entropy.arrange(_one_task_of_squares(n, 500.0), {"p": n})
    assert built == [] and arr.fits and len(arr.layout) == n and arr.z == 0.0
    assert (arr.d_same, arr.d_diff) == pytest.approx(layout_terms(arr.layout)[:2])
    assert arr.d_same > 0.0 and arr.d_diff == 0.0  # one type: every pair is "same"
