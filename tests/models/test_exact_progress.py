"""Live progress of ``cpsat`` and ``milp``: monotone numbers in seconds that end at the result."""

from __future__ import annotations

import itertools

import pytest

from bilevel_kit.methods import solve
from bilevel_kit.progress import Update

pytest.importorskip("ortools")


def check_updates(updates: list[Update], objective: float | None, tol: float) -> None:
    """Monotone incumbents and bounds, bound <= incumbent, the last incumbent the result's."""
    assert updates
    incumbents = [u.incumbent for u in updates if u.incumbent is not None]
    bounds = [u.bound for u in updates if u.bound is not None]
    assert incumbents and bounds
    assert all(b <= a for a, b in itertools.pairwise(incumbents))
    assert all(b >= a for a, b in itertools.pairwise(bounds))
    for u in updates:
        if u.incumbent is not None and u.bound is not None:
            assert u.bound <= u.incumbent
            assert u.gap == pytest.approx((u.incumbent - u.bound) / u.incumbent)
    assert objective is not None
    assert incumbents[-1] == pytest.approx(objective, abs=tol)
    assert all(u.unit == "s" for u in updates)


@pytest.mark.parametrize(
    ("trays", "mode", "stage"),
    [(1, "benders", "CP-SAT Benders"), ("unlimited", "embedded", "CP-SAT")],
)
def test_cpsat_reports_progress_on_the_table(table, trays, mode, stage):
    instance = table.with_overrides(trays=trays)
    updates: list[Update] = []
    r = solve(instance, "cpsat", time_limit=30, progress=updates.append, workers=2)
    check_updates(updates, r.objective, tol=r.extra["time_resolution"])
    assert updates[-1].bound == pytest.approx(min(r.bound, r.objective), abs=1e-9)
    assert {u.objective for u in updates} == {"makespan"}
    assert r.extra["tray_mode"] == mode
    assert updates[0].stage == "warm start"
    assert any(u.stage.startswith(stage) for u in updates)


def test_cpsat_progress_in_human_idle(table):
    updates: list[Update] = []
    r = solve(table, "cpsat", time_limit=30, progress=updates.append, objective="human_idle")
    assert {u.objective for u in updates} == {"human_idle"}
    check_updates(updates, r.metrics["human_idle"], tol=r.extra["time_resolution"])


def test_no_sink_no_updates_same_contract(table):
    r = solve(table, "single-task", progress=lambda u: pytest.fail("single-task reported"))
    assert r.objective is not None


@pytest.mark.parametrize("objective", ["makespan", "human_idle"])
def test_milp_reports_the_highs_child_bounds(table, objective):
    pytest.importorskip("highspy")
    updates: list[Update] = []
    r = solve(table, "milp", time_limit=40, progress=updates.append, objective=objective)
    value = r.objective if objective == "makespan" else r.metrics["human_idle"]
    check_updates(updates, value, tol=1e-6)
    assert {u.objective for u in updates} == {objective}
    assert any(u.stage.startswith("MILP (highs)") for u in updates)
    if objective == "makespan":
        assert updates[-1].bound == pytest.approx(r.bound, abs=1e-6)
