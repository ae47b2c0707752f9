"""The work cell's geometry is the ``work_cell`` section; ``station`` is its old name, still
read with a notice (issue 40, item 9; docs/formats.md#the-work-cell-section)."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import pytest

from bilevel_kit import InstanceBuilder, InstanceError
from bilevel_kit.cli import main
from bilevel_kit.instance import from_dict, load
from bilevel_kit.sawyer import workcell

ROOT = Path(__file__).resolve().parents[2]
GEOMETRY = {"tray_pose": {"x": 500.0, "yaw": -90.0}, "bins": {"leg": [350.0, 450.0, -100.0]}}


def _table(**sections: Any) -> dict[str, Any]:
    doc: dict[str, Any] = json.loads((ROOT / "instances/hrc_table.json").read_text())
    return {**doc, **sections}


def _notice(source: str) -> str:
    return (
        f"bilevel-kit: notice: {source}: the 'station' section (the work cell's geometry) is "
        "now named 'work_cell'; read as 'work_cell' (docs/formats.md#the-work-cell-section)\n"
    )


def test_an_old_station_section_reads_as_the_work_cell_with_one_notice(tmp_path, capsys):
    old_path, new_path = tmp_path / "old.json", tmp_path / "new.json"
    old_path.write_text(json.dumps(_table(station=GEOMETRY)))
    new_path.write_text(json.dumps(_table(work_cell=GEOMETRY)))
    new = load(new_path)
    assert capsys.readouterr().err == ""
    old = load(old_path)
    assert capsys.readouterr().err == _notice(str(old_path))
    assert old.work_cell == new.work_cell and old.work_cell.tray_x == 500.0
    assert old.work_cell.bins == (("leg", (350.0, 450.0, -100.0)),)
    assert old.to_dict() == new.to_dict()  # the same instance, whatever the key
    load(old_path)
    assert capsys.readouterr().err == ""  # one notice per file and run


def test_a_file_with_both_keys_is_one_line_naming_file_and_field(tmp_path, capsys):
    path = tmp_path / "both.json"
    path.write_text(json.dumps(_table(station=GEOMETRY, work_cell=GEOMETRY)))
    with pytest.raises(InstanceError) as exc:
        load(path)
    assert str(exc.value) == (
        f"{path}: $.station: the work cell is given twice: 'station' is the former name of "
        "'work_cell' (docs/formats.md#the-work-cell-section); keep 'work_cell' only"
    )
    assert main(["solve", str(path), "-m", "single-task"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and f"{path}: $.station: the work cell is given twice" in err


@pytest.mark.parametrize(
    ("section", "path", "detail"),
    [
        ({"tray_pose": {"x": "far"}}, "$.{key}.tray_pose.x", "'far' is not of type 'number'"),
        ({"tray_pose": {"q": 1}}, "$.{key}.tray_pose", "unknown field 'q'"),
        ({"bins": {"wheel": [1, 2, 3]}}, "$.{key}.bins.wheel", "unknown part type 'wheel'"),
        ({"grasp_yaws": [0, 0]}, "$.{key}.grasp_yaws", "angles must be distinct"),
    ],
)
@pytest.mark.parametrize("key", ["work_cell", "station"])
def test_errors_name_the_files_own_key(key, section, path, detail):
    with pytest.raises(InstanceError) as exc:
        from_dict(_table(**{key: section}), f"errors-{key}.json")
    assert exc.value.path == path.format(key=key)
    assert detail in exc.value.detail, exc.value


def test_every_writer_writes_work_cell(tmp_path):
    old = from_dict(_table(station=GEOMETRY), "writer-old.json")
    doc = old.to_dict()
    assert "station" not in doc and doc["work_cell"]["tray_pose"]["x"] == 500.0
    assert from_dict(doc, "w.json") == from_dict(_table(work_cell=GEOMETRY), "w.json")
    moved = workcell.apply_work_cell(old, workcell.parse_work_cell({"place_height": 30.0}))
    assert moved.work_cell.place_height == 30.0 and moved.work_cell.tray_x == 500.0
    assert "station" not in moved.to_dict()
    built = (
        InstanceBuilder("cell", tray=(300, 200))
        .part_type("block", 40, 30, pick_time=3)
        .task("t1", {"block": 1}, human_time=10, station=None)
        .work_cell(tray_pose={"x": 600.0})
        .work_cell(place_height=25.0)
    )
    assert built.document()["work_cell"] == {"tray_pose": {"x": 600.0}, "place_height": 25.0}
    inst = built.save(tmp_path / "built.json")
    assert (inst.work_cell.tray_x, inst.work_cell.place_height) == (600.0, 25.0)
    assert "station" not in json.loads((tmp_path / "built.json").read_text())


def test_assembly_stations_keep_their_names_beside_an_old_work_cell(capsys):
    """A task's ``station`` and the ``stations`` list are the assembly stations: untouched by
    the rename, also in a file that still calls its work cell ``station``."""
    from stations_example import worked_example_doc

    inst = from_dict(worked_example_doc(station={"tray_pose": {"x": 520.0}}), "assembly.json")
    assert capsys.readouterr().err == _notice("assembly.json")
    assert inst.station_ids == ("A", "B") and inst.work_cell.tray_x == 520.0
    assert {t.id: t.station for t in inst.tasks} == {"a1": "A", "b1": "B", "a2": "A"}
    out = inst.to_dict()
    assert [t["station"] for t in out["tasks"]] == ["A", "B", "A"]
    assert [s["id"] for s in out["stations"]] == ["A", "B"] and "station" not in out


def test_the_former_public_names_are_aliases():
    from bilevel_kit import sawyer
    from bilevel_kit.instance import schema

    assert sawyer.Station is sawyer.WorkCell
    assert sawyer.DEFAULT_STATION is sawyer.DEFAULT_WORK_CELL
    assert sawyer.StationError is sawyer.WorkCellError
    assert sawyer.station_schema is sawyer.work_cell_schema
    top = schema()["properties"]
    assert top["work_cell"] == sawyer.work_cell_schema() and "station" not in top
