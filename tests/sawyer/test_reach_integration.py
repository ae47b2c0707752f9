"""Sawyer reachability in the toolkit: instance section, checker, CE, baselines, CLI."""

from __future__ import annotations

import json
from dataclasses import replace

import pytest

from bilevel_kit import InstanceError, Kit, Placement, Plan, check, solve
from bilevel_kit.cli import main
from bilevel_kit.instance import from_dict
from bilevel_kit.reachability import reach_grid


def _doc(root, tray_x: float, **extra):
    doc = json.loads((root / "instances/hrc_table.json").read_text())
    doc["work_cell"] = {"tray_pose": {"x": tray_x, "y": 150, "z": -150, "yaw": -90}}
    doc["reachability"] = True
    doc.update(extra)
    return doc


@pytest.fixture(scope="module")
def half(root):
    """The table with its tray 900 mm ahead: the far part of the tray is out of reach."""
    return from_dict(_doc(root, 900))


def test_reach_grid_of_the_half_reachable_tray(half):
    g = reach_grid(half)
    assert g.reachable.shape == (20, 30)
    assert 0.40 < g.reachable.mean() < 0.50  # 44.3% measured
    # tray y runs away from the robot: near rows reachable, far rows not
    assert g.reachable[0].all() and not g.reachable[-1].any()


def test_checker_reports_unreachable_placements(half):
    far = Placement("foot-1", "foot", 150, 190 - 21.5, 0, 43, 43)
    near = replace(far, y=21.5)
    kit_parts = [
        Placement("leg-1", "leg", 100, 60, 0, 152.4, 12.7),
        Placement("screw_short-1", "screw_short", 250, 10, 0, 8, 6),
    ]
    bad = Plan((Kit(("foot1",), (far, *kit_parts)),))
    good = Plan((Kit(("foot1",), (near, *kit_parts)),))
    v = [x for x in check(half, bad) if x.kind == "unreachable"]
    assert len(v) == 1 and "'foot-1'" in v[0].message
    # (one-kit plans: the other tasks are missing on purpose)
    assert [x.kind for x in check(half, good) if x.kind != "missing_task"] == []


@pytest.mark.parametrize(
    ("method", "params"),
    [("single-task", {}), ("greedy-ce", {}), ("greedy-ce", {"snap": True})],
    ids=["single-task", "greedy-ce", "greedy-ce-snap"],
)
def test_plans_respect_reachability(half, method, params):
    res = solve(half, method, check=True, **params)
    assert res.extra["violations"] == []
    g = reach_grid(half)
    for kit in res.plan.kits:
        assert all(g.lookup(p.x, p.y) for p in kit.layout)


def test_tray_out_of_reach_is_a_clear_error(root, tmp_path, capsys):
    path = tmp_path / "far.json"
    path.write_text(json.dumps(_doc(root, 1500)))
    code = main(["solve", str(path), "-m", "single-task", "-o", str(tmp_path / "s.json")])
    err = capsys.readouterr().err
    assert code == 2 and "no point of the 300 x 200 mm tray is reachable" in err
    assert not (tmp_path / "s.json").exists()
    # the map itself is just empty
    assert main(["reach", str(path)]) == 0
    assert "reachable 0.0%" in capsys.readouterr().out


def test_bad_work_cell_names_the_field(root, tmp_path, capsys):
    doc = _doc(root, 900)
    doc["work_cell"]["grasp_yaws"] = []
    path = tmp_path / "bad.json"
    path.write_text(json.dumps(doc))
    assert main(["solve", str(path), "-m", "single-task"]) == 2
    assert "$.work_cell.grasp_yaws: [] should be non-empty" in capsys.readouterr().err


def test_motion_robot_times(root):
    from bilevel_kit.sawyer import DEFAULT_WORK_CELL, tray_average_time

    inst = from_dict(_doc(root, 450, robot_times="motion", reachability=False))
    work_cell = inst.work_cell
    want = tray_average_time(work_cell, "leg", 300, 200)
    assert inst.part_types["leg"].pick_time == pytest.approx(want)
    assert inst.part_types["leg"].nominal_pick_time == 12.0
    assert inst.robot_time("top1") == pytest.approx(2 * inst.part_types["screw_long"].pick_time)
    assert 3.0 < want < 8.0  # a Sawyer pick-and-place cycle takes seconds
    assert work_cell != DEFAULT_WORK_CELL
    again = from_dict(json.loads(json.dumps(inst.to_dict())))
    assert again == inst  # the file keeps the nominal pick times, loading recomputes


def test_reach_cli_draws_a_kit(root, tmp_path, capsys, monkeypatch):
    inst_path = tmp_path / "half.json"
    inst_path.write_text(json.dumps(_doc(root, 900)))
    sol = tmp_path / "s.json"
    assert main(["solve", str(inst_path), "-m", "greedy-ce", "-o", str(sol)]) == 0
    png = tmp_path / "reach.png"
    capsys.readouterr()
    from bilevel_kit import plots

    titles: list[str] = []
    save = plots.save_figure

    def keep_title(fig, path, **kw):
        titles.extend(ax.get_title() for ax in fig.axes if ax.get_title())
        return save(fig, path, **kw)

    monkeypatch.setattr(plots, "save_figure", keep_title)
    code = main(["reach", str(inst_path), "--solution", str(sol), "--kit", "1", "--png", str(png)])
    out = capsys.readouterr().out
    assert code == 0 and "reachable 44.3%" in out and "0 unreachable" in out
    assert png.read_bytes()[:4] == b"\x89PNG"
    # the figure names the instance and the kit drawn on it
    (title,) = titles
    assert title.startswith("hrc_table: Sawyer reachability, 44% of 30 x 20 cells\n")
    assert "kit 1 of s.json: " in title and "0 unreachable" in title


def test_reachability_needs_no_work_cell_section(root):
    doc = json.loads((root / "instances/hrc_table.json").read_text())
    doc["reachability"] = True
    inst = from_dict(doc)
    assert inst.work_cell is None and reach_grid(inst).reachable.all()
    with pytest.raises(InstanceError, match=r"\$\.robot_times"):
        from_dict(
            {
                **doc,
                "robot_times": "motion",
                "work_cell": {"tray_pose": {"x": 2000, "y": 0, "z": 0, "yaw": 0}},
            }
        )
