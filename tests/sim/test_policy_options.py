"""Policy options are validated against each policy's options dataclass (exit 2 on the CLI)."""

from __future__ import annotations

import pytest

from bilevel_kit.cli import main
from bilevel_kit.errors import UsageError
from bilevel_kit.options import NoOptions
from bilevel_kit.sim import POLICIES, SimParams, make_policy
from bilevel_kit.sim.cpsat_rolling import CPSATRollingOptions


def test_registry_is_lazy_and_ordered():
    assert list(POLICIES) == [
        "single-task",
        "whole-assembly",
        "optimized",
        "cpsat-rolling",
        "optimized-adaptive",
        "optimized-oracle",
        "cpsat-rolling-adaptive",
        "cpsat-rolling-oracle",
        "fixed-plan",
    ]
    assert "optimized" in POLICIES and "magic" not in POLICIES
    assert POLICIES.spec("single-task").options_class() is NoOptions
    assert POLICIES.spec("cpsat-rolling").options_class() is CPSATRollingOptions


def test_options_reach_the_policy(table):
    pol = make_policy(
        "cpsat-rolling", table, params=SimParams(policy_options={"window": "3", "tray": "auto"})
    )
    assert pol.options == CPSATRollingOptions(window=3, tray="auto")
    with pytest.raises(UsageError, match="policy 'single-task': unknown option 'window'"):
        make_policy("single-task", table, params=SimParams(policy_options={"window": 3}))


@pytest.mark.parametrize(
    ("argv", "msg"),
    [
        (["-p", "foo=1"], "policy 'optimized': unknown option 'foo'"),
        (["--policy", "single-task", "-p", "window=3"], "policy 'single-task': unknown option"),
        (["--policy", "cpsat-rolling", "-p", "window=abc"], "option 'window': expected an int"),
        (["--policy", "cpsat-rolling", "-p", "window=0"], "option 'window': must be >= 1"),
    ],
)
def test_simulate_bad_policy_option_is_exit_2(argv, msg, root, capsys):
    code = main(["simulate", str(root / "instances/hrc_table.json"), "--reps", "1", *argv])
    err = capsys.readouterr().err
    assert code == 2 and msg in err and err.count("\n") == 1
