"""The registry of simulation policies: name -> import path, summary and options dataclass.

Like :mod:`bilevel_kit.methods`, entries are strings, so listing or checking a policy name
imports nothing heavy and no policy module imports the registry back (no import cycle).
:data:`POLICIES` maps a name to its class, imported on first access; :func:`make_policy`
validates the policy's ``key=value`` options (``SimParams.policy_options``) against its options
dataclass with :func:`bilevel_kit.options.parse_options`, so an unknown key or a bad value is a
:class:`~bilevel_kit.errors.UsageError` naming the policy and the key.
"""

from __future__ import annotations

from collections.abc import Callable, Iterator, Mapping
from dataclasses import dataclass
from typing import TYPE_CHECKING, ClassVar, cast

from ..errors import UsageError
from ..options import Registered, import_target
from ..registry import Registry

if TYPE_CHECKING:
    from ..instance import Instance
    from .params import SimParams
    from .state import Policy


@dataclass(frozen=True)
class PolicySpec(Registered):
    """A registered policy (see :class:`~bilevel_kit.options.Registered`)."""

    kind: ClassVar[str] = "policy"

    def load(self) -> type[Policy]:
        cls: type[Policy] = import_target(self.target)
        return cls


class PolicyRegistry(Mapping[str, "type[Policy]"]):
    """Policy name -> class (imported lazily); :meth:`spec` gives the registration."""

    def __init__(self) -> None:
        self._specs: Registry[PolicySpec] = Registry("policy")

    def register(self, name: str, target: str, summary: str, options: str | None = None) -> None:
        """Add a policy by import paths; a name already registered is a :class:`UsageError`."""
        self._specs.add(PolicySpec(name, target, summary, options))

    def remove(self, name: str) -> None:
        self._specs.remove(name)

    def spec(self, name: str) -> PolicySpec:
        if name not in self._specs:
            raise UsageError(
                f"unknown policy {name!r}; policies are {', '.join(sorted(self._specs))}"
            )
        return self._specs[name]

    def __getitem__(self, name: str) -> type[Policy]:
        return self._specs[name].load()

    def __contains__(self, name: object) -> bool:
        return name in self._specs

    def __iter__(self) -> Iterator[str]:
        return iter(self._specs)

    def __len__(self) -> int:
        return len(self._specs)


#: Every policy of the shop-floor simulation, in the order the CLI lists them.
POLICIES = PolicyRegistry()
POLICIES.register(
    "single-task",
    "bilevel_kit.sim.policies:SingleTaskPolicy",
    "the paper's Single Task baseline: one kit per task, topological order",
)
POLICIES.register(
    "whole-assembly",
    "bilevel_kit.sim.policies:WholeAssemblyPolicy",
    "the paper's Whole Assembly baseline: one kit per unit",
)
POLICIES.register(
    "optimized",
    "bilevel_kit.sim.policies:OptimizedPolicy",
    "the paper's Optimized condition: greedy-ce decided online",
)
POLICIES.register(
    "cpsat-rolling",
    "bilevel_kit.sim.cpsat_rolling:CPSATRollingPolicy",
    "exact CP-SAT re-planning of a window of the remaining tasks at each epoch",
    options="bilevel_kit.sim.cpsat_rolling:CPSATRollingOptions",
)
POLICIES.register(
    "optimized-adaptive",
    "bilevel_kit.sim.adaptive:OptimizedAdaptivePolicy",
    "optimized, planning with a Bayesian estimate of the human's pace from observed tasks",
    options="bilevel_kit.sim.pace:PaceOptions",
)
POLICIES.register(
    "optimized-oracle",
    "bilevel_kit.sim.adaptive:OptimizedOraclePolicy",
    "optimized, planning with the participant's true speed factor (a reference)",
)
POLICIES.register(
    "cpsat-rolling-adaptive",
    "bilevel_kit.sim.adaptive:CPSATRollingAdaptivePolicy",
    "cpsat-rolling, planning with a Bayesian estimate of the human's pace",
    options="bilevel_kit.sim.adaptive:CPSATRollingAdaptiveOptions",
)
POLICIES.register(
    "cpsat-rolling-oracle",
    "bilevel_kit.sim.adaptive:CPSATRollingOraclePolicy",
    "cpsat-rolling, planning with the participant's true speed factor (a reference)",
    options="bilevel_kit.sim.cpsat_rolling:CPSATRollingOptions",
)
POLICIES.register(
    "fixed-plan",
    "bilevel_kit.sim.fixed:FixedPlanPolicy",
    "a plan fixed before the run (a solution file, or greedy-ce's offline plan), not re-planned",
    options="bilevel_kit.sim.fixed:FixedPlanOptions",
)


def make_policy(
    name: str, instance: Instance, *, seed: int = 0, params: SimParams | None = None
) -> Policy:
    """Build a registered policy by name, its options validated (a clear error for an unknown
    policy, an unknown option key or a bad value); with several stations, one per station
    (:class:`.stations.StationsPolicy`), or a clear error if the policy does not take them."""
    spec = POLICIES.spec(name)
    options = spec.parse(params.policy_options if params is not None else {})
    factory: Callable[..., Policy] = spec.load()  # cls(instance, *, seed, params, options)
    if instance.stations:  # one policy per station (docs/simulation.md#several-stations)
        from .stations import StationsPolicy, require_station_policy

        require_station_policy(instance, name)
        # (its ``name`` is the wrapped policy's, an instance attribute: hence the cast)
        wrapped = StationsPolicy(instance, factory, seed=seed, params=params, options=options)
        return cast("Policy", wrapped)
    return factory(instance, seed=seed, params=params, options=options)
