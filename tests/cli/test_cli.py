"""The CLI: solve/check/schema, exit codes, one-line errors and no half-written output."""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from typing import Literal

import pytest

from bilevel_kit import load
from bilevel_kit.cli import main
from bilevel_kit.solution import read


def run(capsys, *argv):
    code = main([str(a) for a in argv])
    out, err = capsys.readouterr()
    return code, out, err


def test_solve_writes_a_valid_solution(capsys, tmp_path, root):
    out = tmp_path / "s.json"
    code, text, _ = run(
        capsys,
        "solve",
        root / "instances/hrc_table.json",
        "--method",
        "single-task",
        "--out",
        out,
        "--check",
        "--trays",
        "unlimited",
    )
    assert code == 0
    assert "makespan 459.78 s" in text and "check: valid" in text
    doc = json.loads(out.read_text())
    for key in (
        "method",
        "status",
        "objective",
        "makespan",
        "seed",
        "params",
        "wall_time_s",
        "metrics",
        "kits",
    ):
        assert key in doc
    assert doc["objective"]["name"] == "makespan"
    assert doc["objective"]["value"] == doc["makespan"]["value"] == pytest.approx(459.78)
    assert doc["metrics"] == {
        "makespan": pytest.approx(459.78),
        "human_idle": pytest.approx(37),
        "robot_idle": pytest.approx(131.78),
        "n_kits": 12,
    }
    assert set(doc["kits"][0]) == {
        "tasks",
        "robot_start",
        "robot_end",
        "arrive",
        "human_start",
        "human_end",
        "layout",
    }
    assert set(doc["kits"][0]["layout"][0]) == {"part", "type", "x", "y", "theta", "w", "h"}
    table = root / "instances/hrc_table.json"
    code, text, _ = run(capsys, "check", table, out, "--trays", "unlimited")
    assert code == 0 and text.startswith("valid: 12 kits, 12 tasks")
    code, text, _ = run(capsys, "check", table, out)  # the file records --trays unlimited
    assert code == 0 and text.startswith("valid: 12 kits, 12 tasks")
    del doc["overrides"]  # a file without the record is checked on the instance's one tray
    out.write_text(json.dumps(doc))
    code, text, _ = run(capsys, "check", table, out)
    assert code == 1
    assert "[instance_mismatch] the solution was computed with trays = unlimited" in text


def test_solution_json_round_trip_is_lossless(capsys, tmp_path, root, table):
    from bilevel_kit import solve

    for method in ("single-task", "whole-assembly"):
        out = tmp_path / f"{method}.json"
        assert (
            run(capsys, "solve", root / "instances/hrc_table.json", "-m", method, "-o", out)[0] == 0
        )
        loaded = read(out)
        assert loaded.plan == solve(table, method).plan
        from bilevel_kit.plan import evaluate

        assert loaded.reported_kits == evaluate(table, loaded.plan).kits


def test_check_reports_violations_with_exit_1(capsys, tmp_path, root):
    out = tmp_path / "s.json"
    run(capsys, "solve", root / "instances/hrc_table.json", "-m", "single-task", "-o", out)
    doc = json.loads(out.read_text())
    doc["kits"][0], doc["kits"][1] = doc["kits"][1], doc["kits"][0]
    out.write_text(json.dumps(doc))
    code, text, _ = run(capsys, "check", root / "instances/hrc_table.json", out)
    assert code == 1
    assert "[precedence] 'foot1' must precede 'conn1'" in text
    assert "[times_inconsistent]" in text


def test_overrides_change_the_timeline(capsys, root):
    code, text, _ = run(
        capsys, "solve", root / "instances/stool.json", "-m", "single-task", "--d", "0", "-q"
    )
    assert code == 0 and "makespan 77.00 s" in text


def test_schema_command(capsys):
    code, text, _ = run(capsys, "schema")
    assert code == 0 and json.loads(text)["properties"]["format"]["const"] == "bilevel-kit/1"
    code, text, _ = run(capsys, "schema", "--solution")
    assert json.loads(text)["title"] == "bilevel-kit solution"


