"""The paper's upper level (greedy-ce): validity, memoisation, weights, online policy."""

from __future__ import annotations

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from strategies import part_types_and_tasks

from bilevel_kit import check, load, solve
from bilevel_kit.heuristics.cross_entropy import CEParams
from bilevel_kit.heuristics.greedy_ce import GreedyCEPolicy, GreedyParams, PolicyState, plan
from bilevel_kit.instance import from_dict

FAST_CE = CEParams(samples=60, elite=10, max_iter=30)


def test_plans_pass_the_checker_on_every_instance(root):
    for path in sorted((root / "instances").rglob("*.json")):
        if "kitbench" in path.parts:  # the benchmark library: tests/experiments/ covers it
            continue
        inst = load(path)
        res = solve(inst, "greedy-ce", check=True)
        assert res.extra["violations"] == [], path.name
        assert res.status == "feasible" and res.objective >= res.bound - 1e-9


@pytest.mark.parametrize(
    ("trays", "makespan", "idle", "single_task"),
    [(1, 463.78, 57.0, 466.695), ("unlimited", 459.78, 53.0, 459.78)],
)
def test_table_plan_numbers(table, trays, makespan, idle, single_task):
    inst = table.with_overrides(trays=trays)  # the study's one tray, and no limit
    res = solve(inst, "greedy-ce", seed=0)
    sizes = [len(k.tasks) for k in res.plan.kits]
    # Eq. 6 pairs the first tasks of each leg (foot+conn), the tops follow one by one
    assert sizes == [2, 2, 2, 2, 1, 1, 1, 1]
    assert res.objective == pytest.approx(makespan)
    assert res.metrics["human_idle"] == pytest.approx(idle)
    st_ = solve(inst, "single-task")
    wa = solve(inst, "whole-assembly")
    assert st_.objective == pytest.approx(single_task)
    assert res.objective <= st_.objective + 1e-9 < wa.objective


def test_memoisation_each_multiset_arranged_once(table):
    policy = GreedyCEPolicy(table, GreedyParams(ce=FAST_CE), seed=0)
    p = plan(table, policy=policy)
    assert check(table, p) == []
    st_ = policy.stats
    # every CE call is a distinct part multiset, and most look-ups were served from the cache
    assert st_.ce_calls == len(policy._arrangements)
    assert st_.fitness_cache_hits > st_.ce_calls
    # asking for a kit already arranged does not call CE again
    calls = st_.ce_calls
    policy.arrangement(table.kit_parts(["foot1"]))
    assert policy.stats.ce_calls == calls


def test_w2_controls_kit_size(table):
    big = solve(table.with_overrides(weights={"W2": 200}), "greedy-ce")
    small = solve(table.with_overrides(delivery_time=0, weights={"W2": 0}), "greedy-ce")
    big_sizes = [len(k.tasks) for k in big.plan.kits]
    small_sizes = [len(k.tasks) for k in small.plan.kits]
    # W2 = 200 s/task outweighs every timing term: the horizon's 5 tasks go in one kit twice
    assert big_sizes == [5, 5, 2]
    # W2 = 0, d = 0: only the timing terms count; no kit holds more than 2 tasks and half of
    # the kits are single tasks (the tops, once the legs are prepared)
    assert max(small_sizes) == 2 and small_sizes.count(1) == 4 and len(small_sizes) == 8
    assert sum(big_sizes) / len(big_sizes) > 2 * sum(small_sizes) / len(small_sizes)


def test_same_seed_same_plan_and_options_reach_the_method(stool):
    a = solve(stool, "greedy-ce", seed=3, samples=50, elite=10, max_iter=20)
    b = solve(stool, "greedy-ce", seed=3, samples=50, elite=10, max_iter=20)
    assert a.plan == b.plan
    assert a.params["samples"] == 50


def test_unknown_option_is_a_usage_error(stool):
    from bilevel_kit import UsageError

    with pytest.raises(UsageError, match="unknown option"):
        solve(stool, "greedy-ce", colour="red")


@pytest.mark.parametrize(
    ("params", "match"),
    [
        ({"samples": "abc"}, "option 'samples': expected an integer"),
        ({"W5": "abc"}, "option 'W5': expected"),
        ({"w5": "abc"}, "option 'W5': expected"),
        ({"horizon": 0}, "option 'horizon'"),
        ({"precedence": "soft"}, "option 'precedence': must be one of"),
        ({"precision": "float16"}, "option 'precision': must be one of"),
        ({"samples": 20, "elite": 30}, "need samples >= elite"),
        ({"cov_smoothing": 0}, "smoothing and cov_smoothing must lie in"),
    ],
)
def test_bad_option_values_are_usage_errors(stool, params, match):
    from bilevel_kit import UsageError

    with pytest.raises(UsageError, match="greedy-ce") as info:
        solve(stool, "greedy-ce", **params)
    assert match in str(info.value)


