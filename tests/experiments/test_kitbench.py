"""KitBench (docs/kitbench.md) on a tiny temporary library: run, update, verify, filters, and
every bad input of ``bench update`` (exit 2, nothing written)."""

from __future__ import annotations

import csv
import io
import json
import shutil
from pathlib import Path

import pytest

from bilevel_kit.cli import main
from bilevel_kit.experiments.kitbench import (
    Library,
    Record,
    parse_filter,
    render_blocks,
    select,
    update,
    verify,
)
from bilevel_kit.experiments.kitbench.library import record_status
from bilevel_kit.experiments.kitbench.update import UpdateRefused

#: (generate arguments, family, tray label): three small instances of three families.
TINY = [
    (["stool", "--size", "2", "--d", "10", "--trays", "1", "--name", "stool2"], "stool", "loose"),
    (
        ["intree", "--size", "6", "--seed", "1", "--tightness", "1", "--d", "0", "--name", "it6"],
        "intree",
        "loose",
    ),
    (
        ["sparse", "--size", "8", "--seed", "2", "--tightness", "2", "--d", "30", "--name", "sp8"],
        "sparse",
        "tight",
    ),
]
METHODS = "single-task,whole-assembly"


def _make_library(folder: Path) -> Library:
    from bilevel_kit.instance import load

    folder.mkdir(parents=True)
    records = []
    for args, family, tray in TINY:
        name = args[args.index("--name") + 1]
        assert main(["generate", *args, "--out", str(folder / f"{name}.json")]) == 0
        inst = load(folder / f"{name}.json")
        records.append(Record(name, family, inst.n_tasks, inst.trays, inst.delivery_time, tray))
    Library(folder).write(records)
    return Library(folder)


@pytest.fixture(scope="module")
def pristine(tmp_path_factory):
    """A library without records and one run of two methods on it."""
    base = tmp_path_factory.mktemp("kitbench")
    lib = _make_library(base / "lib")
    run = base / "run"
    code = main(
        [
            "bench",
            "run",
            "--library",
            str(lib.folder),
            "--methods",
            METHODS,
            "--out",
            str(run),
            "-q",
        ]
    )
    assert code == 0
    return lib.folder, run


@pytest.fixture
def lib_and_run(pristine, tmp_path):
    """Private copies (tests edit them)."""
    lib, run = pristine
    shutil.copytree(lib, tmp_path / "lib")
    shutil.copytree(run, tmp_path / "run")
    return Library(tmp_path / "lib"), tmp_path / "run"


@pytest.fixture
def merged(lib_and_run):
    lib, run = lib_and_run
    assert main(["bench", "update", str(run), "--library", str(lib.folder)]) == 0
    return lib, run


def _snapshot(folder: Path) -> dict[str, bytes]:
    return {
        str(p.relative_to(folder)): p.read_bytes() for p in sorted(folder.rglob("*")) if p.is_file()
    }


def _cell(run: Path, instance: str, method: str = "single-task") -> Path:
    (path,) = (run / "cells").glob(f"{instance}__{method}__*.json")
    return path


def _edit(path: Path, **changes) -> None:
    doc = json.loads(path.read_text())
    doc.update(changes)
    path.write_text(json.dumps(doc))


# ---------------------------------------------------------------------------------------------
# run, update, verify
# ---------------------------------------------------------------------------------------------


def test_run_writes_every_output_and_resumes(pristine, capsys):
    lib, run = pristine
    for name in ("results.csv", "results.md", "profile.png", "gap_size.png", "run.json"):
        assert (run / name).is_file(), name
    rows = list(csv.DictReader(io.StringIO((run / "results.csv").read_text())))
    assert len(rows) == 3 * 2
    assert {"above_best_known", "certified_gap", "best_known", "best_bound"} <= set(rows[0])
    md = (run / "results.md").read_text()
    assert "within 1% of best-known" in md and "median certified gap (%)" in md
    before = _snapshot(run / "cells")
    code = main(["bench", "run", "--library", str(lib), "--methods", METHODS, "--out", str(run)])
    assert code == 0
    assert "0 done, 6 skipped" in capsys.readouterr().err
    assert _snapshot(run / "cells") == before


