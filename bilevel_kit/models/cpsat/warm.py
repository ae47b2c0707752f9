"""The warm start of ``cpsat``: the best plan of some heuristics within a share of the time
limit (option ``hint``; :mod:`.method`), by the exact methods' one warm-start loop
(:func:`..exact.warm.best_heuristic_plan`, re-exported here with its constants), and the
closed-form bound live progress reports."""

from __future__ import annotations

from ...bounds import best_bound
from ...instance import Instance
from ...objectives import Objective
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
    "hint_methods",
]


def closed_bound(instance: Instance, objective: Objective) -> float | None:
    """The closed-form makespan bound (:mod:`bilevel_kit.bounds`) when ``objective`` is the
    makespan; None for the others (live progress reports no closed-form bound on them)."""
    return best_bound(instance) if objective.is_makespan else None
