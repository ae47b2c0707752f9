"""`bilevel-kit pack` and the registered exact method `cpsat` through the CLI and `solve`."""

from __future__ import annotations

import json

import pytest
from timing import PROOF_LIMIT

from bilevel_kit import check, solve
from bilevel_kit.cli import main
from bilevel_kit.geometry import corners, inside_tray, rects_overlap


def _pack_file(tmp_path, width, items, name="p.json"):
    path = tmp_path / name
    path.write_text(json.dumps({"tray": {"width": width, "height": 100}, "items": items}))
    return path


def test_pack_perfect_packing_and_one_unit_smaller(tmp_path, capsys):
    items = [{"id": "sq", "width": 50, "height": 50, "count": 4}]
    out = tmp_path / "layout.json"
    assert main(["pack", str(_pack_file(tmp_path, 100, items)), "--out", str(out)]) == 0
    assert ": feasible in" in capsys.readouterr().out
    doc = json.loads(out.read_text())
    shapes = [corners(p["x"], p["y"], p["w"], p["h"], p["theta"]) for p in doc["layout"]]
    assert len(shapes) == 4 and all(inside_tray(c, 100, 100) for c in shapes)
    assert not any(rects_overlap(a, b) for i, a in enumerate(shapes) for b in shapes[i + 1 :])
    assert main(["pack", str(_pack_file(tmp_path, 99, items, "q.json"))]) == 0
    assert ": infeasible in" in capsys.readouterr().out


def test_pack_unknown_within_the_time_limit_exits_3(tmp_path, capsys):
    """A kit that neither fast packer lays out (CJCM E02F17, tests/slowclock.py): CP-SAT's
    answer needs more than a microsecond."""
    from slowclock import SIZES

    items = [
        {"id": f"p{j}", "width": w, "height": h, "rotatable": False}
        for j, (w, h) in enumerate(SIZES)
    ]
    path = tmp_path / "p.json"
    path.write_text(json.dumps({"tray": {"width": 20, "height": 20}, "items": items}))
    assert main(["pack", str(path), "--time-limit", "1e-6"]) == 3
    assert ": unknown in" in capsys.readouterr().out
    assert main(["pack", str(path), "--time-limit", "20"]) == 0
    assert ": feasible in" in capsys.readouterr().out


def test_pack_instance_tasks_and_bad_input(tmp_path, capsys, root, monkeypatch):
    from bilevel_kit import plots

    inst = str(root / "instances/hrc_table.json")
    png = tmp_path / "l.png"
    titles: list[str] = []
    save = plots.save_figure

    def keep_title(fig, path, **kw):
        titles.extend(ax.get_title() for ax in fig.axes)
        return save(fig, path, **kw)

    monkeypatch.setattr(plots, "save_figure", keep_title)
    assert (
        main(
            [
                "pack",
                inst,
                "--tasks",
                "foot1,conn1",
                "--objective",
                "fitness",
                "--time-limit",
                "5",
                "--png",
                str(png),
            ]
        )
        == 0
    )
    assert "true Euclidean fitness" in capsys.readouterr().out and png.exists()
    # the figure says what was packed, its fitness and how (not just "hrc_table: feasible")
    (title,) = titles
    assert title.startswith("hrc_table, tasks foot1, conn1: 5 parts, kit fitness ")
    assert "mm\nCP-SAT feasible, objective fitness, 1 mm grid" in title
    assert main(["pack", inst, "--tasks", "foot1,nope"]) == 2
    assert "unknown task(s) nope" in capsys.readouterr().err
    bad = _pack_file(tmp_path, 100, [{"id": "a", "width": -1, "height": 3}], "bad.json")
    assert main(["pack", str(bad)]) == 2
    assert "$.items[0].width: -1 is less than or equal to the minimum of 0" in (
        capsys.readouterr().err
    )


def test_cpsat_method_is_exact_and_valid(stool, tiny, table):
    for inst in (stool, tiny):
        res = solve(inst, "cpsat", time_limit=PROOF_LIMIT, check=True)
        assert res.status == "optimal" and res.extra["violations"] == []
        assert res.gap == 0.0 and res.bound == pytest.approx(res.objective)
        for heuristic in ("single-task", "greedy-ce"):
            assert res.objective <= solve(inst, heuristic).objective + 1e-9
    free = table.with_overrides(trays="unlimited")  # the first round's shop: no tray limit
    res = solve(free, "cpsat", time_limit=30)
    assert res.status == "optimal" and res.objective == pytest.approx(431.78)
    assert check(free, res.plan) == []
    x = res.extra  # hint_method names the warm start's method when its plan is the incumbent
    assert x["hint_used"] is (x["hint_method"] in ("single-task", "whole-assembly", "greedy-ce"))
    assert x["hint_used"] or x["hint_method"] is None
    assert res.objective <= x["upper_start"] + 1e-9


def test_cpsat_options_are_checked(stool):
    from bilevel_kit import UsageError

    with pytest.raises(UsageError, match="unknown option"):
        solve(stool, "cpsat", colour=1)
    with pytest.raises(UsageError, match="option 'tray': must be one of"):
        solve(stool, "cpsat", tray="magic")
    res = solve(stool, "cpsat", hint="none", tray="benders", time_limit=10)
    assert res.status == "optimal" and res.extra["hint_method"] is None


def test_stations_objectives_gantt_and_refusals_through_the_cli(tmp_path, capsys):
    """Several stations (docs/timeline.md#several-stations): ``-p objective=sum_completion``
    of cpsat prints that objective's value, bound and gap; a heuristic refuses the option
    (exit 2, one line); ``--gantt`` draws a lane per station."""
    import strategies

    path = tmp_path / "s3.json"
    path.write_text(json.dumps(strategies.stations_doc(4, 3, n=5)))
    args = ["solve", str(path), "-m", "cpsat", "-p", "objective=sum_completion", "-q", "--check"]
    assert main([*args, "--time-limit", "60"]) == 0
    out = capsys.readouterr().out
    first = out.splitlines()[0]  # the makespan's numbers, no status beside them
    assert "cpsat  makespan" in first and "optimal" not in first and "makespan gap" in first
    assert "  sum_completion: optimal  " in out and "gap 0.00%" in out
    gantt = tmp_path / "g.png"
    assert main(["solve", str(path), "-m", "single-task", "-q", "--gantt", str(gantt)]) == 0
    assert gantt.stat().st_size > 0
    capsys.readouterr()
    for method in ("single-task", "greedy-ce"):
        assert main(["solve", str(path), "-m", method, "-p", "objective=human_idle"]) == 2
        err = capsys.readouterr().err.strip()
        assert "unknown option 'objective'" in err and len(err.splitlines()) == 1
