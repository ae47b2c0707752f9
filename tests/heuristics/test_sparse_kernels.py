"""The compiled parts of greedy-ce's decision on sparse wide graphs (issue 27, item 3,
docs/scaling.md) against the Python code they replace: every call gives the same result, on
random small instances (with non-integer robot times: the depth-first rest search decides)
and on generated graphs, also with the searches capped."""

from __future__ import annotations

import math

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from test_greedy_search import TINY_CE, enumerable_instances

from bilevel_kit.generate import generate
from bilevel_kit.heuristics import _dfs_kernel
from bilevel_kit.heuristics.greedy_ce import GreedyCEPolicy, GreedyParams, plan
from bilevel_kit.heuristics.prefix import rests
from bilevel_kit.instance import Instance, from_dict


def _plan_checking_every_rest_search(inst: Instance, params: GreedyParams) -> int:
    """Plan with every depth-first rest search run twice, compiled and in Python, asserting
    the same (F, rest, capped); returns the searches compared."""
    if _dfs_kernel.kernel() is None:
        pytest.skip("numba is not available")
    original = rests.RestSearch.depth_first
    calls = []

    def both(self, window, prefix, m, score, bound, threshold, cutoff=math.inf, terms=None):
        assert terms is not None  # greedy-ce always offers the compiled search
        fast = original(self, window, prefix, m, score, bound, threshold, cutoff, terms)
        slow = original(self, window, prefix, m, score, bound, threshold, cutoff, None)
        assert fast[1:] == slow[1:]
        assert fast[0] == slow[0] or (math.isinf(fast[0]) and math.isinf(slow[0]))
        calls.append(fast[2])
        return fast

    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(rests.RestSearch, "depth_first", both)
        plan(inst, policy=GreedyCEPolicy(inst, params, 0))
    return len(calls)


@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(enumerable_instances(), st.integers(1, 30), st.booleans(), st.booleans())
def test_compiled_depth_first_is_the_python_search(inst, max_rest, signed, jitter):
    """Random instances (robot times made non-integer: the depth-first search finds every
    rest), capped or not, signed or not."""
    if jitter:  # pick times off the 1/64 grid: the decomposition is not used
        doc = inst.to_dict()
        for k, p in enumerate(doc["part_types"]):
            p["pick_time"] += 0.013 * (k + 1)
        inst = from_dict(doc)
    params = GreedyParams(ce=TINY_CE, max_rest_nodes=max_rest, signed=signed)
    _plan_checking_every_rest_search(inst, params)


@pytest.mark.parametrize(
    ("family", "size", "max_rest"),
    [("sparse", 60, 2000), ("sparse", 80, 25), ("intree", 60, 40), ("series-parallel", 40, 9)],
)
def test_compiled_depth_first_on_generated_graphs(family, size, max_rest):
    """Wide windows (sparse), deep ones (in-trees, series-parallel), capped searches."""
    inst = from_dict(generate(family, size, seed=2))
    assert _plan_checking_every_rest_search(inst, GreedyParams(ce=TINY_CE, max_rest_nodes=max_rest))
