"""The registered method ``bbr``: branch, bound and remember over the precedence ideals.

1. **Start**: ``lns`` within ``start_share`` of the time limit (``start="lns"``), or the
   quick plans alone (``start="quick"``; with several stations the better of single-task's
   and whole-assembly's): its plan is the incumbent, its makespan the first upper bound of
   the search; option ``upper``, when below it, replaces that first upper bound (a plan
   known elsewhere, e.g. a KitBench record's: the search then proves that no plan is below
   it, or finds one; ``extra["upper_given"]``, and ``optimal`` only for a plan held).
2. **Search** (:mod:`.search`) with the rest of the time: best-first over (ideal, timeline
   state) nodes, pruned by the state's lower bound (:mod:`.space`) and by dominance, the tray
   asked lazily (the packing oracle, memoised, limited by deterministic time so its verdicts
   do not depend on the load, docs/simulation.md#determinism).
3. **A 0/90-degree pass** when the search ended with a relaxed plan (a kit without a layout
   nor a proof for every layout, :mod:`.search`) below the incumbent: the same search with
   such kits dropped, for the claims about 0/90-degree plans.
4. **Result**: the best plan (the start's, or a better one a search found, with the
   oracle's layouts); ``optimal`` when the first search proved it (for every plan); ``bound``
   the higher of the search's (the least of its open bounds and relaxed plans) and the
   start's, for every plan.

The makespan, one or more trays, one station (:mod:`.space`) or several (:mod:`.stations`,
docs/timeline.md#several-stations); no other objective. ``extra``: ``start_method``,
``start_makespan``, ``stop`` (``exhausted``, ``time_limit``, ``expansions``, ``memory``),
``expanded``, ``resumed`` (partial expansions resumed, option ``batch``), ``generated``, ``kept``,
``dominated``, ``oracle`` (packing calls), ``ideals``,
``bound_source`` (``bbr`` or the start's), ``bound_axis_aligned`` and
``optimal_axis_aligned`` (what the searches proved for 0/90-degree plans), ``relaxed_kits``,
``axis_aligned`` (the second pass's stop, bound and counters), ``proof_scope``, ``makespan``,
``n_kits``, ``gap``, ``wall_time_s``, ``upper_given`` (the option ``upper`` when used).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Literal

from ...instance import Instance
from ...methods import MethodOutput, Status, gap
from ...options import option
from ...plan import Kit, Plan, evaluate
from ..budget import Budget
from ..common import Packer, claim_scope, unfit_outcome
from ..packing import ANY_ANGLE, AXIS_ALIGNED
from .search import MAX_NODES, Outcome, packer_fits, search
from .search import Space as SearchSpace
from .space import Space
from .stations import StationSpace

#: Seconds kept back at the end for the layouts of a new plan, plus this share of the limit.
MARGIN_S, MARGIN_SHARE = 0.2, 0.02


@dataclass(frozen=True)
class BbrOptions:
    """Options of the registered method ``bbr``."""

    start: Literal["lns", "quick"] = option(
        "lns",
        "first incumbent: lns within start_share, or the quick plans alone "
        "(reproducible: with expansions, the whole run is)",
    )
    start_share: float = option(0.25, "share of the time limit for the lns start", min=0.0, max=1.0)
    expansions: int | None = option(
        None, "nodes to expand (none: until exhausted or the time limit)", min=1
    )
    max_nodes: int = option(
        MAX_NODES, "nodes kept in memory before the search stops (about 1.1 kB each)", min=1
    )
    batch: int | None = option(
        None,
        "children a node pushes per expansion before it goes back on the heap (partial "
        "expansion; none: all at once)",
        min=1,
    )
    pack_time: float = option(2.0, "deterministic time per packing call (about seconds)", min=0.01)
    upper: float | None = option(
        None,
        "a makespan to prove (s): the search starts below it as below a plan (a known plan "
        "elsewhere, e.g. a KitBench record); exhausted, it proves no plan is below it",
        min=0.0,
    )


def bbr(
    instance: Instance,
    options: BbrOptions,
    *,
    seed: int = 0,
    time_limit: float | None = None,
) -> MethodOutput:
    """Registered method ``bbr`` (module docstring)."""
    budget = Budget(time_limit)
    packer = Packer(instance, options.pack_time, budget, deterministic=True)
    extra: dict[str, Any] = {}
    unfit = packer.task_not_fitting()
    if unfit is not None:
        return MethodOutput(None, unfit_outcome(unfit, extra), None, extra)
    start, start_bound = _start(instance, options, seed, budget, packer, extra)
    upper = evaluate(instance, start).makespan if start is not None else math.inf
    if options.upper is not None and options.upper < upper:  # the first upper: no plan held
        upper = extra["upper_given"] = options.upper
    space: SearchSpace = StationSpace(instance) if instance.stations else Space(instance)
    stop_at = budget.deadline - MARGIN_S - MARGIN_SHARE * budget.time_limit
    fits = packer_fits(packer)

    def run(upper: float, relax: bool, expansions: int | None) -> Outcome:
        return search(
            space,
            fits,
            upper=upper,
            deadline=stop_at,
            max_expansions=expansions,
            max_nodes=options.max_nodes,
            relax=relax,
            batch=options.batch,
        )

    every = run(upper, True, options.expansions)
    extra.update(every.counters, stop=every.stop)
    plan = _better(instance, packer, start, every)
    axis = None
    if every.stop == "exhausted" and not every.exhausted:  # relaxed plans below the incumbent
        held = evaluate(instance, plan).makespan if plan is not None else math.inf
        axis = run(min(held, upper), False, None)
        extra["axis_aligned"] = {"stop": axis.stop, "bound": axis.bound, **axis.counters}
        plan = _better(instance, packer, plan, axis)
    return _conclude(instance, plan, (every, axis), start_bound, extra, budget)


def _better(instance: Instance, packer: Packer, plan: Plan | None, out: Outcome) -> Plan | None:
    """The search's plan with its layouts when it found one below ``plan``, else ``plan``."""
    if out.kits is None:
        return plan
    return with_layouts(instance, packer, out.kits) or plan