def test_figures_are_written(capsys, tmp_path, root):
    g, t = tmp_path / "g.png", tmp_path / "t.png"
    code, _, _ = run(
        capsys,
        "solve",
        root / "instances/stool.json",
        "-m",
        "single-task",
        "--gantt",
        g,
        "--tray",
        t,
    )
    assert code == 0
    assert g.read_bytes()[:4] == b"\x89PNG" and t.read_bytes()[:4] == b"\x89PNG"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["g.png", "t.png"]


BAD_CASES = {
    "malformed JSON": ('{"format": "bilevel-kit/1",', "$: malformed JSON"),
    "missing field": (lambda d: d.pop("part_types"), "$: missing required field 'part_types'"),
    "unknown part type": (
        lambda d: d["tasks"][0]["parts"][0].update(type="gear"),
        "$.tasks[0].parts[0].type: unknown part type 'gear'",
    ),
    "duplicate task id": (
        lambda d: d["tasks"][1].update(id="x"),
        "$.tasks[1].id: duplicate task id 'x'",
    ),
    "precedence cycle": (
        lambda d: d["precedence"].append(["y", "x"]),
        "$.precedence: precedence cycle x -> y -> x",
    ),
    "edge to unknown task": (
        lambda d: d["precedence"].append(["q", "x"]),
        "$.precedence[1][0]: unknown task 'q'",
    ),
    "negative time": (
        lambda d: d["part_types"][0].update(pick_time=-1),
        "$.part_types[0].pick_time: -1 is less than the minimum of 0",
    ),
    "NaN time": (
        lambda d: d["tasks"][2]["human_time"].update(mean=float("nan")),
        "$.tasks[2].human_time.mean: must be a finite number",
    ),
    "part larger than tray": (
        lambda d: d["part_types"][0].update(width=101, height=101),
        "$.part_types[0]: part 'a' (101 x 101 mm) does not fit",
    ),
    "empty task list": (lambda d: d.update(tasks=[]), "$.tasks: [] should be non-empty"),
    "wrong format version": (
        lambda d: d.update(format="bilevel-kit/9"),
        "$.format: unsupported format 'bilevel-kit/9'",
    ),
}


@pytest.mark.parametrize("case", sorted(BAD_CASES))
def test_bad_input_exits_2_with_one_line(case, capsys, tmp_path, doc):
    change, expected = BAD_CASES[case]
    path = tmp_path / "bad.json"
    if isinstance(change, str):
        path.write_text(change)
    else:
        change(doc)
        path.write_text(json.dumps(doc))
    out = tmp_path / "out.json"
    code, _text, err = run(capsys, "solve", path, "-m", "single-task", "-o", out)
    assert code == 2
    assert err.count("\n") == 1 and "Traceback" not in err
    assert f"{path}: " in err and expected in err
    assert not out.exists()


def test_missing_file_exits_2(capsys, tmp_path):
    code, _, err = run(capsys, "solve", tmp_path / "none.json", "-m", "single-task")
    assert code == 2 and err.strip().endswith("none.json: $: file not found")


@pytest.mark.parametrize(
    "argv",
    [
        ["solve", "instances/tiny.json", "-m", "nope"],
        ["solve", "instances/tiny.json", "-m", "single-task", "--weights", "W3"],
        ["solve", "instances/tiny.json", "-m", "single-task", "--weights", "W9=1"],
        ["solve", "instances/tiny.json", "-m", "single-task", "--d", "-1"],
        ["solve", "instances/tiny.json", "-m", "single-task", "--horizon", "0"],
        ["solve", "instances/tiny.json", "-m", "single-task", "-p", "foo=1"],
        ["solve", "instances/tiny.json"],
        ["frobnicate"],
    ],
)
def test_usage_errors_exit_2(argv, capsys, root, monkeypatch):
    monkeypatch.chdir(root)
    code, _, err = run(capsys, *argv)
    assert code == 2 and err.count("\n") == 1 and "Traceback" not in err


