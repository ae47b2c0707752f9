"""The independent checker: each violation kind on a deliberately broken plan."""

from __future__ import annotations

from dataclasses import replace

import pytest

from bilevel_kit import Kit, KitTimes, Placement, Plan, check, evaluate
from bilevel_kit.solvers.baselines import single_task, whole_assembly


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
    from bilevel_kit.solvers.baselines import packed_kit

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

    for path in sorted((root / "instances").glob("*.json")):
        inst = load(path)
        out = method(inst)
        assert check(inst, out.plan) == [], path.name
