"""One set of ``extra`` keys and one meaning per option for ``cpsat`` and ``milp``
(docs/formulations.md, "One driver for cpsat and milp"; bilevel_kit/models/exact/keys.py)."""

from __future__ import annotations

from types import SimpleNamespace

import pytest

from bilevel_kit import solve
from bilevel_kit.cli.solve import no_model_note
from bilevel_kit.models.cpsat import CpsatOptions
from bilevel_kit.models.cpsat.warm import HINT_METHODS, hint_methods
from bilevel_kit.models.exact import keys
from bilevel_kit.models.milp.method import MilpOptions
from bilevel_kit.validate import check

OLD = ("cpsat_status", "termination", "benders_iterations", "iterations")
S = "optimal"
SHARED = ("solver_status", "backend_status", "master_solves", "upper_start", "hint_method")


@pytest.mark.parametrize("method", ["cpsat", "milp"])
def test_both_report_the_same_keys_in_one_vocabulary(method, table):
    # the run ends at the model's proof (1-7 s unloaded); the limit leaves the model time to
    # be built and solved after the LNS first's windows on a busy machine (at a load of 10,
    # milp's build took 7 s: at 10 s the model was built and never solved)
    out = solve(table, method, seed=0, time_limit=30)
    x = out.extra
    assert out.plan is not None and check(table, out.plan) == []
    assert set(SHARED) <= set(x) and not set(OLD) & set(x)
    assert x["solver_status"] in keys.NO_SOLVE + keys.SOLVE_OUTCOMES
    assert x["solver_status"] == x["solver_status"].lower()
    if x["solver_status"] in keys.NO_SOLVE:
        assert x["master_solves"] == 0 and x["backend_status"] is None
    else:
        assert x["master_solves"] >= 1 and isinstance(x["backend_status"], str)
    # the incumbent's makespan (the minimised objective): never below the result's
    assert x["upper_start"] >= out.objective - 1e-9
    assert x["hint_method"] is None or x["hint_method"] in HINT_METHODS
    assert x["tray_mode"] in ("embedded", "benders")


@pytest.mark.parametrize("method", ["cpsat", "milp"])
def test_upper_start_is_the_minimised_objective(method, stool):
    """``objective=human_idle``: ``upper_start`` is the incumbent's human idle (s), not its
    makespan (what cpsat reported before); the result is never worse than it."""
    out = solve(stool, method, seed=0, time_limit=20, objective="human_idle")
    x = out.extra
    assert x["human_idle"] <= x["upper_start"] + 1e-6
    assert x["upper_start"] < 0.5 * x["makespan"]  # idle, far below any makespan


def test_the_options_mean_the_same():
    assert CpsatOptions().hint == MilpOptions().hint == "auto"
    assert CpsatOptions().tray == MilpOptions().tray == "auto"
    assert hint_methods("auto") == ("single-task", "whole-assembly", "greedy-ce")
    assert hint_methods("none") == () and hint_methods("lns") == ("lns",)


def test_milp_hint_none_is_the_quick_plan_and_auto_names_the_winner(stool):
    cold = solve(stool, "milp", seed=0, time_limit=20, hint="none")
    assert cold.extra["hint_method"] is None
    warm = solve(stool, "milp", seed=0, time_limit=20, hint="greedy-ce")
    assert warm.extra["hint_method"] in (None, "greedy-ce")
    assert warm.objective == pytest.approx(cold.objective)  # both proven optimal
    assert cold.status == warm.status == "optimal"


@pytest.mark.parametrize(
    ("old", "status", "solves"),
    [
        # a committed cpsat record (bench/results/gap_cells/*.json)
        (
            {"cpsat_status": "OPTIMAL", "benders_iterations": 1, "tray_mode": "benders"},
            "optimal",
            1,
        ),
        (
            {"cpsat_status": "OPTIMAL", "benders_iterations": 0, "tray_mode": "embedded"},
            "optimal",
            1,
        ),
        ({"cpsat_status": "NOT_BUILT", "benders_iterations": 0}, "not_built", 0),
        ({"cpsat_status": "RELEASE_BOUND", "benders_iterations": 0}, "release_bound", 0),
        ({"cpsat_status": "FEASIBLE", "benders_iterations": 3}, "feasible", 3),
        ({"termination": "too_large", "iterations": 0}, "too_large", 0),
        ({"termination": "optimal", "iterations": 2}, "optimal", 2),
        ({"termination": "infeasibleOrUnbounded", "iterations": 1}, "infeasible", 1),
        ({"termination": "maxTimeLimit", "iterations": 4}, "unknown", 4),
    ],
)
def test_old_records_are_read_in_the_new_vocabulary(old, status, solves):
    assert keys.read(old, keys.SOLVER_STATUS) == status
    assert keys.read(old, keys.MASTER_SOLVES) == solves


def test_new_keys_win_and_missing_ones_are_none():
    rec = {"solver_status": "feasible", "cpsat_status": "OPTIMAL", "master_solves": 5}
    assert keys.read(rec, keys.SOLVER_STATUS) == "feasible"
    assert keys.read(rec, keys.MASTER_SOLVES) == 5
    assert keys.read({}, keys.SOLVER_STATUS) is None


@pytest.mark.parametrize(
    "extra",
    [
        {"solver_status": "not_built", "reason": "milp: too slow", "hint_method": "greedy-ce"},
        {"termination": "not_built", "reason": "milp: too slow", "hint_method": "greedy-ce"},
        {"cpsat_status": "NOT_BUILT", "reason": "milp: too slow", "hint_method": "greedy-ce"},
    ],
)
def test_the_no_model_note_reads_new_and_old_records(extra):
    note = no_model_note(SimpleNamespace(method="milp", extra=extra))  # type: ignore[arg-type]
    assert note == "milp: no model built (too slow to build): too slow (the plan is greedy-ce's)"
    assert no_model_note(SimpleNamespace(method="milp", extra={"solver_status": "optimal"})) is None
