"""The method contract as one function, so every method is held to it: the built-ins in
tests/core/test_contract.py and a method written outside the package (docs/extending.md).

A solve on ``inst``: the status is a :class:`Status`, there is a plan and the independent
checker accepts it, the bound never exceeds the objective, "optimal" for the makespan means a
zero gap, and the same seed gives the same plan (for an exact method: whenever it finished
within its time limit in both runs, since a search stopped by the wall clock stops where the
machine's load let it get).
"""

from __future__ import annotations

from typing import Any

import pytest

from bilevel_kit import Instance, check, solve
from bilevel_kit.methods import Status

#: The committed instances every method is held to (those small enough for all of them).
INSTANCES = [
    "tiny.json",
    "stool.json",
    "hrc_table.json",
    "generated/intree_n8_s0.json",
    "generated/sp_n8_s0.json",
]
EXACT = {"cpsat", "milp", "bilevel-milp"}


def assert_contract(inst: Instance, method: str, params: dict[str, Any]) -> None:
    first = solve(inst, method, seed=3, time_limit=30, **params)
    assert isinstance(first.status, Status)
    assert first.plan is not None, f"{method} gave no plan on {inst.name}"
    assert check(inst, first.plan) == []
    assert first.makespan_bound is None or first.makespan_bound <= first.makespan + 1e-6
    assert first.bound is None or first.bound <= first.objective + 1e-6  # the minimised one's
    if first.status == Status.OPTIMAL and first.status_objective == "makespan":
        assert first.gap == pytest.approx(0.0, abs=1e-6)
    if method == "bilevel-milp":
        assert first.status_objective == "J" and "(for J)" in first.status_text
    again = solve(inst, method, seed=3, time_limit=30, **params)
    if method in EXACT and not first.status == again.status == Status.OPTIMAL:
        # at least one run was stopped by the wall clock: where its search stood depends on
        # the machine's load, so only the other properties are deterministic
        assert again.plan is not None and check(inst, again.plan) == []
        return
    if method == "bilevel-milp" and not all(
        r.extra.get("local_search_converged", True) and r.extra["lower_level_cut"] == 0
        for r in (first, again)
    ):
        # its warm start's local search or a kit's packing was stopped by the wall clock: the
        # MILP may pick another plan, or a kit another layout: both must still be valid
        assert again.plan is not None and check(inst, again.plan) == []
        return
    assert again.plan == first.plan
