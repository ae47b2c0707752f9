"""When ``cpsat`` builds no model: too large or too slow to build (:func:`buildable`), and
what it does with the time left then (:func:`handoff`: the LNS from the incumbent,
docs/formulations.md, "Model too large")."""

from __future__ import annotations

from typing import Any

from ...instance import Instance
from ...plan import Plan
from ..budget import Budget, no_model_reason
from ..common import assignment_cells
from .context import MARGIN, Context, State
from .proven import known_bound
from .scaling import scaled_makespan

#: Peak memory per task x kit variable, model and a 2-worker solve (measured: 4.5-4.7 kB per
#: variable above a 216 MB run of 14,000 variables, 1.27 GB at 247,000 on a 500-task in-tree).
BYTES_PER_CELL = 6_000
#: Build time per task x kit variable (measured: 90-120 us on in-trees of 60-500 tasks).
BUILD_S_PER_CELL = 150e-6


def buildable(
    instance: Instance, K: int, budget: Budget, extra: dict[str, Any], has_plan: bool
) -> bool:
    """Whether to build the model with K kits: False (with a ``reason``) when it would exceed
    the memory limit (a UsageError when there is no incumbent to return instead) or would not
    be built and solved within the time left."""
    cells = assignment_cells(instance, K)
    extra["model_cells"] = cells
    n = instance.n_tasks
    what = f"task x kit variables ({n} tasks, K = {K})"
    costs = (BYTES_PER_CELL, BUILD_S_PER_CELL)
    why = no_model_reason("cpsat", cells, costs, what, budget, MARGIN, has_plan)
    if why is None:
        return True
    kind, reason = why
    keep = "the incumbent is returned" + (" with the proven bound" if kind == "too_large" else "")
    extra.update(
        reason=f"{reason}; {keep}",
        build_time_s=0.0,
        cpsat_status="TOO_LARGE" if kind == "too_large" else "NOT_BUILT",
        cuts=0,
    )
    return False


def handoff(ctx: Context, state: State, plan: Plan, seed: int, extra: dict[str, Any]) -> State:
    """``state`` (the incumbent, whose plan is ``plan``), or the better plan the LNS finds
    from it in the time left (:func:`..lns.fallback.improve`; makespan objective without
    release times, which the LNS does not model; not in a reproducible run, ``deterministic``,
    whose result must not depend on the clock). ``extra`` gets ``improved_by`` (``lns`` or
    None) and ``fallback`` (what happened)."""
    from ..lns.fallback import improve

    extra["improved_by"] = None
    if ctx.objective != "makespan" or any(ctx.sc.rel) or ctx.instance.stations:
        return state
    if ctx.budget.stretch != 1.0:  # deterministic (budget.py): the LNS's start is clock-bound
        return state
    better, info = improve(
        ctx.instance, plan, bound=known_bound(ctx), seed=seed, time_limit=ctx.left()
    )
    extra["fallback"] = info
    if better is None:
        return state
    idx = ctx.instance.index
    kits = [[idx[t] for t in k.tasks] for k in better.kits if k.tasks]
    layouts = [k.layout for k in better.kits if k.tasks]
    extra["improved_by"] = "lns"
    return State(kits, scaled_makespan(ctx.sc, kits), layouts=layouts)
