"""The edges of the toolkit, one row per kind of bad input: every one is a clean exit code
(2 with one line on stderr naming the culprit, or 1 with the checker's violations, or pack's
4), never a traceback, never a silent acceptance, and nothing is written.

Each row names the files it needs (in ``tmp/in``), the command line (``{i}`` the instance,
``{s}`` the solution, ``{p}`` the pack file, ``{f}`` a regular file, ``{d}`` a folder, ``{o}``
an empty output folder, ``{table}`` the paper's table) and what must come back. Every row runs
in-process through :func:`bilevel_kit.cli.main`; the whole tmp tree is compared before and
after, so "nothing written" covers every output option.
"""

from __future__ import annotations

import copy
import json
import os
from collections.abc import Callable
from dataclasses import dataclass, field
from functools import cache
from pathlib import Path
from typing import Any

import pytest
from offgrid_example import offgrid_doc
from stations_example import first_tray_doc

from bilevel_kit.cli import main

ROOT = Path(__file__).resolve().parents[2]
TINY = ROOT / "instances" / "tiny.json"
TABLE = ROOT / "instances" / "hrc_table.json"

Doc = dict[str, Any]
Content = str | Callable[[], str]


@cache
def tiny_doc() -> Doc:
    return json.loads(TINY.read_text())


@cache
def tiny_solution() -> Doc:
    """The single-task solution of the tiny instance, as a format-1 file holds it: the claims
    rows below use its keys (still read, docs/formats.md#solutions; format 2's claims:
    tests/core/test_result_objective.py)."""
    from solution_v1 import to_format_1

    from bilevel_kit import load, solve
    from bilevel_kit.solution import result_to_dict

    return to_format_1(json.loads(json.dumps(result_to_dict(solve(load(TINY), "single-task")))))


PACK_DOC: Doc = {
    "tray": {"width": 100, "height": 100},
    "items": [{"id": "sq", "width": 50, "height": 50, "count": 4}],
}


def _mutated(base: Callable[[], Doc], change: Callable[[Doc], Any]) -> Callable[[], str]:
    def text() -> str:
        doc = copy.deepcopy(base())
        change(doc)
        return json.dumps(doc)

    return text


def instance(change: Callable[[Doc], Any]) -> Callable[[], str]:
    return _mutated(tiny_doc, change)


def solution(change: Callable[[Doc], Any]) -> Callable[[], str]:
    return _mutated(tiny_solution, change)


def pack_file(change: Callable[[Doc], Any]) -> Callable[[], str]:
    return _mutated(lambda: PACK_DOC, change)


def unchanged(doc: Doc) -> None:
    """The valid document as it is."""


def tiny_text() -> str:
    return TINY.read_text()


#: A folder to create instead of a file.
DIR = object()


@dataclass(frozen=True)
class Row:
    argv: tuple[str, ...]
    code: int
    words: tuple[str, ...]
    files: dict[str, Any] = field(default_factory=dict)


def row(argv: str, code: int, *words: str, i: Content | None = None, **files: Any) -> Row:
    """A row; ``i`` is the instance text (default: the tiny instance), ``files`` others."""
    return Row(tuple(argv.split()), code, words, {"i": tiny_text if i is None else i, **files})


SOLVE = "solve {i} -m single-task -o {o}/s.json"
CHECK = "check {i} {s}"


def bad_instance(change: Callable[[Doc], Any], *words: str) -> Row:
    return row(SOLVE, 2, "{i}", *words, i=instance(change))


def raw_instance(text: str, *words: str) -> Row:
    return row(SOLVE, 2, "{i}", *words, i=text)


def bad_solution(change: Callable[[Doc], Any], *words: str) -> Row:
    return row(CHECK, 2, "{s}", *words, s=solution(change))


def invalid_solution(change: Callable[[Doc], Any], *words: str) -> Row:
    return row(CHECK, 1, *words, s=solution(change))


def bad_pack(change: Callable[[Doc], Any], *words: str) -> Row:
    return row("pack {p} --out {o}/l.json", 2, "{p}", *words, p=pack_file(change))


def _set(path: str, value: Any) -> Callable[[Doc], None]:
    """Set ``doc[a][b]...`` (``a.b.0.c``) to ``value``."""
    keys: list[Any] = [int(k) if k.isdigit() else k for k in path.split(".")]

    def change(doc: Doc) -> None:
        obj = doc
        for k in keys[:-1]:
            obj = obj[k]
        obj[keys[-1]] = value

    return change


def _del(path: str) -> Callable[[Doc], None]:
    keys: list[Any] = [int(k) if k.isdigit() else k for k in path.split(".")]

    def change(doc: Doc) -> None:
        obj = doc
        for k in keys[:-1]:
            obj = obj[k]
        del obj[keys[-1]]

    return change


def _all(*changes: Callable[[Doc], Any]) -> Callable[[Doc], None]:
    def change(doc: Doc) -> None:
        for c in changes:
            c(doc)

    return change


def _strip_times(doc: Doc) -> None:
    for kit in doc["kits"]:
        for k in ("robot_start", "robot_end", "arrive", "human_start", "human_end"):
            del kit[k]
    doc.pop("metrics")


