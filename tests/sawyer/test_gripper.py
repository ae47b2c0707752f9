"""The station's gripper and ``execute``'s feasibility pass (docs/execution.md#the-gripper)."""

from __future__ import annotations

import json
import math
from pathlib import Path

import pytest

from bilevel_kit import load, solve
from bilevel_kit import solution as solution_io
from bilevel_kit.cli import main
from bilevel_kit.errors import InstanceError
from bilevel_kit.plan import Kit, Placement, Plan
from bilevel_kit.sawyer.gripper import DEFAULT_GRIPPER, Gripper, check_grasps, verdicts
from bilevel_kit.sawyer.station import Station, StationError

ROOT = Path(__file__).resolve().parents[2]
TABLE = ROOT / "instances" / "hrc_table.json"


@pytest.fixture(scope="module")
def table():
    return load(TABLE)


def _plan(*layout: Placement) -> Plan:
    return Plan((Kit(("foot1",), tuple(layout)),))


def _screw(part: str, x: float, y: float, theta: float = 0.0) -> Placement:
    return Placement(part, "screw_short", x, y, theta, 8.0, 6.0)


def test_the_default_gripper_is_the_urdfs_fingers():
    assert DEFAULT_GRIPPER.stroke_max == pytest.approx(2 * 20.833)
    assert Station().gripper == DEFAULT_GRIPPER
    assert "gripper" not in Station().to_dict()
    g = Station.from_dict({"gripper": {"stroke_min": 19.0, "stroke_max": 60.0}}).gripper
    assert (g.stroke_min, g.stroke_max, g.finger_width) == (19.0, 60.0, 12.0)
    assert Station.from_dict(Station(gripper=g).to_dict()).gripper == g


@pytest.mark.parametrize(
    ("gripper", "message"),
    [
        ({"stroke": 3}, "station.gripper: unknown key(s) stroke"),
        ({"stroke_max": -1}, "station.gripper.stroke_max: expected a finite number >= 0"),
        ({"stroke_min": 50}, "station.gripper.stroke_max: 41.666 mm must exceed stroke_min"),
        ({"finger_width": 0}, "station.gripper.finger_width: expected a number > 0"),
        ([1, 2], "station.gripper: expected an object"),
    ],
)
def test_a_bad_gripper_is_named(gripper, message):
    with pytest.raises(StationError) as exc:
        Station.from_dict({"gripper": gripper})
    assert str(exc.value).startswith(message), exc.value


def test_a_grasp_width_wider_than_the_part_is_named(tmp_path):
    doc = json.loads(TABLE.read_text())
    doc["part_types"][3]["grasp_width"] = 7.0  # screw_long is 14 x 6 mm
    bad = tmp_path / "bad.json"
    bad.write_text(json.dumps(doc))
    with pytest.raises(InstanceError) as exc:
        load(bad)
    assert "$.part_types[3].grasp_width" in str(exc.value) and "7 mm exceeds" in str(exc.value)


def test_the_fingers_close_across_the_side_that_fits(table):
    # a leg along the tray's y axis: the fingers close across its 12.7 mm, along the tray x
    (c,) = check_grasps(table, _plan(Placement("leg-1", "leg", 80.0, 100.0, 90.0, 152.4, 12.7)))
    assert c.problem == "" and c.grasp_width == 12.7
    assert c.span == pytest.approx(12.7 + 2 + 24)
    assert c.tray_clearance == pytest.approx(80 - (12.7 + 2 + 24) / 2)
    assert c.part_clearance == math.inf


def test_fingers_leaving_the_tray_are_named(table):
    (c,) = check_grasps(table, _plan(_screw("s", 20.0, 3.0)))
    assert c.fault == "tray"
    assert c.problem.startswith(
        "kit 1, part s (type screw_short): the open fingers (34 mm across: grasp width 8 + "
        "clearance 2 + 2 x finger width 12) leave the 300 x 200 mm tray by 3.00 mm"
    )


