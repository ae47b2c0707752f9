"""One driver for the exact whole-horizon methods ``cpsat`` and ``milp`` (docs/formulations.md,
"CP-SAT schedule", "MILP schedule"): the steps every run takes, in one order, over a small
backend protocol (:class:`.backend.Backend`) that builds, solves and cuts its own model.

1. A task whose parts alone do not fit ends the run (:func:`..common.unfit_outcome`).
2. The backend's incumbent, kit cap K and proven bound (:meth:`Backend.start`;
   :func:`proven_bound`).
3. An incumbent that attains a bound known before the model is optimal: no model
   (:meth:`Backend.shortcut`).
4. The no-model rule (:func:`.nomodel.buildable`): a model over the memory limit or too slow to
   build is not built; the time left goes to the LNS from the incumbent (option ``fallback``,
   :meth:`Backend.hand_off`) and the incumbent is concluded with the bound known before the
   model. The rule is applied again after step 5's LNS first, in the time it left.
5. Otherwise the LNS improves the incumbent first within a share of the time left
   (:mod:`.lns_first`; option ``fallback=lns``): a plan that meets the bound known before the
   model is concluded without one, else the backend builds its model and searches from it
   (:meth:`Backend.solve`); with option ``search``, the ideal search first runs from the
   incumbent (:mod:`.search_first`) and may prove it optimal without a model.
6. The plan returned is never worse than the incumbent the model started from
   (:func:`never_worse`; without release times, whose makespan the timeline does not see).
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

from ...bounds import best_bound
from ...instance import Instance
from ...methods import REGISTRY, MethodOutput, Status
from ...plan import evaluate
from ..budget import Budget
from ..common import claim_scope, unfit_outcome
from ..packing import ANY_ANGLE, AXIS_ALIGNED
from . import keys, lns_first, search_first
from .backend import Backend, Inc
from .nomodel import buildable

if TYPE_CHECKING:
    from ..relax import ProvenBound

#: The share of the time limit the warm start (option ``hint``) may use.
HINT_SHARE = 0.3


def drive(
    backend: Backend[Inc], fallback: str, search: float = 0.0, releases: bool = False
) -> MethodOutput:
    """One run of an exact method: the steps of the module docstring (``search``: option
    ``search``, the ideal search's share; ``releases``: the run has release times)."""
    unfit = backend.packer.task_not_fitting()  # then no plan exists (or none at 0/90 degrees)
    if unfit is not None:
        status = unfit_outcome(unfit, backend.extra)
        bound = None if status == Status.INFEASIBLE else best_bound(backend.instance)
        return backend.finish(None, status, bound)
    inc = backend.start()
    proven = backend.shortcut(inc)
    if proven is not None:
        return proven
    extra, has_plan = backend.extra, inc is not None
    cells = backend.cells()
    spec, budget, margin = backend.spec, backend.budget, backend.margin
    built = buildable(spec, backend.instance, backend.K, cells, budget, margin, extra, has_plan)
    if built and inc is not None:
        better, met = lns_first.before_model(backend, inc, fallback)
        if met:  # the LNS's plan meets the proven bound: optimal without a model
            return backend.conclude(better)
        better, met = search_first.before_model(backend, better, search, releases)
        if met:  # the ideal search proved the incumbent optimal: no model
            return backend.conclude(better)
        inc = better
        # the rule again in the time the LNS left (it may have used what the build needed)
        built = buildable(spec, backend.instance, backend.K, cells, budget, margin, extra, True)
    if built:
        t_model = budget.elapsed()
        with lns_first.model_share(backend, inc is not None and not releases):
            out = lns_first.after_model(backend, backend.solve(inc), t_model)
        if inc is None or releases:  # (the model's makespan is the released one: cpsat)
            return out
        return lns_first.after_share(backend, never_worse(backend, inc, out))
    if inc is None:
        return backend.finish(None, Status.UNKNOWN, backend.known_bound())
    if fallback == "lns":  # the time left to the LNS from the incumbent
        inc = _rest_to_lns(backend, inc)
    return backend.conclude(inc)


def _rest_to_lns(backend: Backend[Inc], inc: Inc) -> Inc:
    """The no-model hand-off of the time left; ``improved_by`` stays ``lns`` when the LNS first
    improved the incumbent and this hand-off did not."""
    before = backend.extra.get("improved_by")
    inc = backend.hand_off(inc)
    if backend.extra.get("improved_by") is None:
        backend.extra["improved_by"] = before
    return inc


def never_worse(backend: Backend[Inc], inc: Inc, out: MethodOutput) -> MethodOutput:
    """``out``, or the incumbent ``inc`` concluded without the model (the bound known before
    it) when the model's plan is missing or has a longer makespan: the model searches from the
    incumbent under C <= U, so this is a safety net against a plan lost in the model's
    re-packing or re-timing (docs/formulations.md, "The LNS first").
    ``extra["model_plan_worse"]`` then keeps the model's makespan (None: no plan), status and
    bound. The model's bound (for every plan, :func:`..common.scope_claims`) still holds, so
    the incumbent is concluded with it when it is higher than the bound known before the
    model (``bound_source`` ``model``); a bound above the incumbent's makespan contradicts
    that plan and is not taken (``model_plan_worse["bound_taken"]`` says which)."""
    if not backend.is_makespan:
        return out
    before = evaluate(backend.instance, backend.plan(inc)).makespan
    after = None if out.plan is None else evaluate(backend.instance, out.plan).makespan
    if after is not None and after <= before + lns_first.TOL:
        return out
    worse = {"makespan": after, "status": str(out.status), "bound": out.bound}
    worse["bound_taken"] = lns_first.take_model_bound(backend, out.bound, before)
    result = backend.conclude(inc)
    result.extra[keys.MODEL_PLAN_WORSE] = worse
    return result


def without_plan(backend: Backend[Inc], infeasible: bool, scope: str | None) -> MethodOutput:
    """The model ended without a plan: ``infeasible`` (no plan among those of ``scope``) is a
    proof for every plan, or for the 0/90-degree plans only (unknown: one at other angles may
    exist; docs/formulations.md#what-optimal-means); else unknown with the bound known before
    the model."""
    if infeasible and scope == ANY_ANGLE:
        return backend.finish(None, Status.INFEASIBLE, None)
    if infeasible and scope == AXIS_ALIGNED:
        backend.extra["infeasible_axis_aligned"] = True
        claim_scope(backend.extra, scope)
    return backend.finish(None, Status.UNKNOWN, backend.known_bound())


def check_hint(hint: str, words: tuple[str, ...]) -> None:
    """Option ``hint``: one of ``words`` or a registered method (the backends' words and
    defaults differ: docs/formulations.md, "One driver for cpsat and milp")."""
    if hint not in words and hint not in REGISTRY:
        raise ValueError(
            f"option 'hint': unknown method {hint!r}; choose {', '.join(words)} or one of "
            f"{', '.join(REGISTRY)}"
        )


def proven_bound(
    instance: Instance,
    budget: Budget,
    upper: float | None,
    extra: dict[str, Any],
    margin: float = 0.0,
) -> ProvenBound:
    """The proven makespan bound of :mod:`bilevel_kit.models.relax` within its share of the
    time limit (``upper``: the incumbent's makespan in s, which ends the kit-count scan early;
    a reproducible run's scan is limited by work); ``extra`` gets ``bound_sources``,
    ``bound_lp_kits`` and ``bound_time_s`` (docs/formulations.md, "Stronger lower bounds")."""
    from ..relax import for_model

    t0 = budget.elapsed()
    left = budget.remaining(margin)
    out = for_model(instance, budget.time_limit, left, upper, budget.deterministic)
    if out.safety_net:
        budget.net_fired()
    extra.update(
        bound_sources=out.sources,
        bound_lp_kits=dict(out.per_kits),
        bound_time_s=budget.elapsed() - t0,
    )
    return out


def known_bound(closed: float, proven: ProvenBound | None) -> float:
    """The best makespan bound known before the model (s): the closed form and the proven."""
    return closed if proven is None else max(closed, proven.value)


def bound_source(
    closed: float, proven: ProvenBound | None, model_any: float | None, tol: float
) -> str:
    """Which bound is the best: ``model`` (the model's bound for every plan, ``model_any``),
    the source of the proven bound, or ``closed_form`` (ties within ``tol``)."""
    if model_any is not None and model_any > known_bound(closed, proven) + tol:
        return "model"
    if proven is not None and proven.value >= closed - tol:
        return str(proven.source)
    return "closed_form"