def test_options_mirror_ce_params_and_convert():
    from dataclasses import fields

    from bilevel_kit.heuristics.greedy_ce import GreedyCEOptions
    from bilevel_kit.methods import get_method

    opts = {f.name: f for f in fields(GreedyCEOptions)}
    for f in fields(CEParams):  # every CE field, same default
        assert opts[f.name].default == f.default, f.name
    assert all(f.metadata.get("help") for f in opts.values())
    assert [o.name for o in get_method("greedy-ce").describe_options()] == list(opts)
    params = GreedyCEOptions().to_params()
    assert params == GreedyParams()
    spec = get_method("greedy-ce")
    o = spec.parse({"horizon": "3", "w2": "7", "signed": "true", "samples": "80", "elite": 12})
    assert o.to_params() == GreedyParams(
        horizon=3, weights={"W2": 7.0}, signed=True, ce=CEParams(samples=80, elite=12)
    )


def test_online_policy_decides_from_state(table):
    policy = GreedyCEPolicy(table, GreedyParams(ce=FAST_CE), seed=0)
    first = policy.decide(PolicyState())
    assert first.tasks[0] == "foot1"
    done = frozenset(t.id for t in table.tasks) - {"top4"}
    assert policy.decide(PolicyState(done=done)).tasks == ("top4",)
    assert policy.decide(PolicyState(done=frozenset(t.id for t in table.tasks))) is None


def test_w7_avoids_unavailable_parts(table):
    policy = GreedyCEPolicy(
        table.with_overrides(weights={"W7": 1000}), GreedyParams(ce=FAST_CE), seed=0
    )
    # no legs available: the first kits must be the connector-free... only foot tasks need legs
    kit = policy.decide(
        PolicyState(
            available={"leg": 0, "foot": 4, "connector": 4, "screw_short": 8, "screw_long": 8}
        )
    )
    # every task that can go first (foot1..4) needs a leg, so W7 cannot be avoided; the policy
    # takes exactly one leg-needing task (one unavailable part), never several
    assert table.kit_parts(kit.tasks)["leg"] == 1
    default = GreedyCEPolicy(table, GreedyParams(ce=FAST_CE), seed=0).decide(PolicyState())
    assert table.kit_parts(default.tasks)["leg"] == 1  # (the default also starts with one leg)
    done = frozenset({"foot1", "foot2"})
    kit = policy.decide(
        PolicyState(
            done=done,
            available={"leg": 0, "foot": 4, "connector": 4, "screw_short": 8, "screw_long": 8},
        )
    )
    assert all(not any(p == "leg" for p, _ in table.task_by_id[t].parts) for t in kit.tasks)


def test_signed_and_penalty_forms_run(stool):
    for opts in ({"signed": True}, {"precedence": "penalty"}):
        res = solve(stool, "greedy-ce", check=True, **opts)
        assert res.extra["violations"] == []


@st.composite
def small_instances(draw):
    types, tasks = part_types_and_tasks(draw, max_side=60, max_tasks=6)
    n = len(tasks)
    edges = [
        [f"t{a}", f"t{b}"]
        for a in range(n)
        for b in range(a + 1, n)
        if draw(st.integers(0, 3)) == 0
    ]
    return from_dict(
        {
            "format": "bilevel-kit/1",
            "name": "h",
            "tray": {"width": 200.0, "height": 150.0},
            "delivery_time": draw(st.integers(0, 10)) * 1.0,
            "kit_overhead": {"robot": draw(st.integers(0, 5)) * 1.0, "human": 1.0},
            "part_types": types,
            "tasks": tasks,
            "precedence": edges,
            "horizon": draw(st.integers(1, 4)),
        }
    )


