"""``lns -p objective=expected_makespan``: the sample-average makespan
(docs/formulations.md#stochastic-human-times-sample-average-approximation); ``-p
objective=cvar_makespan -p alpha=A`` its CVaR at level A
(docs/formulations.md#cvar-of-the-makespan), the same two steps with that objective in step 2
and in every value below.

1. The mean-time ``lns`` (the objective ``makespan``) with :data:`MEAN_SHARE` of the time
   limit: its plan is the *mean-value plan* and the start.
2. The exact SAA model (:func:`bilevel_kit.models.cpsat.saa.solve_saa`) on ``scenarios``
   scenarios of the ``OPTIMISE`` stream of ``scenario_seed`` (:mod:`bilevel_kit.stochastic`),
   hinted with that plan, with the rest of the time. The result is the better plan on the
   scenarios, so it is never worse there than the mean-value plan.

**Result.** ``status_objective`` ``expected_makespan``; ``status`` ``optimal`` when the model
proved the plan optimal for the scenarios (among the plans the packing oracle accepts, as
``cpsat``'s Benders); ``bound`` is the mean-time run's proven bound on the *makespan* (the
result's ``makespan_bound``, docs/formats.md). ``extra``: ``objective_value`` (the in-sample
sample average, biased low: estimate a plan on an independent sample,
:func:`bilevel_kit.stochastic.estimate`), ``objective_bound`` (the model's bound on the sample
average of every plan on these scenarios), ``objective_gap``: the result's ``objective``,
``bound`` and ``gap`` (:func:`bilevel_kit.methods.solve`); ``mean_plan_expected_makespan``
(the mean-value plan on the same scenarios; ``mean_plan_cvar_makespan`` too with the CVaR, and
``alpha``), ``scenarios``, ``scenario_seed``, ``cv``,
``makespan`` (mean times) and the SAA loop's counters (``saa_*``).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import replace
from typing import Any

from ...instance import Instance
from ...methods import MethodOutput, Status, gap
from ...plan import Kit, Plan, evaluate
from ...stochastic import OPTIMISE, cvar_makespan, expected_makespan, sample
from ..budget import Budget

#: The share of the time limit of the mean-time start (step 1).
MEAN_SHARE = 0.3


def lns_saa(
    instance: Instance,
    options: Any,
    *,
    seed: int = 0,
    time_limit: float | None = None,
    start_plan: Plan | None = None,
    mean_time: Callable[..., MethodOutput],
) -> MethodOutput:
    """The module docstring's two steps; ``mean_time`` is the mean-time ``lns`` (passed in by
    :func:`.method.lns`, so this module does not import it back)."""
    from ..cpsat.saa import solve_saa

    lns = mean_time

    name = options.objective  # expected_makespan or cvar_makespan
    budget = Budget(time_limit)
    mean = lns(
        instance,
        replace(options, objective="makespan"),
        seed=seed,
        time_limit=MEAN_SHARE * budget.time_limit,
        start_plan=start_plan,
    )
    extra: dict[str, Any] = {
        "scenarios": options.scenarios,
        "scenario_seed": options.scenario_seed,
        "cv": options.cv,
        "mean_value_status": str(mean.status),
    }
    if mean.plan is None:
        extra["reason"] = mean.extra.get("reason", "no mean-time plan")
        return MethodOutput(None, mean.status, mean.bound, extra, name)
    scenarios = sample(
        instance, options.scenarios, options.scenario_seed, cv=options.cv, stream=OPTIMISE
    )
    extra["mean_plan_expected_makespan"] = expected_makespan(instance, mean.plan, scenarios)
    alpha = options.alpha if name == "cvar_makespan" else None
    if alpha is not None:
        extra["alpha"] = alpha
        extra["mean_plan_cvar_makespan"] = cvar_makespan(instance, mean.plan, scenarios, alpha)
    out = solve_saa(
        instance,
        scenarios,
        time_limit=budget.remaining(0.1),
        start=mean.plan,
        seed=seed,
        alpha=alpha,
    )
    assert out.kits is not None and out.value is not None and out.layouts is not None
    plan, value = mean.plan, out.value
    pairs = list(zip(out.kits, out.layouts, strict=True))
    if any(lay is None and instance.kit_parts(k) for k, lay in pairs):
        extra["reason"] = "no layout for some kit of the SAA plan in time: the mean-value plan"
        value, out.proven = extra[f"mean_plan_{name}"], False
    else:
        plan = Plan(tuple(Kit(k, lay or ()) for k, lay in pairs))
    optimal = out.proven and out.bound is not None and value - out.bound <= _tol(name, value)
    extra.update(
        out.info,
        objective_value=value,  # the result's own (methods.OBJECTIVE_KEYS)
        objective_bound=out.bound,
        objective_gap=None if out.bound is None else gap(value, out.bound),
        makespan=evaluate(instance, plan).makespan,
        n_kits=len(plan.kits),
    )
    status = Status.OPTIMAL if optimal else Status.FEASIBLE
    return MethodOutput(plan, status, mean.bound, extra, name)


def _tol(name: str, value: float) -> float:
    """The objective's tolerance (:data:`bilevel_kit.objectives.OBJECTIVES`)."""
    from ...objectives import OBJECTIVES
    from ...validate import TIME_TOL

    return TIME_TOL + OBJECTIVES[name].rel_tol * max(1.0, abs(value))
