r"""The registered method ``milp``: the exact whole-horizon schedule as a Pyomo MILP.

The same problem as :mod:`bilevel_kit.models.cpsat` (docs/timeline.md,
docs/formulations.md), written as a position-based batching MILP (:mod:`.model`) so that an
LP-based branch and bound (HiGHS by default, any Pyomo solver by name, :mod:`.solver`)
cross-checks the CP-SAT model. It shares only the packing oracle with it.

**Tray (logic-based Benders).** The master holds the area relaxation. Each kit of an
incumbent is checked with the memoised packing oracle
(:func:`..packing_oracle.fit_verdict`); a part multiset M that provably does not fit is shrunk by
a deletion filter to a minimal non-fitting one (with a proof of the same scope) and cut from
**every** kit (:func:`.model.add_cut`). The master is re-solved
until its optimum packs (then it is optimal for the full problem) or the time is up; kits that
do not fit are split greedily to keep an incumbent. Cuts are first seeded for every pair of
tasks that does not fit (``tray`` ``auto`` and ``benders`` alike, as ``cpsat``'s Benders; not
with several stations). "Fits"
means what the oracle means: an axis-aligned layout on its grid (a "no" confirmed on the exact
grid), the same notion as the CP-SAT model; "optimal" and ``bound`` speak of every plan the
checker accepts, the master's own verdict and bound of the plans its cuts were proven for
(docs/formulations.md#what-optimal-means). The incumbent (the quick plan, then the best
packable plan) is the MIP start.

**Time.** ``time_limit`` (default 60 s) covers everything (packing, model building and all
master solves), up to a small margin (0.2 s kept back); a model over the memory limit or too
slow to build is not built (:mod:`..exact.nomodel`; docs/formulations.md, "Model too large").
The proven bound of :mod:`bilevel_kit.models.relax` takes at most 5 % of the time limit
(:func:`~bilevel_kit.models.relax.for_model`), the ``hint`` method at most 30 %.

**Result.** ``status`` optimal / feasible / infeasible / unknown; ``bound`` a proven lower
bound on the makespan in seconds (the master's best bound when every cut is proven, never below
the closed-form bounds). The run's steps are those of :mod:`..exact.driver`; the ``extra`` keys,
and where they differ from ``cpsat``'s, are listed in docs/formulations.md, "One driver for
cpsat and milp" (for an objective besides the makespan also ``objective_value``,
``objective_bound``, ``objective_gap``: :func:`.model.objective_extra`). With stations the
incumbent is the best of the baselines', greedy-ce's and the ``hint`` method's plans
(:mod:`.warm`).

On the table (12 tasks) both exact models take about 1-3 s; on 5 tables (60 tasks) HiGHS
needed 45-110 s against 33 s for CP-SAT on a 2-core machine (bench/bench_milp.py).
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass, field, replace
from typing import TYPE_CHECKING, Any, ClassVar

from ... import progress
from ...bounds import best_bound, min_kits
from ...instance import Instance
from ...methods import MethodOutput, Status, gap
from ...objectives import Objective, human_times
from ...objectives import get as get_objective
from ...options import keyword_run
from ...plan import Kit, Plan, evaluate
from ..budget import Budget
from ..common import (
    Packer,
    claim_scope,
    johnson_plan,
    pack_time_limit,
    plan_extra,
    quick_plan,
)
from ..exact.driver import (
    HINT_SHARE,
    bound_source,
    drive,
    known_bound,
    proven_bound,
    without_plan,
)
from ..exact.keys import CLOSED_FORM_BOUND, PROVEN_BOUND, no_solve, solve_outcome, solved
from ..exact.nomodel import MILP as MILP_NO_MODEL
from ..exact.nomodel import WHOLE, HandOff, NoModelSpec, improve
from ..exact.options import SEARCH_DEFAULT
from ..exact.station_options import check_station_options
from ..packing import ANY_ANGLE
from . import warm
from .benders import Benders, Live
from .model import (
    build,
    human_order,
    kit_cap,
    model_cells,
    objective_extra,
    objective_value,
)
from .options import MARGIN, STATION_OPTIONS, MilpOptions
from .solver import SOLVER_OPTIONS, TOL, SolveInfo, ensure_ortools, make_solver

if TYPE_CHECKING:  # (annotations only: models.relax loads when a bound is computed)
    from ..relax import ProvenBound


def solve(
    instance: Instance,
    *,
    seed: int = 0,
    time_limit: float | None = 60.0,
    solver: str = "highs",
    objective: str = "makespan",
    tray: str = "auto",
    log: bool = False,
    solver_options: Mapping[str, Any] | None = None,
    hint: str = "auto",
    fallback: str = "lns",
    search: float = SEARCH_DEFAULT,
) -> MethodOutput:
    """The Python entry: :func:`run` with the options as keywords (validated like the
    method's); ``solver_options`` are passed to the solver."""
    return keyword_run(run, MilpOptions, locals(), "milp")


def run(
    instance: Instance,
    options: MilpOptions,
    *,
    seed: int = 0,
    time_limit: float | None = None,
    solver_options: Mapping[str, Any] | None = None,
) -> MethodOutput:
    """Minimise makespan (or human idle) over all segmentations and orders with a MILP; the
    registered method ``milp`` (no time limit: the budget's default, 60 s).

    Returns the result of the module docstring: ``bound`` is a proven lower bound on the
    makespan in seconds, every kit has a topological human order and a non-overlapping layout
    from the packing oracle. Several assembly stations: the station part of :mod:`.model`,
    with the options of :data:`STATION_OPTIONS`.
    """
    check_station_options(instance, "milp", options, STATION_OPTIONS)
    warm.check_station_hint(instance, options.hint)
    if not instance.stations and get_objective(options.objective).makespan_with_one_station:
        options = replace(options, objective="makespan")  # e.g. sum_completion
    instance = instance.as_one_station()  # one declared station: the S = 1 model, no z[s,k]
    budget = Budget(time_limit)
    ensure_ortools(options.solver)
    opt = make_solver(options.solver)
    closed = best_bound(instance)
    pack_tl = pack_time_limit(budget)
    packer = Packer(instance, pack_tl, budget.cut(MARGIN))
    live = Live(progress.tracker(options.objective), instance, get_objective(options.objective))
    r = _Run(instance, options, budget, packer, closed, live, seed, opt, solver_options)
    r.extra.update(
        solver=options.solver,
        objective=options.objective,
        tray_mode="benders",  # (auto: milp has no embedded tray)
        master_solves=0,
        hint_method=None,
        cuts=0,
        unproven_cuts=0,
        time_limit_enforced=options.solver == "highs" or options.solver in SOLVER_OPTIONS,
    )
    return drive(r, options.fallback, options.search)


milp = run  # the registered method ``milp`` (module docstring)


def prepare(notify: Callable[[str], None] | None = None) -> float | None:
    """The registered method's ``prepare`` step, run before its clock: greedy-ce's kernels
    (its warm start and LNS may run greedy-ce) and Pyomo's import, which every master build
    needs: charged to the time limit, a process's first ``milp`` solve on a loaded 2-core
    machine spent 2-10 s in its first master build, and a 10 s run took 16.0-17.6 s once the
    LNS first had used its share (docs/formulations.md, "The budget split of issue 37")."""
    import time

    from ...heuristics.warmup import compile_kernels

    t0 = time.perf_counter()
    compile_kernels(notify)
    import pyomo.environ  # noqa: F401

    return time.perf_counter() - t0


@dataclass
class _Run:
    """The MILP backend of the exact driver (:mod:`..exact.driver`; the incumbent is a list of
    kits of task ids): what the steps of one run share, and how it ends (wall time, the last
    live report)."""

    instance: Instance
    options: MilpOptions
    budget: Budget
    packer: Packer
    closed: float  # the closed-form makespan bound
    live: Live
    seed: int
    opt: Any  # the solver
    solver_options: Mapping[str, Any] | None
    extra: dict[str, Any] = field(default_factory=dict)
    proven: ProvenBound | None = None  # the proven bound of models.relax (None: not computed)
    K: int = 1
    upper: float | None = None  # the incumbent's makespan (makespan objective)
    inc_obj: float | None = None  # the incumbent's objective
    spec: ClassVar[NoModelSpec] = MILP_NO_MODEL
    margin: ClassVar[float] = MARGIN

    @property
    def minimised(self) -> Objective:
        """The registry's objective the run minimises (:mod:`bilevel_kit.objectives`)."""
        return get_objective(self.options.objective)

    @property
    def best(self) -> float:
        """The best makespan bound known before the model (s)."""
        return known_bound(self.closed, self.proven)

    def known_bound(self) -> float:
        return self.best

    def finish(self, plan: Plan | None, status: Status, bound: float | None) -> MethodOutput:
        self.extra["wall_time_s"] = self.budget.elapsed()
        if plan is not None:
            self.live.final(plan, bound, self.extra)
        objective = self.options.objective
        return MethodOutput(plan, status, bound, self.extra, status_objective=objective)

    def start(self) -> list[list[str]] | None:
        """The incumbent, its objective, the upper bound U and the kit cap K."""
        instance = self.instance
        if instance.stations:  # docs/timeline.md#several-stations
            inc, inc_obj, upper, K = warm.station_incumbent(self, self.seed)
            upper_start = self.live.seconds(inc_obj)  # the objective's value in s
            self.extra.update(max_kits=K, upper_start=upper_start)
        else:
            inc, inc_obj, upper, K = _incumbent(self, pack_time_limit(self.budget), self.seed)
            K = max(_strong_bound(self, upper, K), len(inc) if inc is not None else 1)
        self.inc_obj, self.upper, self.K = inc_obj, upper, K
        return inc

    def shortcut(self, inc: list[list[str]] | None) -> MethodOutput | None:
        """The quick plan attains a closed-form bound (e.g. Johnson's makespan) or the proven
        bound of models.relax: optimal without a model (bilevel_kit/bounds.py, (d))."""
        upper = self.upper
        if upper is None or upper > self.best + TOL or not self.minimised.is_makespan:
            return None
        done = CLOSED_FORM_BOUND if upper <= self.closed + TOL else PROVEN_BOUND
        no_solve(self.extra, done)
        return _conclude(self, inc, None, None, ANY_ANGLE, proven=True)

    def cells(self) -> int:
        return model_cells(self.instance, self.K)

    def hand_off(self, inc: list[list[str]], limit: HandOff = WHOLE) -> list[list[str]]:
        """The incumbent, or the LNS's better plan from it (makespan objective, one station;
        several: every objective); its layouts taught to the packer, which lays it out."""
        self.extra["improved_by"] = None
        if self.instance.stations:  # lns's station search (docs/stations.md)
            return warm.station_hand_off(self, inc, limit.within(self.budget.remaining(MARGIN)))
        plan = _with_layouts(self.instance, inc, self.packer, {})
        if plan is None or not self.minimised.is_makespan:
            return inc
        within = limit.within(self.budget.remaining(MARGIN))
        better = improve(
            self.instance, plan, bound=self.best, seed=self.seed, limit=within, extra=self.extra
        )
        if better is None:
            return inc
        return self.adopt(better)

    @property
    def is_makespan(self) -> bool:
        return self.minimised.is_makespan

    def plan(self, inc: list[list[str]]) -> Plan:
        return Plan(tuple(Kit(tuple(k)) for k in inc))

    def adopt(self, plan: Plan) -> list[list[str]]:
        """A better plan as the incumbent: its layouts taught to the packer, which lays the
        result out, and its makespan the model's U."""
        for kit in plan.kits:
            if kit.layout:
                self.packer.learn(self.instance.kit_parts(kit.tasks), kit.layout)
        self.upper = self.inc_obj = evaluate(self.instance, plan).makespan
        return [list(k.tasks) for k in plan.kits if k.tasks]

    def raise_bound(self, value: float, source: str) -> None:
        from ..relax import raised

        self.proven = raised(self.proven, value, source, self.instance)

    def conclude(self, inc: list[list[str]]) -> MethodOutput:
        return _conclude(self, inc, None, None, ANY_ANGLE, proven=False)

    def solve(self, inc: list[list[str]] | None) -> MethodOutput:
        return _solve_master(self, inc)


def _incumbent(
    r: _Run, pack_tl: float, seed: int
) -> tuple[list[list[str]] | None, float | None, float | None, int]:
    """The quick plan (for makespan, first the Johnson order's, optimal at once when it attains
    the closed-form bound, else the better of it and the topological order's; ties: the
    topological order's) or the hint's plan if better, its objective, the upper bound U and
    the kit cap K (valid only for plans at least as good)."""
    instance, budget, objective = r.instance, r.budget, r.options.objective
    makespan = r.minimised.is_makespan
    johnson, optimal = None, False
    if makespan:
        packer = Packer(instance, min(0.2, pack_tl), budget.next(0.05))
        johnson, optimal = johnson_plan(instance, packer)
    inc = johnson if optimal else None
    inc = inc or quick_plan(instance, Packer(instance, min(0.2, pack_tl), budget.next(0.1)))
    inc_obj = None if inc is None else objective_value(instance, inc, objective)
    if johnson is not None and not optimal:
        johnson_obj = objective_value(instance, johnson, objective)
        if inc_obj is None or johnson_obj < inc_obj - TOL:
            inc, inc_obj = johnson, johnson_obj
    if r.options.hint != "none" and (inc is None or inc_obj is None or inc_obj > r.closed + TOL):
        inc, inc_obj = _hinted(r, inc, inc_obj, seed)
    upper = None
    K = instance.n_tasks
    if inc is not None and inc_obj is not None and makespan:
        upper = inc_obj
        K = min(K, kit_cap(instance, upper))
        K = max(K, len(inc))
    r.extra["max_kits"] = K
    r.extra["upper_start"] = r.live.seconds(inc_obj)  # the objective's value in s
    r.live.tracker.report(
        r.live.seconds(inc_obj),
        r.closed if makespan else None,
        stage=f"MILP ({r.options.solver})",
    )
    return inc, inc_obj, upper, K


def _hinted(
    r: _Run, inc: list[list[str]] | None, inc_obj: float | None, seed: int
) -> tuple[list[list[str]] | None, float | None]:
    """The plan of the ``hint`` method within :data:`HINT_SHARE` of the time limit when its
    kits pack and it beats ``inc`` (``extra['hint_method']`` names it), else ``inc``."""
    from ..exact.warm import best_heuristic_plan, hint_methods

    left = min(HINT_SHARE * r.budget.time_limit, r.budget.remaining(MARGIN))
    methods = hint_methods(r.options.hint)
    kw: dict[str, Any] = {"seed": seed, "time_limit": left, "objective": r.options.objective}
    plan, source = best_heuristic_plan(r.instance, methods, **kw)
    r.extra["hint_method"] = None
    if plan is None:
        return inc, inc_obj
    kits = [list(k.tasks) for k in plan.kits if k.tasks]
    obj = objective_value(r.instance, kits, r.options.objective)
    if (inc_obj is not None and obj >= inc_obj - TOL) or not all(r.packer.fits(k) for k in kits):
        return inc, inc_obj
    r.extra["hint_method"] = source
    return kits, obj


def _strong_bound(r: _Run, upper: float | None, K: int) -> int:
    """The proven makespan bound of :mod:`bilevel_kit.models.relax` into ``r.proven``
    (makespan objective only, :func:`..exact.driver.proven_bound`); the kit cap K lowered by
    it."""
    if not r.minimised.is_makespan:
        return K
    from ..relax import closed_at

    r.proven = proven_bound(r.instance, r.budget, upper, r.extra, MARGIN)
    if upper is not None:
        cap = r.proven.kit_cap(upper + TOL * max(1.0, upper), closed_at(r.instance))
        if cap is not None:
            K = max(1, min(K, cap))
            r.extra["max_kits"] = K
    return K


def _solve_master(r: _Run, inc: list[list[str]] | None) -> MethodOutput:
    """Build the master with K kits (and C <= U) and run the Benders loop from the incumbent."""
    options, K, upper = r.options, r.K, r.upper
    lower = None if r.proven is None else r.proven.value
    if r.instance.stations:  # the closed form (the stations' bounds) on C, or the ideal
        lower = r.best  # search's when higher (:mod:`..exact.search_first`, makespan only)
    master = build(r.instance, K, upper, options.objective, lower)
    r.extra["build_time_s"] = r.budget.elapsed()
    loop = Benders(r.instance, master, r.packer, r.budget, options, inc, r.inc_obj, r.live)
    if not r.instance.stations:  # (stations: docs/formulations.md, "Options with several stations")
        loop.cuts.seed_pairs()  # tray=auto or benders: pair cuts seeded, as cpsat's Benders
    info = loop.run(r.opt, r.seed, r.solver_options)
    scope = loop.cuts.scope
    r.extra.update(master_solves=loop.iterations, cuts=master.n_cuts, **loop.cut_counts())
    r.extra["master_time_s"] = None if info is None else info.wall_time_s
    solved(r.extra, *_outcome(info))
    if loop.kits is None:  # (an infeasible master has every cut proven: scope not None)
        return without_plan(r, loop.infeasible, scope)
    return _conclude(r, loop.kits, loop.lower, loop.lower_any, scope, proven=loop.proven)


def _outcome(info: SolveInfo | None) -> tuple[str, str | None]:
    """The last master solve's ``solver_status`` and ``backend_status`` (:mod:`..exact.keys`;
    no solve: ``unknown``)."""
    if info is None:
        return "unknown", None
    kw = {"optimal": info.optimal, "has_solution": info.has_solution}
    return solve_outcome(**kw, infeasible=info.infeasible), info.termination


def _conclude(
    r: _Run,
    kits: list[list[str]] | None,
    lower: float | None,
    lower_any: float | None,
    scope: str | None,
    *,
    proven: bool,
) -> MethodOutput:
    """The plan of ``kits``, proven optimal (``proven``) among the plans of ``scope``
    (docs/formulations.md#what-optimal-means), with its makespan bound from the master's
    bounds ``lower`` (for 0/90-degree plans) and ``lower_any`` (for every plan); unknown when
    there are no kits or some kit has no layout in time."""
    plan = None if kits is None else _with_layouts(r.instance, kits, r.packer, r.extra)
    if plan is None:
        return r.finish(None, Status.UNKNOWN, r.best)
    objective = r.minimised
    bound = _makespan_bound(r.instance, plan, r.closed, lower_any, objective, r.extra)
    real = evaluate(r.instance, plan).makespan
    if objective.is_makespan:  # the proven bound of models.relax holds for every plan
        r.extra["bound_source"] = bound_source(r.closed, r.proven, lower_any, TOL)
        bound = min(max(bound, r.best), real)
        r.extra["gap"] = gap(real, bound) or 0.0
    optimal = (proven and scope == ANY_ANGLE) or (
        objective.is_makespan and real <= bound + TOL * max(1.0, real)
    )
    r.extra["optimal_axis_aligned"] = proven and scope is not None
    if objective.is_makespan:
        axis = r.best if lower is None else max(r.best, lower)
        r.extra.update(bound_axis_aligned=min(real, axis), bound_model=lower)
    claim_scope(r.extra, ANY_ANGLE if optimal else scope)
    # docs/timeline.md#several-stations: its value, bound and gap not the result's own
    if not objective.top_level:
        proofs = (optimal, bool(r.extra["optimal_axis_aligned"]))
        lows = (lower_any, lower)
        r.extra.update(objective_extra(r.instance, plan, objective.name, lows, proofs))
    return r.finish(plan, Status.OPTIMAL if optimal else Status.FEASIBLE, bound)


def _with_layouts(
    instance: Instance, kits: list[list[str]], packer: Packer, extra: dict[str, Any]
) -> Plan | None:
    """The plan of ``kits`` in human order with the oracle's layouts; None (and a ``reason``)
    when some kit has none within the time limit."""
    kits_out = []
    for kit in kits:
        tasks = human_order(instance, kit)
        layout = packer.layout(tasks)
        if layout is None and instance.kit_parts(tasks):
            extra["reason"] = "no layout for some kit within the time limit"
            return None
        kits_out.append(Kit(tasks, layout or ()))
    return Plan(tuple(kits_out))


def _makespan_bound(
    instance: Instance,
    plan: Plan,
    closed: float,
    lower: float | None,
    objective: Objective,
    extra: dict[str, Any],
) -> float:
    """The proven makespan bound in seconds from the closed-form bound and the master's bound
    ``lower`` on its own objective; fills the plan's entries of ``extra``."""
    real = evaluate(instance, plan)
    if objective.is_makespan:
        bound = closed if lower is None else max(closed, lower)
    elif instance.stations:  # the master's bound is on another objective: objective_extra
        bound = closed
    else:  # the makespan bound its bound implies (human idle: C = idle + work)
        obj_lb = None if lower is None else lower - objective.dropped(human_times(instance))
        m_min = min_kits(instance)
        implied = None if obj_lb is None else objective.makespan_bound(instance, obj_lb, m_min)
        bound = closed if implied is None else max(closed, implied)
    if bound > real.makespan:  # only float noise of the solver can do this
        bound = real.makespan
    extra.update(plan_extra(plan, real, bound, closed, lower))
    return bound