def test_update_fills_the_records_and_verify_passes(merged, capsys):
    lib, run = merged
    records, problems = verify(lib)
    assert problems == []
    assert all(r.best_known is not None and r.best_bound is not None for r in records)
    for r in records:
        assert r.plan is not None and r.plan.method in METHODS.split(",")
        assert r.plan.commit and r.plan.date and r.plan.time_limit is None
        assert (lib.folder / "solutions" / f"{r.instance}.json").is_file()
    assert main(["bench", "verify", "--library", str(lib.folder)]) == 0
    assert "all hold" in capsys.readouterr().out
    # merging the same run again changes nothing
    before = _snapshot(lib.folder)
    assert update(lib, [run]).changes == []
    assert _snapshot(lib.folder) == before


def test_update_takes_a_better_plan_and_a_higher_bound(lib_and_run, tmp_path):
    lib, run = lib_and_run
    # first the single-task plans alone: on stool2 whole-assembly's single kit is better
    single = tmp_path / "single"
    shutil.copytree(run, single)
    for path in (single / "cells").glob("*__whole-assembly__*.json"):
        path.unlink()
    update(lib, [single])
    before = {r.instance: r for r in lib.read()}
    assert before["stool2"].plan is not None and before["stool2"].plan.method == "single-task"
    merge = update(lib, [run])
    assert [(c.instance, c.what, c.method) for c in merge.changes] == [
        ("stool2", "plan", "whole-assembly")
    ]
    assert merge.changes[0].old == before["stool2"].best_known > merge.changes[0].new
    # a higher bound, still below the plan (a method that reports it as proven): accepted
    old = {r.instance: r for r in lib.read()}["it6"]
    path = _cell(run, "it6")
    doc = json.loads(path.read_text())
    higher = (old.best_bound + old.best_known) / 2
    doc["bound"] = higher
    for block in ("objective", "makespan"):  # the makespan: one claim in both blocks
        doc["solution"][block]["bound"] = higher
        doc["solution"][block]["gap"] = (doc["makespan"] - higher) / doc["makespan"]
    path.write_text(json.dumps(doc))
    merge = update(lib, [run])
    assert [(c.instance, c.what) for c in merge.changes] == [("it6", "bound")]
    new = {r.instance: r for r in lib.read()}["it6"]
    assert new.best_bound == higher and new.bound is not None
    assert new.bound.method == "single-task" and new.status == "open"
    assert verify(lib)[1] == []


def test_verify_finds_a_record_edited_by_hand(merged, capsys):
    lib, _ = merged
    text = lib.index_path.read_text()
    rec = lib.read()[0]
    lib.index_path.write_text(text.replace(repr(rec.best_known), repr(rec.best_known - 1), 1))
    # the status and gap columns now disagree with the numbers: refused when read
    assert main(["bench", "verify", "--library", str(lib.folder)]) == 2
    assert rec.instance in capsys.readouterr().err


def _edit_plan_file(lib: Library) -> str:
    """Shift the first record's plan (its kits' times stay consistent): its makespan is no
    longer the index's best_known."""
    from bilevel_kit import solve
    from bilevel_kit.instance import load
    from bilevel_kit.solution import result_to_dict

    rec = lib.read()[0]
    inst = load(lib.instance_path(rec.instance))
    other = solve(inst, "single-task")
    doc = result_to_dict(other)
    if abs(other.objective - rec.best_known) < 1e-6:  # single-task is the record: reverse it
        res = solve(inst, "whole-assembly")
        doc = result_to_dict(res)
    lib.solution_path(rec.instance).write_text(json.dumps(doc))
    return rec.instance


def test_verify_and_update_refuse_a_plan_that_disagrees_with_its_record(merged, capsys):
    lib, run = merged
    name = _edit_plan_file(lib)
    assert main(["bench", "verify", "--library", str(lib.folder)]) == 1
    err = capsys.readouterr().err
    assert name in err and "index says" in err
    before = _snapshot(lib.folder)
    assert main(["bench", "update", str(run), "--library", str(lib.folder)]) == 2
    err = capsys.readouterr().err
    assert name in err and "does not hold" in err
    assert _snapshot(lib.folder) == before


# ---------------------------------------------------------------------------------------------
# bad input of bench update: exit 2, the instance named, nothing written
# ---------------------------------------------------------------------------------------------


