"""``cpsat -p finger_room=true``: the trays packed with the parts' grasp footprints, as
greedy-ce's option (docs/execution.md#finger-room): on the paper's table in its work cell the
optimal makespan stays 435.085 s and no part fails the gripper's pass (20 of 28 without)."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from bilevel_kit import load, solve
from bilevel_kit import solution as solution_io
from bilevel_kit.cli import main
from bilevel_kit.errors import UsageError
from bilevel_kit.sawyer.gripper import check_grasps
from bilevel_kit.sawyer.workcell import apply_work_cell, load_work_cell, parse_work_cell

ROOT = Path(__file__).resolve().parents[2]
TABLE = ROOT / "instances" / "hrc_table.json"
CELL = ROOT / "examples" / "hrc_table_cell.json"
#: cpsat's optimal makespan of the table, with and without finger room.
OPTIMUM = 435.085


@pytest.fixture(scope="module")
def cell():
    return apply_work_cell(load(TABLE), load_work_cell(CELL))


def test_finger_room_from_the_command_line(capsys, cell, tmp_path):
    """solve with the option and the work cell, then execute with the strict pass: exit 0,
    the same optimum, true part sizes in the layouts and the packed footprints in extra."""
    sol = tmp_path / "room.json"
    argv = ["solve", str(TABLE), "-m", "cpsat", "--time-limit", "30", "-q", "--check"]
    code = main([*argv, "-p", "finger_room=true", "--work-cell", str(CELL), "--out", str(sol)])
    assert code == 0
    doc = json.loads(sol.read_text())
    assert doc["makespan"]["value"] == pytest.approx(OPTIMUM, abs=1e-6)
    assert doc["status"] == "optimal" and doc["params"]["finger_room"] is True
    assert doc["extra"]["finger_room"]["leg"] == pytest.approx([152.4, 38.7])
    assert doc["extra"]["finger_room"]["screw_short"] == pytest.approx([12.0, 32.0])
    plan = solution_io.read(sol).plan
    sizes = {(p.type, p.w, p.h) for k in plan.kits for p in k.layout}
    assert {(t, pt.width, pt.height) for t, pt in cell.part_types.items()} >= sizes
    checks = check_grasps(cell, plan)
    assert len(checks) == 28 and [c for c in checks if c.problem] == []
    capsys.readouterr()
    bags = tmp_path / "bags"
    run = ["execute", str(TABLE), str(sol), "--grasp-check", "strict", "--format", "ros1"]
    assert main([*run, "--bag", str(bags)]) == 0  # the recorded work cell applies
    assert "gripper: all 28 part(s) pass" in capsys.readouterr()[0]


def test_without_finger_room_20_parts_fail(cell):
    res = solve(cell, "cpsat", time_limit=30, check=True)
    assert res.makespan == pytest.approx(OPTIMUM, abs=1e-6)
    checks = check_grasps(cell, res.plan)
    assert sum(bool(c.problem) for c in checks) == 20
    assert "finger_room" not in res.extra


def test_room_larger_than_the_tray_is_refused(cell):
    """Fingers 150 mm wide make a leg's footprint wider than the tray: exit 2 naming it."""
    huge = apply_work_cell(cell, parse_work_cell({"gripper": {"finger_width": 150.0}}))
    with pytest.raises(UsageError, match="finger_room: part type 'leg'"):
        solve(huge, "cpsat", time_limit=5, finger_room=True)