ROWS: dict[str, Row] = {
    # --- instance files: JSON itself ----------------------------------------------------------
    "instance duplicate key": raw_instance(
        '{"format": "bilevel-kit/1", "name": "a", "name": "b"}', "$: duplicate key 'name'"
    ),
    "instance duplicate nested key": raw_instance(
        tiny_text().replace('"mean": 10.0', '"mean": 10.0, "mean": 1.0'),
        "$.tasks[0].human_time: duplicate key 'mean'",
    ),
    "instance NaN": raw_instance(
        tiny_text().replace('"delivery_time": 1.0', '"delivery_time": NaN'),
        "$.delivery_time: must be a finite number",
    ),
    "instance Infinity": raw_instance(
        tiny_text().replace('"mean": 10.0', '"mean": Infinity'), "human_time.mean", "finite"
    ),
    "instance malformed JSON": raw_instance('{"format": ', "malformed JSON at line 1"),
    "instance empty file": raw_instance("", "malformed JSON"),
    "instance top-level array": raw_instance("[]", "is not of type 'object'"),
    "instance not UTF-8": raw_instance("\udcff", "cannot read file"),
    # --- instance files: ranges ---------------------------------------------------------------
    "negative weight": bad_instance(_set("weights", {"W3": -1}), "$.weights.W3", "minimum of 0"),
    "huge weight": bad_instance(_set("weights", {"W1": 1e9}), "$.weights.W1", "maximum of"),
    "human time 1e308": bad_instance(
        _set("tasks.0.human_time.mean", 1e308), "$.tasks[0].human_time.mean", "maximum of"
    ),
    "negative sd": bad_instance(_set("tasks.0.human_time.sd", -1), "human_time.sd"),
    "robot time 1e9": bad_instance(_set("tasks.0.robot_time", 1e9), "$.tasks[0].robot_time"),
    "pick time 1e8": bad_instance(_set("part_types.0.pick_time", 1e8), "pick_time"),
    "negative pick time": bad_instance(_set("part_types.0.pick_time", -1), "pick_time"),
    "tray 1e20 mm": bad_instance(_set("tray.width", 1e20), "$.tray.width", "maximum of"),
    "tray 0 mm": bad_instance(_set("tray.height", 0), "$.tray.height"),
    "tray below 0.01 mm": bad_instance(
        _set("tray.height", 0.001), "$.tray.height", "smallest length 0.01 mm"
    ),
    "part 1e-300 mm": bad_instance(
        _set("part_types.0.width", 1e-300), "$.part_types[0].width", "smallest length"
    ),
    "part 0 mm": bad_instance(_set("part_types.0.height", 0), "$.part_types[0].height"),
    "negative delivery time": bad_instance(_set("delivery_time", -1), "$.delivery_time"),
    "delivery time 1e300": bad_instance(_set("delivery_time", 1e300), "$.delivery_time"),
    "negative overhead": bad_instance(_set("kit_overhead.robot", -2), "$.kit_overhead.robot"),
    "supply mat 0": bad_instance(_set("supply", {"block": {"mat": 0}}), "$.supply.block.mat"),
    "supply mttf 1e12": bad_instance(
        _set("supply", {"block": {"mat": 5, "mttf": 1e12}}), "$.supply.block.mttf"
    ),
    "supply unknown type": bad_instance(
        _set("supply", {"nope": {"mat": 5}}), "unknown part type 'nope'"
    ),
    "reach resolution 1e-3": bad_instance(
        _set("reach_resolution", 1e-3), "$.reach_resolution", "smallest length"
    ),
    # --- instance files: structure ------------------------------------------------------------
    "missing format": bad_instance(_del("format"), "missing required field 'format'"),
    "wrong format": bad_instance(_set("format", "bilevel-kit/9"), "unsupported format"),
    "unknown field": bad_instance(_set("colour", "red"), "unknown field 'colour'"),
    "missing name": bad_instance(_del("name"), "missing required field 'name'"),
    "empty name": bad_instance(_set("name", ""), "$.name"),
    "missing tray": bad_instance(_del("tray"), "missing required field 'tray'"),
    "tray as list": bad_instance(_set("tray", [1, 2]), "$.tray", "not of type 'object'"),
    "no part types": bad_instance(_set("part_types", []), "$.part_types", "non-empty"),
    "duplicate part id": bad_instance(
        _set("part_types.1.id", "block"), "duplicate part type id 'block'"
    ),
    "part larger than tray": bad_instance(
        _set("part_types.1.width", 150.0), "$.part_types[1]", "does not fit"
    ),
    "unknown part in task": bad_instance(
        _set("tasks.0.parts.0.type", "nope"), "unknown part type 'nope'"
    ),
    "part listed twice in task": bad_instance(
        _set("tasks.2.parts.1.type", "block"), "listed twice"
    ),
    "count 0": bad_instance(_set("tasks.0.parts.0.count", 0), "$.tasks[0].parts[0].count"),
    "count 1.5": bad_instance(_set("tasks.0.parts.0.count", 1.5), "parts[0].count"),
    "count as string": bad_instance(_set("tasks.0.parts.0.count", "2"), "parts[0].count"),
    "duplicate task id": bad_instance(_set("tasks.1.id", "t1"), "duplicate task id 't1'"),
    "@ in task id": bad_instance(_set("tasks.1.id", "t@2"), "$.tasks[1].id", "does not match"),
    "slash in task id": bad_instance(_set("tasks.1.id", "a/b"), "$.tasks[1].id"),
    "edge to unknown task": bad_instance(
        _set("precedence", [["q", "t1"]]), "$.precedence[0][0]: unknown task 'q'"
    ),
    "self edge": bad_instance(_set("precedence", [["t1", "t1"]]), "cannot precede itself"),
    "cycle": bad_instance(
        _set("precedence", [["t1", "t3"], ["t3", "t1"]]), "precedence cycle t1 -> t3 -> t1"
    ),
    "edge of three": bad_instance(_set("precedence", [["t1", "t2", "t3"]]), "$.precedence[0]"),
    "horizon 0": bad_instance(_set("horizon", 0), "$.horizon"),
    "units 0": bad_instance(_set("units", 0), "$.units"),
    "trays 0": bad_instance(_set("trays", 0), "$.trays"),
    "trays as word": bad_instance(_set("trays", "many"), "$.trays"),
    "rotatable as word": bad_instance(_set("part_types.0.rotatable", "yes"), "rotatable"),
    "robot_times unknown": bad_instance(_set("robot_times", "fast"), "$.robot_times"),
    "missing human time": bad_instance(_del("tasks.0.human_time"), "'human_time'"),
    # --- files that are not there or not files ------------------------------------------------
    "instance not found": row("solve {o}/none.json -m single-task", 2, "file not found"),
    "instance is a folder": row("solve {d} -m single-task", 2, "cannot read file", d=DIR),
    "solution not found": row("check {i} {o}/none.json", 2, "none.json: $: file not found"),
    # --- options: shared argument types -------------------------------------------------------
    "solve seed -1": row("solve {i} -m single-task --seed -1", 2, "--seed", "-1"),
    "solve seed word": row("solve {i} -m single-task --seed abc", 2, "--seed", "integer"),
    "solve seed 2^31": row("solve {i} -m single-task --seed 2147483648", 2, "--seed"),
    "compare seed -1": row("compare {i} --methods single-task --seed -1", 2, "--seed"),
    "generate seed -1": row("generate intree --size 4 --seed -1", 2, "--seed"),
    "simulate seed -1": row("simulate {i} --reps 1 --seed -1", 2, "--seed"),
    "pack seed -1": row("pack {p} --seed -1", 2, "--seed", p=pack_file(unchanged)),
    "repro seed -1": row("repro user-study --quick --seed -1 --out {o}/r", 2, "--seed"),
    "weights nan": row("solve {i} -m single-task --weights W3=nan", 2, "W3", "finite"),
    "weights inf": row("solve {i} -m single-task --weights W3=inf", 2, "W3", "finite"),
    "weights negative": row("solve {i} -m single-task --weights W4=-1", 2, "W4", ">= 0"),
    "weights word": row("solve {i} -m single-task --weights W3=abc", 2, "must be a number"),
    "weights unknown": row("solve {i} -m single-task --weights W9=1", 2, "unknown weight"),
    "weights no value": row("solve {i} -m single-task --weights W3", 2, "KEY=VALUE"),
    "check weights nan": row("check {i} {s} --weights W5=nan", 2, "W5", s=solution(unchanged)),
    "d negative": row("solve {i} -m single-task --d -1", 2, "--d"),
    "d inf": row("solve {i} -m single-task --d inf", 2, "--d"),
    "d 1e300": row("solve {i} -m single-task --d 1e300", 2, "$.delivery_time"),
    "horizon option 0": row("solve {i} -m single-task --horizon 0", 2, "--horizon"),
    "units option 0": row("solve {i} -m single-task --units 0", 2, "--units"),
    "trays option 0": row("solve {i} -m single-task --trays 0", 2, "--trays"),
    "time limit negative": row("solve {i} -m single-task --time-limit -1", 2, "--time-limit"),
    "time limit nan": row("solve {i} -m single-task --time-limit nan", 2, "--time-limit"),
    "unknown method": row("solve {i} -m nope", 2, "nope"),
    "missing method": row("solve {i}", 2, "--method"),
    "unknown option": row("solve {i} -m single-task -p foo=1", 2, "foo"),
    "param without value": row("solve {i} -m single-task -p foo", 2, "KEY=VALUE"),
    "cpsat hint unknown": row("solve {i} -m cpsat -p hint=foo --time-limit 5", 2, "hint"),
    "convergence kit 0": row("solve {i} -m single-task --convergence-kit 0", 2, "--convergence"),
    "convergence without trace": row(
        "solve {i} -m single-task --convergence {o}/c.png", 2, "records no CE trace"
    ),
    "unknown command": row("frobnicate", 2, "invalid choice"),
    "compare unknown method": row("compare {i} --methods single-task,nope", 2, "nope"),
    "compare param bad method": row(
        "compare {i} --methods single-task -p milp:foo=1", 2, "METHOD:KEY=VALUE"
    ),
    "compare param no colon": row("compare {i} --methods single-task -p foo=1", 2, "--param"),
    "compare bad instance": row(
        "compare {i} --methods single-task", 2, "duplicate key", i='{"a": 1, "a": 2}'
    ),
    # --- output paths: checked before any work, nothing written ------------------------------
    "solve out is a folder": row(SOLVE.replace("{o}/s.json", "{d}"), 2, "--out", "folder", d=DIR),
    "solve out under a file": row(
        "solve {i} -m single-task -o {f}/s.json", 2, "--out", "not a folder", f="x"
    ),
    "solve out missing": row("solve {i} -m single-task -o", 2, "--out"),
    "solve gantt bad after out": row(
        "solve {i} -m single-task -o {o}/s.json --gantt {d}", 2, "--gantt", d=DIR
    ),
    "solve tray under a file": row("solve {i} -m single-task --tray {f}/t.png", 2, "--tray", f="x"),
    "solve convergence folder": row(
        "solve {i} -m single-task --convergence {d}", 2, "--convergence", d=DIR
    ),
    "solve out twice": row(
        "solve {i} -m single-task --gantt {o}/a.png --tray {o}/a.png", 2, "--tray", "same file"
    ),
    "solve out deep under a file": row(
        "solve {i} -m single-task -o {f}/a/b/s.json", 2, "--out", "not a folder", f="x"
    ),
    "compare csv folder": row("compare {i} --methods single-task --csv {d}", 2, "--csv", d=DIR),
    "compare md under a file": row(
        "compare {i} --methods single-task --md {f}/t.md", 2, "--md", f="x"
    ),
    "compare figures is a file": row(
        "compare {i} --methods single-task --figures {f}", 2, "--figures", "not a folder", f="x"
    ),
    "compare cells is a file": row(
        "compare {i} --methods single-task --cells {f}", 2, "--cells", "not a folder", f="x"
    ),
    "compare cells under a file": row(
        "compare {i} --methods single-task --cells {f}/c", 2, "--cells", f="x"
    ),
    "schema out folder": row("schema --out {d}", 2, "--out", d=DIR),
    "schema solution out under a file": row("schema --solution --out {f}/x", 2, "--out", f="x"),
    "generate out folder": row("generate intree --size 4 --out {d}", 2, "--out", d=DIR),
    "simulate csv folder": row("simulate {i} --reps 1 --csv {d}", 2, "--csv", d=DIR),
    "pack out folder": row("pack {p} --out {d}", 2, "--out", d=DIR, p=pack_file(unchanged)),
    "pack png under a file": row(
        "pack {p} --png {f}/l.png", 2, "--png", f="x", p=pack_file(unchanged)
    ),
    "repro out is a file": row("repro user-study --quick --out {f}", 2, "--out", f="x"),
    "reach png folder": row("reach {i} --png {d}", 2, "--png", d=DIR),
    # --- pack ---------------------------------------------------------------------------------
    **{
        f"pack resolution {name}": row(
            f"pack {{p}} --resolution {value}", 2, "--resolution", p=pack_file(unchanged)
        )
        for name, value in (
            ("0", "0"),
            ("inf", "inf"),
            ("nan", "nan"),
            ("negative", "-1"),
            ("1e6", "1e6"),
        )
    },
    "pack coarse grid is not infeasible": row(
        "pack {p} --resolution 1000", 4, "no layout on the 1000 mm grid", p=pack_file(unchanged)
    ),
    "pack coarse grid, layout file": row(
        "pack {p} --resolution 30 --out {o}/l.json", 4, "not a proof", p=pack_file(unchanged)
    ),
    "pack tasks empty": row("pack {table} --tasks ,,", 2, "--tasks", "no task given"),
    "pack tasks twice": row("pack {table} --tasks foot1,foot1", 2, "given twice: foot1"),
    "pack tasks unknown": row("pack {table} --tasks foot1,nope", 2, "unknown task(s) nope"),
    "pack instance without tasks": row("pack {table}", 2, "needs --tasks"),
    "pack file with tasks": row("pack {p} --tasks a", 2, "--tasks applies", p=pack_file(unchanged)),
    "pack objective unknown": row(
        "pack {p} --objective best", 2, "--objective", p=pack_file(unchanged)
    ),
    "pack workers 0": row("pack {p} --workers 0", 2, "--workers", p=pack_file(unchanged)),
    "pack file without items": bad_pack(_del("items"), "missing required field 'items'"),
    "pack file duplicate key": row(
        "pack {p}", 2, "duplicate key 'width'", p='{"tray": {"width": 1, "width": 2}}'
    ),
    "pack item 1e-300 mm": bad_pack(_set("items.0.width", 1e-300), "$.items[0].width"),
    "pack tray 1e20 mm": bad_pack(_set("tray.width", 1e20), "$.tray.width"),
    "pack duplicate item id": bad_pack(
        _set("items", [{"id": "a", "width": 1, "height": 1}] * 2), "duplicate item id 'a'"
    ),
    "pack unknown field": bad_pack(_set("colour", 1), "unknown field"),
    "pack item count 0": bad_pack(_set("items.0.count", 0), "$.items[0].count"),
    "pack no items": bad_pack(_set("items", []), "$.items"),
    # --- generate -----------------------------------------------------------------------------
    "generate table tightness": row("generate table --size 1 --tightness 0.1", 2, "--tightness"),
    "generate mixed seed": row("generate mixed --size 1 --seed 3", 2, "--seed", "random"),
    "generate unsolvable": row(
        "generate intree --size 8 --tightness 50 --out {o}/g.json", 2, "no method can solve"
    ),
    "generate unknown family": row("generate pyramid --size 3", 2, "unknown family"),
    "generate size 0": row("generate intree --size 0", 2, "--size"),
    "generate tightness 0": row("generate intree --size 4 --tightness 0", 2, "--tightness"),
    "generate tightness nan": row("generate intree --size 4 --tightness nan", 2, "--tightness"),
    "generate tightness inf": row("generate intree --size 4 --tightness inf", 2, "--tightness"),
    # --- reach and simulate -------------------------------------------------------------------
    "reach kit without solution": row("reach {i} --kit 3", 2, "--kit needs --solution"),
    "reach resolution 0": row("reach {i} --resolution 0", 2, "--resolution"),
    "reach kit 0": row("reach {i} --kit 0 --solution {s}", 2, "--kit", s=solution(unchanged)),
    "simulate unknown mat type": row("simulate {i} --mat nope=1", 2, "unknown part type"),
    "simulate mat 0": row("simulate {i} --mat block=0", 2, "--mat"),
    "simulate reps 0": row("simulate {i} --reps 0", 2, "--reps"),
    "simulate mttf without feeders": row("simulate {i} --mttf 100", 2, "--mttf needs feeders"),
    # --- solution files: malformed (exit 2) ---------------------------------------------------
    "makespan as word": bad_solution(_set("metrics.makespan", "abc"), "$.metrics.makespan"),
    "makespan null": bad_solution(_set("metrics.makespan", None), "$.metrics.makespan"),
    "makespan as list": bad_solution(_set("metrics.makespan", [1]), "$.metrics.makespan"),
    "n_kits as string": bad_solution(_set("metrics.n_kits", "8"), "$.metrics.n_kits"),
    "n_kits fractional": bad_solution(_set("metrics.n_kits", 2.5), "$.metrics.n_kits"),
    "n_kits negative": bad_solution(_set("metrics.n_kits", -1), "$.metrics.n_kits"),
    "metrics without n_kits": bad_solution(_del("metrics.n_kits"), "'n_kits'"),
    "metrics unknown key": bad_solution(_set("metrics.speed", 1), "unknown field"),
    "one kit without arrive": bad_solution(
        _del("kits.0.arrive"), "$.kits[0]", "missing time field 'arrive'"
    ),
    "last kit without human_end": bad_solution(
        _del("kits.2.human_end"), "$.kits[2]", "'human_end'"
    ),
    "times on one kit only": bad_solution(
        _all(_strip_times, _set("kits.1.arrive", 9.0)), "$.kits[0]", "missing time field"
    ),
    "kit time as word": bad_solution(_set("kits.0.arrive", "x"), "$.kits[0].arrive"),
    "kit time NaN": row(
        CHECK,
        2,
        "finite",
        s=lambda: json.dumps(tiny_solution()).replace('"arrive": 4.0', '"arrive": NaN', 1),
    ),
    "kits not a list": bad_solution(_set("kits", {}), "$.kits"),
    "tasks not a list": bad_solution(_set("kits.0.tasks", "t1"), "$.kits[0].tasks"),
    "task not a string": bad_solution(_set("kits.0.tasks", [1]), "$.kits[0].tasks[0]"),
    "placement without x": bad_solution(_del("kits.0.layout.0.x"), "'x'"),
    "placement x as string": bad_solution(_set("kits.0.layout.0.x", "1"), "layout[0].x"),
    "placement unknown key": bad_solution(_set("kits.0.layout.0.z", 1), "unknown field"),
    "kit unknown key": bad_solution(_set("kits.0.colour", 1), "unknown field"),
    "status unknown word": bad_solution(_set("status", "great"), "$.status"),
    "wrong solution format": bad_solution(_set("format", "x"), "$.format"),
    "solution unknown key": bad_solution(_set("score", 1), "unknown field"),
    "objective as string": bad_solution(_set("objective", "400"), "$.objective"),
    "bound as list": bad_solution(_set("bound", [1]), "$.bound"),
    "seed negative": bad_solution(_set("seed", -1), "$.seed"),
    "gap negative": bad_solution(_set("gap", -0.1), "$.gap"),
    "wall time negative": bad_solution(_set("wall_time_s", -1), "$.wall_time_s"),
    "solution missing method": bad_solution(_del("method"), "'method'"),
    "solution duplicate key": row(
        CHECK,
        2,
        "duplicate key 'status'",
        s=lambda: json.dumps(tiny_solution())[:-1] + ', "status": "optimal"}',
    ),
    "solution malformed": row(CHECK, 2, "malformed JSON", s="{"),
    # --- solution files: claims the checker recomputes (exit 1) ------------------------------
    "objective and bound 400, optimal": invalid_solution(
        _all(_set("objective", 400), _set("bound", 400), _set("gap", 0), _set("status", "optimal")),
        "objective_mismatch",
        "bound_above_makespan",
    ),
    "objective off": invalid_solution(_set("objective", 25.0), "[objective_mismatch]"),
    "bound above makespan": invalid_solution(_set("bound", 30.0), "[bound_above_makespan]"),
    "gap zero": invalid_solution(_set("gap", 0.0), "[gap_mismatch]"),
    "gap null with a bound": invalid_solution(_set("gap", None), "[gap_mismatch]"),
    "optimal with a gap": invalid_solution(_set("status", "optimal"), "[status_mismatch]"),
    "optimal without bound": invalid_solution(
        _all(_set("status", "optimal"), _set("bound", None), _set("gap", None)),
        "[status_mismatch]",
    ),
    "infeasible with a plan": invalid_solution(_set("status", "infeasible"), "[status_mismatch]"),
    # issue 35, items 1, 2 and 4: every objective a status names is checked (the registry of
    # bilevel_kit/objectives.py), not the makespan alone
    **{
        f"{name} optimal without a bound": invalid_solution(
            _all(_set("status_objective", name), _set("status", "optimal")),
            f"[status_mismatch] status 'optimal' for {name} without a bound",
        )
        for name in ("human_idle", "sum_completion")
    },
    "J optimal without a bound": invalid_solution(
        _all(
            _set("status_objective", "J"),
            _set("status", "optimal"),
            _set("extra.plan_objective_J", -3.0),
        ),
        "[status_mismatch] status 'optimal' for J without a bound",
    ),
    "J optimal without its value": invalid_solution(
        _all(_set("status_objective", "J"), _set("status", "optimal")),
        "[status_mismatch] status 'optimal' for J without its value",
    ),
    **{
        f"human_idle value tampered to {v:g}": invalid_solution(
            _all(_set("status_objective", "human_idle"), _set("extra.objective_value", v)),
            f"[objective_mismatch] extra.objective_value {v:g} for human_idle, the plan's is 4",
        )
        for v in (1.0, 1e9, 0.0)
    },
    "sum_completion bound 1e9": invalid_solution(
        _all(_set("status_objective", "sum_completion"), _set("extra.objective_bound", 1e9)),
        "[bound_above_objective] bound 1e+09 on sum_completion is above its value 25.5",
    ),
    "human_idle optimal, bound 1": invalid_solution(
        _all(
            _set("status_objective", "human_idle"),
            _set("status", "optimal"),
            _set("extra.objective_bound", 1.0),
        ),
        "[status_mismatch] status 'optimal' but human_idle 4 is above its bound 1",
    ),
    "human_idle gap 0 with a bound 1": invalid_solution(
        _all(
            _set("status_objective", "human_idle"),
            _set("extra.objective_bound", 1.0),
            _set("extra.objective_gap", 0.0),
        ),
        "[gap_mismatch] human_idle gap 0, recomputed from its value and bound: 0.75",
    ),
    "J gap tampered": invalid_solution(
        _all(
            _set("status_objective", "J"),
            _set("extra.plan_objective_J", -3.0),
            _set("extra.plan_objective_J_bound", -5.0),
            _set("extra.plan_objective_J_gap", 0.0),
        ),
        "[gap_mismatch] J gap 0, recomputed from its value and bound: 0.666667",
    ),
    "objective_value a string": invalid_solution(
        _all(_set("status_objective", "human_idle"), _set("extra.objective_value", "4")),
        "[bad_number] $.extra.objective_value: '4' is not a number",
    ),
    "makespan off": invalid_solution(_set("metrics.makespan", 20.0), "[times_inconsistent]"),
    "n_kits off": invalid_solution(_set("metrics.n_kits", 8), "reported n_kits 8"),
    "idle off": invalid_solution(_set("metrics.human_idle", 0.0), "reported human_idle"),
    "human_end off": invalid_solution(_set("kits.1.human_end", 20.0), "kit 2: reported human_end"),
    "no times, kits swapped": invalid_solution(
        _all(_strip_times, lambda d: d["kits"].reverse()), "[precedence]"
    ),
    "part outside the tray": invalid_solution(_set("kits.0.layout.0.x", 110.0), "[outside_tray]"),
    "part drawn wrong size": invalid_solution(
        _set("kits.0.layout.0.w", 40.0), "[footprint_mismatch]"
    ),
    "unknown task in kit": invalid_solution(_set("kits.0.tasks", ["t9"]), "[unknown_task]"),
    "task twice": invalid_solution(_set("kits.1.tasks", ["t2", "t1"]), "[repeated_task]"),
    "kit dropped": invalid_solution(
        _all(_strip_times, _set("objective", None), lambda d: d["kits"].pop()),
        "[missing_task]",
    ),
    "empty kit": invalid_solution(
        _all(_strip_times, lambda d: d["kits"].append({"tasks": [], "layout": []})), "[empty_kit]"
    ),
}


