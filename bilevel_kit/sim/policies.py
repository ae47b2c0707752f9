"""Kitting policies for the shop-floor simulation: what the robot kits next, decided online.

A policy is a small object built from ``(instance, seed=..., params=...)`` (the *effective*
instance of the run: units expanded, overrides applied) with two methods:

* ``decide(state: SimState) -> Kit | None``: the next kit (tasks in the human's order, with a
  tray layout), or ``None`` when every task has been kitted;
* ``reset()``: forget everything learnt during a run, so one object can serve many runs. Caches
  whose content is a pure function of the construction arguments (layouts) may be kept: a run
  stays a pure function of (instance, policy, parameters, seed).

Adding a policy is one class plus one line in :data:`POLICIES`.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, ClassVar, Protocol, runtime_checkable

from ..instance import Instance, Supply, topological_order
from ..layout.cross_entropy import CEParams
from ..plan import Kit
from ..solvers.baselines import packed_kit
from ..solvers.greedy_ce import GreedyCEPolicy, GreedyParams, GreedyStats, PolicyState

if TYPE_CHECKING:
    from .shopfloor import SimParams

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


class _LayoutCache:
    """Shelf-packer layouts memoised by part multiset (the baselines' layout)."""

    def __init__(self, instance: Instance) -> None:
        self.instance = instance
        self._layouts: dict[tuple[tuple[str, int], ...], Kit] = {}

    def kit(self, tasks: tuple[str, ...], label: str) -> Kit:
        key = tuple(sorted(self.instance.kit_parts(tasks).items()))
        hit = self._layouts.get(key)
        if hit is None:
            hit = packed_kit(self.instance, tasks, label)
            self._layouts[key] = hit
        return Kit(tasks, hit.layout)


class SingleTaskPolicy:
    """The paper's Single Task baseline: one kit per task, in the deterministic topological
    order (:func:`bilevel_kit.instance.topological_order`), shelf-packer layout."""

    name: ClassVar[str] = "single-task"

    def __init__(
        self, instance: Instance, *, seed: int = 0, params: SimParams | None = None
    ) -> None:
        self.instance = instance
        self._order = topological_order(instance)
        self._layouts = _LayoutCache(instance)
        self._pos = 0

    def reset(self) -> None:
        self._pos = 0

    def decide(self, state: SimState) -> Kit | None:
        while self._pos < len(self._order) and self._order[self._pos] in state.done:
            self._pos += 1
        if self._pos == len(self._order):
            return None
        t = self._order[self._pos]
        return self._layouts.kit((t,), f"kit for task {t!r}")


class WholeAssemblyPolicy:
    """The paper's Whole Assembly baseline: all (remaining) tasks of the next unit in one kit,
    in topological order, shelf-packer layout."""

    name: ClassVar[str] = "whole-assembly"

    def __init__(
        self, instance: Instance, *, seed: int = 0, params: SimParams | None = None
    ) -> None:
        self.instance = instance
        order = topological_order(instance)
        unit = {t.id: t.unit for t in instance.tasks}
        self._units = [
            tuple(t for t in order if unit[t] == u) for u in range(1, instance.units + 1)
        ]
        self._layouts = _LayoutCache(instance)

    def reset(self) -> None:
        pass

    def decide(self, state: SimState) -> Kit | None:
        for u, tasks in enumerate(self._units, start=1):
            left = tuple(t for t in tasks if t not in state.done)
            if left:
                return self._layouts.kit(left, f"whole-assembly kit of unit {u}")
        return None


class OptimizedPolicy:
    """The paper's Optimized condition: greedy-ce called online through ``decide``.

    Passes the done set, the human's remaining time and (when some type has a supply process)
    the stock, so the W7 availability term acts on what the feeders actually delivered. Greedy
    options come from ``SimParams`` (``ce``, ``signed``; horizon and weights are already on the
    effective instance). The CE layouts are memoised per part multiset with seeds derived from
    (seed, multiset), so :meth:`reset` keeps them: they are a pure function of the seed.
    """

    name: ClassVar[str] = "optimized"

    def __init__(
        self, instance: Instance, *, seed: int = 0, params: SimParams | None = None
    ) -> None:
        self.instance = instance
        ce = params.ce if params is not None and params.ce is not None else CEParams()
        signed = bool(params.signed) if params is not None else False
        self.greedy = GreedyCEPolicy(instance, GreedyParams(signed=signed, ce=ce), seed)

    def reset(self) -> None:
        self.greedy.stats = GreedyStats()

    def decide(self, state: SimState) -> Kit | None:
        return self.greedy.decide(state.policy_state())


#: Policy name -> class; every class takes ``(instance, *, seed, params)``.
POLICIES: dict[str, type[Policy]] = {
    SingleTaskPolicy.name: SingleTaskPolicy,
    WholeAssemblyPolicy.name: WholeAssemblyPolicy,
    OptimizedPolicy.name: OptimizedPolicy,
}


def _register_late() -> None:
    """Policies that live in their own module (imported here, after POLICIES exists)."""
    from .cpsat_rolling import CPSATRollingPolicy

    POLICIES[CPSATRollingPolicy.name] = CPSATRollingPolicy


_register_late()


def make_policy(
    name: str, instance: Instance, *, seed: int = 0, params: SimParams | None = None
) -> Policy:
    """Build a registered policy by name (a clear error for an unknown one)."""
    from ..errors import UsageError

    try:
        cls = POLICIES[name]
    except KeyError:
        raise UsageError(
            f"unknown policy {name!r}; policies are {', '.join(sorted(POLICIES))}"
        ) from None
    return cls(instance, seed=seed, params=params)
