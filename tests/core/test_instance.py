"""Instance loading, validation errors (each naming the file and JSON path), units, schema."""

from __future__ import annotations

import json

import jsonschema
import pytest

from bilevel_kit import InstanceError, load
from bilevel_kit.instance import DEFAULT_WEIGHTS, from_dict, schema, topological_order


def test_table_instance_numbers(table):
    assert table.n_tasks == 12
    assert len(table.precedence) == 8
    assert table.robot_time("foot1") == pytest.approx(27.0)  # leg 12 + foot 10 + screw 5
    assert table.robot_time("conn1") == pytest.approx(15.0)
    assert table.robot_time("top1") == pytest.approx(10.0)
    assert sum(table.human_time(t.id) for t in table.tasks) == pytest.approx(374.78)
    assert table.weights == DEFAULT_WEIGHTS
    assert table.horizon == 5
    assert dict(table.kit_parts([t.id for t in table.tasks])) == {
        "leg": 4,
        "foot": 4,
        "connector": 4,
        "screw_short": 8,
        "screw_long": 8,
    }


def test_every_shipped_instance_validates_against_schema(root):
    validator = jsonschema.Draft202012Validator(schema())
    for path in sorted((root / "instances").rglob("*.json")):
        if "solutions" in path.parent.parts:  # KitBench's best-known plans: solution files
            continue
        validator.validate(json.loads(path.read_text()))
        load(path)


def test_round_trip_is_lossless(table, stool, tiny):
    for inst in (table, stool, tiny):
        again = from_dict(json.loads(json.dumps(inst.to_dict())), inst.source)
        assert again == inst


def test_topological_order_is_leg_by_leg(table):
    assert topological_order(table) == [
        f"{k}{i}" for i in range(1, 5) for k in ("foot", "conn", "top")
    ]


def test_units_expand_tasks_and_chain_units(stool):
    three = stool.with_overrides(units=3)
    assert three.n_tasks == 9
    assert three.tasks[3].id == "a1@2" and three.tasks[3].unit == 2
    edges = set(three.precedence)
    # within a unit the product's edges, between units sinks (a2, a3) -> source (a1)
    assert ("a1@2", "a2@2") in edges
    assert ("a2@1", "a1@2") in edges and ("a3@1", "a1@2") in edges
    assert ("a3@2", "a1@3") in edges
    assert len(edges) == 3 * 2 + 2 * 2
    # every task of unit 1 is an ancestor of every task of unit 2
    assert {"a1@1", "a2@1", "a3@1"} <= three.ancestors["a2@2"]


def test_overrides(table):
    t = table.with_overrides(delivery_time=30, weights={"W3": 2.5}, horizon=3)
    assert t.delivery_time == 30 and t.weights["W3"] == 2.5 and t.weights["W4"] == 1.0
    assert t.horizon == 3 and table.delivery_time == 2.0
    with pytest.raises(InstanceError, match="unknown weight"):
        table.with_overrides(weights={"W9": 1})


def _error(doc, tmp_path) -> str:
    p = tmp_path / "bad.json"
    p.write_text(json.dumps(doc) if not isinstance(doc, str) else doc)
    with pytest.raises(InstanceError) as exc:
        load(p)
    msg = str(exc.value)
    assert msg.startswith(str(p) + ": $")
    assert "\n" not in msg
    return msg


def test_missing_field(doc, tmp_path):
    del doc["tray"]
    assert "$: missing required field 'tray'" in _error(doc, tmp_path)


def test_missing_nested_field(doc, tmp_path):
    del doc["tasks"][1]["human_time"]
    assert "$.tasks[1]: missing required field 'human_time'" in _error(doc, tmp_path)


def test_unknown_part_type(doc, tmp_path):
    doc["tasks"][1]["parts"][0]["type"] = "gear"
    assert "$.tasks[1].parts[0].type: unknown part type 'gear'" in _error(doc, tmp_path)


def test_duplicate_task_id(doc, tmp_path):
    doc["tasks"][2]["id"] = "x"
    assert "$.tasks[2].id: duplicate task id 'x'" in _error(doc, tmp_path)


def test_precedence_cycle_is_named(doc, tmp_path):
    doc["precedence"] += [["y", "z"], ["z", "x"]]
    assert "$.precedence: precedence cycle x -> y -> z -> x" in _error(doc, tmp_path)


def test_edge_to_unknown_task(doc, tmp_path):
    doc["precedence"].append(["x", "nope"])
    assert "$.precedence[1][1]: unknown task 'nope'" in _error(doc, tmp_path)


def test_negative_time(doc, tmp_path):
    doc["tasks"][0]["human_time"]["mean"] = -3
    assert "$.tasks[0].human_time.mean: -3 is less than the minimum of 0" in _error(doc, tmp_path)


def test_nan_time(doc, tmp_path):
    text = json.dumps(doc).replace('"pick_time": 2.0', '"pick_time": NaN')
    assert "$.part_types[1].pick_time: must be a finite number" in _error(text, tmp_path)


def test_part_larger_than_tray(doc, tmp_path):
    doc["part_types"][1]["width"] = 120.0  # not rotatable: 120 > 100
    msg = _error(doc, tmp_path)
    assert "$.part_types[1]: part 'b' (120 x 5 mm) does not fit the 100 x 100 mm tray" in msg
    doc["part_types"][1]["rotatable"] = True  # rotating does not help a 120 mm part either
    doc["part_types"][1]["height"] = 101.0
    assert "either axis-aligned orientation" in _error(doc, tmp_path)


def test_part_within_the_length_tolerance_of_the_tray(doc, tmp_path):
    """The packers' and the checker's rule (geometry.length_fits): a part up to TOL longer
    than the tray is accepted, one 2 TOL longer is not."""
    from bilevel_kit.geometry import TOL

    doc["part_types"][1]["width"] = 100.0 + TOL
    path = tmp_path / "i.json"
    path.write_text(json.dumps(doc))
    assert load(path).part_types["b"].width == 100.0 + TOL
    doc["part_types"][1]["width"] = 100.0 + 2 * TOL
    assert "does not fit the 100 x 100 mm tray in its fixed orientation" in _error(doc, tmp_path)


def test_rotation_makes_a_long_part_acceptable(doc):
    doc["tray"] = {"width": 30.0, "height": 100.0}
    doc["part_types"][1].update(rotatable=True)  # 40 x 5 fits only turned by 90 degrees
    assert from_dict(doc).part_types["b"].width == 40.0


def test_empty_task_list(doc, tmp_path):
    doc["tasks"] = []
    assert "$.tasks: [] should be non-empty" in _error(doc, tmp_path)


def test_wrong_format_version(doc, tmp_path):
    doc["format"] = "bilevel-kit/0"
    assert "$.format: unsupported format 'bilevel-kit/0'" in _error(doc, tmp_path)


def test_malformed_json(tmp_path):
    assert "$: malformed JSON at line 1 column" in _error('{"format": ', tmp_path)


def test_unknown_field_is_rejected(doc, tmp_path):
    doc["tray"]["depth"] = 3
    assert "$.tray: unknown field" in _error(doc, tmp_path)


def test_missing_file(tmp_path):
    with pytest.raises(InstanceError, match=r"nope\.json: \$: file not found"):
        load(tmp_path / "nope.json")
