"""The ``fixed-plan`` policy: a plan decided before the run, executed as it is
(docs/simulation.md#a-fixed-plan).

Why: the offline methods (``solve``) and the robust study (docs/robust.md) judge plans on the
timeline; running the *same* plan in the shop-floor simulation shows whether its value
survives the simulator's human model and its feeders. The policy returns the plan's kits, with
their layouts, one per decision epoch in the plan's order. It never re-plans: when a feeder
runs dry or a human is slow, the next kit simply waits (the robot waits for the missing part
while picking, as for every policy).

The plan is

* ``plan=FILE``: a solution file written by ``solve -o`` (:mod:`bilevel_kit.solution`), or a
  :class:`~bilevel_kit.plan.Plan` given to :class:`FixedPlanPolicy` directly (Python API);
* by default (no option): greedy-ce's offline plan on the run's effective instance with the
  mean times (:func:`bilevel_kit.heuristics.greedy_ce.plan`, the policy seed), i.e. the paper's
  heuristic planned once, against ``optimized`` which calls it at every epoch.

Either way the plan is checked first with :func:`bilevel_kit.validate.check` against the
*effective* instance the simulation runs (units, trays, delivery time and the timing model's
overheads applied); a file is checked with every number it states (its timeline parameters,
kit times and metrics), so a plan solved for another instance or other overrides is refused
with one line naming the file (:class:`~bilevel_kit.errors.UsageError`, exit 2) before any run.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, ClassVar

from ..errors import UsageError
from ..instance import Instance
from ..options import option
from ..plan import Kit, Plan
from ..validate import check
from .state import PolicyBase, SimState

if TYPE_CHECKING:
    from .params import SimParams


@dataclass(frozen=True)
class FixedPlanOptions:
    """Options of the ``fixed-plan`` policy (see the module docstring)."""

    plan: str = option(
        "",
        "solution file (solve -o) whose kits run in its order; default: greedy-ce's offline plan",
    )


def _refusal(source: str, violations: list[str]) -> UsageError:
    more = f" (and {len(violations) - 1} more; `bilevel-kit check` lists them)"
    return UsageError(
        f"{source}: the plan does not fit the simulated instance: {violations[0]}"
        f"{more if len(violations) > 1 else ''}"
    )


def load_plan(path: str, instance: Instance) -> Plan:
    """The plan of solution file ``path``, checked with every number it states against the
    effective ``instance`` (a :class:`UsageError` naming the file when it does not fit)."""
    from .. import solution

    sol = solution.read(path)
    found = sol.check(instance)
    if found:
        raise _refusal(path, [str(v) for v in found])
    return sol.plan


def checked_plan(plan: Plan, instance: Instance, source: str = "the plan") -> Plan:
    """``plan`` if it is valid on ``instance`` (:func:`bilevel_kit.validate.check`)."""
    found = check(instance, plan)
    if found:
        raise _refusal(source, [str(v) for v in found])
    return plan


def _offline_plan(instance: Instance, seed: int, params: SimParams | None) -> Plan:
    from ..heuristics.greedy_ce import plan as greedy_plan
    from .policies import greedy_params

    return greedy_plan(instance, greedy_params(params), seed)


class FixedPlanPolicy(PolicyBase):
    """Executes a fixed plan kit by kit (module docstring); ``plan`` overrides the options
    (``built``: the seed, params and options of :class:`~.state.PolicyBase`)."""

    name: ClassVar[str] = "fixed-plan"

    def __init__(self, instance: Instance, *, plan: Plan | None = None, **built: Any) -> None:
        self._given = plan
        super().__init__(instance, **built)

    def _setup(self, instance: Instance, seed: int, params: SimParams | None, options: Any) -> None:
        path = options.plan if options is not None else ""
        if self._given is not None:
            self.plan = checked_plan(self._given, instance)
        elif path:
            self.plan = load_plan(path, instance)
        else:
            self.plan = checked_plan(
                _offline_plan(instance, seed, params), instance, "greedy-ce's plan"
            )
        self._next = 0

    def reset(self) -> None:
        self._next = 0

    def decide(self, state: SimState) -> Kit | None:
        """The plan's next kit, whenever the robot is free: no re-planning."""
        kits = self.plan.kits
        if self._next == len(kits):
            return None
        self._next += 1
        return kits[self._next - 1]
