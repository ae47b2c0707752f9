"""The method contract, over every registered method and every committed instance small enough:
the plan passes the independent checker, the same seed gives the same plan (for an exact method:
whenever it finished within its time limit, since a search stopped by the wall clock stops
where the machine's load let it get), the bound never exceeds the objective, the status is a
:class:`Status`, and an unknown option is refused."""

from __future__ import annotations

import pytest
from contract import INSTANCES, assert_contract

from bilevel_kit import UsageError, load, solve
from bilevel_kit.methods import REGISTRY

FAST = {
    "greedy-ce": {"samples": 60, "elite": 10, "max_iter": 30},
    "cpsat": {"workers": 1},  # one worker: CP-SAT is deterministic for a given seed
    "bilevel-milp": {"lower": "ce", "pack_time_limit": 5.0},  # packing decided, not timed out
    "lns": {"iterations": 20, "start": "quick"},  # a fixed number of windows: deterministic
}
SLOW = {("bilevel-milp", "hrc_table.json")}  # its column MILP needs minutes on the table


def _cases():
    for method in REGISTRY:
        for name in INSTANCES:
            if (method, name) not in SLOW:
                yield pytest.param(method, name, id=f"{method}-{name}")


@pytest.mark.parametrize(("method", "name"), list(_cases()))
def test_contract(method, name, root):
    assert_contract(load(root / "instances" / name), method, FAST.get(method, {}))


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
