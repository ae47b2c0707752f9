"""The work cell's gripper, the work-cell file and ``execute``'s feasibility pass
(docs/execution.md#the-gripper, #the-work-cell, #finger-room)."""

from __future__ import annotations

import json
import math
import re

import pytest
from paths import INSTANCES, ROOT

from bilevel_kit import load, solve
from bilevel_kit import solution as solution_io
from bilevel_kit.cli import main
from bilevel_kit.errors import InstanceError, UsageError
from bilevel_kit.plan import Kit, Placement, Plan
from bilevel_kit.sawyer.cell import WorkCell, WorkCellError
from bilevel_kit.sawyer.gripper import (
    DEFAULT_GRIPPER,
    Gripper,
    check_grasps,
    grasp_footprint,
    verdicts,
    with_finger_room,
)
from bilevel_kit.sawyer.workcell import (
    WorkCellFileError,
    apply_work_cell,
    load_work_cell,
    parse_work_cell,
)

TABLE = INSTANCES / "hrc_table.json"
CELL = ROOT / "examples" / "hrc_table_cell.json"


@pytest.fixture(scope="module")
def table():
    return load(TABLE)


@pytest.fixture(scope="module")
def cell(table):
    """The paper's table in its documented work cell."""
    return apply_work_cell(table, load_work_cell(CELL))


@pytest.fixture(scope="module")
def plans(cell):
    """The table's greedy-ce (without and with finger room) and cpsat plans."""
    return {
        "greedy-ce": solve(cell, "greedy-ce", check=True),
        "greedy-ce finger room": solve(cell, "greedy-ce", check=True, finger_room=True),
        "cpsat": solve(cell, "cpsat", check=True, time_limit=60),
    }


def _plan(*layout: Placement) -> Plan:
    return Plan((Kit(("foot1",), tuple(layout)),))


def _screw(part: str, x: float, y: float, theta: float = 0.0) -> Placement:
    return Placement(part, "screw_short", x, y, theta, 8.0, 6.0)


def test_the_default_gripper_is_the_urdfs_fingers():
    assert DEFAULT_GRIPPER.stroke_max == pytest.approx(2 * 20.833)
    assert WorkCell().gripper == DEFAULT_GRIPPER
    assert "gripper" not in WorkCell().to_dict()
    g = WorkCell.from_dict({"gripper": {"stroke_min": 19.0, "stroke_max": 60.0}}).gripper
    assert (g.stroke_min, g.stroke_max, g.finger_width) == (19.0, 60.0, 12.0)
    assert WorkCell.from_dict(WorkCell(gripper=g).to_dict()).gripper == g


@pytest.mark.parametrize(
    ("gripper", "message"),
    [
        ({"stroke": 3}, "work_cell.gripper: unknown key(s) stroke"),
        ({"stroke_max": -1}, "work_cell.gripper.stroke_max: expected a finite number >= 0"),
        ({"stroke_min": 50}, "work_cell.gripper.stroke_max: 41.666 mm must exceed stroke_min"),
        ({"finger_width": 0}, "work_cell.gripper.finger_width: expected a number > 0"),
        ([1, 2], "work_cell.gripper: expected an object"),
    ],
)
def test_a_bad_gripper_is_named(gripper, message):
    with pytest.raises(WorkCellError) as exc:
        WorkCell.from_dict({"gripper": gripper})
    assert str(exc.value).startswith(message), exc.value


def test_a_grasp_width_in_the_instance_is_still_read(tmp_path):
    doc = json.loads(TABLE.read_text())
    doc["part_types"][1]["grasp_width"] = 3.0
    doc["part_types"][3]["grasp_width"] = 7.0  # screw_long is 14 x 6 mm
    bad = tmp_path / "bad.json"
    bad.write_text(json.dumps(doc))
    with pytest.raises(InstanceError) as exc:
        load(bad)
    assert "$.part_types[3].grasp_width" in str(exc.value) and "7 mm exceeds" in str(exc.value)
    del doc["part_types"][3]["grasp_width"]
    bad.write_text(json.dumps(doc))
    assert load(bad).part_types["foot"].grasp_width == 3.0


