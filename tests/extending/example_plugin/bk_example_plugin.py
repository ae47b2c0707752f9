"""The worked example of docs/extending.md: a method and an objective written outside the
package.

``pairs`` puts ``size`` consecutive tasks of the topological order into each kit (fewer where
their parts do not fit the tray), laid out by the shelf packer. It is deliberately simple: a
baseline between Single Task (``size=1``) and Whole Assembly, and on the paper's table a
surprisingly good one (docs/extending.md says by how much).

``kit_handling`` is the makespan plus ``HANDLING_WEIGHT`` times the human's kit handling
``sum_s o_H,s m_s`` (``m_s`` kits at station ``s``): every kit is charged ``HANDLING_WEIGHT *
o_H,s`` seconds on top of the time it costs the schedule, the makespan-against-kit-count
trade-off of a line where handing over a tray has a cost of its own (the operator's walk, a
tray to clean). ``cpsat`` and ``milp`` minimise it as they are.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING

from bilevel_kit import Instance, Kit, KitDoesNotFit, MethodOutput, Plan, topological_order
from bilevel_kit.bounds import min_kits
from bilevel_kit.heuristics.baselines import packed_kit
from bilevel_kit.methods import Status
from bilevel_kit.objectives import EXTRA_KEYS, ModelTerms, Objective

if TYPE_CHECKING:
    from bilevel_kit.objectives import Bound, StationBounds
    from bilevel_kit.plan import Timeline
    from bilevel_kit.sim import SimParams, SimState


@dataclass(frozen=True)
class PairsOptions:
    """Every option is typed and documented: ``-p size=3`` is checked before the method runs."""

    size: int = field(
        default=2, metadata={"help": "tasks per kit (fewer where they do not fit)", "min": 1}
    )


def pairs(
    instance: Instance,
    options: PairsOptions,
    *,
    seed: int = 0,
    time_limit: float | None = None,
) -> MethodOutput:
    """Consecutive groups of the topological order; a group that does not fit, or that would
    mix assembly stations (a kit serves one), is shortened."""
    order = topological_order(instance)
    kits = []
    start = 0
    while start < len(order):
        size = min(options.size, _same_station(instance, order, start))
        while True:
            tasks = order[start : start + size]
            try:
                kits.append(packed_kit(instance, tasks, f"kit of tasks {', '.join(tasks)}"))
                break
            except KitDoesNotFit:
                if size == 1:
                    raise  # one task alone does not fit: no plan exists
                size -= 1
        start += size
    # a plan, not a proof: FEASIBLE, and no bound of its own (solve() adds the closed forms)
    return MethodOutput(Plan(tuple(kits)), Status.FEASIBLE)


def _same_station(instance: Instance, order: list[str], start: int) -> int:
    """How many tasks from ``order[start]`` on are for its station (all of them on an
    instance without stations: every task's station is "")."""
    station = instance.station_of(order[start])
    run = 1
    while start + run < len(order) and instance.station_of(order[start + run]) == station:
        run += 1
    return run


class PairsPolicy:
    """The same rule decided online in the shop-floor simulation: at each epoch, the next
    ``size`` undone tasks of the topological order (fewer where they do not fit)."""

    def __init__(
        self,
        instance: Instance,
        *,
        seed: int = 0,
        params: SimParams | None = None,
        options: PairsOptions = PairsOptions(),
    ) -> None:
        self.instance = instance
        self.size = options.size
        self.order = topological_order(instance)

    def reset(self) -> None:
        """No state survives a run: the done set in the state says where we are."""

    def decide(self, state: SimState) -> Kit | None:
        left = [t for t in self.order if t not in state.done]
        if not left:
            return None  # everything kitted: the robot stops
        for size in range(min(self.size, len(left)), 0, -1):
            try:
                return packed_kit(self.instance, left[:size], f"kit of {', '.join(left[:size])}")
            except KitDoesNotFit:
                if size == 1:
                    raise
        raise AssertionError("unreachable")


# --8<-- [start:objective]
#: Seconds of makespan one second of kit handling is worth (an integer: CP-SAT's objective
#: has integer coefficients on its time grid).
HANDLING_WEIGHT = 2


def kit_handling(timeline: Timeline) -> float:
    """The makespan plus ``HANDLING_WEIGHT`` times the human's kit handling: each kit's human
    time less its tasks' own (docs/timeline.md: a task starts after the kit's ``o_H,s``)."""
    human = sum(k.human_end - k.human_start for k in timeline.kits)
    tasks = sum(timeline.task_end[t] - timeline.task_start[t] for t in timeline.task_end)
    return timeline.makespan + HANDLING_WEIGHT * (human - tasks)


class KitHandling(Objective):
    """What the exact models need beyond the evaluation: a closed-form bound, a horizon and
    the expression on the models' terms (bilevel_kit.objectives.ModelTerms)."""

    def bound(self, instance: Instance, makespan: Bound, stations: StationBounds) -> float:
        """The makespan's bound, plus each station's handling for its fewest kits (the
        tray-area bound on its kit count)."""
        handling = sum(one.kit_overhead_human * min_kits(one) for one, _ in stations(instance))
        return makespan(instance) + HANDLING_WEIGHT * handling

    def horizon(self, instance: Instance, timeline: Timeline) -> float:
        """A plan at least as good has a makespan at most this value (its handling >= 0)."""
        return kit_handling(timeline)

    def expression(self, terms: ModelTerms) -> object:
        """C plus the weight times the human's overheads ``sum_s o_H,s m_s``."""
        return terms.makespan + HANDLING_WEIGHT * terms.overhead()


KIT_HANDLING = KitHandling(
    "kit_handling",
    f"the makespan plus {HANDLING_WEIGHT} x the human's kit handling",
    kit_handling,
    *EXTRA_KEYS,  # its value, bound and gap: extra["objective_value" / "_bound" / "_gap"]
)
# --8<-- [end:objective]


def register_plugin() -> None:
    """The plugin's entry point (group ``bilevel_kit.plugins``): register by import path, so
    nothing above is imported until the method or the policy is used."""
    from bilevel_kit import objectives
    from bilevel_kit.methods import register
    from bilevel_kit.sim.registry import POLICIES

    # first the objective, so that a method may declare it; cpsat and milp take every
    # modelled objective: `-p objective=kit_handling`
    objectives.register(KIT_HANDLING)
    register(
        "pairs",
        "bk_example_plugin:pairs",
        "worked example: consecutive tasks of the topological order, `size` per kit",
        "bk_example_plugin:PairsOptions",
        # it plans for several assembly stations (its kits never mix two), so `solve` takes
        # instances with stations; without this `solve` refuses them (exit 2)
        supports_stations=True,
        # the objectives it minimises, its default first (the registry's names, bilevel_kit/
        # objectives.py, the plugin's own too); an `objective` option of PairsOptions would be
        # held to them
        objectives=("makespan",),
    )
    POLICIES.register(
        "pairs",
        "bk_example_plugin:PairsPolicy",
        "worked example: the next `size` undone tasks of the topological order per kit",
        options="bk_example_plugin:PairsOptions",
    )
