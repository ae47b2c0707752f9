"""milp with several assembly stations (docs/timeline.md#several-stations) equals the brute
force (tests/brute.py, the one evaluator, kits of one station) on random two- and
three-station instances with their own delivery times, trays and human overheads (the
generator of tests/models/test_cpsat_stations.py)."""

from __future__ import annotations

import pytest
import strategies
from brute import assert_model_optimal, best_makespan

from bilevel_kit.instance import from_dict
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


def test_milp_stations_refuses_other_objectives():
    from bilevel_kit.errors import UsageError
    from bilevel_kit.models.milp import MilpOptions, milp

    inst = from_dict(strategies.stations_doc(1, 2, n=4))
    with pytest.raises(UsageError, match="objective=makespan"):
        milp(inst, MilpOptions(objective="human_idle"), time_limit=5)


def test_milp_stations_through_solve():
    """The registry lets milp take stations; the result reports each station."""
    from bilevel_kit.methods import solve

    inst = from_dict(strategies.stations_doc(4, 3, n=5))
    res = solve(inst, "milp", time_limit=60, check=True)
    assert res.extra["violations"] == []
    metrics = res.extra["station_metrics"]
    assert max(m["completion"] for m in metrics.values()) == res.objective
