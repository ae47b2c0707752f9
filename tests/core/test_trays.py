"""The tray rule (docs/timeline.md): the instance field, the evaluator, the checker."""

from __future__ import annotations

import copy
import json

import pytest

from bilevel_kit import InstanceError, Kit, Plan, check, evaluate, load
from bilevel_kit.instance import document, from_dict
from bilevel_kit.plan import KitTimes

# three one-task kits: r = 3, 1, 1 s; h = 10, 1, 1 s; d = 1 s, o_R = 0, o_H = 2 s
DOC = document(
    "trays",
    [{"id": "a", "width": 10.0, "height": 10.0, "pick_time": 1.0}],
    [
        {"id": "x", "parts": [], "robot_time": 3.0, "human_time": {"mean": 10.0}},
        {"id": "y", "parts": [], "robot_time": 1.0, "human_time": {"mean": 1.0}},
        {"id": "z", "parts": [], "robot_time": 1.0, "human_time": {"mean": 1.0}},
    ],
    overhead=(0.0, 2.0),
)
PLAN = Plan((Kit(("x",)), Kit(("y",)), Kit(("z",))))


def _inst(trays):
    doc = copy.deepcopy(DOC)
    if trays != "absent":
        doc["trays"] = trays
    return from_dict(doc, "trays.json")


def _times(tl):
    return [(k.robot_start, k.robot_end, k.arrive, k.human_start, k.human_end) for k in tl.kits]


def test_unlimited_trays_let_the_robot_run_ahead():
    for trays in ("absent", None, 3, 50):
        tl = evaluate(_inst(trays), PLAN)
        assert _times(tl) == [(0, 3, 4, 4, 16), (4, 5, 6, 16, 19), (6, 7, 8, 19, 22)]
        assert tl.makespan == 22


def test_one_tray_waits_for_the_human_to_take_the_parts():
    # kit 2 waits for kit 1's tray: back at human_start 4 + o_H 2 = 6;
    # kit 3 waits for kit 2's tray: back at 16 + 2 = 18
    tl = evaluate(_inst(1), PLAN)
    assert _times(tl) == [(0, 3, 4, 4, 16), (6, 7, 8, 16, 19), (18, 19, 20, 20, 23)]
    assert tl.makespan == 23
    assert tl.human_idle == 23 - (12 + 3 + 3)


def test_two_trays_bind_only_from_the_third_kit():
    # kit 3 may start once kit 1's tray is back (4 + 2 = 6) and kit 2 has arrived (6)
    tl = evaluate(_inst(2), PLAN)
    assert _times(tl) == [(0, 3, 4, 4, 16), (4, 5, 6, 16, 19), (6, 7, 8, 19, 22)]


def test_a_tray_limit_never_shortens_a_plan(table):
    plan = Plan(tuple(Kit((t.id,)) for t in table.tasks))
    free = evaluate(table.with_overrides(trays="unlimited"), plan).makespan
    spans = [evaluate(table.with_overrides(trays=k), plan).makespan for k in (1, 2, 3)]
    assert spans[0] >= spans[1] >= spans[2] >= free


def test_trays_round_trip_and_override(table):
    inst = _inst(1)
    assert inst.trays == 1 and inst.tray_limit == 1
    assert from_dict(inst.to_dict()).trays == 1
    assert "trays" not in _inst("absent").to_dict()
    assert inst.with_overrides(trays="unlimited").trays is None
    assert inst.with_overrides(trays=2).trays == 2
    assert _inst(3).tray_limit is None  # as many trays as tasks: no limit


@pytest.mark.parametrize("bad", [0, -1, 1.5, "two", True, [1]])
def test_bad_trays_name_the_field(bad, tmp_path):
    doc = copy.deepcopy(DOC)
    doc["trays"] = bad
    p = tmp_path / "bad.json"
    p.write_text(json.dumps(doc))
    with pytest.raises(InstanceError) as exc:
        load(p)
    msg = str(exc.value)
    assert msg.startswith(f"{p}: $.trays") and "\n" not in msg


def test_nan_trays_is_rejected(tmp_path):
    p = tmp_path / "bad.json"
    p.write_text(json.dumps(DOC)[:-1] + ', "trays": NaN}')
    with pytest.raises(InstanceError, match=r"\$\.trays"):
        load(p)


@pytest.mark.parametrize("bad", [0, -2, 1.5, "x", float("nan")])
def test_bad_tray_override(bad):
    with pytest.raises(InstanceError, match=r"\$\.trays"):
        _inst(1).with_overrides(trays=bad)


def test_checker_rejects_times_that_ignore_the_tray():
    inst = _inst(1)
    free = evaluate(_inst(None), PLAN)  # the robot ran ahead
    found = check(inst, PLAN, reported_kits=free.kits)
    kinds = {v.kind for v in found}
    assert "tray_not_returned" in kinds and "times_inconsistent" in kinds
    assert any("kit 2" in v.message and "back at 6 s" in v.message for v in found)
    honest = evaluate(inst, PLAN)
    assert check(inst, PLAN, reported_kits=honest.kits, reported_metrics=honest.metrics()) == []


def test_checker_tray_rule_uses_the_reported_times():
    inst = _inst(1)
    kits = list(evaluate(inst, PLAN).kits)
    k = kits[2]
    kits[2] = KitTimes(k.robot_start - 1, k.robot_end - 1, k.arrive - 1, k.human_start, k.human_end)
    kinds = [v.kind for v in check(inst, PLAN, reported_kits=kits)]
    assert kinds.count("tray_not_returned") == 1
