"""Packing limits: wall-clock (the default) or CP-SAT's deterministic time (reproducible),
and the oracle's memo keeping the two apart (docs/simulation.md#determinism)."""

from __future__ import annotations

import pytest
from slowclock import TRAY, hard_counts, hard_items, part_types, slow_packing_clock

from bilevel_kit.models import packing as pk
from bilevel_kit.models import packing_oracle as po
from bilevel_kit.models.budget import Budget
from bilevel_kit.models.common import Packer

pytest.importorskip("ortools")


@pytest.fixture(autouse=True)
def _fresh_cache():
    po.clear_cache()
    yield
    po.clear_cache()


def test_the_kit_needs_cp_sat():
    res = pk.pack(TRAY, hard_items(), time_limit=30.0, deterministic_time=5.0)
    assert res.status == "feasible" and "reason" not in res.extra  # not the shelf heuristic
    assert res.extra["cpsat_status"] == "OPTIMAL"
    assert 0 < res.extra["deterministic_time"] < 5.0 and res.extra["safety_net"] is False


def test_a_slow_clock_changes_a_wall_limited_answer_not_a_deterministic_one(monkeypatch):
    slow_packing_clock(monkeypatch)
    wall = pk.pack(TRAY, hard_items(), time_limit=0.5)
    assert wall.status == "unknown"  # as before: the wall limit had passed
    assert "safety_net" not in wall.extra
    det = pk.pack(TRAY, hard_items(), time_limit=30.0, deterministic_time=5.0)
    assert det.status == "feasible" and det.extra["safety_net"] is False
    # too little deterministic time: unknown, and the same whatever the clock
    short = pk.pack(TRAY, hard_items(), time_limit=30.0, deterministic_time=1e-3)
    assert short.status == "unknown" and short.extra["safety_net"] is False


def test_the_safety_net_is_marked():
    # an absurd wall-clock net (CP-SAT's 10 ms minimum): the kit's 0.02 units take longer
    res = pk.pack(TRAY, hard_items(), time_limit=1e-6, deterministic_time=5.0)
    assert res.status == "unknown" and res.extra["safety_net"] is True


def test_the_oracle_memoises_unknowns_per_kind_of_limit(monkeypatch):
    types, counts = part_types(), hard_counts()
    key = frozenset(counts.items())
    with monkeypatch.context() as m:
        slow_packing_clock(m)
        fit = po.fit_verdict(TRAY, types, counts, time_limit=0.5)
        assert fit.fits is None and fit.why == po.WHY_TIME
        # a wall-clock unknown is not a deterministic one: the call solves, the clock is slow
        fit = po.fit_verdict(TRAY, types, counts, time_limit=30.0, deterministic_time=5.0)
        assert fit.fits is True
    po.clear_cache()
    fit = po.fit_verdict(TRAY, types, counts, time_limit=30.0, deterministic_time=1e-3)
    assert fit.fits is None
    cache = next(iter(po._CACHES.values()))
    assert cache.unknown == {(key, po.DET): (1e-3, po.WHY_TIME)}
    # ... and a deterministic unknown says nothing of a wall-clock limit
    assert po.fit_verdict(TRAY, types, counts, time_limit=30.0).fits is True


def test_the_oracle_is_reproducible_under_a_slow_clock(monkeypatch):
    types, counts = part_types(), hard_counts()
    quiet = po.fit_verdict(TRAY, types, counts, time_limit=30.0, deterministic_time=5.0)
    po.clear_cache()
    slow_packing_clock(monkeypatch)
    loaded = po.fit_verdict(TRAY, types, counts, time_limit=30.0, deterministic_time=5.0)
    assert loaded == quiet  # the same verdict and layout (one worker, same limit)
    assert quiet.fits is True


def test_packer_limits(table):
    budget = Budget(100.0)
    wall = Packer(table, 0.5, budget)
    assert wall.limits() == {"time_limit": 0.5}  # as before
    assert wall.limits(0.05) == {"time_limit": 0.05}
    det = Packer(table, 0.5, budget, deterministic=True)
    dtime, net = po.deterministic_limits(0.5)
    assert det.limits() == {"deterministic_time": dtime, "time_limit": net}
    assert net == pytest.approx(po.SAFETY_NET * 0.5) and dtime == pytest.approx(0.5 * po.DET_PER_S)
    assert det.sub(0.2, budget).deterministic and not wall.sub(0.2, budget).deterministic
    assert wall.limits(deterministic=True) == det.limits()
    assert det.limits(deterministic=False) == wall.limits()


def test_a_deterministic_budget_gives_sub_steps_the_whole_budget_and_records_its_net():
    """docs/simulation.md#determinism: a reproducible run's steps are limited by work, the
    budget's deadline is their one safety net, and a sub-budget that sees it records it."""
    plain = Budget(10.0, start=0.0, deadline=10.0)
    stretched = Budget(10.0, start=0.0, deadline=10.0, stretch=10.0)
    assert plain.head(0.05).deadline == pytest.approx(0.5)
    assert not plain.deterministic and stretched.deterministic
    assert stretched.head(0.05).deadline == pytest.approx(10.0)
    assert stretched.head(0.5).deadline == pytest.approx(10.0)  # never past the deadline
    sub = stretched.cut(1.0).next(0.1)
    assert sub.stretch == 10.0 and not stretched.net
    assert sub.expired() and stretched.net  # (start 0: the deadline has long passed)
    assert plain.expired() and not plain.net  # a wall-clock run has no net to record
