"""Statistics of the simulation's random ingredients: feeders and the task-time model."""

from __future__ import annotations

import math

import numpy as np
import pytest
import simpy

from bilevel_kit.instance import Supply
from bilevel_kit.sim import (
    PAPER_TABLE_MEAN,
    PAPER_TABLE_SD,
    Feeder,
    SimParams,
    TimingModel,
    effective_instance,
)
from bilevel_kit.sim.timing import sample_participants, sample_times

HORIZON = 1_000_000.0  # simulated seconds; a feeder alone runs this in well under a second


def _feeder(supply: Supply, seed: int, until: float = HORIZON) -> Feeder:
    env = simpy.Environment()
    f = Feeder(env, "leg", supply, np.random.default_rng(seed))
    env.run(until=until)
    return f


@pytest.mark.parametrize(("mat", "mttf"), [(60.0, 90.0), (30.0, 30.0), (120.0, 60.0)])
def test_feeder_rate_and_fraction_broken(mat: float, mttf: float) -> None:
    repair = 30.0
    f = _feeder(Supply(mat, mttf, repair), seed=int(mat + mttf))
    frac_broken = f.time_broken() / HORIZON
    # fraction broken: ~8000 up/down cycles or more, SD of the estimate < 0.01
    assert frac_broken == pytest.approx(repair / (mttf + repair), abs=0.03)
    up = HORIZON - f.time_broken()
    # arrivals per up-second: Poisson count of >= 6000, relative SD < 1.3 %
    assert f.arrivals / up == pytest.approx(1 / mat, rel=0.05)
    # the long-run rate, including the up/down variability
    assert f.arrivals / HORIZON == pytest.approx((1 / mat) * mttf / (mttf + repair), rel=0.06)
    # failures: one per cycle of mean length MTTF + repair
    assert f.failures == pytest.approx(HORIZON / (mttf + repair), rel=0.06)
    # the state's expected time to the next arrival is the inverse long-run rate when up
    if not f.broken:
        assert f.expected_time_to_arrival() == pytest.approx(mat * (1 + repair / mttf))


def test_feeder_without_failures_has_rate_one_over_mat() -> None:
    f = _feeder(Supply(60.0, None, 30.0), seed=3)
    assert f.failures == 0
    assert f.time_broken() == 0.0
    assert f.arrivals / HORIZON == pytest.approx(1 / 60.0, rel=0.04)
    assert f.stock == f.arrivals  # nobody consumed
    assert f.expected_time_to_arrival() == 60.0


def test_feeder_broken_means_no_arrivals() -> None:
    """With repairs much longer than up times, arrivals scale with the (short) up time."""
    f = _feeder(Supply(10.0, 5.0, 100.0), seed=5, until=200_000.0)
    up = 200_000.0 - f.time_broken()
    assert f.time_broken() / 200_000.0 == pytest.approx(100 / 105, abs=0.02)
    assert f.arrivals / up == pytest.approx(0.1, rel=0.1)


def test_feeder_take_and_arrival_event() -> None:
    env = simpy.Environment()
    f = Feeder(env, "foot", Supply(5.0), np.random.default_rng(0), initial=2)
    f.take()
    f.take()
    with pytest.raises(RuntimeError):
        f.take()
    ev = f.arrival()
    assert f.arrival() is ev  # shared by everyone waiting now
    env.run(until=ev)
    assert f.stock == 1 and f.arrivals == 1 and f.consumed == 2
    assert f.stats()["initial"] == 2


def test_participant_totals_match_the_paper(table) -> None:
    """Per-table human totals: mean 374.78 s, SD 61.14 s (the paper's user-study numbers)."""
    base = sum(t.human_mean for t in table.base_tasks)
    assert base == pytest.approx(PAPER_TABLE_MEAN)
    n = 20_000
    for dist in ("lognormal", "normal"):
        model = TimingModel(participant_dist=dist)
        s = sample_participants(table, model, np.random.default_rng(11), n)
        totals = base * s
        assert (s > 0).all()
        # SE of the mean ~0.43 s, of the SD ~0.35 s at n = 20000
        assert totals.mean() == pytest.approx(PAPER_TABLE_MEAN, abs=2.0)
        assert totals.std(ddof=1) == pytest.approx(PAPER_TABLE_SD, abs=2.0)


def test_sampled_task_times_per_unit(table) -> None:
    """One participant per unit: within a unit every task is scaled by the same factor."""
    inst = effective_instance(table, SimParams(units=400))
    st = sample_times(inst, TimingModel(), np.random.default_rng(1), np.random.default_rng(2))
    totals = np.zeros(inst.units)
    for t in inst.tasks:
        ratio = st.human[t.id] / t.human_mean
        assert ratio == pytest.approx(st.speed[t.unit - 1], rel=1e-12)
        totals[t.unit - 1] += st.human[t.id]
    assert totals.mean() == pytest.approx(PAPER_TABLE_MEAN, abs=3 * 61.14 / math.sqrt(400) + 1)
    # robot picks are deterministic by default: the instance's pick times
    for t in inst.tasks:
        assert st.robot(t.id) == pytest.approx(inst.robot_time(t.id), abs=1e-12)


def test_task_noise_and_robot_noise(table) -> None:
    inst = effective_instance(table, SimParams(units=300))
    model = TimingModel(participant_cv=0.0, task_cv=0.2, robot_cv=0.1)
    st = sample_times(inst, model, np.random.default_rng(4), np.random.default_rng(5))
    ratios = np.array([st.human[t.id] / t.human_mean for t in inst.tasks])
    assert ratios.mean() == pytest.approx(1.0, abs=0.02)
    assert ratios.std() == pytest.approx(0.2, abs=0.02)
    picks = np.array(
        [d / inst.part_types[p].pick_time for t in inst.tasks for p, d in st.picks[t.id]]
    )
    assert picks.mean() == pytest.approx(1.0, abs=0.01)
    assert picks.std() == pytest.approx(0.1, abs=0.01)


def test_participant_cv_from_instance(stool) -> None:
    model = TimingModel(participant_cv=None)
    want = (3 + 2 + 2) / (20 + 15 + 15)
    assert model.cv_for(stool) == pytest.approx(want)


def test_robot_time_override_is_spread_over_parts(doc) -> None:
    from bilevel_kit.instance import from_dict

    doc["tasks"][0]["robot_time"] = 9.0  # x: 2 parts of type a
    doc["tasks"][2]["robot_time"] = 4.0  # z: no parts -> one block
    inst = from_dict(doc)
    st = sample_times(
        inst, TimingModel.deterministic(), np.random.default_rng(0), np.random.default_rng(0)
    )
    assert st.picks["x"] == (("a", 4.5), ("a", 4.5))
    assert st.picks["y"] == (("b", 2.0),)
    assert st.picks["z"] == ((None, 4.0),)


def test_timing_model_rejects_bad_values() -> None:
    from bilevel_kit.errors import UsageError

    with pytest.raises(UsageError):
        TimingModel(participant_dist="uniform")
    with pytest.raises(UsageError):
        TimingModel(task_cv=-0.1)
    with pytest.raises(UsageError):
        TimingModel(robot_scale=0.0)
