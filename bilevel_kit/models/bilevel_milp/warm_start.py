"""The MIP start: a plan (greedy-ce's by default) improved by local search on J."""

from __future__ import annotations

import time
from collections.abc import Iterator, Sequence
from typing import Any

from ...errors import UsageError
from ...instance import Instance
from ...plan import Kit, Plan
from ..budget import Budget
from ..milp.model import human_order
from .lower import LowerLevel
from .objective import paper_objective


def local_search(
    instance: Instance,
    kits: Sequence[Sequence[str]],
    lower: LowerLevel,
    deadline: float,
    *,
    signed: bool = False,
) -> tuple[list[list[str]], float, bool]:
    """First-improvement hill climbing on J (a good MIP start lets the MILP prune early);
    returns the kits, their J and whether a local optimum was reached before ``deadline``
    (else the start, hence possibly the MILP's choice among equal-J plans, depends on the
    machine's speed).

    Moves: a task to the previous or next kit or into a new kit of its own just before or
    after its kit, merging or swapping two adjacent kits. A plan is kept only if every kit fits
    and precedence holds between kits (which also makes every kit convex).
    """
    succ: dict[str, list[str]] = {t.id: [] for t in instance.tasks}
    for a, b in instance.precedence:
        succ[a].append(b)

    def value(plan: list[frozenset[str]]) -> float:
        for kit in plan:
            if not lower.value(instance.kit_parts(kit)).fits:
                return float("inf")
        where = {t: k for k, kit in enumerate(plan) for t in kit}
        if any(where[a] > where[b] for a in succ for b in succ[a]):
            return float("inf")
        p = Plan(tuple(Kit(human_order(instance, kit)) for kit in plan))
        return paper_objective(instance, p, lower, signed=signed)

    def neighbours(plan: list[frozenset[str]]) -> Iterator[list[frozenset[str]]]:
        m = len(plan)
        for k in range(m - 1):
            yield [*plan[:k], plan[k] | plan[k + 1], *plan[k + 2 :]]
            yield [*plan[:k], plan[k + 1], plan[k], *plan[k + 2 :]]
        for k, kit in enumerate(plan):
            for t in sorted(kit, key=instance.index.__getitem__):
                rest = kit - {t}
                one = frozenset({t})
                for j in (k - 1, k + 1):
                    if 0 <= j < m:
                        new = list(plan)
                        new[j] = plan[j] | one
                        new[k] = rest
                        yield [q for q in new if q]
                if rest:
                    yield [*plan[:k], one, rest, *plan[k + 1 :]]
                    yield [*plan[:k], rest, one, *plan[k + 1 :]]

    cur = [frozenset(k) for k in kits]
    best = value(cur)
    improved = True
    while improved and time.perf_counter() < deadline:
        improved = False
        for cand in neighbours(cur):
            v = value(cand)
            if v < best - 1e-9:
                cur, best, improved = cand, v, True
                break
    return [list(human_order(instance, k)) for k in cur], best, not improved


def warm_start(
    instance: Instance,
    warm_plan: Plan | str,
    lower_level: LowerLevel,
    *,
    ce_params: Any,
    budget: Budget,
    signed: bool,
    seed: int,
) -> tuple[Plan, float, float, bool]:
    """The MIP start: ``warm_plan`` (``"greedy"``: greedy-ce's plan) improved by
    :func:`local_search` in a tenth of the time left; with J before and after, and whether the
    local search converged."""
    if isinstance(warm_plan, str):
        if warm_plan != "greedy":
            raise UsageError(f"warm_plan must be a Plan, 'greedy' or None, not {warm_plan!r}")
        from ...heuristics.cross_entropy import CEParams
        from ...heuristics.greedy_ce import GreedyParams
        from ...heuristics.greedy_ce import plan as greedy_plan

        gp = GreedyParams(ce=ce_params or CEParams())
        warm_plan = greedy_plan(instance, gp, seed)
    ls_until = budget.share(0.1)
    kits_ls, j_ls, converged = local_search(
        instance, [k.tasks for k in warm_plan.kits], lower_level, ls_until, signed=signed
    )
    start_j = paper_objective(instance, warm_plan, lower_level, signed=signed)
    return Plan(tuple(Kit(tuple(k)) for k in kits_ls)), start_j, j_ls, converged
