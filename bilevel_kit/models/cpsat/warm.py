"""The warm start of ``cpsat``: the best plan of some heuristics within a share of the time
limit (option ``hint``; :mod:`.method`), by the exact methods' one warm-start loop
(:func:`..exact.warm.best_heuristic_plan`, re-exported here with its constants), and the
closed-form shortcut's checks."""

from __future__ import annotations

from ...bounds import best_bound
from ...instance import Instance
from ...objectives import Objective
from ..budget import Budget
from ..common import Packer, closed_form_plan, pack_time_limit
from ..exact.warm import (
    HINT_METHODS,
    HINT_OVERRUN_S_PER_TASK,
    KERNEL_LOAD_S,
    MIN_HINT,
    MIN_RUN,
    best_heuristic_plan,
    hint_methods,
)

__all__ = [
    "HINT_METHODS",
    "HINT_OVERRUN_S_PER_TASK",
    "KERNEL_LOAD_S",
    "MIN_HINT",
    "MIN_RUN",
    "best_heuristic_plan",
    "closed_bound",
    "closed_form_optimal",
    "hint_methods",
]


def closed_bound(instance: Instance, objective: Objective) -> float | None:
    """The closed-form makespan bound (:mod:`bilevel_kit.bounds`) when ``objective`` is the
    makespan; None for the others (live progress reports no closed-form bound on them)."""
    return best_bound(instance) if objective.is_makespan else None


def closed_form_optimal(instance: Instance, budget: Budget) -> bool:
    """Does a quick plan attain the closed-form bound (then :func:`run` ends at once)?"""
    packer = Packer(instance, min(0.2, pack_time_limit(budget)), budget.head(0.05))
    return closed_form_plan(instance, packer) is not None
