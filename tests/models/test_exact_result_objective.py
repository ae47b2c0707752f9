"""``cpsat`` and ``milp`` with ``-p objective=sum_completion`` / ``human_idle``: the result's
``objective``, ``bound`` and ``gap`` are that objective's (issue 36, item 1), the value the
registry's evaluation of the returned timeline, the gap the one formula, the makespan's
numbers beside them; the solution file states both and checks (docs/formats.md#solutions)."""

from __future__ import annotations

import json

import pytest
import strategies

from bilevel_kit import solution
from bilevel_kit.instance import from_dict
from bilevel_kit.methods import OBJECTIVE_KEYS, solve
from bilevel_kit.objectives import OBJECTIVES, relative_gap

pytest.importorskip("ortools")


#: The optima of strategies.stations_doc(0, 2, n=5), both methods proving them (s).
OPTIMA = {"sum_completion": 100.5, "human_idle": 41.5}


@pytest.mark.parametrize("objective", sorted(OPTIMA))
@pytest.mark.parametrize("method", ["cpsat", "milp"])
def test_the_result_reports_the_minimised_objective(method, objective):
    inst = from_dict(strategies.stations_doc(0, 2, n=5))
    params = {"workers": 1} if method == "cpsat" else {}
    res = solve(inst, method, time_limit=60, check=True, objective=objective, **params)
    assert res.extra["violations"] == []
    assert res.objective_name == objective and res.status == "optimal", (res.status, res.extra)
    assert res.objective == OBJECTIVES[objective].value(res.timeline)
    assert res.objective == pytest.approx(OPTIMA[objective], abs=1e-6)
    assert res.bound is not None and res.bound <= res.objective + 1e-9
    assert res.gap == relative_gap(res.objective, res.bound)
    assert res.gap == pytest.approx(0.0, abs=1e-9)  # proven optimal for every plan
    # the makespan: a metric with its own bound, not the minimised objective's numbers
    assert res.makespan == res.metrics["makespan"] == res.timeline.makespan
    assert res.makespan_bound is not None and res.makespan_bound <= res.makespan + 1e-9
    assert res.makespan_gap == relative_gap(res.makespan, res.makespan_bound)
    assert res.objective != res.makespan  # two stations: a sum, an idle, differ from it
    assert not set(OBJECTIVE_KEYS) & set(res.extra)  # stated once, not again in extra
    doc = json.loads(json.dumps(solution.result_to_dict(res)))
    assert doc["objective"] == {
        "name": objective,
        "value": res.objective,
        "bound": res.bound,
        "gap": res.gap,
    }
    assert doc["makespan"]["value"] == res.makespan
    assert solution.from_dict(doc).check(inst) == []


def test_one_station_human_idle_reports_its_numbers(tiny):
    """cpsat on one station: the idle bound was only in ``extra["idle_bound"]`` before; the
    result now states the idle (4 s on tiny, proven) as its objective."""
    res = solve(tiny, "cpsat", time_limit=30, check=True, objective="human_idle", workers=1)
    assert res.extra["violations"] == []
    assert (res.objective_name, res.status) == ("human_idle", "optimal")
    assert res.objective == res.timeline.human_idle == 4.0
    assert res.bound == pytest.approx(4.0) and res.gap == pytest.approx(0.0)
    assert (res.makespan, res.makespan_bound) == (25.5, 24.5)
