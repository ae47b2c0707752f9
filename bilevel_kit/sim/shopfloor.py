"""The shop-floor discrete-event simulation (paper Section V-B) on SimPy.

Processes:

* **Feeders** (:mod:`.feeders`): one per part type with a supply process.
* **Robot**: at each decision epoch (t = 0, then each time it is back from a delivery) it asks
  its policy for the next kit with a :class:`~.policies.SimState`; spends the kit overhead
  ``o_R``; picks the kit's parts one by one (each part's pick time, :mod:`.timing`), and when a
  part is out of stock waits until its feeder delivers one (recorded as a wait); then delivers
  in ``d`` (busy while delivering) and is free again.
* **Human**: takes a kit when it arrives if idle, otherwise the kit waits in a FIFO queue at the
  assembly station; spends ``o_H`` and assembles the kit's tasks in order with the sampled
  durations. The run ends when the human finishes the last task.

With no supply process and deterministic times this is exactly the timeline of
:func:`bilevel_kit.plan.evaluate` (docs/timeline.md) on the plan of kits the simulation
produced; the tests check it to 1e-9 for every policy. Note that the queue is not limited to
one kit: the evaluator lets the robot start kit k+1 as soon as kit k has arrived, so a fast
robot can stack several kits at a slow human (``max_queue`` in the record says how many).

Choices (also in :class:`SimParams`):

* ``human_remaining`` in the state is observed progress plus expected durations: the robot
  sees which step of which kit the human is on and since when, and adds the instance's mean
  times for the rest (``human_estimate="oracle"`` uses the sampled durations instead).
* Parts are picked in kit order (tasks in order, each task's parts in file order);
  ``pick_order="available-first"`` picks in-stock parts first and waits only when none of the
  remaining parts is in stock.
* Robot idle = makespan - sum(R_k + d), as in the evaluator: time spent waiting for parts is
  robot idle time (and is also reported on its own as ``robot_wait``).

Randomness: :func:`run` is a pure function of (instance, policy, params, seed). Each run's
:class:`numpy.random.SeedSequence` ``[seed, 0x5EED, stream]`` feeds separate streams for the
human times, the robot times and each feeder (by the part type's index in sorted order), all
drawn independently of the policy's decisions: the same seed gives every policy the same
participants and the same arrivals (common random numbers for paired comparisons).
"""

from __future__ import annotations

import math
from collections import deque
from collections.abc import Callable, Generator, Iterable, Mapping
from dataclasses import asdict, dataclass, field, replace
from typing import Any

import numpy as np
import simpy

from ..errors import BilevelKitError, UsageError
from ..instance import DEFAULT_REPAIR_TIME, Instance, Supply
from ..layout.cross_entropy import CEParams
from ..plan import Kit, KitTimes, Plan
from .feeders import Feeder
from .policies import UNLIMITED, Policy, SimState, make_policy
from .timing import SampledTimes, TimingModel, sample_times

_STREAM = 0x5EED
_PICK_ORDERS = ("kit", "available-first")
_ESTIMATES = ("expected", "oracle")


class SimulationError(BilevelKitError):
    """A policy did something the shop floor cannot execute (or the run did not finish)."""