# --- issue 23, items 1 and 4 (claims of the exact models, the checker's numbers) -----------
# Kept in a block of their own: another change adds rows to ROWS above.

BIG = int("9" * 400)


def _claims_optimal(doc: Doc) -> None:
    """The tiny single-task solution claimed optimal with a bound equal to its makespan (the
    claim is wrong, but consistent in itself: what is checked is the objective's name)."""
    doc.update(status="optimal", bound=doc["objective"], gap=0.0)


def offgrid_text(side: float = 50.25, tray: float = 100.5) -> str:
    """The off-grid instance as a file's text: one kit on the exact 0.75 mm grid, none on the
    1 mm grid (tests/offgrid_example.py)."""
    return json.dumps(offgrid_doc(side, tray))


ISSUE_23A_ROWS: dict[str, Row] = {
    **{
        f"status_objective {name!r} with optimal": invalid_solution(
            _all(_claims_optimal, _set("status_objective", name)),
            "[status_mismatch]",
            "names no known objective",
        )
        for name in ("", "banana", "J ", "Makespan")
    },
    **{
        f"400-digit integer in {path}": invalid_solution(
            _set(path, BIG), "[bad_number]", "a 400-digit integer is out of range"
        )
        for path in (
            "objective",
            "bound",
            "gap",
            "metrics.makespan",
            "metrics.human_idle",
            "metrics.n_kits",
            "kits.0.robot_start",
            "kits.2.human_end",
            "kits.0.layout.0.x",
            "kits.0.layout.0.y",
            "kits.0.layout.0.theta",
            "kits.0.layout.0.w",
            "kits.0.layout.0.h",
            "timeline_params.delivery_time",
            "timeline_params.kit_overhead.robot",
            "timeline_params.trays",
        )
    },
    "negative 400-digit coordinate": invalid_solution(
        _set("kits.1.layout.0.y", -BIG), "[bad_number] $.kits[1].layout[0].y"
    ),
    "coordinate 1e300": invalid_solution(
        _set("kits.0.layout.0.x", 1e300), "[bad_number] $.kits[0].layout[0].x: 1e+300"
    ),
    "kit time -1e300": invalid_solution(_set("kits.1.arrive", -1e300), "[bad_number]"),
    "objective 1e300 optimal": invalid_solution(
        _all(_claims_optimal, _set("objective", 1e300)), "[bad_number] $.objective"
    ),
    "cpsat off the packing grid": row(
        "solve {i} -m cpsat --time-limit 20 --check -q",
        0,
        "optimal",
        "makespan 46.00",
        i=offgrid_text(),
    ),
    "cpsat without an exact grid": row(  # fallback=none: the model's own plan, no LNS first
        "solve {i} -m cpsat -p hint=none -p fallback=none --time-limit 20 --check -q",
        0,
        "feasible",
        "makespan 56.00",
        "bound 46.00",
        i=offgrid_text(50.1234567, 100.2469134),
    ),
    "cpsat without an exact grid, the LNS first meets the bound": row(
        "solve {i} -m cpsat -p hint=none --time-limit 20 --check -q",
        0,
        "optimal",  # proven by the closed-form bound the LNS's plan meets, not by the model
        "makespan 46.00",
        "bound 46.00",
        i=offgrid_text(50.1234567, 100.2469134),
    ),
    "cpsat coarse packing grid": row(
        "solve {table} -m cpsat -p pack_resolution=160 --time-limit 30 --check -q",
        0,
        "optimal",
        "makespan 435.08",
    ),
}
ROWS.update(ISSUE_23A_ROWS)


