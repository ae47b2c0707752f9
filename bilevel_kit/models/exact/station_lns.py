"""The exact models' hand-off with several assembly stations: ``lns``'s station search
(docs/stations.md#lns-with-several-stations) from their incumbent, before the model (the LNS
first, :mod:`.lns_first`, makespan) and in the time left when no model is built (every
objective). ``cpsat`` and ``milp`` call it alike; each turns the plan into its incumbent."""

from __future__ import annotations

from dataclasses import replace
from typing import Any

from ...instance import Instance
from ...objectives import get as get_objective
from ...plan import Plan, evaluate
from .nomodel import HandOff

#: Seconds the search needs at least to be worth starting.
MIN_S = 0.5


def station_lns(
    instance: Instance,
    plan: Plan,
    objective: str,
    *,
    seed: int,
    limit: HandOff,
    extra: dict[str, Any],
) -> Plan | None:
    """The search's plan from ``plan`` within ``limit`` (its seconds; its ``windows`` as the
    search's ``iterations``, its ``stall`` in sweeps of the plan's kits) when it is strictly
    better for ``objective`` and passes the checker (then ``extra["improved_by"]`` is
    ``lns``), else None.
    ``extra["fallback"]``: ``method``, ``time_s``, ``objective_before``/``_after``,
    ``makespan_before``/``_after``, ``windows`` (the search's iterations), ``improvements``,
    ``stop``; ``skipped`` or ``rejected`` when it did not run or its plan was refused."""
    from ...validate import check
    from ..lns.method import LnsOptions, lns

    minimised = get_objective(objective)
    timeline = evaluate(instance, plan)
    now = minimised.value(timeline)
    assert now is not None  # (the modelled objectives: timeline values)
    info: dict[str, Any] = {"method": "lns", "time_s": round(max(0.0, limit.seconds), 3)}
    info.update(objective_before=now, objective_after=now)
    info.update(makespan_before=timeline.makespan, makespan_after=timeline.makespan)
    extra["fallback"] = info
    if limit.seconds < MIN_S:
        info["skipped"] = f"less than {MIN_S:g} s left"
        return None
    chosen: Any = objective  # any modelled objective: the search times it by its expression
    # a window of the one-station LNS frees several kits, a visit of the search one: the LNS
    # first's stall of W windows is W sweeps of visits here
    stall = None if limit.stall is None else limit.stall * max(1, len(plan.kits))
    options = LnsOptions(start="quick", stall=stall, iterations=limit.windows, objective=chosen)
    if limit.cut_share is not None:
        options = replace(options, cut_share=limit.cut_share)
    out = lns(instance, options, seed=seed, time_limit=limit.seconds, start_plan=plan)
    info.update(
        windows=out.extra.get("iterations", 0),
        improvements=out.extra.get("improvements", 0),
        stop=out.extra.get("stop"),
    )
    if out.plan is None:
        return None
    timeline = evaluate(instance, out.plan)
    value = minimised.value(timeline)
    assert value is not None
    if value >= now - 1e-9:
        return None
    problems = check(instance, out.plan)  # the caller returns it as its own: checked
    if problems:
        info["rejected"] = f"the checker refused the LNS's plan: {problems[0]}"
        return None
    info.update(objective_after=value, makespan_after=timeline.makespan)
    extra["improved_by"] = "lns"
    return out.plan
