"""The stronger lower bounds of bilevel_kit.models.relax against brute force: never above the
optimum (overall, and the kit-count LP for every kit count against the best plan of exactly
that many kits), with one, two and unlimited trays, delivery, overheads and precedence."""

from __future__ import annotations

import math

import pytest
from brute import agrees, fits, segmentations
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from reference_timeline import timeline, times_of
from test_exact_trays import random_doc

from bilevel_kit import load
from bilevel_kit.bounds import best_bound
from bilevel_kit.instance import from_dict
from bilevel_kit.models.relax import closed_at, proven_bound, time_grid
from bilevel_kit.models.relax.precedence import head_tail_bounds
from bilevel_kit.plan import Kit, Plan, evaluate


def best_by_kits(inst) -> dict[int, float]:
    """The least makespan of the plans of exactly m kits whose kits fit, for every m (the
    reference timeline's, the evaluator held to it on every plan: tests/brute.py)."""
    times = times_of(inst)
    best: dict[int, float] = {}
    for kits in segmentations(inst):
        if all(fits(inst, k) for k in kits):
            ref = timeline(times, kits)
            agrees(ref, evaluate(inst, Plan(tuple(Kit(k) for k in kits))), kits)
            best[len(kits)] = min(best.get(len(kits), math.inf), ref.makespan)
    return best


def check_bounds(inst) -> None:
    per_m = best_by_kits(inst)
    opt = min(per_m.values())
    bound = proven_bound(inst, time_limit=30.0)
    assert bound.value <= opt + 1e-6, (bound, opt)
    for m, value in bound.per_kits.items():
        if m in per_m:
            assert value <= per_m[m] + 1e-6, (m, value, per_m[m])
    closed = closed_at(inst)
    for m, value in per_m.items():
        assert bound.at(m, closed) <= value + 1e-6, (m, bound.at(m, closed), value)
    for m, value in per_m.items():  # the kit cap never excludes a plan as good as the optimum
        cap = bound.kit_cap(opt, closed)
        assert cap is None or value > opt + 1e-9 or m <= cap
    ht = head_tail_bounds(inst)
    assert ht["head"] <= opt + 1e-6 and ht["tail"] <= opt + 1e-6
    assert bound.value >= best_bound(inst) - 1e-6


@pytest.mark.parametrize("trays", [1, 2, None])
@pytest.mark.parametrize("seed", range(6))
def test_bounds_never_exceed_the_brute_force_optimum(seed, trays):
    check_bounds(from_dict(random_doc(seed, trays)))


@settings(max_examples=25, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(st.integers(100, 10_000), st.sampled_from([1, 2, None]), st.integers(2, 6))
def test_bounds_hold_on_random_instances(seed, trays, n):
    check_bounds(from_dict(random_doc(seed, trays, n)))


@settings(max_examples=15, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(st.integers(0, 10_000), st.sampled_from([1, None]))
def test_robot_heavy_instances(seed, trays):
    """A busy robot (long picks, short assembly): the tail bound's side."""
    doc = random_doc(seed, trays, 5)
    for task in doc["tasks"]:
        task["robot_time"] = 5.0 + (seed % 7) + len(task["id"])
        task["human_time"] = {"mean": 1.0 + (seed % 3)}
    check_bounds(from_dict(doc))


def test_kit_lp_beats_the_closed_forms_on_the_table():
    """One tray: 430.37 s against 415.78 s (the optimum is 435.085 s)."""
    inst = load("instances/hrc_table.json")
    bound = proven_bound(inst, time_limit=30.0)
    assert bound.source == "kit_lp"
    assert bound.value == pytest.approx(430.37, abs=0.01)
    assert best_bound(inst) == pytest.approx(415.78)
    assert time_grid(inst) == pytest.approx(0.005)


def test_kit_count_lp_gives_the_same_bound_after_many_lps() -> None:
    """Each LP gets a HiGHS object of its own (docs/simulation.md#determinism): a reused one
    (HiGHS before 2.0 measures ``time_limit`` against the run time it accumulated over all its
    runs) timed every LP out once the process had spent one LP's limit in earlier ones, which
    made a stations-study cell's result depend on the cells its worker ran before it."""
    import time

    from bilevel_kit.bounds import min_kits
    from bilevel_kit.models.relax.kit_lp import kit_count_bound

    inst = load("instances/hrc_table.json")
    closed = closed_at(inst)

    def scan() -> dict[int, float]:
        deadline = time.perf_counter() + 0.5  # each LP a limit of under 0.5 s
        return kit_count_bound(inst, closed, m_min=min_kits(inst), deadline=deadline).per_kits

    first = scan()
    assert first and round(min(first.values()), 2) == 430.37
    t0 = time.perf_counter()
    while time.perf_counter() - t0 < 1.5:  # more than one LP's limit spent in earlier LPs
        assert scan() == first


def test_deterministic_kit_count_scan_is_limited_by_work() -> None:
    """``deterministic``: the scan stops by its LPs' task x kit variables, not the clock; a
    wall-clock safety net that fires is recorded."""
    import time
    from types import SimpleNamespace

    from bilevel_kit.models import relax
    from bilevel_kit.models.relax import kit_lp

    inst = load("instances/hrc_table.json")
    full = proven_bound(inst, time_limit=0.5, deterministic=True)
    assert full.value == 430.37 and not full.safety_net
    # work for the first kit count's LP alone: the scan stops there, whatever the clock says
    m0 = min(full.per_kits)
    one = kit_lp.kit_count_bound(
        inst,
        closed_at(inst),
        m_min=m0,
        deadline=time.perf_counter() + 60.0,
        work=inst.n_tasks * m0,
    )
    assert list(one.per_kits) == [m0] and not one.safety_net
    now = [time.perf_counter()]

    def late() -> float:  # every reading 100 s later: the safety net has passed
        now[0] += 100.0
        return now[0]

    clock = SimpleNamespace(perf_counter=late)
    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(relax, "time", clock)
        mp.setattr(kit_lp, "time", clock)
        cut = proven_bound(inst, time_limit=0.5, deterministic=True)
    assert cut.safety_net and cut.per_kits == {}
