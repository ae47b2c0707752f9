"""What a simulation policy sees (:class:`SimState`) and what it must implement
(:class:`Policy`); docs/simulation.md.

A policy is a small object built from ``(instance, *, seed, params, options)`` (the
*effective* instance of the run: units expanded, overrides applied; ``options`` its frozen
options dataclass, validated by :func:`.registry.make_policy`) with two methods:

* ``decide(state: SimState) -> Kit | None``: the next kit (tasks in the human's order, with a
  tray layout), or ``None`` when every task has been kitted;
* ``reset()``: forget everything learnt during a run, so one object can serve many runs. Caches
  whose content is a pure function of the construction arguments (layouts) may be kept: a run
  stays a pure function of (instance, policy, parameters, seed).
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass, field, replace
from typing import TYPE_CHECKING, Any, ClassVar, Protocol, runtime_checkable

from ..heuristics.greedy_ce import PolicyState
from ..instance import Instance, Supply
from ..plan import Kit

if TYPE_CHECKING:
    from .params import SimParams

#: Stock reported for part types without a supply process (they never run out).
UNLIMITED = 10**9


@dataclass(frozen=True)
class HumanProgress:
    """What the robot observes of the human's work at an epoch: task ids and clock times, no
    durations (a policy must not see how long unfinished tasks will take).

    Attributes:
        now: the simulated clock (s).
        overhead: the per-kit pickup time ``o_H`` (s).
        in_hand: the tasks of the kit the human holds, in order (empty when idle).
        phase: -1 while the human takes the parts off the tray, else the index in ``in_hand``
            of the task being assembled.
        phase_start: when the current phase began (s).
        queued: the tasks of each delivered kit still waiting at the station, in order.
    """

    now: float = 0.0
    overhead: float = 0.0
    in_hand: tuple[str, ...] = ()
    phase: int = -1
    phase_start: float = 0.0
    queued: tuple[tuple[str, ...], ...] = ()

    def remaining(self, duration: Callable[[str], float]) -> float:
        """Expected seconds until the human has finished everything delivered, with
        ``duration(task)`` for every task not finished yet: the current phase's rest (never
        negative), the in-hand kit's later tasks, then per queued kit ``o_H`` plus its tasks."""
        oh, now = self.overhead, self.now
        rem = 0.0
        if self.in_hand:
            tasks = self.in_hand
            if self.phase < 0:
                rem += max(0.0, self.phase_start + oh - now) + sum(duration(t) for t in tasks)
            else:
                rem += max(0.0, self.phase_start + duration(tasks[self.phase]) - now)
                rem += sum(duration(t) for t in tasks[self.phase + 1 :])
        for kit in self.queued:
            rem += oh + sum(duration(t) for t in kit)
        return rem


@dataclass(frozen=True)
class SimState:
    """What the robot knows at a decision epoch (t = 0, then each return from a delivery).

    Attributes:
        time: the simulated clock (s).
        done: tasks already kitted (every earlier kit has been delivered).
        human_remaining: expected seconds until the human has finished every kit delivered so
            far (in hand and queued); 0 when idle. Observed progress (which step of which kit
            the human is on, since when) plus expected durations, see ``SimParams``.
        available: stock of every part type now; :data:`UNLIMITED` for unsupplied types.
        expected_arrival: per supplied type, expected seconds until its next part arrives
            (exact for the feeder process, see ``Feeder.expected_time_to_arrival``).
        repair_remaining: per supplied type, seconds until its machine is repaired (0: up).
        supply: the supply process of each supplied type.
        kits_delivered: kits delivered so far.
        observed: the human's measured duration (s) of every task finished by now (task id ->
            seconds); never a task in progress or not started (docs/simulation.md, "What the
            robot knows").
        progress: the human's position (:class:`HumanProgress`), from which a policy with
            its own duration estimates recomputes ``human_remaining``.
        true_speed: the participant's true speed factor per unit (the sampled factor times
            the timing model's ``session_factor``), given only to policies whose class sets
            ``sees_true_speed = True`` (the oracle references); empty for every other policy.

    With several stations (docs/timeline.md#several-stations) ``human_remaining`` and
    ``progress`` are the first station's; per station id:

    Attributes:
        station_progress: the human's position (:class:`HumanProgress`).
        station_remaining: expected seconds until the human has finished its delivered kits.
        station_free: when the human runs out of work: ``time`` plus the above while it has
            work, else when it finished its last kit (0 before its first), the clock time
            of the baselines' "earliest need".
        station_left: tasks of the station not kitted yet.
        trays_free: trays of the station back at the robot (:data:`UNLIMITED` when its
            limit never binds); a kit for a station with none waits for one.
    """

    time: float
    done: frozenset[str]
    human_remaining: float
    available: Mapping[str, int]
    expected_arrival: Mapping[str, float] = field(default_factory=dict)
    repair_remaining: Mapping[str, float] = field(default_factory=dict)
    supply: Mapping[str, Supply] = field(default_factory=dict)
    kits_delivered: int = 0
    observed: Mapping[str, float] = field(default_factory=dict)
    progress: HumanProgress = field(default_factory=HumanProgress)
    true_speed: tuple[float, ...] = ()
    station_progress: Mapping[str, HumanProgress] = field(default_factory=dict)
    station_remaining: Mapping[str, float] = field(default_factory=dict)
    station_free: Mapping[str, float] = field(default_factory=dict)
    station_left: Mapping[str, int] = field(default_factory=dict)
    trays_free: Mapping[str, int] = field(default_factory=dict)

    def for_station(self, station: str, tasks: frozenset[str]) -> SimState:
        """The view of one station as if the robot served it alone: its human's progress and
        remaining work, ``done`` restricted to its ``tasks``; stock and feeders shared."""
        return replace(
            self,
            done=self.done & tasks,
            human_remaining=self.station_remaining[station],
            progress=self.station_progress[station],
            station_progress={},
            station_remaining={},
            station_free={},
            station_left={},
            trays_free={},
        )

    def expected_wait(self, part_type: str, count: int = 1) -> float:
        """Expected seconds until ``count`` parts of a type are in stock (0 if they are).

        Uses the feeder's mean time between arrivals including failures,
        ``MAT * (1 + repair / MTTF)``, for every part after the next one.
        """
        short = count - self.available.get(part_type, UNLIMITED)
        if short <= 0:
            return 0.0
        cycle = self.supply[part_type].cycle  # (Supply.cycle)
        return self.expected_arrival[part_type] + (short - 1) * cycle

    def policy_state(self) -> PolicyState:
        """The greedy heuristic's view; ``available`` is None (W7 off) without supply."""
        avail = dict(self.available) if self.supply else None
        return PolicyState(self.done, self.human_remaining, avail)


@runtime_checkable
class Policy(Protocol):
    """The interface every simulation policy implements (see the module docstring)."""

    name: ClassVar[str]
    instance: Instance

    def decide(self, state: SimState) -> Kit | None: ...

    def reset(self) -> None: ...


class PolicyBase:
    """The constructor the package's policies share: ``cls(instance, *, seed, params,
    options)`` keeps the instance and hands it, the seed, the params and the options (None:
    the policy's defaults) to its ``_setup``."""

    def __init__(
        self,
        instance: Instance,
        *,
        seed: int = 0,
        params: SimParams | None = None,
        options: Any = None,
    ) -> None:
        self.instance = instance
        self._setup(instance, seed, params, options)

    def _setup(self, instance: Instance, seed: int, params: SimParams | None, options: Any) -> None:
        raise NotImplementedError