def test_the_example_work_cell(table, cell):
    """examples/hrc_table_cell.json: the URDF's fingers, both brackets by a 3 mm wall, the
    default work cell's geometry; the product file is untouched."""
    assert table.work_cell is None and table.part_types["foot"].grasp_width is None
    assert cell.work_cell.gripper == Gripper(stroke_max=41.666)
    assert {k: p.grasp_width for k, p in cell.part_types.items()} == {
        "leg": None,
        "foot": 3.0,
        "connector": 3.0,
        "screw_long": None,
        "screw_short": None,
    }
    assert cell.work_cell == WorkCell()  # spelled out in the file, equal to the default
    assert cell.tasks == table.tasks and cell.part_types["leg"] == table.part_types["leg"]


def test_a_work_cell_merges_geometry_keys(table):
    moved = apply_work_cell(table, parse_work_cell({"place_height": 30.0, "tray_pose": {"x": 700}}))
    assert moved.work_cell.place_height == 30.0 and moved.work_cell.tray_x == 700.0
    assert moved.work_cell.approach_height == WorkCell().approach_height
    assert moved.work_cell.gripper == DEFAULT_GRIPPER


@pytest.mark.parametrize(
    ("doc", "field", "message"),
    [
        ([], "$", "expected an object"),
        ({"grippers": {}}, "$.grippers", "unknown key"),
        ({"gripper": {"stroke_max": -1}}, "$.gripper.stroke_max", "expected a finite number >= 0"),
        ({"gripper": {"stroke": 3}}, "$.gripper", "unknown key(s) stroke"),
        ({"place_height": "low"}, "$.place_height", "expected a finite number"),
        ({"grasp_widths": [3]}, "$.grasp_widths", "expected an object part type -> mm"),
        ({"grasp_widths": {"foot": 0}}, "$.grasp_widths.foot", "expected a number > 0"),
        ({"grasp_widths": {"bolt": 3}}, "$.grasp_widths.bolt", "no part type 'bolt'"),
        ({"grasp_widths": {"screw_long": 7}}, "$.grasp_widths.screw_long", "7 mm exceeds"),
        ({"bins": {"bolt": [1, 2, 3]}}, "$.bins.bolt", "unknown part type 'bolt'"),
        ({"description": 3}, "$.description", "expected a string"),
    ],
)
def test_a_bad_work_cell_is_one_line_naming_file_and_field(
    capsys, tmp_path, table, doc, field, message
):
    path = tmp_path / "cell.json"
    path.write_text(json.dumps(doc))
    with pytest.raises(WorkCellFileError) as exc:
        apply_work_cell(table, load_work_cell(path))
    assert exc.value.path == field and message in exc.value.detail, exc.value
    sol = tmp_path / "s.json"
    solution_io.write(sol, solve(table, "single-task"))
    out = tmp_path / "out"
    code = main(["execute", str(TABLE), str(sol), "--work-cell", str(path), "--bag", str(out)])
    text, err = capsys.readouterr()
    assert code == 2 and text == "" and "Traceback" not in err
    assert len(err.strip().splitlines()) == 1 and f"{path}: {field}: " in err
    assert not out.exists()


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


def test_fingers_hitting_a_placed_part_are_named(cell):
    placed = Placement("foot-1", "foot", 150.0, 100.0, 0.0, 43.0, 43.0)
    screw = _screw("s", 150.0, 124.5)  # touching the bracket's side (y = 121.5)
    checks = check_grasps(cell, _plan(placed, screw))
    assert [c.fault for c in checks] == ["", "part"]
    assert "overlap part foot-1, placed before it, by 3.00 mm" in checks[1].problem
    # the screw placed first: the bracket's fingers close on its wall, inside its footprint
    checks = check_grasps(cell, _plan(screw, placed))
    assert [c.fault for c in checks] == ["", ""]
    assert checks[1].part_clearance == pytest.approx(15.5)


