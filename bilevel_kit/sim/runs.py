"""Runs of the shop-floor simulation: :func:`simulate` (a :class:`SimResult`), :func:`run` (its
plain record) and :func:`replicate` (one record per seed); docs/simulation.md.

Each is a pure function of (instance, policy, :class:`~.params.SimParams`, seed). The executed
schedule is a :class:`bilevel_kit.plan.Timeline`, the same type the evaluator returns, so with
no supply process and deterministic times the two can be compared field by field.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from dataclasses import asdict, dataclass, field, replace
from typing import Any

import numpy as np

from ..errors import UsageError
from ..instance import Instance
from ..plan import KitTimes, Plan, Timeline
from .params import SimParams, effective_instance
from .registry import make_policy
from .shopfloor import STREAM, ShopFloor, SimulationError
from .state import Policy
from .stations import StationsPolicy, require_station_policy
from .timing import SampledTimes, sample_times


@dataclass(frozen=True)
class SimResult:
    """One simulated run: the executed kits (and their layouts) as a :class:`Plan`, their
    schedule as a :class:`Timeline`, and what only a simulation has (waits, feeders, ...)."""

    instance: Instance  # the effective instance
    policy: str
    seed: int
    plan: Plan
    timeline: Timeline
    kit_waits: tuple[float, ...]
    robot_wait: float
    n_waits: int
    robot_blocked: float
    max_queue: int
    unit_end: tuple[float, ...]
    times: SampledTimes
    feeders: Mapping[str, Mapping[str, float | int]]
    params: SimParams
    arrival_times: Mapping[str, tuple[float, ...]] = field(default_factory=dict)
    #: decisions a wall-clock safety net cut short (``cpsat-rolling``: not reproducible,
    #: docs/simulation.md#determinism); 0 for the other policies
    safety_nets: int = 0
    #: committed kits split because the policy's plan had a first kit that nothing laid out
    #: (``cpsat-rolling``, docs/simulation.md#determinism); 0 for the other policies
    layout_fallbacks: int = 0

    @property
    def kit_times(self) -> tuple[KitTimes, ...]:
        return self.timeline.kits

    @property
    def task_start(self) -> Mapping[str, float]:
        return self.timeline.task_start

    @property
    def task_end(self) -> Mapping[str, float]:
        return self.timeline.task_end

    @property
    def makespan(self) -> float:
        return self.timeline.makespan

    @property
    def human_idle(self) -> float:
        return self.timeline.human_idle

    @property
    def robot_idle(self) -> float:
        return self.timeline.robot_idle

    @property
    def human_work(self) -> float:
        return self.timeline.human_work

    @property
    def robot_work(self) -> float:
        return self.timeline.robot_work

    @property
    def n_kits(self) -> int:
        return len(self.plan.kits)

    def record(self) -> dict[str, Any]:
        """The plain JSON-serialisable record :func:`run` returns."""
        return {
            "instance": self.instance.name,
            "policy": self.policy,
            "seed": self.seed,
            "units": self.instance.units,
            "makespan": self.makespan,
            "human_idle": self.human_idle,
            "robot_idle": self.robot_idle,
            "human_work": self.human_work,
            "robot_work": self.robot_work,
            "n_kits": self.n_kits,
            "robot_wait": self.robot_wait,
            "n_waits": self.n_waits,
            "robot_blocked": self.robot_blocked,
            "max_queue": self.max_queue,
            "unit_end": list(self.unit_end),
            "kits": [list(k.tasks) for k in self.plan.kits],
            "kit_times": [
                {**asdict(kt), "wait": w}
                for kt, w in zip(self.kit_times, self.kit_waits, strict=True)
            ],
            "speed": list(self.times.speed),
            "human_times": dict(self.times.human),
            "robot_times": self.times.robot_times(),
            "feeders": {k: dict(v) for k, v in self.feeders.items()},
            "params": self.params.to_dict(),
            **({"stations": self.timeline.station_metrics()} if self.instance.stations else {}),
            # (only when it happened: the records of every other run stay as they were)
            **({"layout_fallbacks": self.layout_fallbacks} if self.layout_fallbacks else {}),
        }


def _policy(instance: Instance, policy: str | Policy, params: SimParams, seed: int) -> Policy:
    """The run's policy: built by name, or the given object (checked and ``reset()``)."""
    if isinstance(policy, str):
        pseed = seed if params.policy_seed is None else params.policy_seed
        return make_policy(policy, instance, seed=pseed, params=params)
    if instance.stations and not isinstance(policy, StationsPolicy):
        raise UsageError(
            "with several stations the policy object must be built by make_policy "
            "(one policy per station, docs/simulation.md#several-stations)"
        )
    if getattr(policy, "instance", None) is not None and [t.id for t in policy.instance.tasks] != [
        t.id for t in instance.tasks
    ]:
        raise UsageError("the policy object was built for a different instance or units")
    policy.reset()
    return policy