def _start(
    instance: Instance,
    options: BbrOptions,
    seed: int,
    budget: Budget,
    packer: Packer,
    extra: dict[str, Any],
) -> tuple[Plan | None, float | None]:
    """The first incumbent and its proven bound (module docstring, step 1): ``lns``'s plan
    and bound, or the quick plans' best (:func:`_quick`: one station's every packing call
    limited by deterministic time, so the start does not depend on the load) and no bound."""
    if options.start == "quick":
        plan = _quick(instance, packer, seed, budget)
        extra.update(start_method="quick", start_makespan=_makespan(instance, plan))
        return plan, None
    from ..lns.method import LnsOptions, lns

    limit = min(max(0.5, options.start_share * budget.time_limit), budget.remaining())
    got = lns(instance, LnsOptions(), seed=seed, time_limit=limit)
    extra.update(
        start_method="lns",
        start_makespan=got.extra.get("makespan"),
        start_bound_source=got.extra.get("bound_source"),
    )
    return got.plan, got.bound


def _quick(instance: Instance, packer: Packer, seed: int, budget: Budget) -> Plan | None:
    """The quick start: one station's quick plans, or with several stations the better of
    single-task's and whole-assembly's (as ``lns``'s station search starts,
    docs/stations.md#lns-with-several-stations): deterministic methods, each within the
    time left."""
    if instance.stations:
        from ..exact.warm import best_heuristic_plan

        methods = ("single-task", "whole-assembly")
        return best_heuristic_plan(instance, methods, seed=seed, time_limit=budget.remaining())[0]
    from ..common import quick_plan

    kits = quick_plan(instance, packer)
    return None if kits is None else with_layouts(instance, packer, kits)


def _makespan(instance: Instance, plan: Plan | None) -> float | None:
    return evaluate(instance, plan).makespan if plan is not None else None


def with_layouts(instance: Instance, packer: Packer, kits: list[list[str]]) -> Plan | None:
    """The search's plan with the oracle's layout of every kit (None: a layout is missing)."""
    from ..packing_oracle import typed_to_placements

    out = []
    for kit in kits:
        counts = dict(instance.kit_parts(kit))
        if not counts:
            out.append(Kit(tuple(kit)))
            continue
        verdict = packer.verdict(counts)
        if not verdict.fits or verdict.layout is None:
            return None
        out.append(Kit(tuple(kit), typed_to_placements(instance, kit, verdict.layout)))
    return Plan(tuple(out))


def _conclude(
    instance: Instance,
    plan: Plan | None,
    outs: tuple[Outcome, Outcome | None],
    start_bound: float | None,
    extra: dict[str, Any],
    budget: Budget,
) -> MethodOutput:
    """Status, bound and ``extra`` (module docstring, step 4): ``outs`` the search for every
    plan (relaxed kits kept) and, when it ran, the one for 0/90-degree plans."""
    every, axis = outs
    real = evaluate(instance, plan).makespan if plan is not None else None
    bound = start_bound
    if bound is None or every.bound > bound:
        bound = every.bound
        extra["bound_source"] = "bbr"
    else:
        extra["bound_source"] = extra.get("start_bound_source")
    if real is not None:
        bound = min(bound, real)  # the search's float sums against the evaluator's
    axis_ok = axis is not None and axis.scope is not None
    bound_axis = max(bound, axis.bound) if axis is not None and axis_ok else bound
    if real is not None:
        bound_axis = min(bound_axis, real)
    # exhausted below a given upper (``upper_given``) proves no plan below it, not that the
    # plan held attains it: then only the bound says so
    proven = every.exhausted and "upper_given" not in extra
    optimal = proven or (real is not None and real <= bound + 1e-9)
    optimal_axis = optimal or bool(axis is not None and axis_ok and axis.exhausted)
    extra.update(
        bound_axis_aligned=bound_axis,
        optimal_axis_aligned=optimal_axis and plan is not None,
        wall_time_s=budget.elapsed(),
    )
    claim_scope(extra, AXIS_ALIGNED if optimal_axis and not optimal else ANY_ANGLE)
    if plan is None:
        if every.stop == "exhausted" and math.isinf(every.bound):
            extra["reason"] = "no plan: every kit order was ruled out"
            return MethodOutput(None, Status.INFEASIBLE, None, extra)
        extra.setdefault("reason", "no plan within the time limit")
        return MethodOutput(None, Status.UNKNOWN, bound, extra)
    assert real is not None
    extra.update(makespan=real, n_kits=len(plan.kits), gap=gap(real, bound))
    return MethodOutput(plan, Status.OPTIMAL if optimal else Status.FEASIBLE, bound, extra)