@dataclass(frozen=True)
class SimParams:
    """Everything about a run except the instance, the policy and the seed.

    Fields:
        units: units built in sequence (None: the instance's ``units``; the paper uses 10).
        delivery_time: overrides the instance's ``d`` (s) when not None.
        mat: part type -> mean inter-arrival time (s) of its feeder; adds or replaces supply
            processes on top of the instance's own ``supply`` (if ``use_instance_supply``).
        mttf: mean time to failure (s) of the feeders: one number for every supplied type, or
            a mapping per type; None keeps the instance's value (no failures if it has none).
        repair_time: fixed repair time (s) of every feeder; None: the instance's (30 s).
        use_instance_supply: start from the instance's ``supply`` section (else from none).
        initial_stock: parts in stock at t = 0 for supplied types (one number or per type;
            default 0, the feeders start empty).
        timing: the task-time model and its calibration knobs (:class:`TimingModel`).
        horizon, weights: greedy-ce's N and W1..W7 overrides (applied to the instance).
        ce: CE parameters of the optimized policy's lower level (None: the paper's).
        signed: greedy-ce's signed terms (5)-(6) as printed.
        policy_seed: seed of the policy's own randomness (CE layouts); None: the run seed. A
            fixed value lets replications share the policy's layout cache.
        pick_order: ``"kit"`` or ``"available-first"`` (see the module docstring).
        human_estimate: ``"expected"`` or ``"oracle"`` (see the module docstring).
        buffer: kits that may wait at the assembly station before the robot stops starting new
            ones: at a decision epoch the robot first waits (``robot_blocked``) until at most
            ``buffer`` delivered kits are still untaken. None (default): unlimited, the
            evaluator's semantics; 0: the user study's protocol ("the robot returned to its
            kitting task once the participant retrieved the parts").
        policy_options: free-form options for policies that need more (e.g. a time limit).
        max_time: simulated-time guard (s); a run that has not ended by then is an error.
    """

    units: int | None = None
    delivery_time: float | None = None
    mat: Mapping[str, float] = field(default_factory=dict)
    mttf: float | Mapping[str, float] | None = None
    repair_time: float | None = None
    use_instance_supply: bool = True
    initial_stock: int | Mapping[str, int] = 0
    timing: TimingModel = field(default_factory=TimingModel)
    horizon: int | None = None
    weights: Mapping[str, float] | None = None
    ce: CEParams | None = None
    signed: bool = False
    policy_seed: int | None = 0
    pick_order: str = "kit"
    human_estimate: str = "expected"
    buffer: int | None = None
    policy_options: Mapping[str, Any] = field(default_factory=dict)
    max_time: float = 1e8

    def __post_init__(self) -> None:
        if self.pick_order not in _PICK_ORDERS:
            raise UsageError(f"pick_order must be one of {_PICK_ORDERS}, got {self.pick_order!r}")
        if self.human_estimate not in _ESTIMATES:
            raise UsageError(
                f"human_estimate must be one of {_ESTIMATES}, got {self.human_estimate!r}"
            )
        if self.buffer is not None and self.buffer < 0:
            raise UsageError(f"buffer must be >= 0 or None, got {self.buffer!r}")

    def to_dict(self) -> dict[str, Any]:
        """A JSON-serialisable view (for run records)."""
        out = asdict(self)
        for k in ("mat", "policy_options"):
            out[k] = dict(getattr(self, k))
        for k in ("mttf", "initial_stock", "weights"):
            v = getattr(self, k)
            out[k] = dict(v) if isinstance(v, Mapping) else v
        return out


def resolve_supply(instance: Instance, params: SimParams) -> dict[str, Supply]:
    """The supply process of every supplied part type under ``params`` (see SimParams)."""
    base = dict(instance.supply) if params.use_instance_supply else {}
    for t in list(params.mat) + (list(params.mttf) if isinstance(params.mttf, Mapping) else []):
        if t not in instance.part_types:
            raise UsageError(
                f"unknown part type {t!r} in the supply options; types are "
                f"{', '.join(sorted(instance.part_types))}"
            )
    for t, mat in params.mat.items():
        old = base.get(t)
        base[t] = Supply(
            float(mat),
            old.mttf if old else None,
            old.repair_time if old else DEFAULT_REPAIR_TIME,
        )
    if isinstance(params.mttf, Mapping):
        missing = sorted(set(params.mttf) - set(base))
        if missing:
            raise UsageError(f"MTTF given for part type(s) without a supply: {missing}")
    out: dict[str, Supply] = {}
    for t, s in base.items():
        mttf = s.mttf
        if isinstance(params.mttf, Mapping):
            mttf = params.mttf.get(t, mttf)
        elif params.mttf is not None:
            mttf = params.mttf
        repair = s.repair_time if params.repair_time is None else params.repair_time
        mttf = None if mttf is None else float(mttf)
        for name, v in (("MAT", s.mat), ("MTTF", mttf)):
            if v is not None and not (math.isfinite(v) and v > 0):
                raise UsageError(f"part type {t!r}: {name} must be finite and > 0, got {v!r}")
        if not (math.isfinite(repair) and repair >= 0):
            raise UsageError(f"part type {t!r}: repair time must be finite and >= 0")
        out[t] = Supply(float(s.mat), mttf, float(repair))
    return out


