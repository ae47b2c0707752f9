"""The method contract, over every registered method and every committed instance small enough:
the plan passes the independent checker, the same seed gives the same plan (for an exact method:
whenever it finished within its time limit, since a search stopped by the wall clock stops
where the machine's load let it get), the bound never exceeds the objective, the status is a
:class:`Status`, and an unknown option is refused."""

from __future__ import annotations

import pytest

from bilevel_kit import UsageError, check, load, solve
from bilevel_kit.methods import REGISTRY, Status

FAST = {
    "greedy-ce": {"samples": 60, "elite": 10, "max_iter": 30},
    "cpsat": {"workers": 1},  # one worker: CP-SAT is deterministic for a given seed
    "bilevel-milp": {"lower": "ce", "pack_time_limit": 5.0},  # packing decided, not timed out
}
INSTANCES = [
    "tiny.json",
    "stool.json",
    "hrc_table.json",
    "generated/intree_n8_s0.json",
    "generated/sp_n8_s0.json",
]
EXACT = {"cpsat", "milp", "bilevel-milp"}
SLOW = {("bilevel-milp", "hrc_table.json")}  # its column MILP needs minutes on the table


def _cases():
    for method in REGISTRY:
        for name in INSTANCES:
            if (method, name) not in SLOW:
                yield pytest.param(method, name, id=f"{method}-{name}")


@pytest.mark.parametrize(("method", "name"), list(_cases()))
def test_contract(method, name, root):
    inst = load(root / "instances" / name)
    params = FAST.get(method, {})
    first = solve(inst, method, seed=3, time_limit=30, **params)
    assert isinstance(first.status, Status)
    assert first.plan is not None, f"{method} gave no plan on {name}"
    assert check(inst, first.plan) == []
    assert first.bound is None or first.bound <= first.objective + 1e-6
    if first.status == Status.OPTIMAL and first.status_objective == "makespan":
        assert first.gap == pytest.approx(0.0, abs=1e-6)
    if method == "bilevel-milp":
        assert first.status_objective == "J" and "(for J)" in first.status_text
    again = solve(inst, method, seed=3, time_limit=30, **params)
    if method in EXACT and Status.OPTIMAL not in (first.status, again.status):
        # stopped by the wall clock: where the search stood depends on the machine's load
        assert again.status != Status.OPTIMAL or first.status != Status.OPTIMAL
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


@pytest.mark.parametrize("method", list(REGISTRY))
def test_unknown_option_is_refused_naming_method_and_key(method, tiny):
    with pytest.raises(UsageError, match=rf"method '{method}'.*'colour'"):
        solve(tiny, method, colour=1)


@pytest.mark.parametrize("method", list(REGISTRY))
def test_every_option_is_typed_and_documented(method):
    for info in REGISTRY[method].describe_options():
        assert info.help, f"{method}: option {info.name} has no help"
        assert info.type


@pytest.mark.parametrize("bad", [-1, 1.5, "x", True])
def test_bad_seed_is_refused(bad, tiny):
    with pytest.raises(UsageError, match="seed"):
        solve(tiny, "single-task", seed=bad)


@pytest.mark.parametrize("bad", [0, -3, float("nan"), float("inf"), "10"])
def test_bad_time_limit_is_refused(bad, tiny):
    with pytest.raises(UsageError, match="time limit"):
        solve(tiny, "single-task", time_limit=bad)
