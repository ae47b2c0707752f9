"""How a ``cpsat`` run ends (:mod:`.method`): the result of its best kits with the status and
bounds it may claim (docs/formulations.md#what-optimal-means; the ``extra`` keys:
docs/formulations.md, "One driver for cpsat and milp"), and the run's report of packing solves
and wall time."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

from ...bounds import best_bound, min_kits, objective_extra
from ...methods import MethodOutput, Status, gap
from ...plan import Kit, Placement, Plan, evaluate
from .. import packing_oracle
from ..budget import Budget
from ..common import Packer, claim_scope, kit_order, plan_extra
from ..packing import ANY_ANGLE
from .context import Context, Model, State
from .proven import bound_source, known_bound
from .scaling import scaled_makespan
from .station_run import station_claims


class Report:
    """The run's ``extra`` and how the run ends (packing solves and wall time added)."""

    def __init__(self, budget: Budget, extra: dict[str, Any]) -> None:
        self.budget = budget
        self.extra = extra
        self.solves_before = packing_oracle.pack_solves()
        self.nets_before = packing_oracle.safety_nets()

    def finish(self, plan: Plan | None, status: Status, bound: float | None) -> MethodOutput:
        extra = self.extra
        extra["pack_solves"] = packing_oracle.pack_solves() - self.solves_before
        extra["wall_time_s"] = self.budget.elapsed()
        if self.budget.deterministic:  # did a wall-clock safety net fire (not reproducible)?
            nets = packing_oracle.safety_nets() - self.nets_before
            extra["safety_net"] = self.budget.net or nets > 0
        return MethodOutput(plan, status, bound, extra, status_objective=extra["objective"])


def _objective_claims(
    ctx: Context, mdl: Model | None, state: State, closed: float, extra: dict[str, Any]
) -> tuple[float, bool, float | None, float | None]:
    """One station, an objective besides the makespan: the makespan bound its model bound
    implies (:meth:`~bilevel_kit.objectives.Objective.makespan_bound`), whether the plan is
    optimal, and the model's bounds on the objective (s; every plan, 0/90 degrees)."""
    sc, instance = ctx.sc, ctx.instance
    obj_bound = obj_axis = None
    if sc.exact and mdl is not None:  # the model's bounds on its objective, in s
        if state.lower is not None:
            obj_axis = round((state.lower + mdl.obj_const) * sc.res, 9)
        if state.lower_any is not None:
            obj_bound = round((state.lower_any + mdl.obj_const) * sc.res, 9)
    implied = (
        None
        if obj_bound is None
        else ctx.minimised.makespan_bound(instance, obj_bound, min_kits(instance))
    )
    bound_s = closed if implied is None else max(closed, implied)
    optimal_axis = state.proven and sc.exact and state.scope is not None
    extra["optimal_axis_aligned"] = optimal_axis
    return bound_s, optimal_axis and state.scope == ANY_ANGLE, obj_bound, obj_axis


def conclude(ctx: Context, mdl: Model | None, state: State, report: Report) -> MethodOutput:
    """The plan of the run's best kits with its status and makespan bound in seconds."""
    instance, sc, extra = ctx.instance, ctx.sc, report.extra
    assert state.kits is not None
    plan = plan_of(ctx, state.kits, state.layouts, ctx.packer)
    real = evaluate(instance, plan)
    closed = best_bound(instance)
    lower_s = None if state.lower is None else round(state.lower * sc.res, 9)  # >= 1e-4
    any_s = None if state.lower_any is None else round(state.lower_any * sc.res, 9)
    obj_bound = obj_axis = None  # another objective's model bounds (s), every plan / 0-90
    if ctx.minimised.is_makespan:
        strong = known_bound(ctx)  # the closed forms and models.relax: every plan
        bound_s = strong if any_s is None else max(strong, any_s)  # every plan (module doc)
        bound_axis = strong if lower_s is None else max(strong, lower_s)
        extra["bound_source"] = bound_source(ctx, any_s)
        exact = sc.exact or (real.makespan <= bound_axis + 1e-6 and not sc.rel)
        optimal_axis = state.proven and state.scope is not None and exact
        optimal = (optimal_axis and state.scope == ANY_ANGLE) or (
            real.makespan <= bound_s + 1e-6 and not sc.rel
        )
        extra.update(bound_axis_aligned=bound_axis, optimal_axis_aligned=optimal_axis)
    elif sc.station:  # several stations: the objective's own bound (docs/formulations.md)
        bound_s, optimal = closed, station_claims(ctx, plan, state, extra)
        obj_bound, lower_s = extra["objective_bound"], None  # (lower: not on the makespan)
    else:
        bound_s, optimal, obj_bound, obj_axis = _objective_claims(ctx, mdl, state, closed, extra)
    claim_scope(extra, ANY_ANGLE if optimal else state.scope)
    missing = [k for k in plan.kits if not k.layout and instance.kit_parts(k.tasks)]
    if missing:  # a kit without a layout (packing timed out at the very end): not a valid plan
        extra["reason"] = "no layout for some kit within the time limit"
        return report.finish(None, Status.UNKNOWN, bound_s)
    if not ctx.minimised.is_makespan and not sc.station:  # the registry's keys
        lows = (obj_bound, obj_axis)
        proofs = (optimal, bool(extra["optimal_axis_aligned"]))
        extra.update(objective_extra(instance, plan, ctx.objective, lows, proofs))
    if ctx.live is not None:  # the final numbers, as the result reports them
        makespan = ctx.minimised.is_makespan
        ctx.live.tracker.report(
            incumbent=ctx.minimised.value(real), bound=bound_s if makespan else obj_bound
        )
    extra.update(plan_extra(plan, real, bound_s, closed, lower_s), scaled_optimal=state.proven)
    if sc.rel:  # the model's makespan is the released one (module docstring)
        released = round(scaled_makespan(sc, state.kits) * sc.res, 9)
        extra.update(release_makespan=released, gap=gap(released, bound_s) or 0.0)
    return report.finish(plan, Status.OPTIMAL if optimal else Status.FEASIBLE, bound_s)


def plan_of(
    ctx: Context,
    kits: Sequence[Sequence[int]],
    layouts: Sequence[tuple[Placement, ...]] | None,
    packer: Packer | None = None,
) -> Plan:
    """Kits of task indices -> a Plan (human order = topological order inside each kit; with
    release times, sorted by release: the robot picks in that order, module docstring)."""
    instance, rel = ctx.instance, ctx.sc.rel
    out = []
    for kk, kit in enumerate(kits):
        tasks = kit_order(instance, [instance.tasks[i].id for i in kit])
        if rel:
            idx = instance.index
            tasks = tuple(sorted(tasks, key=lambda t: rel[idx[t]]))  # stable: topological
        layout: tuple[Placement, ...] = ()
        if layouts is not None:
            layout = layouts[kk]
        elif packer is not None:
            ok, typed = packer.counts(dict(instance.kit_parts(tasks)))
            if ok and typed is not None:
                layout = packing_oracle.typed_to_placements(instance, tasks, typed)
        out.append(Kit(tasks, layout))
    return Plan(tuple(out))
