"""The checker cannot be crashed or fooled (issue 23, item 4), and results are held to their
claims: one strict reader for every number of a solution file, the ``objective`` named a
known objective, the overlap test as a grid hash (the same answers as comparing every pair),
``solve --check`` checking a fresh result's status and bound, and ``compare`` a bound against
every valid plan of the comparison."""

from __future__ import annotations

import copy
import json
import random

import pytest

from bilevel_kit import geometry, solution, solve
from bilevel_kit.methods import MethodOutput, Status
from bilevel_kit.plan import Placement
from bilevel_kit.solution import result_to_dict

BIG = int("9" * 400)


@pytest.fixture(scope="module")
def doc(tiny):
    return json.loads(json.dumps(result_to_dict(solve(tiny, "single-task"))))


def _check(tiny, doc):
    return solution.from_dict(doc).check(tiny)


def _set(doc, path, value):
    out = copy.deepcopy(doc)
    obj = out
    keys = [int(k) if k.isdigit() else k for k in path.split(".")]
    for k in keys[:-1]:
        obj = obj[k]
    obj[keys[-1]] = value
    return out


@pytest.mark.parametrize(
    "path",
    [
        "objective.value",
        "objective.bound",
        "objective.gap",
        "metrics.makespan",
        "metrics.n_kits",
        "kits.0.arrive",
        "kits.1.layout.0.x",
        "kits.1.layout.0.theta",
        "kits.0.layout.0.w",
        "timeline_params.delivery_time",
        "timeline_params.kit_overhead.human",
    ],
)
@pytest.mark.parametrize("value", [BIG, -BIG, 1e300], ids=["big", "-big", "1e300"])
def test_huge_numbers_are_violations_never_exceptions(tiny, doc, path, value):
    changed = _set(doc, path, value)
    if value < 0 and path.split(".")[-1] in ("gap", "n_kits", "delivery_time", "human"):
        with pytest.raises(solution.SolutionError):
            solution.from_dict(changed)  # the schema's minimum: malformed, exit 2
        return
    found = _check(tiny, changed)
    bad = [v for v in found if v.kind == "bad_number"]
    assert len(bad) == 1, found
    where = "$." + ".".join(f"[{k}]" if k.isdigit() else k for k in path.split("."))
    assert bad[0].message.startswith(where.replace(".[", "[")), bad[0].message
    # nothing is checked against a refused number: no follow-up violation about it
    assert [v.kind for v in found if v.kind != "bad_number"] in ([], ["outside_tray"]), found


def test_a_400_digit_integer_reads_as_out_of_range(tiny, doc):
    found = _check(tiny, _set(doc, "objective.value", BIG))
    assert "a 400-digit integer is out of range" in found[0].message


@pytest.mark.parametrize("name", ["", "banana", "J ", "Makespan"])
def test_status_objective_must_name_a_known_objective(tiny, doc, name):
    value = doc["objective"]["value"]
    opt = _set(_set(doc, "status", "optimal"), "objective", {"name": "makespan", "value": value})
    opt = _set(_set(opt, "objective.bound", value), "objective.gap", 0.0)
    opt = _set(opt, "makespan", {"value": value, "bound": value, "gap": 0.0})
    assert _check(tiny, opt) == []
    found = _check(tiny, _set(opt, "objective.name", name))
    assert [v.kind for v in found] == ["status_mismatch"]
    assert f"status_objective {name!r} names no known objective" in found[0].message


def test_known_objectives_are_accepted(tiny, doc):
    for name in ("makespan", "human_idle", "J"):
        assert _check(tiny, _set(doc, "objective", {"name": name})) == []  # no numbers stated


# ---------------------------------------------------------------------------------------------
# the overlap test: a grid hash with the answers of every pair
# ---------------------------------------------------------------------------------------------


def _random_layout(rng: random.Random, n: int, width: float) -> list[Placement]:
    scale = rng.choice([1.0, 5.0, 30.0])
    out = []
    for k in range(n):
        big = 10.0 if rng.random() < 0.05 else 1.0
        out.append(
            Placement(
                f"p{k}",
                "t",
                rng.uniform(0, width),
                rng.uniform(0, width),
                rng.choice([0.0, 90.0, rng.uniform(0, 360)]),
                rng.uniform(0.5, 3.0) * scale * big,
                rng.uniform(0.5, 3.0) * scale,
            )
        )
    return out