def _refused(lib: Library, run: Path, capsys) -> str:
    before = _snapshot(lib.folder)
    assert main(["bench", "update", str(run), "--library", str(lib.folder)]) == 2
    assert _snapshot(lib.folder) == before  # nothing written, no temporary file left
    return capsys.readouterr().err


def test_update_refuses_a_plan_that_fails_the_checker(lib_and_run, capsys):
    lib, run = lib_and_run
    path = _cell(run, "stool2")
    doc = json.loads(path.read_text())
    doc["solution"]["kits"] = doc["solution"]["kits"][1:]  # a task is never kitted
    path.write_text(json.dumps(doc))
    err = _refused(lib, run, capsys)
    assert "stool2: the plan of single-task fails the checker" in err


def test_update_refuses_a_bound_above_a_known_plan(lib_and_run, capsys):
    lib, run = lib_and_run
    path = _cell(run, "it6")
    doc = json.loads(path.read_text())
    _edit(path, bound=doc["makespan"] * 2)
    err = _refused(lib, run, capsys)
    assert "it6: bound" in err and "above the best-known plan" in err


@pytest.mark.parametrize(
    ("cell", "edit", "message"),
    [
        ("sp8", {"instance": "nowhere"}, "nowhere: unknown instance"),
        (
            "sp8",
            {"instance_sha256": "0" * 64},
            "sp8: the run solved another version of the instance file",
        ),
        ("it6", {"method": "my-own-method"}, "it6: a bound from 'my-own-method'"),
    ],
)
def test_update_refuses_a_foreign_cell(lib_and_run, capsys, cell, edit, message):
    """An unknown instance, another version of it, a bound from an unregistered method."""
    lib, run = lib_and_run
    _edit(_cell(run, cell), **edit)
    assert message in _refused(lib, run, capsys)


def test_update_refuses_a_misstated_makespan_and_foreign_files(lib_and_run, capsys):
    lib, run = lib_and_run
    path = _cell(run, "it6")
    _edit(path, makespan=json.loads(path.read_text())["makespan"] - 5)
    (run / "cells" / "stray.json").write_text(json.dumps({"instance": "it6"}))
    err = _refused(lib, run, capsys)
    assert "it6: single-task's record says makespan" in err
    assert "not a bench run cell" in err


def test_an_interrupted_update_leaves_the_library_as_it_was(lib_and_run, monkeypatch):
    lib, run = lib_and_run
    before = _snapshot(lib.folder)
    calls = {"n": 0}
    real = Path.write_text

    def flaky(self, *args, **kwargs):
        calls["n"] += 1
        if calls["n"] == 3:  # the index and one plan are written to their temporary files
            raise KeyboardInterrupt
        return real(self, *args, **kwargs)

    monkeypatch.setattr(Path, "write_text", flaky)
    with pytest.raises(KeyboardInterrupt):
        update(lib, [run])
    monkeypatch.setattr(Path, "write_text", real)
    assert _snapshot(lib.folder) == before


def test_refusal_lists_every_problem(lib_and_run):
    lib, run = lib_and_run
    _edit(_cell(run, "sp8"), instance="nowhere")
    _edit(_cell(run, "stool2"), instance="elsewhere")
    with pytest.raises(UpdateRefused) as info:
        update(lib, [run])
    assert {p.instance for p in info.value.problems} == {"nowhere", "elsewhere"}


# ---------------------------------------------------------------------------------------------
# filters, status, rendering
# ---------------------------------------------------------------------------------------------


def _records() -> list[Record]:
    return [
        Record("a", "intree", 50, 1, 0.0, "tight", 100.0, 100.0),
        Record("b", "sparse", 250, None, 10.0, "loose", 100.0, 90.0),
        Record("table_u2", "table", 24, 1, 30.0, "loose"),
    ]


@pytest.mark.parametrize(
    ("expr", "names"),
    [
        ("", ["a", "b", "table_u2"]),
        ("family=intree", ["a"]),
        ("family=intree|sparse,tasks<=130", ["a"]),
        ("tasks>=24,tasks<250", ["a", "table_u2"]),
        ("trays=1", ["a", "table_u2"]),
        ("trays=unlimited", ["b"]),
        ("trays>1", ["b"]),
        ("instance=table_*", ["table_u2"]),
        ("family!=table, tray = loose", ["b"]),
        ("status=optimal", ["a"]),
        ("gap>0.05", ["b"]),
        ("delivery_time=10", ["b"]),
    ],
)
def test_filter(expr, names):
    assert [r.instance for r in select(_records(), parse_filter(expr))] == names


