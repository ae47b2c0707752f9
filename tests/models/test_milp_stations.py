"""milp with several assembly stations (docs/timeline.md#several-stations) equals the brute
force (tests/brute.py, the one evaluator, kits of one station) on random two- and
three-station instances with their own delivery times, trays and human overheads (the
generator of tests/models/test_cpsat_stations.py), for each objective."""

from __future__ import annotations

import pytest
import strategies
from brute import assert_model_optimal, assert_objective_optimal, best_makespan

from bilevel_kit.bounds import objective_bound
from bilevel_kit.instance import from_dict
from bilevel_kit.plan import evaluate
from bilevel_kit.stations import objective_of
from bilevel_kit.validate import check

pytest.importorskip("ortools")
pytest.importorskip("pyomo")

CASES = [(seed, s) for seed in range(12) for s in (2, 3)]


@pytest.mark.parametrize(("seed", "n_stations"), CASES)
def test_milp_equals_brute_force_on_stations(seed, n_stations):
    from bilevel_kit.models.milp import MilpOptions, milp

    inst = from_dict(strategies.stations_doc(seed, n_stations, n=5 + seed % 2))
    opt, _ = best_makespan(inst)
    out = milp(inst, MilpOptions(), seed=0, time_limit=60)
    assert out.plan is not None
    assert check(inst, out.plan) == []
    assert out.extra["tray_mode"] == "benders"  # as cpsat's stations model
    assert_model_optimal(out, opt, tol=1e-5)  # the solver's tolerance, as tests/models/test_milp.py


@pytest.mark.parametrize("objective", ["sum_completion", "human_idle"])
@pytest.mark.parametrize(("seed", "n_stations"), CASES)
def test_milp_objectives_equal_brute_force_on_stations(seed, n_stations, objective):
    """The sum of completions and the total human idle: the proven optimum is the brute
    force's, the bound valid (at most the optimum) and the closed-form bound below both."""
    from bilevel_kit.models.milp import MilpOptions, milp

    inst = from_dict(strategies.stations_doc(seed, n_stations, n=5 + seed % 2))
    opt, _ = best_makespan(inst, objective)
    out = milp(inst, MilpOptions(objective=objective), seed=0, time_limit=60)
    assert out.plan is not None
    assert check(inst, out.plan) == []
    assert out.status_objective == objective
    assert out.extra["objective_value"] == objective_of(evaluate(inst, out.plan), objective)
    assert_objective_optimal(out, opt)
    assert objective_bound(inst, objective) <= opt + 1e-9
    assert out.bound <= evaluate(inst, out.plan).makespan + 1e-9  # still a makespan bound


def test_milp_stations_refuses_a_hint():
    from bilevel_kit.errors import UsageError
    from bilevel_kit.models.milp import MilpOptions, milp

    inst = from_dict(strategies.stations_doc(1, 2, n=4))
    with pytest.raises(UsageError, match="hint=none"):
        milp(inst, MilpOptions(hint="single-task"), time_limit=5)


def test_milp_sum_completion_on_one_station_is_the_makespan(table):
    """Without stations the sum of the completions is the makespan: solved as such."""
    from bilevel_kit.models.milp import solve

    out = solve(table, objective="sum_completion", time_limit=60)
    assert out.status_objective == "makespan"
    assert out.extra["objective"] == "makespan"


@pytest.mark.parametrize("objective", ["makespan", "sum_completion", "human_idle"])
def test_milp_stations_through_solve(objective):
    """The registry lets milp take stations; the result reports each station, and the chosen
    objective's value is the stations' completions or idles summed; the checker accepts it."""
    from bilevel_kit.methods import solve

    inst = from_dict(strategies.stations_doc(4, 3, n=5))
    res = solve(inst, "milp", time_limit=60, check=True, objective=objective)
    assert res.extra["violations"] == []
    metrics = res.extra["station_metrics"]
    assert max(m["completion"] for m in metrics.values()) == res.objective
    if objective != "makespan":
        key = "completion" if objective == "sum_completion" else "human_idle"
        want = sum(m[key] for m in metrics.values())
        assert res.extra["objective_value"] == pytest.approx(want, abs=1e-9)
        assert res.status_text == f"optimal (for {objective})"