def test_kit_that_does_not_fit_is_a_clear_error(capsys, tmp_path, doc):
    doc["part_types"][0].update(width=60, height=60)  # two 60 x 60 blocks on a 100 x 100 tray
    path = tmp_path / "tight.json"
    path.write_text(json.dumps(doc))
    code, _, err = run(capsys, "solve", path, "-m", "whole-assembly")
    assert code == 2 and "do not fit the 100 x 100 mm tray" in err
    assert load(path).n_tasks == 3


def test_bad_solution_file_exits_2(capsys, tmp_path, root):
    bad = tmp_path / "sol.json"
    bad.write_text(
        json.dumps(
            {
                "format": "bilevel-kit-solution/1",
                "method": "x",
                "status": "feasible",
                "kits": [{"tasks": "t1", "layout": []}],
            }
        )
    )
    code, _, err = run(capsys, "check", root / "instances/tiny.json", bad)
    assert code == 2 and "$.kits[0].tasks: 't1' is not of type 'array'" in err


def test_compare_table_files_and_resume(capsys, tmp_path, root, monkeypatch):
    cells, md, csv_path, figs = (
        tmp_path / "cells",
        tmp_path / "c.md",
        tmp_path / "c.csv",
        tmp_path / "figs",
    )
    argv = [
        "compare",
        str(root / "instances/stool.json"),
        str(root / "instances/tiny.json"),
        "--methods",
        "single-task,whole-assembly",
        "--cells",
        str(cells),
        "--md",
        str(md),
        "--csv",
        str(csv_path),
        "--figures",
        str(figs),
    ]
    code, text, err = run(capsys, *argv)
    assert code == 0
    # drawing is announced after the table, then each file as it is written (issue 40 item 10)
    said = [line.split(": ", 1)[1] for line in err.splitlines() if "figure" in line]
    assert said[0] == f"drawing 10 figure(s) into {figs}"
    assert said[1:] == [f"figure {i}/10: {figs}/{n}" for i, n in enumerate(
        ["stool_compare.png", "stool_single-task_gantt.png", "stool_single-task_trays.png",
         "stool_whole-assembly_gantt.png", "stool_whole-assembly_trays.png", "tiny_compare.png",
         "tiny_single-task_gantt.png", "tiny_single-task_trays.png",
         "tiny_whole-assembly_gantt.png", "tiny_whole-assembly_trays.png"], 1)]  # fmt: skip
    assert len(list(cells.glob("*.json"))) == 4
    lines = md.read_text().splitlines()
    assert lines[0].startswith("| instance | method | makespan (s)") and len(lines) == 6
    assert "| stool | single-task | 91.00 |" in md.read_text()
    import csv

    rows = list(csv.DictReader(csv_path.open()))
    assert {r["method"] for r in rows} == {"single-task", "whole-assembly"}
    assert all(r["valid"] == "True" for r in rows)
    # the gap is measured against the best bound of the instance's rows
    stool = [r for r in rows if r["instance"] == "stool"]
    assert len({r["best_bound"] for r in stool}) == 1
    assert sorted(p.name for p in figs.iterdir()) == [
        "stool_compare.png",
        "stool_single-task_gantt.png",
        "stool_single-task_trays.png",
        "stool_whole-assembly_gantt.png",
        "stool_whole-assembly_trays.png",
        "tiny_compare.png",
        "tiny_single-task_gantt.png",
        "tiny_single-task_trays.png",
        "tiny_whole-assembly_gantt.png",
        "tiny_whole-assembly_trays.png",
    ]
    # a second run reuses every saved cell: no method is called again
    import bilevel_kit.methods as methods

    def boom(*a, **k):
        raise AssertionError("cell recomputed")

    monkeypatch.setattr(methods, "solve", boom)
    code, text2, _ = run(capsys, *argv)
    assert code == 0 and text2 == text