def effective_instance(instance: Instance, params: SimParams) -> Instance:
    """The instance a run simulates and its policy plans with: units, ``d``, weights, horizon,
    the timing model's overheads and scales, and the resolved supply applied."""
    inst = instance.with_overrides(
        delivery_time=params.delivery_time,
        weights=params.weights,
        horizon=params.horizon,
        units=params.units,
    )
    tm = params.timing
    changes: dict[str, Any] = {"supply": resolve_supply(inst, params)}
    if tm.kit_overhead_robot is not None:
        changes["kit_overhead_robot"] = float(tm.kit_overhead_robot)
    if tm.kit_overhead_human is not None:
        changes["kit_overhead_human"] = float(tm.kit_overhead_human)
    if tm.robot_scale != 1.0:
        changes["part_types"] = {
            k: replace(p, pick_time=p.pick_time * tm.robot_scale)
            for k, p in inst.part_types.items()
        }
    if tm.robot_scale != 1.0 or tm.human_scale != 1.0:
        changes["base_tasks"] = tuple(
            replace(
                t,
                human_mean=t.human_mean * tm.human_scale,
                human_sd=t.human_sd * tm.human_scale,
                robot_time=None if t.robot_time is None else t.robot_time * tm.robot_scale,
            )
            for t in inst.base_tasks
        )
    return replace(inst, **changes)


@dataclass(frozen=True)
class SimResult:
    """One simulated run, with the executed kits (and their layouts) as a :class:`Plan`."""

    instance: Instance  # the effective instance
    policy: str
    seed: int
    plan: Plan
    kit_times: tuple[KitTimes, ...]
    kit_waits: tuple[float, ...]
    task_start: Mapping[str, float]
    task_end: Mapping[str, float]
    makespan: float
    human_idle: float
    robot_idle: float
    human_work: float
    robot_work: float
    robot_wait: float
    n_waits: int
    robot_blocked: float
    max_queue: int
    unit_end: tuple[float, ...]
    times: SampledTimes
    feeders: Mapping[str, Mapping[str, float | int]]
    params: SimParams
    arrival_times: Mapping[str, tuple[float, ...]] = field(default_factory=dict)

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
        }