# --- issue 23, items 3, 5, 6, 7 (outputs, tracebacks, sizes, small items) -------------------
# A block of its own, like the one above.

#: A FIFO to create instead of a file (reading one blocked forever).
FIFO = object()


def argv_row(argv: list[str], code: int, *words: str, **files: Any) -> Row:
    """A row whose arguments may be empty or hold spaces (``--methods ""``)."""
    return Row(tuple(argv), code, words, {"i": tiny_text, **files})


SOLVE_TO = "solve {i} -m single-task -o {o}/s.json"
SURROGATE_NAME = tiny_text().replace('"name": "tiny"', '"name": "tiny\\ud800"')
WORK_CELL = {"bins": {"block": [0.6, 0.3, 0.0], "wheel": [0.6, -0.3, 0.0]}}

ISSUE_23B_ROWS: dict[str, Row] = {
    # item 3: outputs never clobber, checked before any work
    "out is the input instance": row(
        "solve {i} -m single-task -o {i}", 2, "--out", "the same file as the input instance"
    ),
    "out a/../y.png is the gantt y.png": row(
        "solve {i} -m single-task -o {o}/a/../y.png --gantt {o}/y.png", 2, "--gantt", "--out"
    ),
    "tray ./x.png is the gantt x.png": row(
        "solve {i} -m single-task --tray {o}/./x.png --gantt {o}/x.png", 2, "same file"
    ),
    "out in /proc": row("solve {i} -m single-task -o /proc/x.json", 2, "--out", "/proc"),
    "out is /proc/version": row("solve {i} -m single-task -o /proc/version", 2, "--out"),
    "gantt g.xyz before out": row(
        SOLVE_TO + " --gantt {o}/g.xyz", 2, "--gantt", "unknown figure format '.xyz'"
    ),
    "tray t.docx": row(SOLVE_TO + " --tray {o}/t.docx", 2, "--tray", "figure format"),
    "convergence c.txt": row(
        "solve {i} -m greedy-ce --convergence {o}/c.txt", 2, "--convergence", "'.txt'"
    ),
    "pack png l.bmp": row(
        "pack {p} --out {o}/l.json --png {o}/l.bmp", 2, "--png", "'.bmp'", p=pack_file(unchanged)
    ),
    "pack out is the pack file": row(
        "pack {p} --out {p}", 2, "--out", "the input file", p=pack_file(unchanged)
    ),
    "pack out is the png": row(
        "pack {p} --out {o}/l.png --png {o}/l.png", 2, "--png", "--out", p=pack_file(unchanged)
    ),
    "reach png r.xyz": row("reach {i} --png {o}/r.xyz", 2, "--png", "figure format"),
    "compare csv is the instance": row(
        "compare {i} --methods single-task --csv {i}", 2, "--csv", "input instances"
    ),
    "compare md is the csv": row(
        "compare {i} --methods single-task --csv {o}/t --md {o}/./t", 2, "--md", "--csv"
    ),
    "simulate csv is the instance": row("simulate {i} --reps 1 --csv {i}", 2, "--csv", "input"),
    # item 5: tracebacks, now one line each, decided before the work
    "milp time limit 1e9": row("solve {i} -m milp --time-limit 1e9", 2, "--time-limit", "1e9"),
    "compare time limit 1e7": row(
        "compare {i} --methods single-task --time-limit 1e7", 2, "--time-limit"
    ),
    "cpsat pack_resolution 1e-12": row(
        "solve {i} -m cpsat -p pack_resolution=1e-12", 2, "'pack_resolution'", ">= 0.01"
    ),
    "cpsat time_resolution 1e-9": row(
        "solve {i} -m cpsat -p time_resolution=1e-9", 2, "'time_resolution'"
    ),
    "5,000-digit integer in an instance": raw_instance(
        tiny_text().replace('"delivery_time": 1.0', '"delivery_time": ' + "7" * 5000),
        "$.delivery_time",
        "an integer of 5000 digits",
    ),
    "400-digit integer in trays": bad_instance(
        _set("trays", int("9" * 400)), "$.trays", "400 digits"
    ),
    "400-digit work cell coordinate": bad_instance(
        _set("work_cell", {"tray_pose": {"x": -int("9" * 400)}}), "$.work_cell.tray_pose.x", "400"
    ),
    "name with a lone surrogate": raw_instance(SURROGATE_NAME, "$.name", "not valid Unicode"),
    "key with a lone surrogate": raw_instance(
        tiny_text().replace('"name": "tiny"', '"name": "tiny", "\\udfff": 1'), "not valid Unicode"
    ),
    "reach_resolution 0.01 with reachability": bad_instance(
        _all(_set("reachability", True), _set("reach_resolution", 0.01)),
        "$.reach_resolution",
        "120,000,000 cells",
    ),
    "reach --resolution 0.01": row("reach {i} --resolution 0.01", 2, "--resolution", "cells"),
    "units 1e9": bad_instance(_set("units", 10**9), "$.units"),
    "units 70,000 of three tasks": bad_instance(_set("units", 70_000), "$.units", "210,000"),
    "--units 100000000": row(SOLVE + " --units 100000000", 2, "$.units", "above the limit"),
    "part count 1e6": bad_instance(_set("tasks.0.parts.0.count", 10**6), "$.tasks[0]"),
    "horizon 1e6": bad_instance(_set("horizon", 10**6), "$.horizon"),
    "pack item count 1e7": bad_pack(_set("items.0.count", 10**7), "$.items[0].count"),
    "pack 4,004 parts in all": bad_pack(
        lambda d: d["items"].extend(
            {"id": f"x{k}", "width": 1, "height": 1, "count": 1000} for k in range(4)
        ),
        "$.items",
        "4,004 parts in all",
    ),
    "compare scheduler garbage": row(
        "compare {i} --methods single-task --scheduler garbage", 2, "--scheduler", "HOST:PORT"
    ),
    "compare scheduler without a port": row(
        "compare {i} --methods single-task --scheduler tcp://localhost", 2, "--scheduler"
    ),
    # item 7: the smaller items
    "part type id with a trailing newline": bad_instance(
        _all(_set("part_types.0.id", "block\n")), "$.part_types[0].id"
    ),
    "task id with a trailing newline": bad_instance(_set("tasks.0.id", "t1\n"), "$.tasks[0].id"),
    "pack item id with a trailing newline": bad_pack(_set("items.0.id", "sq\n"), "$.items[0].id"),
    "work cell bin of an unknown part type": bad_instance(
        _set("work_cell", WORK_CELL), "$.work_cell.bins.wheel", "unknown part type 'wheel'"
    ),
    **{
        f"greedy-ce {opt}=-1": row(f"solve {{i}} -m greedy-ce -p {opt}=-1", 2, f"'{opt}'", ">= 0")
        for opt in ("tol", "out_weight", "restart_sd_scale")
    },
    # item 6: options whose cost no time limit bounds, refused up front
    "greedy-ce samples 1e6": row(
        "solve {i} -m greedy-ce -p samples=1000000 --time-limit 2", 2, "'samples'", "<= 20000"
    ),
    "greedy-ce enumerate at horizon 12": row(
        "solve {table} -m greedy-ce -p horizon=12 -p decision=enumerate --time-limit 2",
        2,
        "more than 200,000 partial sequences",
    ),
    "greedy-ce set-up longer than the limit": row(
        "solve {i} -m greedy-ce --units 20000 --time-limit 2",
        2,
        "--time-limit 2 s is shorter than greedy-ce's set-up for 60,000 tasks",
        "give at least 11 s",
    ),
    # issue 35, item 8: a CE cap whose trace alone outgrows memory, refused with its range
    "greedy-ce max_iter 1e7": row(
        "solve {i} -m greedy-ce -p max_iter=10000000 --time-limit 2", 2, "'max_iter'", "1000000"
    ),
    "greedy-ce patience 1e7": row(
        "solve {i} -m greedy-ce -p patience=10000000", 2, "'patience'", "1000000"
    ),
    "pack 10,000 parts": bad_pack(_set("items.0.count", 10_000), "$.items[0].count"),
    "compare --methods empty": argv_row(
        ["compare", "{i}", "--methods", ""], 2, "--methods", "at least one"
    ),
    "compare --methods comma": row("compare {i} --methods ,", 2, "--methods"),
    "compare repeated method": row(
        "compare {i} --methods single-task,single-task", 2, "'single-task' is named twice"
    ),
    "compare bad -p before any cell": row(
        "compare {i} --methods single-task,cpsat -p cpsat:bogus=1 --cells {o}/c",
        2,
        "unknown option 'bogus'",
    ),
    "compare -p of a method not run": row(
        "compare {i} --methods single-task -p cpsat:workers=2", 2, "--param"
    ),
    "instance is a FIFO": row("solve {q} -m single-task", 2, "{q}", "not a regular file", q=FIFO),
    "instance is /dev/null": row("solve /dev/null -m single-task", 2, "not a regular file"),
    "solve time limit 0": row("solve {i} -m cpsat --time-limit 0", 2, "--time-limit", "> 0"),
    "pack time limit 0": row(
        "pack {p} --time-limit 0", 2, "--time-limit", "> 0", p=pack_file(unchanged)
    ),
}
ROWS.update(ISSUE_23B_ROWS)