@pytest.mark.parametrize(
    ("expr", "message"),
    [
        ("size<3", "unknown key 'size'"),
        ("family<intree", "family is text"),
        ("tasks=many", "tasks takes a number"),
        ("trays=some", "trays takes an integer or 'unlimited'"),
        ("tasks", "is not KEY OP VALUE"),
        ("__import__('os')=1", "is not KEY OP VALUE"),
    ],
)
def test_bad_filter(expr, message):
    from bilevel_kit import UsageError

    with pytest.raises(UsageError, match=message.replace("(", r"\(")):
        parse_filter(expr)


def test_bad_filter_on_the_command_line_is_exit_2(pristine, tmp_path, capsys):
    lib, _ = pristine
    out = tmp_path / "out"
    assert (
        main(["bench", "run", "--library", str(lib), "--filter", "size<3", "--out", str(out)]) == 2
    )
    assert "unknown key 'size'" in capsys.readouterr().err
    assert not out.exists()


def test_status_tolerance():
    assert record_status(100.0, 100.0 - 1e-5) == "optimal"
    assert record_status(100.0, 100.0 - 1e-3) == "open"
    assert record_status(100.0, None) == "open"


def test_blocks_render_from_the_records():
    text = "x\n<!-- kitbench:status -->\nold\n<!-- /kitbench:status -->\ny\n"
    out = render_blocks(text, _records())
    assert "1 of 3 records are proven optimal" in out and "old" not in out
    assert render_blocks(out, _records()) == out


def test_profile_and_gap_plots():
    import matplotlib.pyplot as plt

    from bilevel_kit.plots import plot_gap_vs_size, plot_profile

    ax = plot_profile({"a": [1.0, 1.02, float("inf")], "b": [1.0, 1.0, 1.3]})
    lines = {line.get_gid(): line for line in ax.get_lines()}
    assert {"profile:a", "profile:b", "tau:1 %", "tau:5 %"} <= set(lines)
    # a reaches 2 of 3 instances (the third has no plan), b all three
    assert lines["profile:a"].get_ydata()[-1] == pytest.approx(2 / 3)
    assert lines["profile:b"].get_ydata()[-1] == pytest.approx(1.0)
    # one log scale (no linear part below 1 %), the best-known at the 0.01 % edge
    assert ax.get_xscale() == "log" and ax.get_xlim()[0] == pytest.approx(0.01)
    assert lines["profile:b"].get_xdata()[1] == pytest.approx(0.01)
    # x and y name the same quantity; the legend is outside the axes (not over the curves)
    assert ax.get_xlabel().startswith("x: makespan above best-known (%")
    assert ax.get_ylabel() == "share of instances at most x % above"
    ax.figure.canvas.draw()
    legend_box, axes_box = ax.get_legend().get_window_extent(), ax.get_window_extent()
    assert legend_box.x0 >= axes_box.x1
    plt.close(ax.figure)
    _, mine = plt.subplots()
    rows = [
        {"method": "a", "tasks": 12, "certified_gap": 0.01},
        {"method": "a", "tasks": 1000, "certified_gap": None},
        {"method": "b", "tasks": 50, "certified_gap": 0.2},
    ]
    assert plot_gap_vs_size(rows, ax=mine) is mine
    points = {c.get_gid(): c.get_offsets() for c in mine.collections}
    assert len(points["gap:a"]) == 1 and list(points["gap:b"][0]) == [50, 20]
    assert mine.get_yscale() == "symlog"  # gaps near 0 spread out, large ones on a log scale
    labels = [t.get_text() for t in mine.get_legend().get_texts()]
    assert labels == ["a", "b"]  # no gap of 0: nothing to count
    _, other = plt.subplots()
    plot_gap_vs_size([{**r, "certified_gap": 0.0} for r in rows], ax=other)
    texts = [t.get_text() for t in other.get_legend().get_texts()]
    assert texts == ["a, 2 at 0 %", "b, 1 at 0 %"]  # every row set to 0 here
    assert all(len(c.get_facecolors()) == 0 for c in other.collections)  # hollow markers
    plt.close(other.figure)
    plt.close(mine.figure)
