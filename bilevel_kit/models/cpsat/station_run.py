"""What ``cpsat``'s run does differently with several assembly stations
(docs/timeline.md#several-stations; docs/formulations.md, "Several stations"): the model is
the one model (:mod:`.station_model` adds the station part), the run the one run; these are
its station-specific steps: the baselines' plans as incumbents (a quick plan would mix
stations), ``lns``'s station search as the hand-off (the LNS first, and the time left when no
model is built) and the claims on an objective other than the makespan."""

from __future__ import annotations

from typing import Any

from ...bounds import objective_extra
from ...instance import Instance
from ...plan import Placement, Plan
from ..exact.nomodel import HandOff
from ..exact.station_lns import station_lns
from ..packing import ANY_ANGLE
from .context import Context, State


def station_baselines(instance: Instance) -> list[list[list[int]]]:
    """The kits of single-task and (when its kits fit) whole-assembly, which interleave the
    stations by earliest need (docs/timeline.md#several-stations)."""
    from ...errors import KitDoesNotFit
    from ...heuristics.baselines import single_task, whole_assembly

    idx = instance.index
    out = []
    for baseline in (single_task, whole_assembly):
        try:
            plan = baseline(instance).plan
        except KitDoesNotFit:
            continue
        if plan is not None:
            out.append([[idx[t] for t in k.tasks] for k in plan.kits if k.tasks])
    return out


def station_hand_off(
    ctx: Context, plan: Plan, seed: int, extra: dict[str, Any], limit: HandOff
) -> tuple[list[list[int]], list[tuple[Placement, ...]]] | None:
    """Several stations: ``lns``'s station search from the incumbent ``plan`` within
    ``limit`` for the run's objective (:func:`..exact.station_lns.station_lns`); its kits and
    layouts when its plan is better, else None."""
    found = station_lns(ctx.instance, plan, ctx.objective, seed=seed, limit=limit, extra=extra)
    if found is None:
        return None
    idx = ctx.instance.index
    kits = [[idx[t] for t in k.tasks] for k in found.kits if k.tasks]
    return kits, [k.layout for k in found.kits if k.tasks]


def station_claims(ctx: Context, plan: Plan, state: State, extra: dict[str, Any]) -> bool:
    """Several stations, an objective other than the makespan: its value, bounds and gap
    (:func:`bilevel_kit.bounds.objective_extra`: the model's bounds on an exact grid, else the
    closed form) into ``extra``; whether the plan is optimal for it (every plan)."""
    sc = ctx.sc
    optimal_axis = state.proven and sc.exact and state.scope is not None
    optimal = optimal_axis and state.scope == ANY_ANGLE

    def seconds(v: int | None) -> float | None:
        return None if v is None or not sc.exact else round(v * sc.res, 9)

    lows = (seconds(state.lower_any), seconds(state.lower))
    claims = objective_extra(
        ctx.instance, plan, ctx.objective, lows, (optimal, optimal_axis), model_scale=True
    )
    extra.update(claims, optimal_axis_aligned=optimal_axis)
    return optimal
