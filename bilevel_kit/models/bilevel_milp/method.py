"""The registered method ``bilevel-milp``: kit values, columns, the MIP start, the MILP and
the plan with its J (package docstring, "Result" and "Time")."""

from __future__ import annotations

import math
import time
from collections import Counter
from collections.abc import Collection, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any, Literal

from ... import progress
from ...bounds import best_bound
from ...errors import UsageError
from ...instance import Instance
from ...methods import MethodOutput, Status
from ...options import keyword_run, option
from ...plan import Kit, Plan, evaluate
from ..budget import Budget
from ..milp.model import human_order
from ..milp.solver import SolveInfo, ensure_ortools, make_solver, run_solver
from ..packing import ANY_ANGLE, AXIS_ALIGNED
from .columns import MAX_COLUMNS, Column, build_columns, enumerate_kits
from .lower import LowerLevel
from .model import build_model, chosen_kits, set_start
from .objective import paper_objective
from .warm_start import warm_start

#: Largest number of tasks the column enumeration accepts (option ``max_tasks``).
MAX_TASKS = 16
#: Seconds kept back from the time limit for the final plan.
MARGIN = 0.2


@dataclass(frozen=True)
class BilevelMilpOptions:
    """Options of the registered method ``bilevel-milp`` (the Python :func:`solve` also takes
    a warm-start plan, CE parameters, shared kit values and solver options)."""

    solver: str = option("highs", "highs (HiGHS in a child process) or any Pyomo solver name")
    lower: Literal["ce", "best"] = option(
        "best", "kit values from CE and the oracle, or also CP-SAT's fitness layout"
    )
    pack_time_limit: float = option(
        0.5, "seconds per multiset for the CP-SAT fitness layout", min=0.0
    )
    max_tasks: int = option(MAX_TASKS, "largest instance accepted (tasks)", min=1)
    max_columns: int = option(MAX_COLUMNS, "largest number of candidate kits accepted", min=1)
    signed: bool = option(False, "the printed signed terms 5 and 6 (docs/errata.md)")
    log: bool = option(False, "print the MILP solver's log")


def solve(
    instance: Instance,
    *,
    seed: int = 0,
    time_limit: float | None = 60.0,
    solver: str = "highs",
    lower: str = "best",
    pack_time_limit: float = 0.5,
    max_tasks: int = MAX_TASKS,
    max_columns: int = MAX_COLUMNS,
    signed: bool = False,
    warm_plan: Plan | str | None = "greedy",
    ce_params: Any = None,
    values: LowerLevel | None = None,
    log: bool = False,
    solver_options: Mapping[str, Any] | None = None,
) -> MethodOutput:
    """The Python entry: :func:`run` with the options as keywords (validated like the
    method's) and the Python-only arguments of :func:`run`."""
    return keyword_run(run, BilevelMilpOptions, locals(), "bilevel-milp")