def test_methods_lists_every_registered_method(capsys):
    from bilevel_kit.methods import REGISTRY

    code, text, _ = run(capsys, "methods")
    assert code == 0
    listing, _, note = text.partition("\n\n")  # then a note on J (issue 40, item 2)
    assert [line.split()[0] for line in listing.splitlines()] == list(REGISTRY)
    assert note.startswith("J = the paper's objective")
    assert "single-task      paper baseline: one kit per task" in text


def test_methods_name_without_options(capsys):
    code, text, _ = run(capsys, "methods", "single-task")
    assert code == 0
    assert text.splitlines() == [
        "single-task: paper baseline: one kit per task, deterministic topological order",
        "takes no options",
    ]


@dataclass(frozen=True)
class DemoOptions:
    """Options of every kind ``bilevel-kit methods NAME`` must show."""

    iterations: int = field(default=50, metadata={"help": "iterations of the demo", "min": 1})
    time_limit: float | None = field(default=None, metadata={"help": "seconds, none: no limit"})
    mode: Literal["fast", "exact"] = field(default="fast", metadata={"help": "how to run"})
    polish: bool = False


def test_methods_name_lists_options_with_type_default_and_meaning(capsys, monkeypatch):
    import sys
    import types

    from bilevel_kit.methods import REGISTRY, MethodSpec

    module = types.ModuleType("demo_options")
    module.DemoOptions = DemoOptions
    monkeypatch.setitem(sys.modules, "demo_options", module)
    spec = MethodSpec(
        "demo", "bilevel_kit.heuristics.baselines:single_task", "a demo", "demo_options:DemoOptions"
    )
    monkeypatch.setitem(REGISTRY, spec.name, spec)
    code, text, _ = run(capsys, "methods", "demo")
    assert code == 0
    lines = text.splitlines()
    assert lines[:2] == ["demo: a demo", "options (solve --param KEY=VALUE):"]
    assert [" ".join(line.split()) for line in lines[2:]] == [
        "iterations int default 50 iterations of the demo",
        "time_limit float | none default none seconds, none: no limit",
        "mode 'fast' | 'exact' default fast how to run",
        "polish bool default false",
    ]
    # the columns are aligned
    assert len({line.index("default") for line in lines[2:]}) == 1


def test_methods_unknown_name_exits_2(capsys):
    code, _, err = run(capsys, "methods", "nope")
    assert code == 2 and err.count("\n") == 1 and "unknown method or policy 'nope'" in err


def test_trays_override(capsys, root):
    table = root / "instances/hrc_table.json"
    code, text, _ = run(capsys, "solve", table, "-m", "single-task", "--trays", "1", "--check")
    assert code == 0 and "makespan 466.69 s" in text and "check: valid" in text
    code, text, _ = run(capsys, "solve", table, "-m", "single-task", "--trays", "unlimited")
    assert code == 0 and "makespan 459.78 s" in text
    for bad in ("0", "-1", "1.5", "abc"):
        code, _, err = run(capsys, "solve", table, "-m", "single-task", "--trays", bad)
        assert code == 2 and "--trays" in err and err.count("\n") == 1


@pytest.mark.parametrize("quiet", [False, True])
def test_solve_live_line_on_a_terminal_unless_q(capsys, monkeypatch, root, quiet):
    from bilevel_kit import progress

    monkeypatch.setattr(progress, "is_terminal", lambda stream: True)
    live = not quiet
    args = ["solve", root / "instances/hrc_table.json", "-m", "cpsat", "--time-limit", "20"]
    code, out, err = run(capsys, *args, *(["-q"] if quiet else []))
    assert code == 0 and "hrc_table: cpsat" in out
    assert ("\r" in err and "bound" in err and err.endswith("\n")) is live
    if not live:
        assert err == ""


