"""The warm start of the exact methods ``cpsat`` and ``milp`` (docs/formulations.md, "One driver
for cpsat and milp"): the plan of least objective among some heuristic methods run within a
time limit (:func:`best_heuristic_plan`), one loop for both backends.

How the loop spends its time and breaks ties is a :class:`WarmRule`. Two rules remain, each
kept because its backend's measured results (bench/results, the tests' expected plans) were
computed with it: :data:`DEFAULT` (``cpsat``'s warm start, ``milp``'s ``hint`` with one
station, the LNS's start plans) and ``milp``'s with several stations (:data:`..milp.warm.RULE`:
a smaller overrun margin, no method skipped for lack of time, ties within ``TOL``). Choosing
between the warm start and the backend's own plans stays with the backend: ``cpsat`` prefers
the hint on a tie with its quick plan or the baselines and names only a winning hint in
``extra["hint_method"]``, ``milp`` keeps its quick plan on a tie and, with stations, names the
winning baseline too (docs/formulations.md, "One driver for cpsat and milp").
"""

from __future__ import annotations

import sys
import time
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

from ...instance import Instance
from ...plan import Plan, evaluate
from ...stations import objective_of

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


@dataclass(frozen=True)
class WarmRule:
    """How the warm start spends a time limit and breaks ties (module docstring)."""

    #: Seconds per task kept back from a method's time for its run past its own limit.
    overrun_s_per_task: Mapping[str, float] = field(default_factory=dict)
    #: Seconds kept back from greedy-ce's time when numba is not loaded yet.
    kernel_load_s: float = 0.0
    #: A method that would get at most this (s) is skipped once a plan is known (None: none is).
    min_run: float | None = None
    #: A plan is better only by more than ``tol x max(1, |value|)`` (0: any less value).
    tol: float = 0.0


#: The rule of ``cpsat`` and of the other callers (module docstring).
DEFAULT = WarmRule(HINT_OVERRUN_S_PER_TASK, KERNEL_LOAD_S, MIN_HINT, 0.0)


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
    rule: WarmRule = DEFAULT,
    extra: dict[str, Any] | None = None,
) -> tuple[Plan | None, str | None]:
    """The plan of least ``objective`` among heuristic methods (a warm start for exact models)
    and the method's name; methods that refuse the instance (or do not model its stations)
    are skipped. ``time_limit`` (None: none) bounds them all: each gets what is left of it
    (less ``rule``'s margins); greedy-ce is skipped when its kernels would compile and a plan
    is known (then ``extra["warm_start_skipped"]`` says so, when ``extra`` is given), and a
    method its time limit stopped is listed in ``extra["warm_start_cut"]``: a busy machine
    can leave the warm start worse than the same method run alone with more time."""
    end = None if time_limit is None else time.perf_counter() + time_limit
    best: tuple[float, Plan, str] | None = None
    for name in methods:
        tl = None
        if end is not None:
            tl = _time_for(instance, name, end - time.perf_counter(), rule, best is not None)
            if tl is None:
                continue
            if name == "greedy-ce" and best is not None and _kernels_would_compile():
                # a compile of ~15-60 s (or a load of 1-3 s) is not in the budget;
                # bilevel_kit.solve compiles first
                if extra is not None:
                    extra["warm_start_skipped"] = "greedy-ce: its kernels are not compiled"
                continue
        plan, cut = _heuristic_plan(instance, name, seed, tl)
        if cut and extra is not None:  # its plan is what the time allowed, not its own best
            extra.setdefault("warm_start_cut", []).append(name)
        if plan is None:
            continue
        value = objective_of(evaluate(instance, plan), objective)
        if best is None or value < best[0] - rule.tol * max(1.0, abs(value)):
            best = (value, plan, name)
    return (best[1], best[2]) if best else (None, None)


def _time_for(
    instance: Instance, name: str, left: float, rule: WarmRule, known: bool
) -> float | None:
    """The time limit of method ``name`` with ``left`` s of the warm start left, less its
    overrun (and kernel load); None: skipped (too little time and a plan is ``known``)."""
    left -= rule.overrun_s_per_task.get(name, 0.0) * instance.n_tasks
    if name == "greedy-ce" and "numba" not in sys.modules:
        left -= rule.kernel_load_s
    if rule.min_run is not None and left <= rule.min_run and known:
        return None
    return max(MIN_RUN, left)


def _heuristic_plan(
    instance: Instance, name: str, seed: int, time_limit: float | None
) -> tuple[Plan | None, bool]:
    """The plan of the registered method ``name`` with its default options within
    ``time_limit`` s (None: its own), None when it has none or refuses the instance; and
    whether its time limit stopped it (:func:`bilevel_kit.methods.time_limit_reached`)."""
    from ...errors import BilevelKitError
    from ...methods import get_method, require_stations_support, time_limit_reached

    try:
        require_stations_support(instance, name)  # (several stations: those that plan them)
        spec = get_method(name)
        fn = spec.load()
        t0 = time.perf_counter()
        if spec.options:
            out = fn(instance, spec.parse({}), seed=seed, time_limit=time_limit)
        else:
            out = fn(instance, seed=seed)
        return out.plan, time_limit_reached(out, time.perf_counter() - t0, time_limit)
    except BilevelKitError:
        return None, False


def _kernels_would_compile() -> bool:
    """Would greedy-ce compile (or load) its kernels on this call? :func:`bilevel_kit.solve`
    compiles them before the clock (the method's ``prepare`` step), so this holds only for a
    direct call of the method's function; a time-limited warm start then skips greedy-ce
    rather than overrun (docs/scaling.md#first-run)."""
    from ...heuristics.warmup import ready

    return not ready()