def run(
    instance: Instance,
    options: BilevelMilpOptions,
    *,
    seed: int = 0,
    time_limit: float | None = None,
    warm_plan: Plan | str | None = "greedy",
    ce_params: Any = None,
    values: LowerLevel | None = None,
    solver_options: Mapping[str, Any] | None = None,
) -> MethodOutput:
    """Minimise the paper's whole-plan objective J exactly over enumerated kits (the result:
    package docstring; each kit of the plan has its best known layout); with its defaults, the
    registered method ``bilevel-milp`` (no time limit: the budget's default, 60 s).

    ``warm_plan``: a plan, or ``"greedy"`` (greedy-ce with this seed and these CE parameters),
    improved by :func:`~.warm_start.local_search`, is the MIP start; ``ce_params`` (a
    :class:`~bilevel_kit.heuristics.cross_entropy.CEParams`) must match greedy-ce's for J to
    compare kit by kit; ``values``: a :class:`~.lower.LowerLevel` to use (and fill), so that the
    caller scores other plans with the same kit values; ``solver_options`` go to the MILP
    solver.
    """
    budget = Budget(time_limit)
    _check_size(instance, options.max_tasks)
    ensure_ortools(options.solver)
    opt = make_solver(options.solver)
    live = progress.tracker("J", unit="")  # the terminal's live line: which step runs now
    live.report(stage="enumerating kits")
    kits = enumerate_kits(instance, options.max_columns)
    if budget.expired() and values is None:  # the lower level alone loads numba (1-3 s)
        extra = {"solver": options.solver, "candidates": len(kits), "termination": "time"}
        extra.update(reason="the time limit ran out before the lower level")
        extra["wall_time_s"] = budget.elapsed()
        return MethodOutput(None, Status.UNKNOWN, best_bound(instance), extra, "J")
    lower_level = values or LowerLevel(
        instance,
        seed=seed,
        lower=options.lower,
        pack_time_limit=options.pack_time_limit,
        ce_params=ce_params,
    )
    r = _Run(instance, options, budget, seed, lower_level, best_bound(instance))
    r.extra.update(solver=options.solver, lower=options.lower, candidates=len(kits))
    live.report(stage=f"lower level of {len(kits)} candidate kits")
    cols = _columns(r, kits)
    if isinstance(cols, Status):
        return r.finish(None, cols)
    live.report(stage="warm start (greedy-ce, local search)")
    start = None if warm_plan is None else _start(r, warm_plan, ce_params)
    live.report(stage=f"MILP over {len(cols)} columns ({options.solver})")
    m, keys, info = _solve_milp(r, cols, start, opt, solver_options)
    plan = _incumbent(r, m, keys, cols, info, start)
    if plan is None:
        return r.finish(None, Status.INFEASIBLE if info.infeasible else Status.UNKNOWN)
    _plan_extra(r, plan, info)
    proven = not r.extra["excluded_unproven"] and not r.extra["excluded_axis_aligned"]
    r.extra["optimal_over_columns"] = info.optimal
    if info.optimal and not proven:
        r.extra["status_reason"] = (
            "some candidate kits were left out without a proof for every layout (parts at "
            "other angles, or a packing the oracle could not decide, may fit them): J is "
            "optimal over the columns only"
        )
    return r.finish(plan, Status.OPTIMAL if info.optimal and proven else Status.FEASIBLE)


#: The registered method ``bilevel-milp``: :func:`run` warm-started from greedy-ce's plan.
bilevel_milp = run


@dataclass
class _Run:
    """What the steps of one run share, and how it ends: ``bound`` is the closed-form
    *makespan* bound (the method does not minimise makespan), ``status`` refers to J."""

    instance: Instance
    options: BilevelMilpOptions
    budget: Budget
    seed: int
    lower_level: LowerLevel
    closed: float
    extra: dict[str, Any] = field(default_factory=dict)

    def finish(self, plan: Plan | None, status: Status) -> MethodOutput:
        self.extra["wall_time_s"] = self.budget.elapsed()
        return MethodOutput(plan, status, self.closed, self.extra, status_objective="J")


def _check_size(instance: Instance, max_tasks: int) -> None:
    """UsageError beyond ``max_tasks`` tasks (package docstring, "Size limit")."""
    n = instance.n_tasks
    if n > max_tasks:
        raise UsageError(
            f"bilevel-milp: {instance.name!r} has {n} tasks; the exact column model accepts at "
            f"most {max_tasks} (parameter max_tasks)"
        )


def _columns(r: _Run, kits: Sequence[frozenset[str]]) -> list[Column] | Status:
    """The columns with the lower level's values; the run's status (and a ``reason``) when
    there is no plan to look for."""
    lower_level, extra = r.lower_level, r.extra
    excluded: Counter[str | None] = Counter()
    cols = build_columns(r.instance, kits, lower_level, r.budget.cut(MARGIN), excluded)
    extra.update(
        multisets=lower_level.n_values,
        lower_level_s=lower_level.time_s,
        excluded_unproven=excluded[None],
        excluded_axis_aligned=excluded[AXIS_ALIGNED],
    )
    extra["lower_level_cut"] = lower_level.n_cut  # updated later: the plan's values may cut too
    if cols is None:
        extra["reason"] = "time limit reached while computing the kits' lower-level values"
        return Status.UNKNOWN
    extra["columns"] = len(cols)
    covered = set().union(*(c.tasks for c in cols)) if cols else set()
    alone = [t.id for t in r.instance.tasks if t.id not in covered]
    if alone:  # no plan, if the task's own kit is proven not to fit at any angle
        proofs = [_alone_proof(r, t) for t in alone]
        extra["reason"] = f"task {alone[0]!r} fits in no kit" + (
            "" if all(p == ANY_ANGLE for p in proofs) else " found (not a proof for every layout)"
        )
        return Status.INFEASIBLE if all(p == ANY_ANGLE for p in proofs) else Status.UNKNOWN
    return cols


