"""The paper's objective J of a whole plan (package docstring, Eqs. 3-7): the one function
that scores any plan, the MILP's, the warm start's or greedy-ce's."""

from __future__ import annotations

from collections.abc import Callable, Mapping

import numpy as np

from ...fitness import layout_fitness as layout_fitness_value
from ...heuristics import upper_level
from ...instance import Instance
from ...plan import Kit, Plan, evaluate, kit_durations

FitnessOf = Callable[[Kit], float]


def paper_terms(
    instance: Instance,
    plan: Plan,
    fitness_of: FitnessOf,
    *,
    weights: Mapping[str, float] | None = None,
    signed: bool = False,
) -> list[dict[str, float]]:
    """Per kit: the raw terms ``n_tasks``, ``diff5``, ``diff6``, ``fitness`` and the weighted
    ``score`` of :func:`paper_objective` (package docstring)."""
    w = {**instance.weights, **(weights or {})}
    tl = evaluate(instance, plan)
    r, h = np.array([kit_durations(instance, k.tasks) for k in plan.kits], dtype=float).T
    # H_rem when the robot starts kit k: the human's work left on kit k-1 (tray rule included)
    backlog = [0.0] + [
        prev.human_end - nxt.robot_start for prev, nxt in zip(tl.kits, tl.kits[1:], strict=False)
    ]
    diff5, diff6 = upper_level.plan_balance(
        r, h, np.array(backlog), delivery=instance.params_of().delivery_time, signed=signed
    )
    fit = np.array([float(fitness_of(k)) for k in plan.kits])
    n_tasks = np.array([len(k.tasks) for k in plan.kits], dtype=float)
    score = upper_level.objective(w, n_tasks=n_tasks, diff5=diff5, diff6=diff6, fitness=fit)
    return [
        {
            "n_tasks": float(n_tasks[k]),
            "diff5": float(diff5[k]),
            "diff6": float(diff6[k]),
            "fitness": float(fit[k]),
            "score": float(score[k]),
        }
        for k in range(len(plan.kits))
    ]


def paper_objective(
    instance: Instance,
    plan: Plan,
    fitness_of: FitnessOf,
    *,
    weights: Mapping[str, float] | None = None,
    signed: bool = False,
) -> float:
    """The paper's F as a whole-plan objective J (package docstring); smaller is better."""
    return sum(
        t["score"] for t in paper_terms(instance, plan, fitness_of, weights=weights, signed=signed)
    )


def layout_fitness(instance: Instance) -> FitnessOf:
    """``fitness_of`` that scores each kit by its own layout (Euclidean, with the instance's
    W6): the value greedy-ce itself saw for its kits."""
    w6 = instance.weights["W6"]

    def fitness(kit: Kit) -> float:
        return layout_fitness_value(kit.layout, w6)

    return fitness
