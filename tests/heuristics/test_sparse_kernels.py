"""The compiled parts of greedy-ce's decision on sparse wide graphs (issue 27, item 3,
docs/scaling.md) against the Python code they replace, or for the depth-first search against
its own source run as Python (the fallback without numba): every call gives the same result, on
random small instances (with non-integer robot times: the depth-first rest search decides)
and on generated graphs, also with the searches capped."""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from test_greedy_search import TINY_CE, enumerable_instances

from bilevel_kit.generate import generate
from bilevel_kit.heuristics import _beam_kernel, _dfs_kernel
from bilevel_kit.heuristics.greedy_ce import GreedyCEPolicy, GreedyParams, plan
from bilevel_kit.heuristics.prefix import rests
from bilevel_kit.heuristics.prefix.frontier import smallest
from bilevel_kit.instance import Instance, from_dict

#: The hypothesis settings of the three random-instance comparisons.
EXAMPLES = settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.too_slow])


def _plan_patched(inst: Instance, params: GreedyParams, *patches: tuple[Any, str, Any]) -> None:
    """greedy-ce's plan with each ``(owner, name, value)`` patched for the run."""
    with pytest.MonkeyPatch.context() as mp:
        for owner, name, value in patches:
            mp.setattr(owner, name, value)
        plan(inst, policy=GreedyCEPolicy(inst, params, 0))


def _plan_checking_every_rest_search(inst: Instance, params: GreedyParams) -> int:
    """Plan with every depth-first rest search run twice, compiled and as Python (the
    kernel's ``py_func``, its helpers' too), asserting the same (F, rest, capped); returns the
    searches compared."""
    compiled = _dfs_kernel.kernel()
    if compiled is None:
        pytest.skip("numba is not available")
    original = rests.RestSearch.depth_first
    calls = []

    def both(self, window, prefix, m, terms, threshold, cutoff=math.inf):
        fast = original(self, window, prefix, m, terms, threshold, cutoff)
        assert self._dfs is compiled  # greedy-ce runs the compiled search
        with pytest.MonkeyPatch.context() as inner:
            for name in _dfs_kernel._HELPERS:  # the compiled kernel keeps its compiled helpers
                inner.setattr(_dfs_kernel, name, getattr(_dfs_kernel, name).py_func)
            inner.setattr(self, "_dfs", compiled.py_func)
            slow = original(self, window, prefix, m, terms, threshold, cutoff)
        assert fast[1:] == slow[1:]
        assert fast[0] == slow[0] or (math.isinf(fast[0]) and math.isinf(slow[0]))
        calls.append(fast[2])
        return fast

    _plan_patched(inst, params, (rests.RestSearch, "depth_first", both))
    return len(calls)


@EXAMPLES
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


def _plan_checking_every_beam(inst: Instance, params: GreedyParams) -> int:
    """Plan with every compiled beam level checked against the numpy children, scores and
    choice (``build_levels`` without the compiled beam): the same rows kept in the same
    order, the same floats; returns the levels compared."""
    from bilevel_kit.heuristics import greedy_search
    from bilevel_kit.heuristics.prefix import levels as levels_mod

    if _beam_kernel.kernel() is None:
        pytest.skip("numba is not available")
    original = greedy_search.PrefixSearch._fast_beam
    checked = []

    def both(self, i, length, window, ctx, parents):
        fast = original(self, i, length, window, ctx, parents)
        if fast is None:
            return None
        p_tasks, p_unl, p_robot, p_human, p_counts = parents
        avail = np.array(window.avail, dtype=np.int64)
        par, child = levels_mod._children(avail, p_tasks, p_unl, self.graph.n)
        rows = levels_mod.Children(p_tasks, par, child)
        opt = self._optimistic(
            i,
            length,
            rows,
            p_robot[par] + self.r[child],
            p_human[par] + self.h[child],
            p_counts[par] + self.part_matrix[child],
            ctx,
        )
        keep = smallest(opt, self.limits.beam_width)
        assert fast[0].tolist() == par[keep].tolist()
        assert fast[1].tolist() == child[keep].tolist()
        assert fast[2].tolist() == opt[keep].tolist()
        checked.append(len(par))
        return fast

    _plan_patched(inst, params, (greedy_search.PrefixSearch, "_fast_beam", both))
    return len(checked)