# --- issue 35, items 3, 5, 9 (outputs a command names itself, sizes, small items) ---------
# A block of its own, like the ones above.


@dataclass(frozen=True)
class Tree:
    """A folder to build instead of a file: ``build(path)`` fills it."""

    build: Callable[[Path], None]


def _library(bom: bool = False) -> Tree:
    """A KitBench library without records (``bom``: its index starts with a UTF-8 BOM)."""

    def build(path: Path) -> None:
        from bilevel_kit.experiments.kitbench.library import Library

        path.mkdir()
        Library(path).write([])
        index = path / "index.csv"
        index.write_bytes(b"\xef\xbb\xbf" * bom + index.read_bytes())

    return Tree(build)


def _run_folder(cell: str) -> Tree:
    """A bench run folder holding one cell file of text ``cell``."""

    def build(path: Path) -> None:
        (path / "cells").mkdir(parents=True)
        (path / "cells" / "c.json").write_text(cell)

    return Tree(build)


def _bags(name: str, content: bytes) -> Tree:
    """A ``--bag`` folder already holding ``name`` with ``content``."""

    def build(path: Path) -> None:
        path.mkdir()
        (path / name).write_bytes(content)

    return Tree(build)


ROSBAG = b"#ROSBAG V2.0\n" + b"\0" * 64
PNG = b"\x89PNG\r\n\x1a\n" + b"\0" * 64
HTML = b"<!DOCTYPE html><html></html>\n"
ONE_STATION = instance(_set("stations", [{"id": "S1", "serves": ["tiny"]}]))