class _ShopFloor:
    """One run's processes and bookkeeping (use :func:`simulate`)."""

    def __init__(
        self,
        inst: Instance,
        policy: Policy,
        params: SimParams,
        times: SampledTimes,
        seed: int,
    ) -> None:
        self.inst = inst
        self.policy = policy
        self.params = params
        self.times = times
        self.env = env = simpy.Environment()
        types = sorted(inst.part_types)
        init = params.initial_stock
        self.feeders: dict[str, Feeder] = {}
        for t, s in sorted(inst.supply.items()):
            n0 = init.get(t, 0) if isinstance(init, Mapping) else init
            rng = np.random.default_rng(np.random.SeedSequence([seed, _STREAM, 2, types.index(t)]))
            self.feeders[t] = Feeder(env, t, s, rng, int(n0))
        if params.human_estimate == "oracle":
            self._dur: Callable[[str], float] = times.human.__getitem__
        else:
            self._dur = inst.human_time
        self.kits: list[Kit] = []
        self.kit_times: list[dict[str, float]] = []
        self.kit_waits: list[float] = []
        self.done: set[str] = set()
        self.queue: deque[int] = deque()
        self.max_queue = 0
        self._kit_ready: simpy.Event | None = None
        self._kit_taken: simpy.Event | None = None
        self.robot_blocked = 0.0
        self.in_hand: int | None = None
        self.phase = -1
        self.phase_start = 0.0
        self.task_start: dict[str, float] = {}
        self.task_end: dict[str, float] = {}
        self.human_work = 0.0
        self.robot_work = 0.0
        self.robot_wait = 0.0
        self.n_waits = 0
        self.finished = env.event()
        env.process(self._robot())
        env.process(self._human())

    # -- the robot's view ----------------------------------------------------------------------
    def _human_remaining(self) -> float:
        now = self.env.now
        oh = self.inst.kit_overhead_human
        dur = self._dur
        rem = 0.0
        if self.in_hand is not None:
            tasks = self.kits[self.in_hand].tasks
            if self.phase < 0:
                rem += max(0.0, self.phase_start + oh - now) + sum(dur(t) for t in tasks)
            else:
                rem += max(0.0, self.phase_start + dur(tasks[self.phase]) - now)
                rem += sum(dur(t) for t in tasks[self.phase + 1 :])
        for k in self.queue:
            rem += oh + sum(dur(t) for t in self.kits[k].tasks)
        return rem

    def state(self) -> SimState:
        avail = dict.fromkeys(self.inst.part_types, UNLIMITED)
        for t, f in self.feeders.items():
            avail[t] = f.stock
        return SimState(
            time=self.env.now,
            done=frozenset(self.done),
            human_remaining=self._human_remaining(),
            available=avail,
            expected_arrival={t: f.expected_time_to_arrival() for t, f in self.feeders.items()},
            repair_remaining={t: f.repair_remaining() for t, f in self.feeders.items()},
            supply=dict(self.inst.supply),
            kits_delivered=len(self.kits),
        )

    def _check_kit(self, kit: Kit) -> None:
        name = getattr(self.policy, "name", type(self.policy).__name__)
        if not kit.tasks:
            raise SimulationError(f"policy {name!r} returned an empty kit")
        seen = set(self.done)
        for t in kit.tasks:
            if t not in self.inst.task_by_id:
                raise SimulationError(f"policy {name!r} kitted unknown task {t!r}")
            if t in seen:
                raise SimulationError(f"policy {name!r} kitted task {t!r} twice")
            missing = self.inst.predecessors[t] - seen
            if missing:
                raise SimulationError(
                    f"policy {name!r} kitted {t!r} before its predecessor(s) {sorted(missing)}"
                )
            seen.add(t)

    # -- processes -----------------------------------------------------------------------------
    def _robot(self) -> Generator[simpy.Event, Any, None]:
        env, inst = self.env, self.inst
        o_r, d = inst.kit_overhead_robot, inst.delivery_time
        buffer = self.params.buffer
        while True:
            if buffer is not None and len(self.queue) > buffer and len(self.done) < inst.n_tasks:
                t0 = env.now
                while len(self.queue) > buffer:
                    self._kit_taken = env.event()
                    yield self._kit_taken
                self.robot_blocked += env.now - t0
            kit = self.policy.decide(self.state())
            if kit is None:
                if len(self.done) < inst.n_tasks:
                    raise SimulationError(
                        f"policy stopped with {inst.n_tasks - len(self.done)} task(s) not kitted"
                    )
                return
            self._check_kit(kit)
            k = len(self.kits)
            self.kits.append(kit)
            self.done.update(kit.tasks)
            start = env.now
            if o_r:
                yield env.timeout(o_r)
            picks = [p for t in kit.tasks for p in self.times.picks[t]]
            busy = o_r + sum(dur for _, dur in picks)
            wait = 0.0
            if self.params.pick_order == "kit":
                for ptype, dur in picks:
                    f = self.feeders.get(ptype) if ptype is not None else None
                    if f is not None:
                        if f.stock == 0:
                            t0 = env.now
                            self.n_waits += 1
                            while f.stock == 0:
                                yield f.arrival()
                            wait += env.now - t0
                        f.take()
                    if dur:
                        yield env.timeout(dur)
            else:
                pending = list(picks)
                while pending:
                    idx = next(
                        (
                            i
                            for i, (p, _) in enumerate(pending)
                            if p is None or p not in self.feeders or self.feeders[p].stock > 0
                        ),
                        None,
                    )
                    if idx is None:
                        t0 = env.now
                        self.n_waits += 1
                        needed = dict.fromkeys(p for p, _ in pending)
                        yield env.any_of([self.feeders[p].arrival() for p in needed])  # type: ignore[index]
                        wait += env.now - t0
                        continue
                    ptype, dur = pending.pop(idx)
                    if ptype is not None and ptype in self.feeders:
                        self.feeders[ptype].take()
                    if dur:
                        yield env.timeout(dur)
            end = env.now
            if d:
                yield env.timeout(d)
            self.robot_work += busy + d
            self.robot_wait += wait
            self.kit_waits.append(wait)
            self.kit_times.append({"robot_start": start, "robot_end": end, "arrive": env.now})
            self.queue.append(k)
            self.max_queue = max(self.max_queue, len(self.queue))
            ev = self._kit_ready
            if ev is not None:
                self._kit_ready = None
                ev.succeed()

    def _human(self) -> Generator[simpy.Event, Any, None]:
        env, inst = self.env, self.inst
        oh = inst.kit_overhead_human
        h = self.times.human
        finished_tasks = 0
        while True:
            if not self.queue:
                self._kit_ready = env.event()
                yield self._kit_ready
            k = self.queue.popleft()
            taken = self._kit_taken
            if taken is not None:
                self._kit_taken = None
                taken.succeed()
            tasks = self.kits[k].tasks
            self.in_hand, self.phase, self.phase_start = k, -1, env.now
            self.kit_times[k]["human_start"] = env.now
            work = oh
            if oh:
                yield env.timeout(oh)
            for j, t in enumerate(tasks):
                self.phase, self.phase_start = j, env.now
                self.task_start[t] = env.now
                work += h[t]
                yield env.timeout(h[t])
                self.task_end[t] = env.now
            self.kit_times[k]["human_end"] = env.now
            self.human_work += work
            self.in_hand = None
            finished_tasks += len(tasks)
            if finished_tasks == inst.n_tasks:
                self.finished.succeed()
                return


