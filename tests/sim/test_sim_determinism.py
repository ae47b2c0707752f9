"""A run is a pure function of (instance, policy, params, seed): no wall-time limit and no
cache shared across replications may change a record (docs/simulation.md)."""

from __future__ import annotations

import subprocess
import sys
from collections.abc import Iterator
from typing import Any

import pytest

from bilevel_kit.heuristics.cross_entropy import CEParams
from bilevel_kit.sim import SimParams, replicate

CE = CEParams(samples=60, elite=10, max_iter=30)
DELAYS = SimParams(units=2, ce=CE, mat={"leg": 60.0, "foot": 45.0}, mttf=90.0)
POLICIES = ("single-task", "whole-assembly", "optimized")


def _records(instance: Any, policy: str, seeds: list[int], params: SimParams) -> dict[int, Any]:
    return {r["seed"]: r for r in replicate(instance, policy, params, seeds=seeds)}


@pytest.fixture
def busy_cpu() -> Iterator[None]:
    """Two busy-loop processes competing for the CPU while the test runs."""
    procs = [subprocess.Popen([sys.executable, "-c", "while True: pass"]) for _ in range(2)]
    try:
        yield
    finally:
        for p in procs:
            p.kill()
            p.wait()


@pytest.mark.parametrize("policy", POLICIES)
def test_same_run_under_cpu_load(table, policy: str, request: pytest.FixtureRequest) -> None:
    quiet = _records(table, policy, [0, 1], DELAYS)
    request.getfixturevalue("busy_cpu")
    loaded = _records(table, policy, [0, 1], DELAYS)
    assert loaded == quiet


@pytest.mark.parametrize("policy_seed", [0, None])
def test_records_do_not_depend_on_which_replication_filled_the_cache(
    table, policy_seed: int | None
) -> None:
    """One policy object (and its layout cache) serves every replication: a run's record is
    the same whichever runs came before it, and the same as a run on its own."""
    params = SimParams(units=2, ce=CE, mat={"leg": 50.0}, policy_seed=policy_seed)
    forward = _records(table, "optimized", [3, 4, 5], params)
    backward = _records(table, "optimized", [5, 4, 3], params)
    alone = _records(table, "optimized", [4], params)
    assert forward == backward
    assert alone[4] == forward[4]