@EXAMPLES
@given(enumerable_instances(), st.integers(1, 12), st.integers(1, 6), st.booleans())
def test_compiled_beam_is_the_numpy_beam(inst, max_sets, width, signed):
    """Random instances with a beam from the first levels (small caps), signed or not."""
    params = GreedyParams(ce=TINY_CE, max_prefix_sets=max_sets, beam_width=width, signed=signed)
    _plan_checking_every_beam(inst, params)


def _plan_checking_every_scored_rest(inst: Instance, params: GreedyParams) -> int:
    """Plan with every pair's best rest found twice, compiled and by the decomposition's
    Python loop (told it cannot score compiled; F from the same source, called from
    Python): the same (F, rest); returns the pairs compared."""
    from bilevel_kit.heuristics import _rest_kernel, greedy_search

    if _rest_kernel.rest_kernel() is None:
        pytest.skip("numba is not available")
    original = greedy_search.PrefixSearch._best_pair
    compared = []

    def both(self, dc, li, k, incumbent):
        fast = original(self, dc, li, k, incumbent)
        rests_ = dc.ep.rests
        compiled = rests_ is not None and rests_.scores_compiled(dc.length - li - 1)
        with pytest.MonkeyPatch.context() as inner:
            inner.setattr(rests.RestDecomposition, "scores_compiled", lambda self, m: False)
            slow = original(self, dc, li, k, incumbent)
        assert (fast is None) == (slow is None)
        if fast is not None:
            assert fast[1:] == slow[1:]
            assert fast[0] == slow[0] or (math.isinf(fast[0]) and math.isinf(slow[0]))
        compared.append(compiled and li + 1 < dc.length)
        return fast

    deep = (rests, "MIN_DEEP_COMPILED", 0)  # compiled whenever it can be
    _plan_patched(inst, params, deep, (greedy_search.PrefixSearch, "_best_pair", both))
    return sum(compared)


@EXAMPLES
@given(enumerable_instances(), st.integers(1, 30), st.booleans())
def test_compiled_rest_scores_are_numpys(inst, max_rest, signed):
    """Random instances, the rest search capped or not, signed or not."""
    params = GreedyParams(ce=TINY_CE, max_rest_nodes=max_rest, signed=signed)
    _plan_checking_every_scored_rest(inst, params)


#: (checker, family, size, seed, caps): wide windows (sparse: the beam's second level is a
#: beam), deep ones (in-trees, series-parallel, with unlocked children), capped searches.
GENERATED = [
    (_plan_checking_every_rest_search, "sparse", 60, 2, {"max_rest_nodes": 2000}),
    (_plan_checking_every_rest_search, "sparse", 80, 2, {"max_rest_nodes": 25}),
    (_plan_checking_every_rest_search, "intree", 60, 2, {"max_rest_nodes": 40}),
    (_plan_checking_every_rest_search, "series-parallel", 40, 2, {"max_rest_nodes": 9}),
    (_plan_checking_every_beam, "sparse", 120, 2, {"max_prefix_sets": 5000}),
    (_plan_checking_every_beam, "sparse", 60, 2, {"max_prefix_sets": 300}),
    (_plan_checking_every_beam, "intree", 60, 2, {"max_prefix_sets": 50}),
    (_plan_checking_every_beam, "series-parallel", 60, 2, {"max_prefix_sets": 40}),
    (_plan_checking_every_scored_rest, "sparse", 100, 3, {"max_rest_nodes": 2000}),
    (_plan_checking_every_scored_rest, "sparse", 60, 3, {"max_rest_nodes": 30}),
    (_plan_checking_every_scored_rest, "intree", 60, 3, {"max_rest_nodes": 2000}),
    (_plan_checking_every_scored_rest, "series-parallel", 60, 3, {"max_rest_nodes": 9}),
]


@pytest.mark.parametrize(("checker", "family", "size", "seed", "caps"), GENERATED)
def test_compiled_kernels_on_generated_graphs(checker, family, size, seed, caps):
    """Each compiled search (depth-first rests, beam, scored rests) is the Python one on
    generated graphs, and at least one search is compared."""
    inst = from_dict(generate(family, size, seed=seed))
    assert checker(inst, GreedyParams(ce=TINY_CE, **caps))
