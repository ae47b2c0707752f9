"""The warm start of ``cpsat``: the best plan of some heuristics within a share of the time
limit (:func:`best_heuristic_plan`, option ``hint``; :mod:`.method`)."""

from __future__ import annotations

from collections.abc import Sequence

from ...bounds import best_bound
from ...instance import Instance
from ...objectives import Objective
from ...plan import Plan, evaluate
from ...stations import objective_of
from ..budget import Budget
from ..common import Packer, closed_form_plan, pack_time_limit

#: The heuristics ``hint="auto"`` runs; the best plan is the warm start.
HINT_METHODS = ("single-task", "whole-assembly", "greedy-ce")
#: The least time (s) a step is given even when the budget is spent (it returns at once).
MIN_RUN = 0.05
#: A warm-start heuristic that would get less than this (s) is skipped (if a plan is known).
MIN_HINT = 0.3
#: Seconds per task kept back from a heuristic's share of the warm start for its run past its
#: own ``time_limit``. Measured +4.4 s at 500 and +7.5-10 s at 1,000 tasks for greedy-ce before
#: its incremental timeline, +0.5-1.4 s at 1,000 tasks since (bench/results/scale.md): now a
#: conservative margin, kept because the scale benchmark's cpsat rows were measured with it.
HINT_OVERRUN_S_PER_TASK = {"greedy-ce": 0.01}
#: Seconds greedy-ce spends loading its compiled kernels (numba's import and cache) before it
#: can look at its clock, when numba is not loaded yet: about 1 s idle, 2-3 s on a busy
#: machine (a 4,000-part task at 2 s took 5.1 s with it, docs/scaling.md).
KERNEL_LOAD_S = 1.0


def hint_methods(hint: str) -> tuple[str, ...]:
    """The methods the option ``hint`` runs, the same in ``cpsat`` and ``milp``
    (docs/formulations.md, "One driver for cpsat and milp"): ``auto`` the three of
    :data:`HINT_METHODS`, ``none`` none, else the one named."""
    return {"auto": HINT_METHODS, "none": ()}.get(hint, (hint,))


def best_heuristic_plan(
    instance: Instance,
    methods: Sequence[str] = HINT_METHODS,
    seed: int = 0,
    time_limit: float | None = None,
    objective: str = "makespan",
) -> tuple[Plan | None, str | None]:
    """The plan of least ``objective`` among heuristic methods (a warm start for exact models);
    methods that cannot lay out a kit are skipped. ``time_limit`` (None: none) bounds them
    all: each gets what is left of it, and once it is spent the remaining methods are
    skipped (unless no plan is known yet)."""
    import sys
    import time

    from ...errors import BilevelKitError
    from ...methods import get_method, require_stations_support

    end = None if time_limit is None else time.perf_counter() + time_limit
    best: tuple[float, Plan, str] | None = None
    for name in methods:
        left = None if end is None else end - time.perf_counter()
        if left is not None and left <= 0 and best is not None:
            break
        if left is not None:  # keep back the method's overrun past its own limit
            left -= HINT_OVERRUN_S_PER_TASK.get(name, 0.0) * instance.n_tasks
            if name == "greedy-ce" and "numba" not in sys.modules:
                left -= KERNEL_LOAD_S
            if left <= MIN_HINT and best is not None:
                continue
            if name == "greedy-ce" and best is not None and _kernels_would_compile():
                continue  # a compile of ~15-60 s (or a load of 1-3 s) is not in the budget
        try:
            require_stations_support(instance, name)  # (several stations: those that plan them)
            spec = get_method(name)
            fn = spec.load()
            tl = None if left is None else max(MIN_RUN, left)
            if spec.options:
                out = fn(instance, spec.parse({}), seed=seed, time_limit=tl)
            else:
                out = fn(instance, seed=seed)
        except BilevelKitError:
            continue
        if out.plan is None:
            continue
        ms = objective_of(evaluate(instance, out.plan), objective)
        if best is None or ms < best[0]:
            best = (ms, out.plan, name)
    return (best[1], best[2]) if best else (None, None)


def _kernels_would_compile() -> bool:
    """Would greedy-ce compile (or load) its kernels on this call? :func:`bilevel_kit.solve`
    compiles them before the clock (the method's ``prepare`` step), so this holds only for a
    direct call of the method's function; a time-limited warm start then skips greedy-ce
    rather than overrun (docs/scaling.md#first-run)."""
    from ...heuristics.warmup import ready

    return not ready()


def closed_bound(instance: Instance, objective: Objective) -> float | None:
    """The closed-form makespan bound (:mod:`bilevel_kit.bounds`) when ``objective`` is the
    makespan; None for the others (live progress reports no closed-form bound on them)."""
    return best_bound(instance) if objective.is_makespan else None


def closed_form_optimal(instance: Instance, budget: Budget) -> bool:
    """Does a quick plan attain the closed-form bound (then :func:`run` ends at once)?"""
    packer = Packer(instance, min(0.2, pack_time_limit(budget)), budget.head(0.05))
    return closed_form_plan(instance, packer) is not None
