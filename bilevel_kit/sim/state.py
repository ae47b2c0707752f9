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

from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import ClassVar, Protocol, runtime_checkable

from ..instance import Instance, Supply
from ..plan import Kit
from ..solvers.greedy_ce import PolicyState

#: Stock reported for part types without a supply process (they never run out).
UNLIMITED = 10**9


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
    """

    time: float
    done: frozenset[str]
    human_remaining: float
    available: Mapping[str, int]
    expected_arrival: Mapping[str, float] = field(default_factory=dict)
    repair_remaining: Mapping[str, float] = field(default_factory=dict)
    supply: Mapping[str, Supply] = field(default_factory=dict)
    kits_delivered: int = 0

    def expected_wait(self, part_type: str, count: int = 1) -> float:
        """Expected seconds until ``count`` parts of a type are in stock (0 if they are).

        Uses the feeder's mean time between arrivals including failures,
        ``MAT * (1 + repair / MTTF)``, for every part after the next one.
        """
        short = count - self.available.get(part_type, UNLIMITED)
        if short <= 0:
            return 0.0
        s = self.supply[part_type]
        cycle = s.mat * (1.0 + s.repair_time / s.mttf) if s.mttf is not None else s.mat
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
