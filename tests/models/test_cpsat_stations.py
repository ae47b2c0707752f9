"""cpsat with several assembly stations (docs/timeline.md#several-stations) equals the brute
force (tests/brute.py, the one evaluator, kits of one station) on random two- and
three-station instances with their own delivery times, trays and human overheads, for each
objective."""

from __future__ import annotations

import pytest
import strategies
from brute import assert_model_optimal, assert_objective_optimal, best_makespan

from bilevel_kit.instance import from_dict
from bilevel_kit.plan import evaluate
from bilevel_kit.stations import objective_of
from bilevel_kit.validate import check

pytest.importorskip("ortools")

CASES = [(seed, s) for seed in range(12) for s in (2, 3)]


@pytest.mark.parametrize(("seed", "n_stations"), CASES)
def test_cpsat_equals_brute_force_on_stations(seed, n_stations):
    from bilevel_kit.models.cpsat.method import CpsatOptions, cpsat

    inst = from_dict(strategies.stations_doc(seed, n_stations, n=5 + seed % 2))
    opt, _ = best_makespan(inst)
    out = cpsat(inst, CpsatOptions(workers=1), seed=0, time_limit=60)
    assert out.plan is not None
    assert check(inst, out.plan) == []
    assert_model_optimal(out, opt)


@pytest.mark.parametrize("objective", ["sum_completion", "human_idle"])
@pytest.mark.parametrize(("seed", "n_stations"), CASES)
def test_cpsat_objectives_equal_brute_force_on_stations(seed, n_stations, objective):
    """The sum of completions and the total human idle (tests/models/test_milp_stations.py)."""
    from bilevel_kit.models.cpsat.method import CpsatOptions, cpsat

    inst = from_dict(strategies.stations_doc(seed, n_stations, n=5 + seed % 2))
    opt, _ = best_makespan(inst, objective)
    out = cpsat(inst, CpsatOptions(workers=1, objective=objective), seed=0, time_limit=60)
    assert out.plan is not None
    assert check(inst, out.plan) == []
    assert out.status_objective == objective
    assert out.extra["objective_value"] == objective_of(evaluate(inst, out.plan), objective)
    assert_objective_optimal(out, opt)
    assert out.bound <= evaluate(inst, out.plan).makespan + 1e-9  # still a makespan bound


def test_cpsat_sum_completion_on_one_station_is_the_makespan(table):
    from bilevel_kit.models.cpsat.method import CpsatOptions, cpsat

    out = cpsat(table, CpsatOptions(objective="sum_completion"), time_limit=30)
    assert out.status_objective == "makespan"
    assert out.extra["objective"] == "makespan"