ISSUE_35_ROWS: dict[str, Row] = {
    # item 3: every output a command writes is declared and checked up front
    "execute --html is its own ROS 1 bag": row(
        "execute {i} {s} --bag {o}/b --html {o}/b/tiny.bag",
        2,
        "--html",
        "ROS 1 bag {o}/b/tiny.bag",
        s=solution(unchanged),
    ),
    "execute --html inside its ROS 2 bag": row(
        "execute {i} {s} --bag {o}/b --html {o}/b/tiny_ros2/v.html",
        2,
        "--html",
        "replaced as a whole",
        s=solution(unchanged),
    ),
    "execute --html over a ROS 1 bag": row(
        "execute {i} {s} --format ros1 --bag {o}/b --html {x}",
        2,
        "--html {x}",
        "exists and is a ROS 1 bag",
        s=solution(unchanged),
        x=ROSBAG,
    ),
    "execute bag over an HTML page": row(
        "execute {i} {s} --format ros1 --bag {b}",
        2,
        "--bag {b}",
        "exists and is an HTML page",
        s=solution(unchanged),
        b=_bags("tiny.bag", HTML),
    ),
    "execute kit bag is the --html": row(
        "execute {i} {s} --kit 1 --bag {o}/b --format ros1 --html {o}/b/tiny_kit1.bag",
        2,
        "tiny_kit1.bag",
        "the same file as --html",
        s=solution(unchanged),
    ),
    "compare --csv is one of its figures": row(
        "compare {i} --methods single-task --figures {o}/f --csv {o}/f/tiny_compare.png",
        2,
        "its figure tiny_compare.png",
        "the same file as --csv",
    ),
    "compare --md is a method's Gantt chart": row(
        "compare {i} --methods single-task --figures {o}/f --md {o}/f/tiny_single-task_gantt.png",
        2,
        "--md",
    ),
    "solve -o over a PNG": row(
        "solve {i} -m single-task -o {x}", 2, "--out {x}", "exists and is a PNG image", x=PNG
    ),
    "solve --gantt over a ROS 1 bag": row(
        "solve {i} -m single-task --gantt {x}", 2, "--gantt", "a ROS 1 bag", x=ROSBAG
    ),
    # item 5: sizes checked before building, with the range
    "generate table on 1e9 stations": row(
        "generate table --size 1 --stations 1000000000", 2, "--stations", "[1, 16,666]"
    ),
    "generate table on 1e6 stations": row(
        "generate table --size 1 --stations 1000000", 2, "--stations", "above the limit"
    ),
    "generate intree of 1e7 tasks": row(
        "generate intree --size 10000000", 2, "--size", "[1, 200,000] tasks"
    ),
    "generate sparse on 1e6 stations": row(
        "generate sparse --size 3 --stations 1000000", 2, "--stations", "[1, 66,666]"
    ),
    "generate mixed of 1e5 units on 3 stations": row(
        "generate mixed --size 100000 --stations 3", 2, "--size", "[1, 2,564] units"
    ),
    "generate stool of 1e9 units": row("generate stool --size 1000000000", 2, "--size", "stool"),
    # item 9: the smaller ones
    "solution overrides units 1e8": bad_solution(
        _set("overrides", {"units": 100_000_000}), "$.overrides.units", "above the limit"
    ),
    "solution overrides trays 0": bad_solution(_set("overrides", {"trays": 0}), "$.overrides"),
    "check override clash has the prefix": row(
        "check {i} {s} --units 3",
        2,
        "bilevel-kit check: error: {s}: $.overrides.units",
        s=solution(_set("overrides", {"units": 2})),
    ),
    "bench update bare NaN bound": row(
        "bench update {r} --library {l}",
        2,
        "{r}/cells/c.json: $.bound",
        "finite",
        l=_library(),
        r=_run_folder('{"format": "kitbench-cell/1", "bound": NaN}'),
    ),
    "bench update cell not an object": row(
        "bench update {r} --library {l}",
        2,
        "not a bench cell record",
        l=_library(),
        r=_run_folder("[1, 2]"),
    ),
    "bench verify index with a BOM": row(
        "bench verify --library {l}", 0, "0 records", "all hold", l=_library(bom=True)
    ),
    **{
        f"serves {key!r}": bad_instance(
            _set("stations", [{"id": "S1", "serves": [key]}]), "$.stations[0].serves[0]"
        )
        for key in ("tiny@", "tiny@01", "tiny@1\n", "tiny@\uff11", "@1")
    },
    # one declared station is the S = 1 case (docs/timeline.md#several-stations): its sum of
    # completions is the makespan, solved and reported as without the stations list
    "one station sum_completion is the makespan": row(
        "solve {i} -m cpsat -p objective=sum_completion --time-limit 20 -q",
        0,
        "tiny: cpsat optimal",
        "bound 25.00 s  gap 0.00%",
        "station S1: completion 25.00 s",
        i=ONE_STATION,
    ),
    # item 1: a station's first kit waits for no tray (tests/models/test_milp_stations.py)
    "milp sum of completions with a station's first kit second": row(
        "solve {i} -m milp -p objective=sum_completion --time-limit 60 -q",
        0,
        "sum_completion: optimal  62.00 s  bound 62.00 s  gap 0.00%",
        i=json.dumps(first_tray_doc()),
    ),
}
ROWS.update(ISSUE_35_ROWS)


