"""A result reports the objective it minimised (issue 36, item 1): ``objective``, ``bound``
and ``gap`` are that objective's, named by ``objective_name``; the makespan's stay beside
them (``makespan``, ``makespan_bound``, ``makespan_gap``). Solution files of format 2 say so
in an ``objective`` block; files of format 1 (tests/data/solution_v1/, written by the writer
before this change) still read and check (docs/formats.md#solutions)."""

from __future__ import annotations

import json
from dataclasses import replace
from pathlib import Path

import pytest
from solution_v1 import to_format_1

from bilevel_kit import load, solution, solve
from bilevel_kit.bounds import objective_bound
from bilevel_kit.errors import SolutionError
from bilevel_kit.methods import OBJECTIVE_KEYS, MethodOutput, Status
from bilevel_kit.objectives import OBJECTIVES, relative_gap

ROOT = Path(__file__).resolve().parents[2]
V1 = ROOT / "tests" / "data" / "solution_v1"
INSTANCES = {
    "hrc_table": ROOT / "instances" / "hrc_table.json",
    "tiny": ROOT / "instances" / "tiny.json",
    "stool_u1_s3": ROOT / "instances" / "stations" / "stool_u1_s3.json",
}

#: Each format-1 fixture: its status objective and (value, bound, gap) on it, as its
#: ``extra`` states them under that objective's format-1 keys (None: the makespan's fields).
V1_FILES = {
    "hrc_table_greedy_ce.json": ("makespan", None),
    "stool_cpsat_sum_completion.json": ("sum_completion", (489.0, 240.0, 0.50920245398773)),
    "stool_cpsat_human_idle.json": ("human_idle", (332.0, 81.0, 0.7560240963855421)),
    "tiny_bilevel_milp.json": ("J", (11.377303448189, 11.377303448189, 0.0)),
    "tiny_cpsat_human_idle.json": ("human_idle", (None, 4.0, None)),
}


@pytest.mark.parametrize("name", sorted(V1_FILES))
def test_format_1_files_still_read_and_check(name):
    doc = json.loads((V1 / name).read_text())
    assert doc["format"] == solution.FORMAT_1 == "bilevel-kit-solution/1"
    loaded = solution.read(V1 / name)
    assert loaded.check(load(INSTANCES[doc["instance"]])) == []
    objective, stated = V1_FILES[name]
    claims = loaded.claims
    assert claims.status_objective == objective
    assert (claims.objective, claims.bound, claims.gap) == (
        doc["objective"],
        doc["bound"],
        doc["gap"],
    )
    if stated is None:
        assert claims.objective_claims is None
    else:
        assert claims.objective_claims is not None
        assert claims.objective_claims[:3] == pytest.approx(stated, abs=1e-12)


def test_a_tampered_format_1_claim_is_still_named():
    doc = json.loads((V1 / "stool_cpsat_human_idle.json").read_text())
    doc["extra"]["objective_value"] = 300.0
    found = solution.from_dict(doc).check(load(INSTANCES["stool_u1_s3"]))
    assert [v.kind for v in found] == ["objective_mismatch"]


@pytest.fixture(scope="module")
def tiny_result(tiny):
    return solve(tiny, "single-task")


def test_the_default_objective_is_the_makespan_in_both_sets_of_numbers(tiny_result):
    res = tiny_result
    assert res.objective_name == res.status_objective == "makespan"
    assert res.objective == res.makespan == res.metrics["makespan"] == 25.5
    assert res.bound == res.makespan_bound == 24.5
    assert res.gap == res.makespan_gap == pytest.approx(1 / 25.5)


def test_format_2_round_trip_names_the_objective(tiny, tiny_result):
    doc = json.loads(json.dumps(solution.result_to_dict(tiny_result)))
    assert doc["format"] == solution.FORMAT == "bilevel-kit-solution/2"
    assert doc["objective"] == {"name": "makespan", "value": 25.5, "bound": 24.5, "gap": 1 / 25.5}
    assert doc["makespan"] == {"value": 25.5, "bound": 24.5, "gap": 1 / 25.5}
    assert not {"status_objective", "bound", "gap"} & set(doc)
    loaded = solution.from_dict(doc)
    assert loaded.check(tiny) == []
    assert (loaded.claims.objective, loaded.claims.bound) == (25.5, 24.5)
    old = solution.from_dict(to_format_1(doc))  # the same claims as format 1 states them
    assert old.check(tiny) == [] and old.claims == loaded.claims


def test_format_2_makespan_block_must_match_the_objective_block(tiny, tiny_result):
    doc = json.loads(json.dumps(solution.result_to_dict(tiny_result)))
    doc["makespan"]["bound"] = 20.0
    found = solution.from_dict(doc).check(tiny)
    assert [v.kind for v in found] == ["objective_mismatch"]
    assert "$.makespan.bound 20.0 differs from $.objective.bound 24.5" in found[0].message


def test_an_unknown_format_is_named(tiny_result):
    doc = json.loads(json.dumps(solution.result_to_dict(tiny_result)))
    doc["format"] = "bilevel-kit-solution/9"
    with pytest.raises(SolutionError, match=r"\$\.format: expected 'bilevel-kit-solution/2'"):
        solution.from_dict(doc)


