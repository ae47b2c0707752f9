"""The method registry and the one result contract every solver returns.

A method is a function ``fn(instance, *, seed=0, time_limit=None, **params) -> MethodOutput``
registered here by name and import path, so the CLI looks methods up without importing heavy
back-ends (OR-Tools, Pyomo ...) until one is used, and later issues add methods by adding one
line to :data:`REGISTRY`.

:func:`solve` wraps a method call: it times it, evaluates the plan with the one timeline
evaluator, attaches the closed-form lower bound, computes the gap and (optionally) runs the
independent checker.
"""

from __future__ import annotations

import importlib
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

from .errors import UsageError
from .instance import Instance
from .plan import Plan, Timeline, evaluate

STATUSES = ("optimal", "feasible", "infeasible", "unknown")


@dataclass(frozen=True)
class MethodOutput:
    """What a method function returns; :func:`solve` turns it into a :class:`Result`."""

    plan: Plan | None
    status: str
    bound: float | None = None
    extra: dict[str, Any] = field(default_factory=dict)


@dataclass
class Result:
    """A solve: status, objective (makespan, s), bound, gap, wall time, seed and parameters.

    ``gap = (objective - bound) / objective`` with ``bound`` the best lower bound known (the
    method's own, or the closed-form bounds of :mod:`bilevel_kit.bounds`).
    """

    method: str
    status: str
    plan: Plan | None
    timeline: Timeline | None
    objective: float | None
    bound: float | None
    gap: float | None
    wall_time_s: float
    seed: int | None
    params: dict[str, Any]
    instance: str
    extra: dict[str, Any] = field(default_factory=dict)

    @property
    def metrics(self) -> dict[str, float | int] | None:
        return self.timeline.metrics() if self.timeline is not None else None


@dataclass(frozen=True)
class MethodSpec:
    name: str
    target: str  # "module:function", imported on first use
    summary: str

    def load(self) -> Callable[..., MethodOutput]:
        module, func = self.target.split(":")
        return getattr(importlib.import_module(module), func)


REGISTRY: dict[str, MethodSpec] = {}


def register(name: str, target: str, summary: str) -> None:
    """Add a method (by import path, so registration costs no import)."""
    REGISTRY[name] = MethodSpec(name, target, summary)


register(
    "single-task",
    "bilevel_kit.solvers.baselines:single_task",
    "paper baseline: one kit per task, deterministic topological order",
)
register(
    "whole-assembly",
    "bilevel_kit.solvers.baselines:whole_assembly",
    "paper baseline: one kit per product unit",
)


def method_names() -> list[str]:
    return list(REGISTRY)


def get_method(name: str) -> MethodSpec:
    try:
        return REGISTRY[name]
    except KeyError:
        raise UsageError(
            f"unknown method {name!r}; choose from {', '.join(method_names())}"
        ) from None


def gap(objective: float | None, bound: float | None) -> float | None:
    """Relative optimality gap (objective - bound) / objective, 0 when proven optimal."""
    if objective is None or bound is None or objective <= 0:
        return None
    return max(0.0, (objective - bound) / objective)


def solve(
    instance: Instance,
    method: str,
    *,
    seed: int = 0,
    time_limit: float | None = None,
    check: bool = False,
    **params: Any,
) -> Result:
    """Run a registered method and return the honest :class:`Result`.

    With ``check=True`` the independent checker runs on the plan and its violations are stored
    in ``result.extra["violations"]`` (an empty list means valid).
    """
    from .bounds import best_bound
    from .reachability import ensure_kit_placeable

    fn = get_method(method).load()
    ensure_kit_placeable(instance)  # an empty reach map is a clear error, not "no kit fits"
    t0 = time.perf_counter()
    out = fn(instance, seed=seed, time_limit=time_limit, **params)
    wall = time.perf_counter() - t0
    if out.status not in STATUSES:
        raise ValueError(f"method {method!r} returned unknown status {out.status!r}")
    timeline = evaluate(instance, out.plan) if out.plan is not None else None
    objective = timeline.makespan if timeline is not None else None
    bounds = [b for b in (out.bound, best_bound(instance)) if b is not None]
    bound = max(bounds) if bounds else None
    if out.status == "optimal" and out.bound is None and objective is not None:
        bound = objective  # a proof of optimality is a bound equal to the objective
    extra = dict(out.extra)
    if check and out.plan is not None:
        from .validate import check as run_check

        extra["violations"] = [v.to_dict() for v in run_check(instance, out.plan)]
    return Result(
        method=method,
        status=out.status,
        plan=out.plan,
        timeline=timeline,
        objective=objective,
        bound=bound,
        gap=gap(objective, bound),
        wall_time_s=wall,
        seed=seed,
        params={"time_limit": time_limit, **params},
        instance=instance.name,
        extra=extra,
    )


register(
    "greedy-ce",
    "bilevel_kit.solvers.greedy_ce:greedy_ce",
    "the paper's bilevel heuristic: greedy rolling horizon + cross-entropy tray layout",
)
register(
    "cpsat",
    "bilevel_kit.solvers.cpsat:solve_method",
    "exact: CP-SAT over all segmentations and orders, tray packing embedded or by Benders",
)
register(
    "milp",
    "bilevel_kit.solvers.milp:solve",
    "exact: the schedule as a Pyomo MILP (HiGHS by default, any Pyomo solver), tray by cuts",
)
register(
    "bilevel-milp",
    "bilevel_kit.solvers.bilevel_milp:solve",
    "exact optimum of the paper's own objective F over enumerated kits (<= 16 tasks)",
)
