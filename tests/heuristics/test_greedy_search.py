"""The exact greedy decision (prefix sets, bilevel_kit.heuristics.greedy_search) against the
enumeration of every sequence: same minimum F at every epoch, same kits, same plans."""

from __future__ import annotations

import heapq

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from strategies import part_types_and_tasks

from bilevel_kit import check, solve
from bilevel_kit.heuristics.cross_entropy import CEParams
from bilevel_kit.heuristics.greedy_ce import GreedyCEPolicy, GreedyParams, plan
from bilevel_kit.heuristics.prefix.bounds import fitness_upper_bounds
from bilevel_kit.heuristics.prefix.frontier import Frontier, smallest
from bilevel_kit.heuristics.prefix.levels import unique_rows
from bilevel_kit.instance import Instance, from_dict
from bilevel_kit.plan import evaluate

TINY_CE = CEParams(samples=20, elite=5, max_iter=5)


@st.composite
def enumerable_instances(draw: st.DrawFn) -> Instance:
    """Up to 10 tasks, random precedence, d, overheads, N in 1..5, trays None/1/2."""
    types, tasks = part_types_and_tasks(draw, max_side=50, max_tasks=10)
    n = len(tasks)
    density = draw(st.integers(0, 6))
    edges = [
        [f"t{a}", f"t{b}"]
        for a in range(n)
        for b in range(a + 1, n)
        if draw(st.integers(0, 9)) < density
    ]
    return from_dict(
        {
            "format": "bilevel-kit/1",
            "name": "h",
            "tray": {"width": 200.0, "height": 150.0},
            "delivery_time": draw(st.integers(0, 10)) * 1.0,
            "kit_overhead": {
                "robot": draw(st.integers(0, 5)) * 1.0,
                "human": draw(st.integers(0, 3)) * 1.0,
            },
            "part_types": types,
            "tasks": tasks,
            "precedence": edges,
            "horizon": draw(st.integers(1, 5)),
            "trays": draw(st.sampled_from([None, 1, 2])),
        }
    )


def _run(inst: Instance, decision: str, seed: int, signed: bool) -> GreedyCEPolicy:
    params = GreedyParams(ce=TINY_CE, decision=decision, signed=signed)
    policy = GreedyCEPolicy(inst, params, seed)
    policy.plan_ = plan(inst, policy=policy)  # type: ignore[attr-defined]
    return policy