def simulate(
    instance: Instance,
    policy: str | Policy,
    *,
    params: SimParams | None = None,
    seed: int = 0,
) -> SimResult:
    """Simulate one run (see the module docstring); :func:`run` returns its record.

    ``policy`` is a registered name or a policy object built on
    ``effective_instance(instance, params)`` (it is ``reset()`` first; :func:`replicate` uses
    this to share one policy, and its layout cache, between runs).
    """
    params = params or SimParams()
    seed = int(seed)
    if seed < 0:
        raise UsageError(f"seed must be >= 0, got {seed}")
    inst = effective_instance(instance, params)
    if isinstance(policy, str):
        pseed = seed if params.policy_seed is None else params.policy_seed
        pol = make_policy(policy, inst, seed=pseed, params=params)
    else:
        pol = policy
        if getattr(pol, "instance", None) is not None and [t.id for t in pol.instance.tasks] != [
            t.id for t in inst.tasks
        ]:
            raise UsageError("the policy object was built for a different instance or units")
        pol.reset()
    times = sample_times(
        inst,
        params.timing,
        np.random.default_rng(np.random.SeedSequence([seed, _STREAM, 0])),
        np.random.default_rng(np.random.SeedSequence([seed, _STREAM, 1])),
    )
    shop = _ShopFloor(inst, pol, params, times, seed)
    env = shop.env
    env.run(until=shop.finished | env.timeout(params.max_time))
    if not shop.finished.triggered:
        raise SimulationError(f"the run did not finish within {params.max_time:g} s")
    makespan = env.now
    kit_times = tuple(KitTimes(**kt) for kt in shop.kit_times)
    unit_end = [0.0] * inst.units
    for t in inst.tasks:
        unit_end[t.unit - 1] = max(unit_end[t.unit - 1], shop.task_end[t.id])
    return SimResult(
        instance=inst,
        policy=getattr(pol, "name", type(pol).__name__),
        seed=seed,
        plan=Plan(tuple(shop.kits)),
        kit_times=kit_times,
        kit_waits=tuple(shop.kit_waits),
        task_start=shop.task_start,
        task_end=shop.task_end,
        makespan=makespan,
        human_idle=makespan - shop.human_work,
        robot_idle=makespan - shop.robot_work,
        human_work=shop.human_work,
        robot_work=shop.robot_work,
        robot_wait=shop.robot_wait,
        n_waits=shop.n_waits,
        robot_blocked=shop.robot_blocked,
        max_queue=shop.max_queue,
        unit_end=tuple(unit_end),
        times=times,
        feeders={t: f.stats() for t, f in shop.feeders.items()},
        params=params,
        arrival_times={t: tuple(f.arrival_times) for t, f in shop.feeders.items()},
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
