"""The exact sample-average model (bilevel_kit/models/cpsat/saa.py) equals a brute force over
plans on the same scenarios (issue 41), and the Jensen bound of
docs/formulations.md#stochastic-human-times-sample-average-approximation holds plan by plan.

The brute force is tests/brute.py's: every precedence-feasible segmentation whose kits all
fit (exact 0/90-degree packing on the 1 mm grid), each scored by the sample average of its
makespan under the scenarios (the reference timeline of tests/reference_timeline.py with the
scenario's human times, the package's evaluator held to it on every plan)."""

from __future__ import annotations

import numpy as np
import pytest
import strategies
from brute import fits, segmentations
from reference_timeline import close, timeline, times_of

from bilevel_kit import stochastic as st
from bilevel_kit.instance import from_dict
from bilevel_kit.plan import Kit, Plan, evaluate

pytest.importorskip("ortools")

#: The model rounds scenario times down on a 1 ms grid: n tasks x 1 ms per scenario at most.
TOL = 0.01


def saa_brute(inst, scenarios) -> tuple[float, float]:
    """(the least sample average over every valid plan, the least mean-time makespan with the
    scenarios' average times); asserts Jensen for every plan on the way."""
    means = st.mean_times(scenarios, inst)
    ids = [t.id for t in inst.tasks]
    each = [times_of(inst, human_times=dict(zip(ids, row, strict=True))) for row in scenarios]
    at_means = times_of(inst, human_times=means)
    best, best_mean = np.inf, np.inf
    for kits in segmentations(inst):
        if not all(fits(inst, k) for k in kits):
            continue
        plan = Plan(tuple(Kit(k) for k in kits))
        # the reference timeline's values (tests/reference_timeline.py); the package's agree
        value = float(np.mean([timeline(times, kits).makespan for times in each]))
        assert close(value, st.expected_makespan(inst, plan, scenarios))
        at_mean = timeline(at_means, kits).makespan
        assert close(at_mean, evaluate(inst, plan, human_times=means).makespan)
        assert at_mean <= value + 1e-9  # Jensen: the makespan is convex in the human times
        best, best_mean = min(best, value), min(best_mean, at_mean)
    return best, best_mean


def instance(seed: int, trays: int | None):
    doc = strategies.random_doc(seed, 5)
    if trays is not None:
        doc["trays"] = trays
    return from_dict(doc)


CASES = [(seed, trays) for seed in range(10) for trays in (1, 2, None)]


def check_case(seed: int, trays: int | None, cv: float = 0.4, n: int = 4) -> None:
    from bilevel_kit.models.cpsat.saa import solve_saa

    inst = instance(seed, trays)
    scenarios = st.sample(inst, n, seed, cv=cv)
    opt, jensen = saa_brute(inst, scenarios)
    assert jensen <= opt + 1e-9
    out = solve_saa(inst, scenarios, time_limit=60)
    assert out.proven, out.info
    assert out.value == pytest.approx(opt, abs=TOL), (seed, trays, out.info)
    assert out.value >= opt - 1e-9  # a plan cannot beat the brute force
    assert out.bound is not None and out.bound <= opt + 1e-9
    plan = Plan(tuple(Kit(k) for k in out.kits or ()))
    assert st.expected_makespan(inst, plan, scenarios) == pytest.approx(out.value)


def test_saa_model_equals_the_brute_force_on_one_case():
    check_case(3, 1)


@pytest.mark.slow
@pytest.mark.parametrize(("seed", "trays"), CASES)
def test_saa_model_equals_the_brute_force(seed, trays):
    """30 random 5-task instances x trays 1, 2, unlimited, 4 scenarios at CV 0.4."""
    check_case(seed, trays)


def test_one_scenario_at_the_mean_is_the_mean_time_problem():
    """With the one scenario of the mean times the SAA optimum is the deterministic optimum
    (the brute force's), the mean-time objective unchanged."""
    from brute import best_makespan

    from bilevel_kit.models.cpsat.saa import solve_saa

    inst = instance(7, 1)
    means = np.array([[t.human_mean for t in inst.tasks]])
    out = solve_saa(inst, means, time_limit=60)
    assert out.proven
    assert out.value == pytest.approx(best_makespan(inst)[0], abs=1e-9)


def test_scenarios_have_the_tasks_mean_and_cv_and_separate_streams():
    inst = instance(1, None)
    big = st.sample(inst, 40_000, 5, cv=0.3)
    means = np.array([t.human_mean for t in inst.tasks])
    assert big.mean(axis=0) == pytest.approx(means, rel=0.01)
    assert (big.std(axis=0) / means) == pytest.approx(np.full(len(means), 0.3), rel=0.03)
    a = st.sample(inst, 5, 5, cv=0.3, stream=st.OPTIMISE)
    b = st.sample(inst, 5, 5, cv=0.3, stream=st.EVALUATE)
    assert not np.allclose(a, b)
    assert np.array_equal(a, st.sample(inst, 5, 5, cv=0.3))


def test_lns_expected_makespan_result_passes_the_checker():
    from bilevel_kit.methods import solve

    inst = instance(2, 1)
    res = solve(
        inst, "lns", time_limit=6, check=True, objective="expected_makespan", scenarios=5, cv=0.3
    )
    assert res.status_objective == "expected_makespan"
    assert res.objective <= res.extra["mean_plan_expected_makespan"] + 1e-9
    assert res.bound is None or res.bound <= res.objective + 1e-9
    assert res.extra["violations"] == [], res.extra
    plain = solve(inst, "lns", time_limit=6)
    assert plain.status_objective == "makespan"