@settings(max_examples=25, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(small_instances(), st.integers(0, 3))
def test_property_greedy_plan_is_always_valid(inst, seed):
    p = plan(inst, GreedyParams(ce=FAST_CE), seed=seed)
    assert check(inst, p) == []


def test_cli_greedy_figures_and_options(capsys, tmp_path, root):
    from bilevel_kit.cli import main

    tray, conv, out = tmp_path / "tray.png", tmp_path / "conv.png", tmp_path / "s.json"
    code = main(
        [
            "solve",
            str(root / "instances/stool.json"),
            "--method",
            "greedy-ce",
            "--horizon",
            "2",
            "--weights",
            "W3=1,W4=1",
            "--seed",
            "0",
            "-p",
            "samples=80",
            "--tray",
            str(tray),
            "--convergence",
            str(conv),
            "--out",
            str(out),
            "--check",
        ]
    )
    text = capsys.readouterr().out
    assert code == 0 and "check: valid" in text
    assert tray.read_bytes()[:4] == b"\x89PNG" and conv.read_bytes()[:4] == b"\x89PNG"
    import json

    doc = json.loads(out.read_text())
    assert doc["params"]["samples"] == 80 and doc["extra"]["ce_calls"] >= 1
    assert (
        len(doc["extra"]["kit_terms"][0]["trace"]) == doc["extra"]["kit_terms"][0]["ce_iterations"]
    )
    # --convergence needs a CE trace: a baseline gives exit 2 and writes nothing
    bad = tmp_path / "none.png"
    code = main(
        [
            "solve",
            str(root / "instances/stool.json"),
            "-m",
            "single-task",
            "--convergence",
            str(bad),
            "--out",
            str(tmp_path / "x.json"),
        ]
    )
    assert code == 2 and not bad.exists() and not (tmp_path / "x.json").exists()
    assert "records no CE trace" in capsys.readouterr().err


def test_polish_option_never_lowers_kit_fitness(table):
    plain = GreedyCEPolicy(table, GreedyParams(ce=FAST_CE), seed=0)
    polished = GreedyCEPolicy(table, GreedyParams(ce=FAST_CE, polish=True), seed=0)
    for tasks in (["foot1", "conn1"], ["foot1", "foot2", "foot3"], ["top1", "conn2", "foot3"]):
        counts = table.kit_parts(tasks)
        a, b = plain.arrangement(counts), polished.arrangement(counts)
        assert b.fitness >= a.fitness - 1e-9
        assert b.source.endswith("+polish")
    res = solve(table, "greedy-ce", polish=True, check=True)
    assert res.extra["violations"] == []
    assert res.params["polish"] is True


def test_ce_layouts_pass_the_checker_for_every_kit_of_the_table(table):
    """CE at the paper's parameters on each single-task kit, every greedy-ce kit and the
    whole-assembly kit of hrc_table.json: the checker accepts each layout."""
    from bilevel_kit import Kit, Plan
    from bilevel_kit.heuristics.cross_entropy import arrange

    greedy = solve(table, "greedy-ce").plan
    kits = [(t.id,) for t in table.tasks] + [k.tasks for k in greedy.kits]
    kits.append(tuple(t.id for t in table.tasks))
    for seed, tasks in enumerate(kits):
        arr = arrange(table, table.kit_parts(tasks), rng=seed)
        assert arr.fits and arr.z == 0.0, tasks
        violations = [
            v
            for v in check(table, Plan((Kit(tasks, arr.layout),)))
            if v.kind not in ("missing_task", "precedence")
        ]
        assert violations == [], (tasks, violations)


def test_past_the_time_limit_the_rest_are_single_tasks_in_one_pass(root):
    """Many units past a tiny limit: every remaining task alone, the plan valid (one pass
    over the tasks: 15,000 tasks took 95 s when each rebuilt the set of done tasks)."""
    from bilevel_kit import load, solve
    from bilevel_kit.validate import check

    inst = load(root / "instances" / "tiny.json").with_overrides(units=300)
    res = solve(inst, "greedy-ce", time_limit=1e-6)
    assert res.extra["time_limit_hit"] and len(res.plan.kits) == inst.n_tasks
    assert check(inst, res.plan) == []


def test_the_time_limit_stops_an_enumeration_mid_epoch(table):
    """A long horizon's epoch (horizon 8 enumerated: ~10^5 sequences, dozens of layouts) took
    17 s at a 2 s limit: when the limit passes while the epoch's layouts are computed, the
    epoch takes the single-task kit, without laying out the rest."""
    ce = CEParams(samples=20, elite=5, max_iter=3)
    params = GreedyParams(horizon=8, decision="enumerate", ce=ce)
    policy = GreedyCEPolicy(table, params, seed=0)
    policy.deadline = float("inf")  # not past at the epoch's start
    calls = []

    def past() -> bool:
        calls.append(1)
        return policy.stats.ce_calls >= 3  # the limit passes after three new layouts

    policy.past_deadline = past  # type: ignore[method-assign]
    kit = policy.decide(PolicyState(frozenset(), 0.0))
    assert kit is not None and kit.tasks == ("foot1",)
    # foot1 alone was among the three layouts: the single-task kit reuses it
    assert policy.stats.time_limit_hit and policy.stats.ce_calls == 3
    assert policy.stats.sequences == 36_120 and len(calls) > 3


def test_unique_rows_equals_numpy_row_unique():
    """The mixed-radix shortcut (used by the enumeration too) keeps np.unique's order, keys
    and inverse."""
    import numpy as np

    from bilevel_kit.heuristics.prefix.levels import unique_rows

    rng = np.random.default_rng(0)
    for shape, high in [((500, 3), 4), ((2000, 6), 9), ((1, 2), 1), ((50, 1), 3)]:
        rows = rng.integers(0, high, size=shape)
        keys, inverse = unique_rows(rows)
        want_keys, want_inv = np.unique(rows, axis=0, return_inverse=True)
        assert np.array_equal(keys, want_keys)
        assert np.array_equal(inverse, want_inv.reshape(-1))
    wide = np.array([[2**40, 1], [0, 2**40], [2**40, 1]])  # radix product above 2^62
    keys, inverse = unique_rows(wide)
    assert keys.tolist() == [[0, 2**40], [2**40, 1]] and inverse.tolist() == [1, 0, 1]
