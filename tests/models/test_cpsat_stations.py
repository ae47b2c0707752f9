"""cpsat with several assembly stations (docs/timeline.md#several-stations) equals the brute
force (tests/brute.py, the one evaluator, kits of one station) on random two- and
three-station instances with their own delivery times, trays and human overheads."""

from __future__ import annotations

import pytest
import strategies
from brute import assert_model_optimal, best_makespan

from bilevel_kit.instance import from_dict
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


def test_cpsat_stations_refuses_other_objectives():
    from bilevel_kit.errors import UsageError
    from bilevel_kit.models.cpsat.method import CpsatOptions, cpsat

    inst = from_dict(strategies.stations_doc(1, 2, n=4))
    with pytest.raises(UsageError, match="objective=makespan"):
        cpsat(inst, CpsatOptions(objective="human_idle"), time_limit=5)
