"""The independent checker: each violation kind on a deliberately broken plan."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from bilevel_kit import Kit, KitTimes, Placement, Plan, check, evaluate
from bilevel_kit.heuristics.baselines import single_task, whole_assembly


@pytest.fixture
def valid(tiny):
    # tray 120 x 100; block 50 x 50 (rotatable), bar 100 x 20 (fixed)
    k1 = Kit(
        ("t1", "t2"),
        (
            Placement("block-1", "block", 25, 25, 0, 50, 50),
            Placement("bar-1", "bar", 50, 90, 0, 100, 20),
        ),
    )
    k2 = Kit(
        ("t3",),
        (
            Placement("block-1", "block", 84, 36, 45, 50, 50),  # a diamond: x 48.6..119.4
            Placement("bar-1", "bar", 50, 90, 180, 100, 20),
        ),
    )
    return Plan((k1, k2))


def kinds(violations):
    return sorted({v.kind for v in violations})


def test_valid_plan_has_no_violation(tiny, valid):
    assert check(tiny, valid) == []


def test_missing_and_repeated_and_unknown(tiny, valid):
    plan = Plan((valid.kits[0], Kit(("t1", "zz"), ())))
    v = check(tiny, plan)
    assert {"missing_task", "repeated_task", "unknown_task"} <= set(kinds(v))
    assert any("'t3'" in x.message for x in v if x.kind == "missing_task")


def test_precedence_across_kits(tiny, valid):
    plan = Plan((valid.kits[1], valid.kits[0]))
    v = [x for x in check(tiny, plan) if x.kind == "precedence"]
    assert len(v) == 2 and "delivered in kit 2, after kit 1" in v[0].message


def test_precedence_inside_kit(tiny):
    from bilevel_kit.heuristics.baselines import packed_kit

    kit = packed_kit(tiny, ["t3", "t1", "t2"], "k")
    v = check(tiny, Plan((kit,)))
    assert kinds(v) == ["precedence"]
    assert "comes after it inside kit 1" in v[0].message


def test_parts_mismatch(tiny, valid):
    k1 = replace(valid.kits[0], layout=valid.kits[0].layout[:1])
    v = check(tiny, Plan((k1, valid.kits[1])))
    assert kinds(v) == ["parts_mismatch"]
    assert "bar: needs 1, has 0" in v[0].message


def test_outside_tray(tiny, valid):
    # a 50 x 50 block turned by 45 degrees needs 35.36 mm of clearance around its centre
    moved = (replace(valid.kits[1].layout[0], x=120 - 35.0), *valid.kits[1].layout[1:])
    v = check(tiny, Plan((valid.kits[0], replace(valid.kits[1], layout=moved))))
    assert kinds(v) == ["outside_tray"] and v[0].kit == 2
    ok = (replace(valid.kits[1].layout[0], x=120 - 35.3554), *valid.kits[1].layout[1:])
    assert check(tiny, Plan((valid.kits[0], replace(valid.kits[1], layout=ok)))) == []


def test_overlap_exact_rotated(tiny, valid):
    # the diamond's top corner is at y = 36 + 35.3553 = 71.3553
    lay = list(valid.kits[1].layout)
    lay[1] = replace(lay[1], y=81.0)  # bar spans y 71..91: 0.355 mm into the corner
    v = check(tiny, Plan((valid.kits[0], replace(valid.kits[1], layout=tuple(lay)))))
    assert kinds(v) == ["overlap"]
    assert "depth 0.355 mm" in v[0].message
    lay[1] = replace(lay[1], y=81.3554)  # bar bottom at 71.3554: just clear of the corner
    assert check(tiny, Plan((valid.kits[0], replace(valid.kits[1], layout=tuple(lay))))) == []


def test_touching_parts_are_fine(tiny, valid):
    lay = (
        Placement("block-1", "block", 25, 25, 0, 50, 50),
        Placement("bar-1", "bar", 50, 60, 0, 100, 20),
    )  # bar bottom edge on the block top
    assert check(tiny, Plan((replace(valid.kits[0], layout=lay), valid.kits[1]))) == []
    lay = (lay[0], replace(lay[1], y=60 - 1e-4))
    assert kinds(check(tiny, Plan((replace(valid.kits[0], layout=lay), valid.kits[1])))) == [
        "overlap"
    ]


def test_rotation_not_allowed_and_footprint(tiny, valid):
    lay = (valid.kits[0].layout[0], replace(valid.kits[0].layout[1], theta=90, x=110, y=50))
    v = check(tiny, Plan((replace(valid.kits[0], layout=lay), valid.kits[1])))
    assert "rotation_not_allowed" in kinds(v)
    lay = (replace(valid.kits[0].layout[0], w=40), valid.kits[0].layout[1])
    assert kinds(check(tiny, Plan((replace(valid.kits[0], layout=lay), valid.kits[1])))) == [
        "footprint_mismatch"
    ]


def test_duplicate_part_id_and_unknown_type(tiny, valid):
    lay = (valid.kits[0].layout[0], replace(valid.kits[0].layout[1], part="block-1"))
    assert "duplicate_part_id" in kinds(
        check(tiny, Plan((replace(valid.kits[0], layout=lay), valid.kits[1])))
    )
    lay = (valid.kits[0].layout[0], replace(valid.kits[0].layout[1], type="gear"))
    assert "unknown_part_type" in kinds(
        check(tiny, Plan((replace(valid.kits[0], layout=lay), valid.kits[1])))
    )


def test_empty_kit(tiny, valid):
    assert "empty_kit" in kinds(check(tiny, Plan((*valid.kits, Kit(())))))


def test_reported_times(tiny, valid):
    tl = evaluate(tiny, valid)
    assert check(tiny, valid, reported_kits=tl.kits, reported_metrics=tl.metrics()) == []
    bad = list(tl.kits)
    bad[1] = KitTimes(
        *(getattr(bad[1], f) for f in ("robot_start", "robot_end", "arrive", "human_start")),
        bad[1].human_end + 0.5,
    )
    v = check(tiny, valid, reported_kits=bad, reported_metrics={"makespan": tl.makespan + 1})
    assert kinds(v) == ["times_inconsistent"] and len(v) == 2
    assert "kit 2: reported human_end" in v[0].message


@pytest.mark.parametrize("method", [single_task, whole_assembly])
def test_baselines_are_valid_on_every_instance(method, root):
    from bilevel_kit import load
    from bilevel_kit.errors import KitDoesNotFit

    checked = 0
    for path in sorted((root / "instances").glob("*.json")):
        inst = load(path)
        try:
            out = method(inst)
        except KitDoesNotFit:
            # only a proof excuses a baseline: a unit's parts cover more than the tray
            assert method is whole_assembly, path.name
            area = sum(
                inst.part_types[p].area * n
                for p, n in inst.kit_parts([t.id for t in inst.tasks]).items()
            )
            assert area > inst.tray.area, path.name
            continue
        assert check(inst, out.plan) == [], path.name
        checked += 1
    assert checked >= 3


def _all_pairs_reference(parts, width, height):
    """The checker's former test: every corner inside, every pair by separating axes."""
    from itertools import combinations

    from bilevel_kit import geometry

    cs = [geometry.corners(p.x, p.y, p.w, p.h, p.theta) for p in parts]
    outside = [k for k, c in enumerate(cs) if not geometry.inside_tray(c, width, height)]
    overlaps = [
        (a, b)
        for a, b in combinations(range(len(cs)), 2)
        if geometry.penetration(cs[a], cs[b]) > geometry.TOL
    ]
    return outside, overlaps


