"""The CP-SAT schedule with per-task release times against brute-force enumeration."""

from __future__ import annotations

import itertools
import random

import pytest
from brute import fits, model_verdict, segmentations
from reference_timeline import reference, timeline, times_of
from strategies import random_doc

from bilevel_kit.instance import from_dict
from bilevel_kit.models import cpsat as cs
from bilevel_kit.models.cpsat.model import release_bound
from bilevel_kit.plan import Kit, Plan, evaluate

pytest.importorskip("ortools")

FAST = {"workers": 2, "time_limit": 20.0}


def released_makespan(inst, kits, rel) -> float:
    """The reference timeline (tests/reference_timeline.py) where task i cannot be picked
    before ``rel[i]`` and the robot picks each kit in its best topological order (written
    independently of the model: every order is tried, waits simulated one task after the
    other)."""
    anc = inst.ancestors

    def pick(start: float, kit) -> float:
        best = float("inf")
        for perm in itertools.permutations(kit):
            pos = {t: j for j, t in enumerate(perm)}
            if any(pos.get(a, -1) > pos[t] for t in perm for a in anc[t]):
                continue
            t = start + inst.kit_overhead_robot
            for task in perm:
                t = max(t, rel.get(task, 0.0)) + inst.robot_time(task)
            best = min(best, t)
        return best

    return timeline(times_of(inst), kits, pick).makespan


def brute_force(inst, rel) -> float:
    return min(
        released_makespan(inst, kits, rel)
        for kits in segmentations(inst)
        if all(fits(inst, k) for k in kits)
    )


def _releases(seed: int, inst) -> dict[str, float]:
    """Half-second releases up to 30 s on about half the tasks (at least one)."""
    rng = random.Random(1000 + seed)
    rel = {t.id: rng.randint(1, 60) / 2 for t in inst.tasks if rng.random() < 0.5}
    return rel or {inst.tasks[-1].id: 10.0}


def _instance(seed: int):
    doc = random_doc(seed)
    if seed % 3 == 0:
        doc["trays"] = 1
    return from_dict(doc)


def test_independent_timeline_without_releases_is_the_evaluator():
    for seed in range(6):
        inst = _instance(seed)
        for kits in itertools.islice(segmentations(inst), 40):
            plan = Plan(tuple(Kit(k) for k in kits))
            assert released_makespan(inst, kits, {}) == pytest.approx(
                evaluate(inst, plan).makespan, abs=1e-9
            )


@pytest.mark.parametrize("seed", range(8))
def test_scaled_timeline_with_releases_matches_the_independent_one(seed):
    inst = _instance(seed)
    rel = _releases(seed, inst)
    for kits in itertools.islice(segmentations(inst), 60):
        plan = Plan(tuple(Kit(k) for k in kits))
        best = released_makespan(inst, kits, rel)
        assert cs.released_makespan(inst, plan, rel) == pytest.approx(best, abs=1e-9)
        # picking in order of release is the best order (docs/formulations.md)
        assert reference(inst, kits, releases=rel).makespan == pytest.approx(best, abs=1e-9)


@pytest.mark.parametrize("seed", range(8))
def test_matches_brute_force_with_releases(seed):
    inst = _instance(seed)
    rel = _releases(seed, inst)
    opt = brute_force(inst, rel)
    sc = cs.scale_times(inst, 0.1, True, rel)
    assert release_bound(inst, sc) * sc.res <= opt + 1e-9
    for mode in ("embedded", "benders"):
        out = cs.solve(inst, tray=mode, releases=rel, **FAST)
        proven, bound = model_verdict(out)  # among 0/90-degree plans, like the brute force
        assert proven, (mode, out.extra)
        assert out.extra["release_makespan"] == pytest.approx(opt, abs=1e-9)
        assert bound == pytest.approx(opt, abs=1e-9)
        assert out.bound <= opt + 1e-9
        assert (out.extra["gap"] == 0.0) == (out.status == "optimal")
        plan = out.plan
        kits = [k.tasks for k in plan.kits]
        assert released_makespan(inst, kits, rel) == pytest.approx(opt, abs=1e-9)
        assert out.extra["makespan"] == pytest.approx(evaluate(inst, plan).makespan)
        # each kit lists its tasks in a topological order of (raised) release: the robot
        # picking in the listed order attains the optimum
        for k in plan.kits:
            raised = [
                max([rel.get(t, 0.0)] + [rel.get(a, 0.0) for a in inst.ancestors[t]])
                for t in k.tasks
            ]
            assert raised == sorted(raised)


def test_releases_only_delay():
    """A release at or before the robot's first pick never binds; a late one adds to C."""
    inst = _instance(1)
    plain = cs.solve(inst, tray="benders", **FAST)
    ids = [t.id for t in inst.tasks]
    late = cs.solve(inst, tray="benders", releases={ids[-1]: 500.0}, **FAST)
    assert late.extra["release_makespan"] > plain.extra["makespan"] + 400
    assert model_verdict(late)[0]


@pytest.mark.parametrize("seed", range(4))
def test_zero_releases_give_the_run_without_them(seed):
    inst = _instance(seed)
    one = {"workers": 1, "time_limit": 20.0}  # one worker: CP-SAT is deterministic
    base = cs.solve(inst, tray="benders", **one)
    for rel in ({}, {t.id: 0.0 for t in inst.tasks}):
        out = cs.solve(inst, tray="benders", releases=rel, **one)
        assert out.status == base.status
        assert out.plan == base.plan
        assert "release_makespan" not in out.extra
        for key in ("makespan", "gap", "max_kits", "upper_start", "solver_status"):
            assert out.extra[key] == base.extra[key], key


def test_bad_releases_are_a_usage_error():
    from bilevel_kit import UsageError

    inst = _instance(0)
    with pytest.raises(UsageError, match="unknown tasks"):
        cs.solve(inst, releases={"nope": 1.0}, **FAST)
    with pytest.raises(UsageError, match="finite and >= 0"):
        cs.solve(inst, releases={inst.tasks[0].id: -1.0}, **FAST)