def _snapshot(folder: Path) -> dict[str, tuple[int, int]]:
    """Every path under ``folder`` with its size and mtime (what "nothing written" compares)."""
    out = {}
    for path in sorted(folder.rglob("*")):
        st = path.stat()
        out[str(path.relative_to(folder))] = (st.st_size if path.is_file() else -1, st.st_mtime_ns)
    return out


def test_at_least_a_hundred_rows() -> None:
    assert len(ROWS) >= 100


@pytest.mark.parametrize("name", list(ROWS))
def test_edge(name: str, tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch) -> None:
    case = ROWS[name]
    inputs, outputs = tmp_path / "in", tmp_path / "out"
    inputs.mkdir()
    outputs.mkdir()
    places = {"o": str(outputs), "table": str(TABLE)}
    for key, content in case.files.items():
        path = inputs / key
        places[key] = str(path)
        if content is DIR:
            path.mkdir()
            continue
        if content is FIFO:
            os.mkfifo(path)
            continue
        if isinstance(content, Tree):
            content.build(path)
            continue
        if isinstance(content, bytes):
            path.write_bytes(content)
            continue
        text = content() if callable(content) else content
        if "\udcff" in text:
            path.write_bytes(b"\xff\xfe{")
        else:
            path.write_text(text)
    monkeypatch.chdir(tmp_path)  # a default output folder would land here
    argv = [a.format(**places) for a in case.argv]
    before = _snapshot(tmp_path)
    code = main(argv)
    out, err = capsys.readouterr()
    assert code == case.code, f"{argv}: exit {code}\nstdout: {out}\nstderr: {err}"
    assert "Traceback" not in out + err
    words = [w.format(**places) for w in case.words]
    if code == 2:
        assert err.count("\n") == 1, err
        assert all(w in err for w in words), (words, err)
        assert _snapshot(tmp_path) == before, "a failed command wrote something"
    else:
        assert all(w in out + err for w in words), (words, out, err)
        written = set(_snapshot(tmp_path)) - set(before)
        assert all(p.startswith("out") for p in written), written