@settings(max_examples=50, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(enumerable_instances(), st.integers(0, 3), st.booleans())
def test_exact_decision_equals_the_enumeration(inst, seed, signed):
    exact = _run(inst, "exact", seed, signed)
    enum = _run(inst, "enumerate", seed, signed)
    assert exact.stats.beam_epochs == 0 and exact.stats.rest_capped == 0
    ex_terms, en_terms = exact.stats.objective_terms, enum.stats.objective_terms
    # same kits in the same order (the tie rule), hence the same F at every epoch
    assert exact.plan_.kits == enum.plan_.kits
    for a, b in zip(ex_terms, en_terms, strict=True):
        assert a["score"] == pytest.approx(b["score"], abs=1e-7)
    assert evaluate(inst, exact.plan_).makespan == evaluate(inst, enum.plan_).makespan
    assert check(inst, exact.plan_) == []
    # the search scored fewer candidates than the enumeration
    assert exact.stats.evaluated <= enum.stats.candidates


def test_table_plan_is_the_enumerations(table):
    a = solve(table, "greedy-ce", seed=0)
    b = solve(table, "greedy-ce", seed=0, decision="enumerate")
    assert a.plan == b.plan and a.objective == pytest.approx(463.78)  # one tray
    assert a.extra["decision"] == "exact" and a.extra["beam_epochs"] == 0
    assert b.extra["sequences"] > 0 and a.extra["sequences"] == 0
    for x, y in zip(a.extra["kit_terms"], b.extra["kit_terms"], strict=True):
        assert x["score"] == pytest.approx(y["score"], abs=1e-9)


def test_fitness_bound_holds_for_ce_layouts(table):
    policy = GreedyCEPolicy(table, GreedyParams(ce=CEParams(samples=60, elite=10, max_iter=30)))
    types = policy._types
    for tasks in (["foot1"], ["foot1", "conn1"], ["top1", "conn2", "foot3"], ["top1", "top2"]):
        counts = table.kit_parts(tasks)
        row = np.array([[counts.get(t, 0) for t in types]])
        arr = policy.arrangement(counts)
        assert arr.fits
        assert arr.fitness <= fitness_upper_bounds(table, types, row)[0] + 1e-9


def test_beam_is_reported_and_plans_stay_valid(table):
    inst = table.with_overrides(units=3)
    res = solve(
        inst,
        "greedy-ce",
        check=True,
        max_prefix_sets=5,
        beam_width=3,
        samples=20,
        elite=5,
        max_iter=5,
    )
    assert res.extra["violations"] == []
    assert res.extra["beam_epochs"] > 0


def test_time_limit_finishes_with_single_tasks(table):
    inst = table.with_overrides(units=2)
    res = solve(inst, "greedy-ce", check=True, time_limit=1e-9, samples=20, elite=5, max_iter=5)
    assert res.extra["violations"] == [] and res.extra["time_limit_hit"] is True
    assert res.status == "feasible"
    assert all(len(k.tasks) == 1 for k in res.plan.kits)


def test_one_tray_h_rem_matches_the_timeline(table, stool):
    from bilevel_kit.plan import Plan, next_robot_start

    for base in (table, stool, table.with_overrides(units=2)):
        inst = base.with_overrides(trays=1)
        res = solve(inst, "greedy-ce", check=True, samples=20, elite=5, max_iter=5)
        assert res.extra["violations"] == []
        kits = res.plan.kits
        for k, terms in enumerate(res.extra["kit_terms"]):
            expected = 0.0
            if k:
                tl = evaluate(inst, Plan(kits[:k]))
                expected = max(0.0, tl.kits[-1].human_end - next_robot_start(inst, tl.kits))
            assert terms["h_rem"] == pytest.approx(expected, abs=1e-9)


@settings(max_examples=30, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(enumerable_instances(), st.integers(0, 3), st.integers(1, 4))
def test_exact_sum_shortcuts_change_nothing(inst, seed, width):
    """With robot times summing exactly, the search memoises and skips rest sums; with the
    shortcuts off (as for times like 0.1 s) every number is the same, beam or not."""
    runs = []
    for shortcuts in (True, False):
        params = GreedyParams(ce=TINY_CE, max_prefix_sets=4, beam_width=width)
        policy = GreedyCEPolicy(inst, params, seed)
        assert policy._search._exact_sums  # integer pick times
        policy._search._exact_sums = shortcuts
        kits = plan(inst, policy=policy).kits
        runs.append((kits, [t["score"] for t in policy.stats.objective_terms], policy.stats))
    (kits_a, scores_a, st_a), (kits_b, scores_b, st_b) = runs
    assert kits_a == kits_b and scores_a == scores_b
    assert (st_a.prefix_sets, st_a.evaluated, st_a.beam_epochs, st_a.ce_calls) == (
        st_b.prefix_sets,
        st_b.evaluated,
        st_b.beam_epochs,
        st_b.ce_calls,
    )


def test_smallest_is_the_stable_sorts_first_k():
    rng = np.random.default_rng(0)
    for _ in range(200):
        n, k = int(rng.integers(1, 60)), int(rng.integers(1, 70))
        values = rng.integers(0, 5, n).astype(float)  # many ties
        values[rng.random(n) < 0.1] = -np.inf
        want = np.sort(np.lexsort((np.arange(n), values))[:k])
        assert smallest(values, k).tolist() == want.tolist()


def test_unique_rows_match_numpy():
    rng = np.random.default_rng(1)
    for big in (3, 2**40):  # packed keys, and rows too wide to pack
        counts = rng.integers(0, 4, size=(300, 3))
        counts[:, 0] *= big
        keys, inverse = unique_rows(counts)
        want_keys, want_inverse = np.unique(counts, axis=0, return_inverse=True)
        assert sorted(map(tuple, keys.tolist())) == sorted(map(tuple, want_keys.tolist()))
        assert (keys[inverse] == counts).all() and len(keys) == len(want_keys)
        assert len(want_inverse.reshape(-1)) == len(inverse)


def test_frontier_pops_in_heap_order():
    rng = np.random.default_rng(2)
    bound = rng.integers(0, 20, 600).astype(float)
    stage = rng.integers(0, 2, 600)
    level, row = rng.integers(0, 4, 600), np.arange(600)
    queue = Frontier(bound, stage, level, row)
    heap = list(zip(bound.tolist(), stage.tolist(), level.tolist(), row.tolist(), strict=True))
    heapq.heapify(heap)
    popped = 0
    while heap:
        assert queue.peek() == heap[0]
        item = queue.pop()
        assert item == heapq.heappop(heap)
        popped += 1
        if popped % 3 == 0:  # later pushes interleave with the presorted entries
            new = (item[0] + float(rng.integers(0, 5)), 1, 9, popped)
            queue.push(new)
            heapq.heappush(heap, new)
    assert not queue


def test_one_type_fitness_bound_by_count_is_the_rows(table):
    """One part type: the bound is read from a table per count, equal to the row's own."""
    types = ["foot"]
    counts = np.random.default_rng(3).integers(0, 9, size=(500, 1))
    batch = fitness_upper_bounds(table, types, counts)
    rows = [fitness_upper_bounds(table, types, counts[k : k + 1])[0] for k in range(0, 500, 7)]
    assert batch[::7].tolist() == rows
    assert batch.max() == 0.0 and batch.min() < 0.0  # -D_same's bound, no cross pairs


def _compiled_and_python_runs(inst: Instance, params: GreedyParams, seed: int) -> list[tuple]:
    """A plan with the rest search's compiled core loop wherever it can run, and with the
    Python loop: (kits, scores, counters) of each."""
    from bilevel_kit.heuristics import _rest_kernel
    from bilevel_kit.heuristics.prefix import rests

    if _rest_kernel.kernel() is None:
        pytest.skip("numba is not available")
    runs = []
    for compiled in (True, False):
        with pytest.MonkeyPatch.context() as mp:
            mp.setattr(rests, "MIN_DEEP_COMPILED", 0)  # compiled whenever it can be
            if not compiled:
                mp.setattr(_rest_kernel, "kernel", lambda: None)
            policy = GreedyCEPolicy(inst, params, seed)
            kits = plan(inst, policy=policy).kits
        st_ = policy.stats
        scores = [t["score"] for t in st_.objective_terms]
        counters = (st_.prefix_sets, st_.evaluated, st_.beam_epochs, st_.rest_capped, st_.ce_calls)
        runs.append((kits, scores, counters))
    return runs


@settings(max_examples=30, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(enumerable_instances(), st.integers(0, 3), st.integers(1, 30), st.booleans())
def test_compiled_rest_search_changes_nothing(inst, seed, max_rest, signed):
    """The compiled core loop of the rest search (exact sums) against the Python loop: the
    same kits, scores and counters, also when the rest search stops at its cap."""
    params = GreedyParams(ce=TINY_CE, max_rest_nodes=max_rest, signed=signed)
    runs = _compiled_and_python_runs(inst, params, seed)
    assert runs[0] == runs[1]


def test_epoch_cache_gives_the_decisions_of_a_fresh_search(table):
    """Epochs met again (the simulator's runs) reuse what was computed from ``done`` alone:
    the same kits and scores as a policy that never saw them, at other H_rem, parts at hand
    and human times (changing those empties the cache)."""
    from bilevel_kit.heuristics.greedy_ce import PolicyState

    inst = table.with_overrides(units=2)
    params = GreedyParams(ce=TINY_CE)
    warm = GreedyCEPolicy(inst, params, 0)
    kits = plan(inst, policy=warm).kits
    states, done = [], frozenset()
    for k, kit in enumerate(kits):
        parts = {"leg": k % 3, "foot": 1} if k % 2 else None
        states.append(PolicyState(done, 7.0 * k, parts))
        done = done | frozenset(kit.tasks)
    assert warm._search._epochs  # the plan's epochs are cached
    for scale in (None, 1.3):
        if scale is not None:
            warm.set_human_scale(scale)
            assert not warm._search._epochs
        for _ in range(1 if scale is None else 2):  # (with the scale: fill, then reuse)
            for state in states:
                cold = GreedyCEPolicy(inst, params, 0)
                if scale is not None:
                    cold.set_human_scale(scale)
                assert warm.decide(state) == cold.decide(state)
                scores = [p.stats.objective_terms[-1]["score"] for p in (warm, cold)]
                assert scores[0] == scores[1]
        assert len(warm._search._epochs) == len(states)


@pytest.mark.parametrize(
    ("family", "size", "max_rest"),
    [("intree", 60, 2000), ("intree", 40, 7), ("series-parallel", 60, 30)],
)
def test_compiled_rest_search_on_generated_graphs(family, size, max_rest):
    """The compiled core loop against the Python loop where windows hold many deep tasks
    (generated in-trees and series-parallel graphs), also with the rest search capped."""
    from bilevel_kit.generate import generate

    inst = from_dict(generate(family, size, seed=1))
    runs = _compiled_and_python_runs(inst, GreedyParams(ce=TINY_CE, max_rest_nodes=max_rest), 0)
    assert runs[0] == runs[1]


@pytest.mark.parametrize(("family", "size"), [("intree", 60), ("series-parallel", 60)])
def test_unlocked_rows_are_the_per_row_rule(family, size, table, monkeypatch):
    """The level-at-once unlocked children (numpy) equal :meth:`Precedence.unlocked_after` row
    by row, on graphs where prefixes unlock many tasks (in-trees: joins with several
    predecessors)."""
    from bilevel_kit.generate import generate
    from bilevel_kit.heuristics.prefix.levels import Precedence

    original = Precedence.unlocked_rows
    checked = [0, 0]  # rows, rows with unlocked children

    def spy(self, p_unl, par, child, tasks, undone):
        out = original(self, p_unl, par, child, tasks, undone)
        n = self.n
        assert out.shape[0] == len(child) and (out.shape[1] == 0 or (out < n).any(axis=0).all())
        for k in range(len(child)):
            parent = tuple(int(u) for u in p_unl[par[k]] if u < n)
            want = self.unlocked_after(parent, tuple(tasks[k].tolist()), int(child[k]), undone)
            assert tuple(int(u) for u in out[k] if u < n) == want
            checked[1] += bool(want)
        checked[0] += len(child)
        return out

    monkeypatch.setattr(Precedence, "unlocked_rows", spy)
    for inst in (from_dict(generate(family, size, seed=1)), table):
        res = solve(inst, "greedy-ce", seed=0, samples=20, elite=5, max_iter=5)
        assert check(inst, res.plan) == []
    assert checked[0] > 1000 and checked[1] > 100
