"""The Python instance builder (docs/formats.md#building-an-instance-in-python, issue 40 item 8).

It writes the format's document and validates it with the file parser: the same messages, the
same JSON paths; the document round-trips through a file; the page's example runs and prints
what the page shows.
"""

from __future__ import annotations

import contextlib
import doctest
import io
import json
import re
from pathlib import Path

import pytest

import bilevel_kit.instance.builder as builder_module
from bilevel_kit import InstanceBuilder, load
from bilevel_kit.errors import InstanceError

ROOT = Path(__file__).resolve().parents[2]


def _stool() -> InstanceBuilder:
    b = InstanceBuilder("stool", tray=(300, 200), delivery_time=2, kit_overhead=(3, 1), trays=1)
    b.part_type("leg", 200, 30, pick_time=4).part_type("seat", 180, 180, pick_time=6)
    b.task("legs", {"leg": 3}, human_time=30, human_sd=5).task("seat", {"seat": 1}, human_time=20)
    return b.precede("legs", "seat")


def test_the_module_example_runs() -> None:
    failed, attempted = doctest.testmod(builder_module, verbose=False)
    assert attempted == 6 and failed == 0


def test_the_rebuilt_tutorial_instance_equals_the_file() -> None:
    """Every call of the builder, driven by the tutorial's file, gives the file's instance."""
    path = ROOT / "instances" / "tutorial_shelf.json"
    doc = json.loads(path.read_text())
    b = InstanceBuilder(
        doc["name"],
        tray=(doc["tray"]["width"], doc["tray"]["height"]),
        delivery_time=doc["delivery_time"],
        kit_overhead=(doc["kit_overhead"]["robot"], doc["kit_overhead"]["human"]),
        trays=doc["trays"],
        description=doc["description"],
        assumptions=doc["assumptions"],
    )
    for p in doc["part_types"]:
        b.part_type(p["id"], p["width"], p["height"], pick_time=p["pick_time"],
                    rotatable=p["rotatable"], name=p["name"])  # fmt: skip
    for t in doc["tasks"]:
        b.task(t["id"], {q["type"]: q["count"] for q in t["parts"]},
               human_time=t["human_time"]["mean"], human_sd=t["human_time"]["sd"],
               robot_time=t.get("robot_time"), name=t["name"])  # fmt: skip
    for a, c in doc["precedence"]:
        b.precede(a, c)
    assert b.build().to_dict() == load(path).to_dict()


def test_save_round_trips_through_the_file(tmp_path: Path) -> None:
    b = _stool().station("A", serves=("stool",), trays=2)
    inst = b.save(tmp_path / "stool.json")
    assert json.loads((tmp_path / "stool.json").read_text()) == b.document()
    again = load(tmp_path / "stool.json")
    assert again.to_dict() == inst.to_dict() and again.station_ids == ("A",)
    assert again.trays == 1 and again.stations[0].trays == 2
    assert [t.id for t in again.tasks] == ["legs", "seat"] and again.robot_time("legs") == 12


@pytest.mark.parametrize(
    ("mistake", "where", "words"),
    [
        (lambda b: b.task("x", {"lge": 1}, human_time=1), "$.tasks[2].parts[0].type",
         "unknown part type 'lge'"),
        (lambda b: b.task("legs", {"leg": 1}, human_time=1), "$.tasks[2].id",
         "duplicate task id 'legs'"),
        (lambda b: b.precede("seat", "legs"), "$.precedence", "cycle"),
        (lambda b: b.part_type("big", 400, 10, pick_time=1), "$.part_types[2]", "tray"),
        (lambda b: b.task("y", {"leg": 1}, human_time=-1), "$.tasks[2].human_time.mean", ""),
    ],
)  # fmt: skip
def test_mistakes_get_the_json_parsers_message(tmp_path: Path, mistake, where, words) -> None:
    b = _stool()
    mistake(b)
    path = tmp_path / "bad.json"
    path.write_text(json.dumps(b.document()))
    with pytest.raises(InstanceError) as from_file:
        load(path)
    with pytest.raises(InstanceError) as built:
        b.build(str(path))
    assert str(built.value) == str(from_file.value)
    assert str(built.value).startswith(f"{path}: {where}") and words in str(built.value)
    with pytest.raises(InstanceError, match=r"^<builder stool>: "):
        b.build()
    assert not path.with_name("never.json").exists()
    with pytest.raises(InstanceError):
        b.save(path.with_name("never.json"))  # validated before anything is written
    assert not path.with_name("never.json").exists()


def test_the_formats_page_example_runs_and_prints_what_it_shows(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    page = (ROOT / "docs" / "formats.md").read_text(encoding="utf-8")
    section = page.split("### Building an instance in Python", 1)[1]
    code = re.search(r"```python\n(.*?)```", section, re.DOTALL)
    assert code is not None
    shown = re.search(r"^# (optimal .*)$", code[1], re.MULTILINE)
    assert shown is not None
    monkeypatch.chdir(tmp_path)
    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        exec(compile(code[1], "docs/formats.md", "exec"), {})
    assert out.getvalue().strip() == shown[1] == "optimal 87.0 [('legs',), ('seat', 'inspect')]"
    assert (tmp_path / "bench_stool.json").is_file()
