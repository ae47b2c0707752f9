"""Several assembly stations (docs/timeline.md#several-stations): the brute force over 2-3
stations, the closed-form bound below it, and the baselines' plans, interleaved by earliest
need, accepted by the checker on random two- and three-station instances."""

from __future__ import annotations

import pytest
import strategies
from brute import best_makespan, segmentations

from bilevel_kit import bounds, check
from bilevel_kit.instance import from_dict
from bilevel_kit.methods import solve
from bilevel_kit.plan import evaluate

pytest.importorskip("ortools")

CASES = [(seed, s) for seed in range(12) for s in (2, 3)]


@pytest.mark.parametrize(("seed", "n_stations"), CASES)
def test_brute_force_and_baselines_on_stations(seed, n_stations):
    inst = from_dict(strategies.stations_doc(seed, n_stations, n=5 + seed % 2))
    assert len({t.station for t in inst.tasks}) == n_stations
    opt, plan = best_makespan(inst)
    assert plan is not None
    # the brute force's kits hold one station each (it lays out no parts)
    assert {v.kind for v in check(inst, plan)} <= {"parts_mismatch"}
    assert bounds.best_bound(inst) <= opt + 1e-9
    big = from_dict(
        {
            **strategies.stations_doc(seed, n_stations, n=5 + seed % 2),
            "tray": {"width": 400.0, "height": 400.0},
        }
    )
    for method, on in (("single-task", inst), ("whole-assembly", big)):
        res = solve(on, method, check=True)
        assert res.extra["violations"] == [], (method, res.extra["violations"])
        if on is inst:
            assert res.objective >= opt - 1e-9
            assert res.bound <= opt + 1e-9
        metrics = res.extra["station_metrics"]
        assert max(m["completion"] for m in metrics.values()) == res.objective
        assert sum(m["n_kits"] for m in metrics.values()) == len(res.plan.kits)


def test_segmentations_never_mix_stations():
    inst = from_dict(strategies.stations_doc(3, 3, n=6))
    seen = 0
    for kits in segmentations(inst):
        seen += 1
        assert all(len({inst.station_of(t) for t in k}) == 1 for k in kits)
    assert seen > 0


def test_whole_assembly_interleaves_by_earliest_need():
    """Two stations, one kit each per unit: the robot serves the station whose human is free
    first, so with two units per station the kits alternate as the humans' ends dictate."""
    doc = strategies.stations_doc(5, 2, n=4)
    doc["units"] = 2
    inst = from_dict(doc)
    res = solve(inst, "whole-assembly", check=True)
    assert res.extra["violations"] == []
    assert len(res.plan.kits) == 4
    tl = evaluate(inst, res.plan)
    ends: dict[str, float] = {s: 0.0 for s in inst.station_ids}
    for kit, kt in zip(res.plan.kits, tl.kits, strict=True):
        s = inst.station_of(kit.tasks[0])
        # the chosen station had the earliest free human among those with kits left
        left = {inst.station_of(k.tasks[0]) for k in res.plan.kits[res.plan.kits.index(kit) :]}
        assert ends[s] == min(ends[x] for x in left)
        ends[s] = kt.human_end
