"""Several assembly stations served by one robot (docs/timeline.md#several-stations).

The evaluator (:mod:`bilevel_kit.plan`) and the checker take stations themselves; this module
holds what methods and bounds share about them: a station's tasks as an instance of their own
(:func:`station_instance`, whose closed-form bounds hold for that station's completion), the
objectives the exact models may minimise over them (:func:`objective_of`) and the list of the
methods that model stations.
"""

from __future__ import annotations

from dataclasses import replace
from typing import TYPE_CHECKING, Any

from .errors import UsageError
from .instance import Instance

if TYPE_CHECKING:
    from .plan import Plan, Timeline

#: The methods that plan for several stations; every other one refuses an instance that
#: declares ``stations`` (its times would use the instance's ``d``, ``o_H`` and ``trays``).
STATION_METHODS = frozenset({"single-task", "whole-assembly", "greedy-ce", "cpsat", "milp"})


#: What ``-p objective=...`` of ``cpsat``/``milp`` may name (docs/timeline.md#several-stations):
#: the makespan (max of the completions), the sum of the stations' completions, and the total
#: human idle (the one-station objective ``human_idle``, summed over the stations).
OBJECTIVES = ("makespan", "sum_completion", "human_idle")


def objective_of(timeline: Timeline, objective: str) -> float:
    """The value of ``objective`` (:data:`OBJECTIVES`) on ``timeline`` in seconds: with one
    station ``sum_completion`` is the makespan; ``human_idle`` is the timeline's, already the
    sum over the stations of ``station_metrics()``'s idle."""
    if objective == "human_idle":
        return timeline.human_idle
    if objective == "sum_completion" and timeline.kit_stations:  # else one station
        per = timeline.station_metrics()
        return sum(float(m["completion"]) for m in per.values())
    return timeline.makespan


def objective_bound(instance: Instance, objective: str) -> float:
    """A closed-form lower bound on ``objective`` over every plan (s): the makespan's
    (:func:`bilevel_kit.bounds.best_bound`); for ``sum_completion`` the sum over the stations
    of each one's own bound (:func:`station_instance`); for ``human_idle`` the sum over the
    stations of ``max(o_R + d_s, LB_s - W_s)``: a station's human idles at least until its
    first kit arrives, and its idle is ``C_s`` less its work, at most ``W_s = sum h_i + o_H,s
    n_s`` (one task per kit)."""
    from .bounds import best_bound

    if objective == "makespan":
        return best_bound(instance)
    total = 0.0
    for s in instance.station_ids:
        one = station_instance(instance, s)
        if not one.tasks:
            continue
        lb = best_bound(one)
        if objective == "human_idle":
            work = sum(one.human_time(t.id) for t in one.tasks)
            work += one.kit_overhead_human * one.n_tasks
            lb = max(instance.kit_overhead_robot + one.delivery_time, lb - work)
        total += lb
    return total


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


def objective_extra(
    instance: Instance,
    plan: Plan,
    objective: str,
    lower: tuple[float | None, float | None],
    optimal: tuple[bool, bool],
) -> dict[str, Any]:
    """An exact model's ``extra`` for ``objective`` besides the makespan: ``objective_value``,
    ``objective_bound``, ``objective_gap`` (s; ``idle_bound`` too for the human idle) and
    ``objective_bound_axis_aligned``. Each bound is :func:`objective_bound` or the model's
    ``lower`` (s), valid for every plan and for 0/90-degree plans (None: none); the value when
    ``optimal`` in the same two scopes (docs/formulations.md#what-optimal-means)."""
    from .methods import gap
    from .plan import evaluate

    value = objective_of(evaluate(instance, plan), objective)
    closed = objective_bound(instance, objective)
    bounds = []
    for low, opt in zip(lower, optimal, strict=True):
        bound = closed if low is None else max(closed, low)
        bounds.append(value if opt else min(bound, value))
    out: dict[str, Any] = {
        "objective_value": value,
        "objective_bound": bounds[0],
        "objective_gap": gap(value, bounds[0]),
        "objective_bound_axis_aligned": bounds[1],
    }
    if objective == "human_idle":
        out["idle_bound"] = bounds[0]
    return out


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