def test_fingers_hitting_a_placed_part_are_named(table):
    placed = Placement("foot-1", "foot", 150.0, 100.0, 0.0, 43.0, 43.0)
    screw = _screw("s", 150.0, 124.5)  # touching the bracket's side (y = 121.5)
    checks = check_grasps(table, _plan(placed, screw))
    assert [c.fault for c in checks] == ["", "part"]
    assert "overlap part foot-1, placed before it, by 3.00 mm" in checks[1].problem
    # the screw placed first: the bracket's fingers close on its wall, inside its footprint
    checks = check_grasps(table, _plan(screw, placed))
    assert [c.fault for c in checks] == ["", ""]
    assert checks[1].part_clearance == pytest.approx(15.5)


def _table_variant(tmp_path: Path, change) -> tuple[Path, Path]:
    doc = json.loads(TABLE.read_text())
    change(doc)
    inst = tmp_path / "table.json"
    inst.write_text(json.dumps(doc))
    sol = tmp_path / "sol.json"
    solution_io.write(sol, solve(load(inst), "single-task"))
    return inst, sol


def test_a_part_too_wide_is_exit_2_naming_kit_part_and_widths(capsys, tmp_path):
    def outside(doc):
        del doc["part_types"][1]["grasp_width"]  # the foot bracket by its 43 mm outside

    inst, sol = _table_variant(tmp_path, outside)
    out = tmp_path / "out"
    for extra in ((), ("--grasp-check", "warn")):  # warn does not hide a stroke fault
        code = main(["execute", str(inst), str(sol), "--bag", str(out), *extra])
        text, err = capsys.readouterr()
        assert code == 2 and text == "" and "Traceback" not in err
        assert len(err.strip().splitlines()) == 1
        assert (
            "kit 1, part foot-1 (type foot): grasp width 43 mm is outside the gripper's stroke "
            "0-41.666 mm less 2 mm clearance (2-39.666 mm)" in err
        )
        assert not out.exists()


def test_the_tables_layouts_fail_strict_and_pass_warn(capsys, tmp_path):
    inst, sol = _table_variant(tmp_path, lambda doc: None)
    out = tmp_path / "v.html"
    code = main(["execute", str(inst), str(sol), "--html", str(out)])
    text, err = capsys.readouterr()
    assert code == 2 and "leave the 300 x 200 mm tray" in err and not out.exists()
    assert main(["execute", str(inst), str(sol), "--html", str(out), "--grasp-check", "warn"]) == 0
    text, err = capsys.readouterr()
    assert text.startswith("warning: kit 1, part ") and out.exists()


@pytest.mark.parametrize("method", ["greedy-ce", "cpsat"])
def test_every_part_type_of_the_table_fits_the_declared_gripper(table, method):
    """The stroke holds every part of the table's plans; the fingers' clearances are the
    documented ones (docs/execution.md#the-gripper)."""
    checks = check_grasps(table, solve(table, method).plan)
    assert table.station.gripper == Gripper(stroke_max=41.666)
    assert len(checks) == 28 and not [c for c in checks if c.fault == "stroke"]
    per_type = verdicts(checks)
    assert set(per_type) == {"leg", "foot", "connector", "screw_long", "screw_short"}
    for part_type in ("foot", "connector"):  # grasped across a 3 mm wall, inside the bracket
        bad, tray, near = per_type[part_type]
        assert bad == 0 and tray > 0 and near > 0


def test_the_documented_clearances(table):
    """docs/execution.md's per-type clearances of the table's greedy-ce and cpsat plans."""
    text = (ROOT / "docs" / "execution.md").read_text(encoding="utf-8")
    section = text[text.index("## The gripper") : text.index("## The bags")]
    rows = {
        cells[0]: [math.inf if c == "none placed before" else float(c) for c in cells[1:]]
        for line in section.splitlines()
        if line.startswith("| ") and not line.startswith(("| part type", "| ---"))
        for cells in [[c.strip() for c in line.strip("|").split("|")]]
    }
    mine: dict[str, list[float]] = {t: [] for t in rows}
    for method in ("greedy-ce", "cpsat"):
        for part_type, (_, tray, near) in verdicts(
            check_grasps(table, solve(table, method).plan)
        ).items():
            mine[part_type] += [round(tray, 2), round(near, 2)]
    assert mine == rows  # columns: greedy-ce tray, placed parts, cpsat tray, placed parts