@pytest.mark.parametrize("seed", range(40))
def test_grid_hash_finds_exactly_the_pairs_of_the_full_comparison(seed, monkeypatch):
    rng = random.Random(seed)
    n = rng.randint(2, 160)
    width = rng.choice([100.0, 300.0, 1000.0])
    parts = _random_layout(rng, n, width)
    if seed % 4 == 0:  # touching parts on a grid: near pairs that do not overlap
        parts = [
            Placement(f"p{k}", "t", 5 + 10 * (k % 20), 5 + 10 * (k // 20), 90.0 * (k % 2), 10, 10)
            for k in range(n)
        ]
    monkeypatch.setattr(geometry, "SMALL_LAYOUT", 10**9)
    every = geometry.layout_violations(parts, width, width)
    monkeypatch.setattr(geometry, "SMALL_LAYOUT", 1)
    monkeypatch.setattr(geometry, "PAIR_BLOCK", rng.choice([64, 500, 100_000]))
    hashed = geometry.layout_violations(parts, width, width)
    assert [(f.kind, f.index, f.other) for f in hashed] == [
        (f.kind, f.index, f.other) for f in every
    ]
    for a, b in zip(hashed, every, strict=True):
        assert a.depth == b.depth and a.area == b.area


def test_a_dense_valid_kit_is_valid_and_one_moved_part_is_found():
    """3,000 parts of 10 x 6 mm, each in its own 12 mm cell at 0, 30, 45 or 90 degrees (the
    benchmark's dense kit, bench/bench_check.py): valid; one part moved onto its neighbour is
    the only overlap."""
    side = 55
    parts = [
        Placement(
            f"p{j}",
            "t",
            (j % side + 0.5) * 12,
            (j // side + 0.5) * 12,
            (0, 30, 45, 90)[j % 4],
            10,
            6,
        )
        for j in range(3000)
    ]
    assert geometry.layout_violations(parts, side * 12, side * 12) == []
    moved = list(parts)
    moved[1234] = Placement("p1234", "t", parts[1235].x - 3, parts[1235].y, 0, 10, 6)
    found = geometry.layout_violations(moved, side * 12, side * 12)
    assert [(f.kind, f.index, f.other) for f in found] == [("overlap", 1234, 1235)]


def test_a_stack_of_parts_stops_at_the_limit():
    """20,000 parts on one spot: 2e8 overlapping pairs; the checker lists the first and stops."""
    parts = [Placement(f"p{j}", "t", 50, 50, 0, 10, 10) for j in range(20_000)]
    found = geometry.layout_violations(parts, 100, 100, limit=101)
    assert len(found) == 101 and all(f.kind == "overlap" for f in found)


# ---------------------------------------------------------------------------------------------
# fresh results are held to their claims: solve --check and compare
# ---------------------------------------------------------------------------------------------


def boastful(instance, options, *, seed=0, time_limit=None):
    """Whole-assembly's plan, claimed optimal with a bound of 28 s (its makespan is 32.5 s,
    single-task's valid plan 25.5 s on the tiny instance)."""
    from bilevel_kit.heuristics.baselines import whole_assembly

    plan = whole_assembly(instance).plan
    return MethodOutput(plan, Status(options.status), 28.0)


@pytest.fixture(scope="module")
def registered():
    from dataclasses import dataclass, field

    from bilevel_kit import methods

    @dataclass(frozen=True)
    class BoastOptions:
        status: str = field(default="optimal", metadata={"help": "the status claimed"})

    import sys

    module = sys.modules[__name__]
    module.BoastOptions = BoastOptions  # type: ignore[attr-defined]
    if "boastful-test" not in methods.REGISTRY:
        methods.register(
            "boastful-test", f"{__name__}:boastful", "claims too much", f"{__name__}:BoastOptions"
        )
    return "boastful-test"


def test_solve_check_holds_a_result_to_its_status(tiny, registered, capsys):
    from bilevel_kit.cli import main

    res = solve(tiny, registered, check=True)
    kinds = [v["kind"] for v in res.extra["violations"]]
    assert kinds == ["status_mismatch"], res.extra["violations"]
    code = main(["solve", str(tiny.source), "-m", registered, "--check", "-q"])
    assert code == 1
    assert "[status_mismatch] status 'optimal' but the makespan 32.5 s" in capsys.readouterr().err


def test_compare_reports_a_bound_above_a_valid_plan(tiny, registered, capsys):
    from bilevel_kit.cli import main

    code = main(
        [
            "compare",
            str(tiny.source),
            "--methods",
            f"single-task,{registered}",
            "-p",
            f"{registered}:status=feasible",
        ]
    )
    out, err = capsys.readouterr()
    assert code == 1
    assert (
        "INCONSISTENT: tiny: the bound 28 s of boastful-test is above the makespan 25.5 s of a "
        "valid plan of single-task" in err
    )
    assert "INCONSISTENT" in out  # the best-bound column says so, never a number
    assert "Traceback" not in out + err


def test_add_best_bound_gap_keeps_consistent_bounds():
    from bilevel_kit.experiments import add_best_bound_gap
    from bilevel_kit.experiments.compare import inconsistencies

    rows = [
        {"instance": "a", "method": "x", "bound": 10.0, "makespan": 12.0, "valid": True},
        {"instance": "a", "method": "y", "bound": 11.0, "makespan": 11.0, "valid": True},
    ]
    out = add_best_bound_gap(rows)
    assert [r["best_bound"] for r in out] == [11.0, 11.0]
    assert inconsistencies(out) == []
    rows[0]["bound"] = 11.5
    out = add_best_bound_gap(rows)
    assert [r["best_bound"] for r in out] == [None, None]
    assert inconsistencies(out) == [
        "a: the bound 11.5 s of x is above the makespan 11 s of a valid plan of y: a lower "
        "bound cannot be"
    ]


def test_a_tampered_solution_file_names_every_refused_number(tmp_path, tiny, doc, capsys):
    from bilevel_kit.cli import main

    bad = _set(_set(doc, "objective.value", BIG), "kits.0.layout.0.y", -BIG)
    path = tmp_path / "s.json"
    path.write_text(json.dumps(bad))
    assert main(["check", str(tiny.source), str(path)]) == 1
    out, err = capsys.readouterr()
    err = out + err
    assert "[bad_number] $.objective.value: a 400-digit integer is out of range" in err
    assert "[bad_number] $.kits[0].layout[0].y: a 400-digit integer is out of range" in err


def test_loaded_solutions_of_every_method_still_check(tiny):
    for method in ("single-task", "whole-assembly"):
        d = json.loads(json.dumps(result_to_dict(solve(tiny, method))))
        assert solution.from_dict(d).check(tiny) == []
