"""Several assembly stations served by one robot (docs/timeline.md#several-stations).

The evaluator (:mod:`bilevel_kit.plan`) and the checker take stations themselves; this module
holds what methods and bounds share about them: a station's tasks as an instance of their own
(:func:`station_instance`, whose closed-form bounds hold for that station's completion), the
objectives the exact models may minimise over them (:func:`objective_of`, the registry
:mod:`bilevel_kit.objectives`; their closed-form
bounds: :func:`bilevel_kit.bounds.objective_bound`) and the list of the methods that model
stations.
"""

from __future__ import annotations

from dataclasses import replace
from typing import TYPE_CHECKING

from .errors import UsageError
from .instance import Instance
from .objectives import get as get_objective

if TYPE_CHECKING:
    from .plan import Timeline

#: The methods that plan for several stations; every other one refuses an instance that
#: declares ``stations`` (its times would use the instance's ``d``, ``o_H`` and ``trays``).
STATION_METHODS = frozenset({"single-task", "whole-assembly", "greedy-ce", "cpsat", "milp"})


def objective_of(timeline: Timeline, objective: str) -> float:
    """The value of ``objective`` on ``timeline`` in seconds: the registry's evaluation
    (:data:`bilevel_kit.objectives.OBJECTIVES`; with one station ``sum_completion`` is the
    makespan, ``human_idle`` is the timeline's, the sum over the stations)."""
    value = get_objective(objective).value(timeline)
    if value is None:
        raise ValueError(f"{objective!r} is not a function of the timeline")
    return value


def makespan_horizon(instance: Instance, timeline: Timeline, objective: str) -> float:
    """A bound on the makespan of every plan at least as good as ``timeline``'s for
    ``objective``, the exact models' ``C <= U``: its makespan; its sum of completions (each
    completion is at most the sum); ``idle + sum_i h_i + n max_s o_H,s`` for the human idle
    (a station's completion is its idle plus its work)."""
    if objective != "human_idle":
        return objective_of(timeline, objective)
    o_h = max(p.kit_overhead_human for p in instance.station_params.values())
    work = sum(instance.human_time(t.id) for t in instance.tasks)
    return timeline.human_idle + work + o_h * instance.n_tasks


def station_instance(instance: Instance, station: str) -> Instance:
    """The tasks of ``station`` as an instance of one station, with its ``d_s``, ``o_H`` and
    trays: the robot serving this station alone. Its plans' makespans are at most the
    station's completion in any plan of ``instance`` (dropping the other stations' kits only
    frees the robot earlier, and times are non-decreasing in start times), so its bounds hold
    for that completion and their max over the stations for the makespan."""
    if not instance.stations:
        return instance
    tasks = tuple(replace(t, station="") for t in instance.tasks if t.station == station)
    ids = {t.id for t in tasks}
    spec = next(s for s in instance.stations if s.id == station)
    params = instance.station_params[station]
    return replace(
        instance,
        name=f"{instance.name}:{station}",
        base_tasks=tasks,
        base_precedence=tuple((a, b) for a, b in instance.precedence if a in ids),
        units=1,
        delivery_time=params.delivery_time,
        kit_overhead_human=params.kit_overhead_human,
        trays=spec.trays if spec.trays is not None else instance.trays,
        stations=(),
    )


def require_stations_support(instance: Instance, method: str) -> None:
    """Refuse (exit 2) a method that does not model stations on an instance that has them."""
    if instance.stations and method not in STATION_METHODS:
        raise UsageError(
            f"{instance.source}: method {method!r} does not model several assembly stations "
            f"yet; use one of {', '.join(sorted(STATION_METHODS))} (docs/timeline.md)"
        )