def test_execute_warns_in_one_line_by_default_and_strict_exits_2(capsys, tmp_path, table):
    """Without a work cell the 43 mm bracket exceeds the URDF's stroke: the default (warn)
    reports it in one line and writes; strict names kit, part and widths and writes nothing."""
    sol = tmp_path / "s.json"
    solution_io.write(sol, solve(table, "single-task"))
    out = tmp_path / "out"
    argv = ["execute", str(TABLE), str(sol), "--bag", str(out), "--format", "ros1"]
    assert main(argv) == 0
    text, err = capsys.readouterr()
    (line,) = [s for s in text.splitlines() if s.startswith("gripper:")]
    assert line.startswith(
        "gripper: 28 of 28 part(s) fail the check (8 beyond the stroke, 20 with fingers off "
        "the tray); first: kit 1, part foot-1 (type foot): grasp width 43 mm is outside the "
        "gripper's stroke 0-41.666 mm less 2 mm clearance (2-39.666 mm); declare the gripper "
        "and grasp widths with --work-cell"
    ), line
    assert main([*argv, "--grasp-check", "off"]) == 0
    assert "gripper:" not in capsys.readouterr()[0]
    code = main([*argv[:3], "--bag", str(tmp_path / "strict"), "--grasp-check", "strict"])
    text, err = capsys.readouterr()
    assert code == 2 and text == "" and len(err.strip().splitlines()) == 1
    assert "kit 1, part foot-1 (type foot): grasp width 43 mm is outside" in err
    assert "(28 of 28 part(s) fail the gripper check; nothing written)" in err
    assert not (tmp_path / "strict").exists()


def test_grasp_footprints(cell):
    """The rectangle a packer keeps for a part and its open fingers (12 mm pads, 2 mm
    clearance): grasp width + 26 mm across the grasp, at least a pad along it."""
    g = cell.work_cell.gripper
    sizes = {k: grasp_footprint(p, g) for k, p in cell.part_types.items()}
    assert sizes["screw_short"] == (12.0, pytest.approx(32.0))
    assert sizes["screw_long"] == (14.0, pytest.approx(32.0))
    assert sizes["leg"] == (152.4, pytest.approx(38.7))
    assert sizes["foot"] == (43.0, 43.0) and sizes["connector"] == (41.0, 41.0)  # 3 + 26 < 41
    grown = with_finger_room(cell)
    assert grown.part_types["leg"].height == pytest.approx(38.7)
    assert grown.part_types["foot"] == cell.part_types["foot"]
    huge = apply_work_cell(cell, parse_work_cell({"gripper": {"finger_width": 150.0}}))
    with pytest.raises(UsageError, match="part type 'leg' with its open fingers"):
        with_finger_room(huge)


def test_finger_room_passes_the_strict_check_at_the_same_makespan(plans, cell):
    """greedy-ce's layouts leave no finger room at the tray's edge; with ``finger_room`` every
    part passes, the plan stays valid and its makespan is the same on the table."""
    plain, room = plans["greedy-ce"], plans["greedy-ce finger room"]
    assert plain.extra["violations"] == [] and room.extra["violations"] == []
    bad = [c for c in check_grasps(cell, plain.plan) if c.problem]
    assert len(bad) == 12
    checks = check_grasps(cell, room.plan)
    assert len(checks) == 28 and [c for c in checks if c.problem] == []
    assert room.objective == pytest.approx(plain.objective) == pytest.approx(463.78, abs=0.01)
    assert [k.tasks for k in room.plan.kits] == [k.tasks for k in plain.plan.kits]


def test_finger_room_needing_no_room_changes_nothing(table):
    """A gripper whose stroke holds no part reserves nothing: the layouts are byte for byte
    those of the default run (the default ``finger_room`` false runs the code as before)."""
    shut = apply_work_cell(table, parse_work_cell({"gripper": {"stroke_max": 1.0}}))
    assert with_finger_room(shut).part_types == shut.part_types
    base = solve(table, "greedy-ce").plan
    assert solve(shut, "greedy-ce", finger_room=True).plan == base
    assert solve(table, "greedy-ce", finger_room=False).plan == base


def test_solve_and_execute_with_a_work_cell(capsys, tmp_path, plans):
    sol = tmp_path / "room.json"
    argv = ["solve", str(TABLE), "-m", "greedy-ce", "--work-cell", str(CELL), "--out", str(sol)]
    assert main([*argv, "-p", "finger_room=true", "--check", "-q"]) == 0
    capsys.readouterr()
    run = ["execute", str(TABLE), str(sol), "--work-cell", str(CELL), "--grasp-check", "strict"]
    assert main(run) == 0
    (line,) = [s for s in capsys.readouterr()[0].splitlines() if s.startswith("gripper:")]
    # which part is closest depends on greedy-ce's layouts, which another CPU's float32
    # search can move (docs/scaling.md#portability); the verdict and the form do not
    found = re.fullmatch(
        r"gripper: all 28 part\(s\) pass; smallest finger clearance to the tray ([0-9.]+) mm "
        r"\(kit \d, [a-z_]+-\d\), to a placed part ([0-9.]+) mm \(kit \d, [a-z_]+-\d\)",
        line,
    )
    assert found, line
    assert 0.0 <= float(found[1]) <= float(found[2])
    assert solution_io.read(sol).plan == plans["greedy-ce finger room"].plan
    bad = tmp_path / "cell.json"
    bad.write_text('{"grasp_widths": {"bolt": 3}}')
    assert main([*argv[:4], "--work-cell", str(bad), "-q"]) == 2
    text, err = capsys.readouterr()
    assert text == "" and err.strip().endswith(
        f"{bad}: $.grasp_widths.bolt: no part type 'bolt' in {TABLE}"
    )