def test_format_2_holds_another_objective_to_its_block(tiny, tiny_result):
    """human_idle named: its value is the plan's idle (4 s), its bound at most that; the
    makespan block is held as the makespan's."""
    res = replace(tiny_result, objective_name="human_idle", objective=4.0, bound=3.0, gap=0.25)
    doc = json.loads(json.dumps(solution.result_to_dict(res)))
    assert doc["objective"] == {"name": "human_idle", "value": 4.0, "bound": 3.0, "gap": 0.25}
    assert doc["makespan"] == {"value": 25.5, "bound": 24.5, "gap": 1 / 25.5}
    assert solution.from_dict(doc).check(tiny) == []
    doc["objective"]["value"] = 25.5  # the makespan is not the idle
    found = solution.from_dict(doc).check(tiny)
    assert [v.kind for v in found] == ["objective_mismatch"]
    assert "human_idle" in found[0].message


def idle_claim(instance, options, *, seed=0, time_limit=None):
    """Single-task's plan, stated as minimising the human idle with a bound of 1 s."""
    from bilevel_kit.heuristics.baselines import single_task

    extra = {"objective_value": 1e9, "objective_bound": 1.0, "objective_gap": 0.5, "note": 1}
    return MethodOutput(single_task(instance).plan, Status.FEASIBLE, None, extra, "human_idle")


def test_solve_moves_the_stated_numbers_out_of_extra(tiny):
    """The method's ``extra`` numbers become the result's: the value the registry's evaluation
    (not the stated 1e9), the bound the better of the stated 1 s and the closed-form 3 s
    (``bounds.objective_bound``), the gap recomputed; ``extra`` keeps none of them."""
    from bilevel_kit.methods import REGISTRY, register

    if "idle-claim-test" not in REGISTRY:
        register(
            "idle-claim-test",
            f"{__name__}:idle_claim",
            "states a human-idle bound",
            "bilevel_kit.options:NoOptions",
        )
    res = solve(tiny, "idle-claim-test", check=True)
    assert res.objective_name == "human_idle" and res.status_text == "feasible (for human_idle)"
    assert res.objective == OBJECTIVES["human_idle"].value(res.timeline) == 4.0
    assert objective_bound(tiny, "human_idle") == 3.0
    assert (res.bound, res.gap) == (3.0, relative_gap(4.0, 3.0)) == (3.0, 0.25)
    assert (res.makespan, res.makespan_bound) == (25.5, 24.5)
    assert not set(OBJECTIVE_KEYS) & set(res.extra) and res.extra["note"] == 1
    assert res.extra["violations"] == []


def test_a_format_2_claim_names_the_block_it_is_in(tiny, tiny_result):
    res = replace(tiny_result, status="optimal", objective_name="sum_completion", objective=25.5)
    res = replace(res, bound=None, gap=None)
    doc = json.loads(json.dumps(solution.result_to_dict(res)))
    found = solution.from_dict(doc).check(tiny)
    assert [v.message for v in found] == [
        "status 'optimal' for sum_completion without a bound (objective.bound)"
    ]


def j_claim(instance, options, *, seed=0, time_limit=None):
    """Single-task's plan claimed optimal for J, with J's value and no bound."""
    from bilevel_kit.heuristics.baselines import single_task

    return MethodOutput(
        single_task(instance).plan, Status.OPTIMAL, None, {"objective_value": -3.0}, "J"
    )


def test_an_optimum_without_a_bound_is_not_made_one(tiny):
    """J has no closed-form bound: its stated value stays the result's, with no bound, and
    ``solve --check`` names the unproven "optimal"."""
    from bilevel_kit.methods import REGISTRY, register

    if "j-claim-test" not in REGISTRY:
        register(
            "j-claim-test",
            f"{__name__}:j_claim",
            "claims a J optimum without a bound",
            "bilevel_kit.options:NoOptions",
            objectives=("J",),
        )
    res = solve(tiny, "j-claim-test", check=True)
    assert (res.objective_name, res.objective, res.bound, res.gap) == ("J", -3.0, None, None)
    assert [v["message"] for v in res.extra["violations"]] == [
        "status 'optimal' for J without a bound (bound)"
    ]


def test_a_huge_number_in_the_makespan_block_is_a_bad_number(tiny, tiny_result):
    doc = json.loads(json.dumps(solution.result_to_dict(tiny_result)))
    doc["makespan"]["value"] = 1e300
    found = solution.from_dict(doc).check(tiny)
    assert [(v.kind, v.message.split(":")[0]) for v in found] == [
        ("bad_number", "$.makespan.value")
    ]


def test_the_makespan_block_is_checked_when_the_objective_block_states_nothing(tiny, tiny_result):
    doc = json.loads(json.dumps(solution.result_to_dict(tiny_result)))
    doc["objective"] = {"name": "makespan"}
    assert solution.from_dict(doc).check(tiny) == []
    doc["makespan"]["bound"] = 30.0  # above the makespan 25.5 of the valid plan
    found = solution.from_dict(doc).check(tiny)
    assert "bound_above_makespan" in [v.kind for v in found]