def _alone_proof(r: _Run, task: str) -> str | None:
    """The scope of the proof that ``task``'s parts alone do not fit (more part area than
    tray area rules out every layout)."""
    counts = r.instance.kit_parts([task])
    area = sum(r.instance.part_types[p].area * n for p, n in counts.items())
    if area > r.instance.tray.area:
        return ANY_ANGLE
    return r.lower_level.value(counts).proof


def _start(r: _Run, warm_plan: Plan | str, ce_params: Any) -> Plan:
    """The MIP start (:func:`~.warm_start.warm_start`), with J before and after the local
    search in ``extra``."""
    start, start_j, ls_j, ls_converged = warm_start(
        r.instance,
        warm_plan,
        r.lower_level,
        ce_params=ce_params,
        budget=r.budget,
        signed=r.options.signed,
        seed=r.seed,
    )
    r.extra.update(
        start_objective=start_j,
        local_search_objective=ls_j,
        local_search_converged=ls_converged,
    )
    return start


def _solve_milp(
    r: _Run,
    cols: Sequence[Column],
    start: Plan | None,
    opt: Any,
    solver_options: Mapping[str, Any] | None,
) -> tuple[Any, list[tuple[int, int]], SolveInfo]:
    """Build the MILP, load the MIP start and solve it within the budget (less the margin)."""
    instance, options = r.instance, r.options
    t_milp = time.perf_counter()
    m, keys = build_model(instance, cols, options.signed, dict(instance.weights))
    r.extra["binaries"] = len(keys)
    if start is not None:
        set_start(m, instance, cols, keys, start)
    info = run_solver(
        m,
        opt,
        options.solver,
        budget=r.budget.cut(MARGIN),
        seed=r.seed,
        log=options.log,
        objective=m.obj,
        options=solver_options,
        warmstart=start is not None,
    )
    r.extra.update(milp_s=time.perf_counter() - t_milp, termination=info.termination)
    return m, keys, info


def _incumbent(
    r: _Run,
    m: Any,
    keys: Sequence[tuple[int, int]],
    cols: Sequence[Column],
    info: SolveInfo,
    start: Plan | None,
) -> Plan | None:
    """The MILP's plan; else the MIP start (when the solver stopped without returning a
    solution, e.g. killed past the time limit, it is still a plan whose every kit fits)."""
    if info.has_solution:
        r.extra["incumbent"] = "milp"
        return _with_layouts(r.instance, chosen_kits(m, keys, cols), r.lower_level)
    if (
        start is not None
        and not info.infeasible
        and math.isfinite(r.extra["local_search_objective"])
    ):
        r.extra["incumbent"] = "warm start"
        return _with_layouts(r.instance, [k.tasks for k in start.kits], r.lower_level)
    return None


def _plan_extra(r: _Run, plan: Plan, info: SolveInfo) -> None:
    """The plan's J (by :func:`~.objective.paper_objective`), the MILP's bound on J* and its
    gap, and the plan's makespan."""
    value = paper_objective(r.instance, plan, r.lower_level, signed=r.options.signed)
    bound = info.bound
    if bound is not None and bound > value:
        bound = value  # solver tolerance
    r.extra.update(  # J's value, bound and gap: the result's own (methods.OBJECTIVE_KEYS)
        objective_value=value,
        plan_objective_J_milp=info.objective,
        objective_bound=bound,
        objective_gap=None if bound is None else abs(value - bound) / max(1.0, abs(value)),
        makespan=evaluate(r.instance, plan).makespan,
        lower_level_cut=r.lower_level.n_cut,
    )


def _with_layouts(
    instance: Instance, kits: Sequence[Collection[str]], lower_level: LowerLevel
) -> Plan:
    """``kits`` in delivery order, each in human order with its best known layout."""
    plan_kits = []
    for kit in kits:
        tasks = human_order(instance, kit)
        plan_kits.append(Kit(tasks, lower_level.value(instance.kit_parts(tasks)).layout))
    return Plan(tuple(plan_kits))