def _result(shop: ShopFloor, pol: Policy, seed: int) -> SimResult:
    """The engine's log of a finished run as a :class:`SimResult`."""
    inst = shop.inst
    makespan = shop.env.now
    unit_end = [0.0] * inst.units
    for t in inst.tasks:
        unit_end[t.unit - 1] = max(unit_end[t.unit - 1], shop.task_end[t.id])
    timeline = Timeline.from_work(
        [KitTimes(**kt) for kt in shop.kit_times],
        shop.task_start,
        shop.task_end,
        makespan,
        shop.human_work,
        shop.robot_work,
    )
    if inst.stations:  # each human's idle up to its own completion (docs/timeline.md)
        ends = [h.last_end for h in shop.humans.values()]
        timeline = replace(
            timeline,
            human_idle=sum(ends) - shop.human_work,
            kit_stations=tuple(shop.kit_stations),
        )
    return SimResult(
        instance=inst,
        policy=getattr(pol, "name", type(pol).__name__),
        seed=seed,
        plan=Plan(tuple(shop.kits)),
        timeline=timeline,
        kit_waits=tuple(shop.kit_waits),
        robot_wait=shop.robot_wait,
        n_waits=shop.n_waits,
        robot_blocked=shop.robot_blocked,
        max_queue=shop.max_queue,
        unit_end=tuple(unit_end),
        times=shop.times,
        feeders={t: f.stats() for t, f in shop.feeders.items()},
        params=shop.params,
        arrival_times={t: tuple(f.arrival_times) for t, f in shop.feeders.items()},
    )


def simulate(
    instance: Instance,
    policy: str | Policy,
    *,
    params: SimParams | None = None,
    seed: int = 0,
) -> SimResult:
    """Simulate one run (see :mod:`.shopfloor`); :func:`run` returns its record.

    ``policy`` is a registered name or a policy object built on
    ``effective_instance(instance, params)`` (it is ``reset()`` first; :func:`replicate` uses
    this to share one policy, and its layout cache, between runs).
    """
    params = params or SimParams()
    seed = int(seed)
    if seed < 0:
        raise UsageError(f"seed must be >= 0, got {seed}")
    if isinstance(policy, str):
        require_station_policy(instance, policy)
    inst = effective_instance(instance, params)
    pol = _policy(inst, policy, params, seed)
    times = sample_times(
        inst,
        params.timing,
        np.random.default_rng(np.random.SeedSequence([seed, STREAM, 0])),
        np.random.default_rng(np.random.SeedSequence([seed, STREAM, 1])),
    )
    shop = ShopFloor(inst, pol, params, times, seed)
    env = shop.env
    # (a shared policy counts over its runs: the run's own counts are differences)
    nets, splits = getattr(pol, "safety_nets", 0), getattr(pol, "layout_fallbacks", 0)
    env.run(until=shop.finished | env.timeout(params.max_time))
    if not shop.finished.triggered:
        raise SimulationError(f"the run did not finish within {params.max_time:g} s")
    return replace(
        _result(shop, pol, seed),
        safety_nets=getattr(pol, "safety_nets", 0) - nets,
        layout_fallbacks=getattr(pol, "layout_fallbacks", 0) - splits,
    )


def run(
    instance: Instance,
    policy: str | Policy,
    *,
    params: SimParams | None = None,
    seed: int = 0,
) -> dict[str, Any]:
    """One run as a plain JSON-serialisable record (metrics, executed kits, feeder counters).

    A pure function of (instance, policy, params, seed).
    """
    return simulate(instance, policy, params=params, seed=seed).record()


def replicate(
    instance: Instance,
    policy: str | Policy,
    params: SimParams | None = None,
    seeds: Iterable[int] = range(30),
    progress: bool = False,
) -> list[dict[str, Any]]:
    """Records of one run per seed. With a fixed ``params.policy_seed`` one policy object
    serves every run (same records as separate :func:`run` calls, but the optimized policy
    arranges each distinct kit only once)."""
    params = params or SimParams()
    seeds = list(seeds)
    shared: str | Policy = policy
    if isinstance(policy, str) and params.policy_seed is not None:
        shared = make_policy(
            policy, effective_instance(instance, params), seed=params.policy_seed, params=params
        )
    it: Iterable[int] = seeds
    if progress:
        from tqdm import tqdm

        name = policy if isinstance(policy, str) else getattr(policy, "name", "policy")
        it = tqdm(seeds, desc=f"simulate {name}", unit="run")
    return [run(instance, shared, params=params, seed=s) for s in it]
