"""One tolerance rule for every packer and the checker (docs/timeline.md#packing-tolerance):
three 30.1 mm parts side by side are 90.30000000000001 mm in floats, and a 90.3 mm tray holds
them for the shelf packer, CP-SAT's grid, the cross-entropy's area test, whole-assembly and
the checker alike; 1e-5 mm less tray (ten times the tolerance) holds them for none."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from bilevel_kit import geometry
from bilevel_kit.cli import main
from bilevel_kit.heuristics.shelf import shelf_pack
from bilevel_kit.instance import PartType, Tray
from bilevel_kit.plan import Placement

SIDE = 30.1
BOUNDARY = 90.3
BEYOND = BOUNDARY - 1e-5
PART = PartType("a", SIDE, SIDE, 3.0, rotatable=False)
ITEMS = [(f"p{k}", PART) for k in range(3)]


def side_by_side() -> list[Placement]:
    """The three parts in a row from x = 0, as any packer places them."""
    return [
        Placement(f"p{k}", "a", SIDE * k + SIDE / 2, SIDE / 2, 0.0, SIDE, SIDE) for k in range(3)
    ]


def test_the_boundary_really_is_beyond_the_float_sum() -> None:
    """The case is the float edge itself: the row is longer than the tray in floats."""
    assert SIDE + SIDE + SIDE > BOUNDARY
    assert geometry.length_fits(SIDE + SIDE + SIDE, BOUNDARY)
    assert not geometry.length_fits(SIDE + SIDE + SIDE, BEYOND)


@pytest.mark.parametrize(("width", "fits"), [(BOUNDARY, True), (BEYOND, False)])
def test_every_packer_and_the_checker_agree(width: float, fits: bool) -> None:
    from bilevel_kit.models.packing import pack

    tray = Tray(width, 40.0)
    checker_ok = not geometry.layout_violations(side_by_side(), width, 40.0)
    assert checker_ok is fits
    layout = shelf_pack(tray, ITEMS)
    assert (layout is not None) is fits
    if layout is not None:
        assert not geometry.layout_violations(layout, width, 40.0)
    # CP-SAT on its own grid (the fitness objective skips the shelf packer's first answer)
    res = pack(tray, ITEMS, objective="fitness", resolution=0.1, time_limit=20, workers=1)
    assert (res.layout is not None) is fits, res.status
    if res.layout is not None:
        assert not geometry.layout_violations(res.layout, width, 40.0)
    assert geometry.area_fits(3 * PART.area, width, 40.0)  # the area test never decides here


def _instance(path: Path, width: float) -> Path:
    part = {"type": "a", "count": 1}
    doc = {
        "format": "bilevel-kit/1",
        "name": "tolerance",
        "tray": {"width": width, "height": 40.0},
        "delivery_time": 10.0,
        "kit_overhead": {"robot": 10.0, "human": 0.0},
        "part_types": [
            {"id": "a", "width": SIDE, "height": SIDE, "pick_time": 3.0, "rotatable": False}
        ],
        "tasks": [
            {"id": t, "parts": [part], "human_time": {"mean": 10.0}} for t in ("t1", "t2", "t3")
        ],
        "precedence": [["t1", "t2"], ["t2", "t3"]],
    }
    path.write_text(json.dumps(doc))
    return path


def test_whole_assembly_takes_the_kit_the_exact_models_take(tmp_path, capsys) -> None:
    """The reported case: whole-assembly refused the one kit cpsat, milp and lns built."""
    inst = _instance(tmp_path / "edge.json", BOUNDARY)
    out = tmp_path / "s.json"
    assert main(["solve", str(inst), "-m", "whole-assembly", "-o", str(out), "--check"]) == 0
    assert len(json.loads(out.read_text())["kits"]) == 1
    assert main(["check", str(inst), str(out)]) == 0
    capsys.readouterr()
    beyond = _instance(tmp_path / "beyond.json", BEYOND)
    assert main(["solve", str(beyond), "-m", "whole-assembly"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "do not fit" in err
    assert main(["check", str(beyond), str(out)]) == 1  # the same kit, 1e-5 mm too wide
