"""The flow-shop references of tests/flowshop.py against enumeration of every sequence."""

from __future__ import annotations

import numpy as np
import pytest
from flowshop import (
    best_by_enumeration,
    blocking_makespan,
    flow_makespan,
    gilmore_gomory_order,
    johnson_order,
)


def _cases(seed: int, count: int):
    rng = np.random.default_rng(seed)
    for _ in range(count):
        n = int(rng.integers(1, 8))
        hi = int(rng.choice([3, 20, 1000]))  # small ranges make ties
        yield (
            rng.integers(0, hi, n).astype(float).tolist(),
            rng.integers(0, hi, n).astype(float).tolist(),
        )


@pytest.mark.parametrize("seed", range(3))
def test_gilmore_gomory_is_optimal_for_the_blocking_flow_shop(seed):
    for a, b in _cases(seed, 150):
        order = gilmore_gomory_order(a, b)
        assert sorted(order) == list(range(len(a)))
        assert blocking_makespan(a, b, order) == pytest.approx(
            best_by_enumeration(a, b, blocking_makespan)
        )


@pytest.mark.parametrize("seed", range(3))
def test_johnson_is_optimal_for_the_flow_shop(seed):
    for a, b in _cases(100 + seed, 150):
        assert flow_makespan(a, b, johnson_order(a, b)) == pytest.approx(
            best_by_enumeration(a, b, flow_makespan)
        )


def test_one_tray_can_cost_more_than_a_buffer():
    # robot times a, human times b (found by search: blocking costs 2 s more at best)
    a, b = [8.0, 1.0, 3.0, 4.0], [5.0, 4.0, 2.0, 1.0]
    assert best_by_enumeration(a, b, flow_makespan) == 17.0
    assert flow_makespan(a, b, johnson_order(a, b)) == 17.0
    assert best_by_enumeration(a, b, blocking_makespan) == 19.0
    assert blocking_makespan(a, b, gilmore_gomory_order(a, b)) == 19.0