def test_solve_prints_no_live_line_off_a_terminal(capsys, root):
    args = ["solve", root / "instances/hrc_table.json", "-m", "cpsat", "--time-limit", "20"]
    code, out, err = run(capsys, *args)
    assert code == 0 and "hrc_table: cpsat" in out
    assert err == ""


def help_option_lists(text: str) -> dict[str, list[str]]:
    """The epilog of ``--help``: method or policy name -> the option keys it lists."""
    entries: dict[str, str] = {}
    name = None
    for line in text[text.index(" options (-p") :].splitlines():
        if line.startswith("  ") and line[2] != " ":
            name, _, rest = line.strip().partition(" ")
            entries[name] = rest
        elif line.startswith("   ") and name is not None:
            entries[name] += " " + line
    return {
        k: [] if "no options" in v else v.replace(" ", "").split(",") for k, v in entries.items()
    }


@pytest.mark.parametrize("command", ["solve", "compare", "simulate"])
def test_help_lists_every_option_key(capsys, command):
    from bilevel_kit.methods import REGISTRY
    from bilevel_kit.sim.registry import POLICIES

    code, text, _ = run(capsys, command, "--help")
    assert code == 0
    assert "types, defaults and meaning: bilevel-kit methods NAME" in " ".join(text.split())
    specs = [POLICIES.spec(n) for n in POLICIES] if command == "simulate" else REGISTRY.values()
    listed = help_option_lists(text)
    assert listed == {s.name: [i.name for i in s.describe_options()] for s in specs}
    if command == "simulate":
        assert listed["cpsat-rolling"][0] == "window"
    else:
        assert {"W1", "W7", "samples", "horizon"} <= set(listed["greedy-ce"])
        assert listed["single-task"] == [] and "hint" in listed["cpsat"]


def test_methods_name_describes_a_simulation_policy(capsys):
    code, text, _ = run(capsys, "methods", "cpsat-rolling")
    lines = text.splitlines()
    assert code == 0 and lines[0].endswith("(simulation policy)")
    assert lines[1] == "options (simulate --param KEY=VALUE):"
    assert [line.split()[0] for line in lines[2:]] == [
        "window",
        "supply_window",
        "deterministic_time",
        "time_limit",
        "workers",
        "tray",
    ]
    code, text, _ = run(capsys, "methods", "optimized")
    assert code == 0 and text.splitlines()[1:] == ["takes no options"]


def test_solution_records_overrides_and_check_applies_them(capsys, tmp_path, root):
    """A plan solved with --units 2 --trays unlimited checks valid without repeating them;
    a contradicting option is refused, and a file without the record gets a hint."""
    table = root / "instances/hrc_table.json"
    out = tmp_path / "u2.json"
    args = ("--method", "single-task", "--units", 2, "--trays", "unlimited", "--out", out)
    assert run(capsys, "solve", table, *args)[0] == 0
    doc = json.loads(out.read_text())
    assert doc["overrides"] == {"units": 2, "trays": "unlimited"}
    code, text, err = run(capsys, "check", table, out)
    assert code == 0 and text.startswith("valid: 24 kits, 24 tasks")
    assert "applying the solution's overrides: trays=unlimited, units=2" in err
    # the same value again is fine; a different one is a usage error naming the field
    assert run(capsys, "check", table, out, "--units", 2)[0] == 0
    code, _, err = run(capsys, "check", table, out, "--units", 3)
    assert code == 2 and err.count("\n") == 1
    assert "$.overrides.units: the plan was solved with units=2, but --units 3" in err
    # an older file without the record: the violations, and a hint that names the option
    del doc["overrides"]
    old = tmp_path / "old.json"
    old.write_text(json.dumps(doc))
    code, text, err = run(capsys, "check", table, old)
    assert code == 1 and "[unknown_task]" in text and "--units U" in err
    assert run(capsys, "check", table, old, "--units", 2, "--trays", "unlimited")[0] == 0
    # no override given: the key is left out, so earlier files and new ones read alike
    plain = tmp_path / "plain.json"
    assert run(capsys, "solve", table, "--method", "single-task", "--out", plain)[0] == 0
    assert "overrides" not in json.loads(plain.read_text())