@pytest.mark.parametrize("method", ["greedy-ce", "cpsat"])
def test_every_part_type_of_the_table_fits_the_declared_gripper(cell, plans, method):
    """The stroke holds every part of the table's plans in its work cell."""
    checks = check_grasps(cell, plans[method].plan)
    assert len(checks) == 28 and not [c for c in checks if c.fault == "stroke"]
    per_type = verdicts(checks)
    assert set(per_type) == {"leg", "foot", "connector", "screw_long", "screw_short"}
    for part_type in ("foot", "connector"):  # grasped across a 3 mm wall, inside the bracket
        bad, tray, near = per_type[part_type]
        assert bad == 0 and tray > 0 and near > 0


def test_the_documented_clearances(cell, plans):
    """docs/execution.md's per-type clearances of the table's plans in its work cell."""
    text = (ROOT / "docs" / "execution.md").read_text(encoding="utf-8")
    section = text[text.index("## The gripper") : text.index("## The bags")]
    section = section[section.index("| part type") :]
    rows = {
        cells[0]: [math.inf if c == "none placed before" else float(c) for c in cells[1:]]
        for line in section.splitlines()
        if line.startswith("| ") and not line.startswith(("| part type", "| ---"))
        for cells in [[c.strip() for c in line.strip("|").split("|")]]
    }
    mine: dict[str, list[float]] = {t: [] for t in rows}
    for method in ("greedy-ce", "cpsat", "greedy-ce finger room"):
        for part_type, (_, tray, near) in verdicts(check_grasps(cell, plans[method].plan)).items():
            mine[part_type] += [round(tray, 2) + 0.0, round(near, 2)]
    assert mine.keys() == rows.keys()  # greedy-ce, cpsat, greedy-ce finger room: tray, parts
    for t, doc in rows.items():
        assert [math.isinf(v) for v in mine[t]] == [math.isinf(v) for v in doc], t
        assert mine[t][2:4] == doc[2:4], t  # cpsat's packer: the same layouts on every CPU
        # greedy-ce's float32 layouts may move by up to 13 mm on another CPU
        # (docs/scaling.md#portability): its clearances are compared within that
        for i in (0, 1, 4, 5):
            if not math.isinf(doc[i]):
                assert mine[t][i] == pytest.approx(doc[i], abs=13.0), (t, i)


def test_auto_grasp_check_is_strict_only_with_a_declared_gripper(capsys, tmp_path, plans):
    """``--grasp-check auto`` (the default): with a work cell (given or recorded) a plan the
    declared gripper cannot place is exit 2 writing nothing; without one the URDF's fingers are
    only assumed and the same plan is reported and written (docs/execution.md#the-gripper)."""
    sol = tmp_path / "plain.json"
    solution_io.write(sol, plans["greedy-ce"])
    out = tmp_path / "cell"
    run = ["execute", str(TABLE), str(sol), "--format", "ros1"]
    code = main([*run, "--work-cell", str(CELL), "--bag", str(out)])
    text, err = capsys.readouterr()
    assert code == 2 and text == "" and not out.exists()
    assert "(12 of 28 part(s) fail the gripper check; nothing written)" in err
    assert main([*run, "--work-cell", str(CELL), "--bag", str(out), "--grasp-check", "warn"]) == 0
    assert "gripper: 12 of 28 part(s) fail the check" in capsys.readouterr()[0]
    assert main([*run, "--bag", str(tmp_path / "assumed")]) == 0
    assert "gripper: 20 of 28 part(s) fail the check" in capsys.readouterr()[0]