def test_unwritable_folder_is_refused_before_any_work(tmp_path, capsys) -> None:
    if os.geteuid() == 0:
        pytest.skip("root may write everywhere")
    locked = tmp_path / "locked"
    locked.mkdir(mode=0o500)
    code = main(["solve", str(TINY), "-m", "single-task", "-o", str(locked / "s.json")])
    assert code == 2 and "permission denied" in capsys.readouterr().err


def test_written_files_honour_the_umask(tmp_path, capsys) -> None:
    old = os.umask(0o022)
    try:
        assert main(["solve", str(TINY), "-m", "single-task", "-o", str(tmp_path / "s.json")]) == 0
        assert main(["schema", "--out", str(tmp_path / "x.json")]) == 0
    finally:
        os.umask(old)
    for name in ("s.json", "x.json"):
        assert (tmp_path / name).stat().st_mode & 0o777 == 0o644


def test_instance_name_never_leaves_the_figures_folder(tmp_path, capsys) -> None:
    doc = tiny_doc() | {"name": "../../evil/x"}
    path = tmp_path / "i.json"
    path.write_text(json.dumps(doc))
    figures = tmp_path / "a" / "b" / "figs"
    code = main(["compare", str(path), "--methods", "single-task", "--figures", str(figures)])
    assert code == 0
    written = sorted(p.relative_to(tmp_path) for p in tmp_path.rglob("*.png"))
    assert written and all(p.parts[:3] == ("a", "b", "figs") for p in written), written
    assert not (tmp_path / "evil").exists()


def test_safe_name() -> None:
    from bilevel_kit.paths import safe_name

    assert safe_name("../../evil/x") == "evil_x"
    assert safe_name("/etc/passwd") == "etc_passwd"
    assert safe_name("..") == "unnamed"
    assert safe_name("table_u2") == "table_u2"
    assert "/" not in safe_name("a/" * 200) and len(safe_name("a" * 500)) == 100


def test_coarse_grid_layout_file_says_no_grid_layout(tmp_path, capsys) -> None:
    pack = tmp_path / "p.json"
    pack.write_text(json.dumps(PACK_DOC))
    out = tmp_path / "l.json"
    assert main(["pack", str(pack), "--resolution", "30", "--out", str(out)]) == 4
    assert json.loads(out.read_text())["status"] == "no_grid_layout"
    # the same parts on the exact 1 mm grid: they fit
    assert main(["pack", str(pack), "--out", str(out)]) == 0
    assert json.loads(out.read_text())["status"] == "feasible"
    # more part area than tray area is a proof at any grid
    too_many = PACK_DOC | {"items": [{"id": "sq", "width": 50, "height": 50, "count": 5}]}
    pack.write_text(json.dumps(too_many))
    assert main(["pack", str(pack), "--resolution", "30"]) == 0
    assert ": infeasible in" in capsys.readouterr().out


def test_a_230_character_instance_file_name_is_a_cell_file(tmp_path, capsys) -> None:
    path = tmp_path / ("a" * 230 + ".json")
    path.write_text(tiny_text())
    argv = ["compare", str(path), "--methods", "single-task", "--cells", str(tmp_path / "c")]
    assert main(argv) == 0
    (cell,) = (tmp_path / "c").iterdir()
    assert len(cell.name) <= 180 and cell.name.startswith("a" * 100)
    assert main(argv) == 0  # resumed from the hashed name
    assert "0 done, 1 skipped" in capsys.readouterr().err


@pytest.mark.parametrize("text", ["", "[1]", "{", "null"])
def test_a_cell_file_that_is_no_record_is_exit_2(text, tmp_path, capsys) -> None:
    argv = ["compare", str(TINY), "--methods", "single-task", "--cells", str(tmp_path / "c")]
    assert main(argv) == 0
    (cell,) = (tmp_path / "c").iterdir()
    cell.write_text(text)
    capsys.readouterr()
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "not a saved cell" in err and "Traceback" not in err
    assert cell.read_text() == text


def test_a_device_output_is_written_in_place(tmp_path, capsys) -> None:
    assert main(["solve", str(TINY), "-m", "single-task", "-o", "/dev/null"]) == 0
    assert Path("/dev/null").is_char_device()