def test_check_puts_the_root_cause_first_and_summarises_its_consequences(capsys, tmp_path, root):
    """Two kits swapped: the two precedence errors come first; the 62 shifted kit times are
    summarised (3 shown, the rest counted) instead of filling the listing."""
    table = root / "instances/hrc_table.json"
    out = tmp_path / "s.json"
    assert run(capsys, "solve", table, "--method", "single-task", "--out", out)[0] == 0
    doc = json.loads(out.read_text())
    times = ("robot_start", "robot_end", "arrive", "human_start", "human_end")
    a, b = doc["kits"][0], doc["kits"][5]
    for k in ("tasks", "layout"):
        a[k], b[k] = b[k], a[k]
    assert all(k in a for k in times)
    out.write_text(json.dumps(doc))
    code, text, _ = run(capsys, "check", table, out)
    lines = text.splitlines()
    assert code == 1 and lines[0].startswith("INVALID: ")
    assert lines[1].startswith("  [precedence]") and lines[2].startswith("  [precedence]")
    shown = [x for x in lines if x.startswith("  [times_inconsistent]")]
    assert len(shown) == 3
    more = [x for x in lines if x.endswith("more [times_inconsistent]")]
    assert len(more) == 1 and int(more[0].split()[2]) >= 40


NOTHING = """
from dataclasses import dataclass

from bilevel_kit import MethodOutput
from bilevel_kit.methods import Status


@dataclass(frozen=True)
class NoOptions:
    pass


def nothing(instance, options, *, seed=0, time_limit=None):
    return MethodOutput(None, Status.UNKNOWN)
"""


def test_compare_exits_3_when_a_method_gives_no_plan(capsys, tmp_path, root, monkeypatch):
    """A "no plan" row is not success: exit 3 and a NO PLAN line naming the row; an invalid
    plan or a false claim (exit 1) would win over it."""
    from bilevel_kit.methods import REGISTRY, register

    (tmp_path / "bk_nothing.py").write_text(NOTHING)
    monkeypatch.syspath_prepend(str(tmp_path))
    register("nothing", "bk_nothing:nothing", "gives up at once", "bk_nothing:NoOptions")
    try:
        table = root / "instances/hrc_table.json"
        code, text, err = run(capsys, "compare", table, "--methods", "single-task,nothing")
        assert code == 3
        assert err.splitlines()[-1] == "bilevel-kit compare: NO PLAN: hrc_table / nothing (unknown)"
        assert "no plan" in text or "-" in text
        code, _, err = run(capsys, "compare", table, "--methods", "single-task")
        assert code == 0 and "NO PLAN" not in err
    finally:
        REGISTRY.remove("nothing")


def test_a_status_about_j_prints_j_and_its_bound(tiny):
    """bilevel-milp's status refers to J, so its summary shows J, the J bound and the J gap
    (the makespan's bound and gap on the first line are not what "optimal" is about)."""
    from dataclasses import replace

    from bilevel_kit.cli.solve import summary
    from bilevel_kit.methods import solve

    res = solve(tiny, "single-task")
    assert "refers to J" not in summary(tiny, res, True)
    res = replace(res, objective_name="J", objective=11.375, bound=11.0, gap=0.033)
    lines = summary(tiny, res, True).splitlines()
    assert lines[1] == "  J: feasible  J 11.38  J bound 11.00  J gap 3.30%"
    from bilevel_kit.objectives import J_MEANING

    assert lines[2] == f"  ({J_MEANING})"  # what J is, where solve prints it


def test_methods_with_an_unknown_name_lists_methods_and_policies(capsys):
    code, _, err = run(capsys, "methods", "nonexistent")
    assert code == 2 and err.count("\n") == 1
    assert "unknown method or policy 'nonexistent'; methods: single-task," in err
    assert "simulation policies: " in err and "optimized" in err and "cpsat-rolling" in err
