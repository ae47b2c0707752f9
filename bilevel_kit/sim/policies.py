"""The paper's kitting policies for the shop-floor simulation: what the robot kits next,
decided online (paper Section V-B; docs/simulation.md).

Every policy implements :class:`.state.Policy` and is built as
``cls(instance, *, seed, params, options)``; none of the three takes options
(:class:`~bilevel_kit.options.NoOptions`). Adding a policy is one class plus one
``POLICIES.register(...)`` line in :mod:`.registry`.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any, ClassVar

from ..heuristics.baselines import packed_kit
from ..heuristics.cross_entropy import CEParams
from ..heuristics.greedy_ce import GreedyCEPolicy, GreedyParams, GreedyStats
from ..instance import Instance, topological_order
from ..plan import Kit
from .state import PolicyBase, SimState

if TYPE_CHECKING:
    from .params import SimParams


def greedy_params(params: SimParams | None) -> GreedyParams:
    """greedy-ce's parameters in the simulation: ``SimParams``'s ``ce`` and ``signed`` (horizon
    and weights are already on the effective instance), the defaults without params."""
    ce = params.ce if params is not None and params.ce is not None else CEParams()
    signed = bool(params.signed) if params is not None else False
    return GreedyParams(signed=signed, ce=ce)


class LayoutCache:
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


class SingleTaskPolicy(PolicyBase):
    """The paper's Single Task baseline: one kit per task, in the deterministic topological
    order (:func:`bilevel_kit.instance.topological_order`), shelf-packer layout."""

    name: ClassVar[str] = "single-task"

    def _setup(self, instance: Instance, seed: int, params: SimParams | None, options: Any) -> None:
        self._order = topological_order(instance)
        self._layouts = LayoutCache(instance)
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


class WholeAssemblyPolicy(PolicyBase):
    """The paper's Whole Assembly baseline: all (remaining) tasks of the next unit in one kit,
    in topological order, shelf-packer layout."""

    name: ClassVar[str] = "whole-assembly"

    def _setup(self, instance: Instance, seed: int, params: SimParams | None, options: Any) -> None:
        order = topological_order(instance)
        unit = {t.id: t.unit for t in instance.tasks}
        # the units present (1..units; a station's own instance keeps its tasks' units)
        self._units = [
            (u, tuple(t for t in order if unit[t] == u)) for u in sorted(set(unit.values()))
        ]
        self._layouts = LayoutCache(instance)

    def reset(self) -> None:
        pass

    def decide(self, state: SimState) -> Kit | None:
        for u, tasks in self._units:
            left = tuple(t for t in tasks if t not in state.done)
            if left:
                return self._layouts.kit(left, f"whole-assembly kit of unit {u}")
        return None


class OptimizedPolicy(PolicyBase):
    """The paper's Optimized condition: greedy-ce called online through ``decide``.

    Passes the done set, the human's remaining time and (when some type has a supply process)
    the stock, so the W7 availability term acts on what the feeders actually delivered. Greedy
    options come from ``SimParams`` (``ce``, ``signed``; horizon and weights are already on the
    effective instance). The CE layouts are memoised per part multiset with seeds derived from
    (seed, multiset), so :meth:`reset` keeps them: they are a pure function of the seed.
    """

    name: ClassVar[str] = "optimized"

    def _setup(self, instance: Instance, seed: int, params: SimParams | None, options: Any) -> None:
        self.greedy = GreedyCEPolicy(instance, greedy_params(params), seed)

    def reset(self) -> None:
        self.greedy.stats = GreedyStats()

    def decide(self, state: SimState) -> Kit | None:
        return self.greedy.decide(state.policy_state())
