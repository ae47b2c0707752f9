"""Simulation policies with several assembly stations (docs/simulation.md#several-stations).

One robot serves several stations, each with its own human (docs/timeline.md#several-stations).
A policy written for one station works unchanged: :class:`StationsPolicy` gives each station
its own copy of the policy, built on the station's tasks as an instance of one station
(:func:`bilevel_kit.stations.station_instance`: its ``d_s``, ``o_H,s`` and ``T_s``), and at each
epoch

* **which station**: the one whose human runs out of work first (``SimState.station_free``:
  the clock time its human ends its delivered kits, or ended its last one when idle; ties to
  the station listed first) among the stations with tasks left: the baselines' "earliest
  need" (:mod:`bilevel_kit.heuristics.baselines`), so without supply delays and with
  deterministic times the simulated baselines kit exactly the offline plans;
* **what kit**: that station's policy decides from the station's view of the state
  (:meth:`.state.SimState.for_station`: its human's progress and remaining work, its tasks
  done; stock and feeders are shared).

A station's policy plans as if the robot served it alone: ``cpsat-rolling`` re-plans a window
of that station's tasks exactly, but not the other stations' kits that will share the robot.

Policies with stations: :data:`STATION_POLICIES`, and ``optimized`` (greedy-ce online) when
greedy-ce's method spec declares ``supports_stations`` (:class:`bilevel_kit.methods.MethodSpec`;
the offline method then plans stations by the same rule).
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

from ..errors import UsageError
from ..instance import Instance
from ..plan import Kit
from ..stations import station_instance
from .state import Policy, PolicyBase, SimState

if TYPE_CHECKING:
    from .params import SimParams

#: The policies that take several stations (besides ``optimized``, see :func:`station_policies`).
STATION_POLICIES = ("single-task", "whole-assembly", "cpsat-rolling")


def station_policies() -> tuple[str, ...]:
    """The simulation policies that take several stations now: the baselines, cpsat-rolling,
    and ``optimized`` once greedy-ce plans stations (its spec declares ``supports_stations``)."""
    from ..methods import get_method

    extra = ("optimized",) if get_method("greedy-ce").supports_stations else ()
    return STATION_POLICIES + extra


def require_station_policy(instance: Instance, name: str) -> None:
    """Refuse (exit 2) a policy that does not model several stations on such an instance."""
    allowed = station_policies()
    if instance.stations and name not in allowed:
        raise UsageError(
            f"{instance.source}: policy {name!r} does not model several assembly stations; "
            f"use one of {', '.join(allowed)} (docs/simulation.md#several-stations)"
        )


class StationsPolicy(PolicyBase):
    """One policy per station, the station of earliest need first (the module docstring);
    ``factory`` builds each station's, with the seed, params and options (``built``)."""

    def __init__(self, instance: Instance, factory: Any, **built: Any) -> None:
        self.factory = factory
        super().__init__(instance, **built)

    def _setup(self, instance: Instance, seed: int, params: SimParams | None, options: Any) -> None:
        factory = self.factory
        self.name: str = getattr(factory, "name", "policy")
        self.policies: dict[str, Policy] = {
            s: factory(station_instance(instance, s), seed=seed, params=params, options=options)
            for s in instance.station_ids
        }
        self._tasks = {
            s: frozenset(t.id for t in instance.tasks if t.station == s)
            for s in instance.station_ids
        }

    def reset(self) -> None:
        for p in self.policies.values():
            p.reset()

    @property
    def safety_nets(self) -> int:
        """The stations' decisions a wall-clock safety net cut short (:mod:`.cpsat_rolling`)."""
        return sum(getattr(p, "safety_nets", 0) for p in self.policies.values())

    @property
    def layout_fallbacks(self) -> int:
        """The stations' committed kits split for want of a layout (:mod:`.cpsat_rolling`)."""
        return sum(getattr(p, "layout_fallbacks", 0) for p in self.policies.values())

    def choose(self, state: SimState) -> str | None:
        """The station of the next kit: the earliest need among those with tasks left."""
        ready = [s for s in self.policies if state.station_left[s] > 0]
        if not ready:
            return None
        return min(ready, key=state.station_free.__getitem__)  # stable: file order

    def decide(self, state: SimState) -> Kit | None:
        station = self.choose(state)
        if station is None:
            return None
        return self.policies[station].decide(state.for_station(station, self._tasks[station]))