def test_one_layout_test_for_checker_and_layout_searches():
    """geometry.layout_violations (box pre-filter) finds exactly what testing every pair finds,
    and cross-entropy's and the convex polish's acceptance gates agree with it."""
    from bilevel_kit import geometry
    from bilevel_kit.heuristics import convex
    from bilevel_kit.heuristics.cross_entropy import _exactly_valid
    from bilevel_kit.instance import Tray

    rng = np.random.default_rng(7)
    seen = set()
    for _ in range(400):
        n = int(rng.integers(1, 7))
        parts = [
            Placement(
                f"p{k}",
                "x",
                float(rng.uniform(0, 120)),
                float(rng.uniform(0, 100)),
                float(rng.choice([0.0, 90.0, 45.0, rng.uniform(-180, 180)])),
                float(rng.uniform(5, 40)),
                float(rng.uniform(5, 40)),
            )
            for k in range(n)
        ]
        found = geometry.layout_violations(parts, 120.0, 100.0)
        outside, overlaps = _all_pairs_reference(parts, 120.0, 100.0)
        assert [f.index for f in found if f.kind == "outside_tray"] == outside
        assert [(f.index, f.other) for f in found if f.kind == "overlap"] == overlaps
        valid = not outside and not overlaps
        seen.add(valid)
        assert geometry.exactly_valid(parts, 120.0, 100.0) == valid
        assert convex.exactly_valid(parts, 120.0, 100.0) == valid
        assert _exactly_valid(parts, Tray(120.0, 100.0)) == valid
    assert seen == {True, False}


def test_layout_violations_reports_depth_area_and_stops_first():
    from bilevel_kit import geometry

    parts = [
        Placement("a", "x", 10, 10, 0, 20, 20),
        Placement("b", "x", 25, 10, 0, 20, 20),  # 5 mm into a: 5 x 20 = 100 mm^2
        Placement("c", "x", 118, 50, 0, 10, 10),  # 3 mm out of a 120 mm tray
    ]
    found = geometry.layout_violations(parts, 120, 100)
    assert [(f.kind, f.index, f.other) for f in found] == [
        ("outside_tray", 2, None),
        ("overlap", 0, 1),
    ]
    assert found[1].depth == pytest.approx(5.0) and found[1].area == pytest.approx(100.0)
    assert len(geometry.layout_violations(parts, 120, 100, first=True)) == 1
    assert geometry.layout_violations(parts[:1], 120, 100) == []
