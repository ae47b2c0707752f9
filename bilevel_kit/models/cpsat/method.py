r"""The registered method ``cpsat``: the exact whole-horizon schedule with CP-SAT.

It minimises makespan (or human idle) over all segmentations and orders (the model:
:mod:`.model`, docs/formulations.md; the timeline: docs/timeline.md), warm-started from the
best heuristic plan (:func:`best_heuristic_plan`, option ``hint``).

**Tray mode.** ``embedded`` puts the rectangles into the model, ``benders`` checks the kits
of master solutions with the packing oracle and cuts those that do not fit (:mod:`.tray`,
:mod:`.benders`). ``auto`` uses ``embedded`` when the number of optional (part, kit)
rectangles is at most :data:`AUTO_EMBEDDED_MAX_RECTS`, the instance does not enforce
reachability, has no tray limit, and the embedded tray proves optimality for every plan
(:func:`embed_scope`), else ``benders`` (measured: :data:`.tray.AUTO_EMBEDDED_MAX_RECTS`).
Embedded models run with :data:`~bilevel_kit.models.packing.SAFE_NO_OVERLAP_2D` (an
OR-Tools 9.15 workaround).
"optimal" and ``bound`` speak of every plan the checker accepts (parts at any angle); the
model's own optimum and bound hold for the plans its exclusions were proven for, which may be
the 0/90-degree plans only (``optimal_axis_aligned``, ``bound_axis_aligned``,
docs/formulations.md#what-optimal-means). The closed-form bounds of :mod:`bilevel_kit.bounds`,
which the bound never undercuts, hold for every plan. Times are scaled to integers
(:mod:`.scaling`).

**Kit count** (docs/formulations.md, "Kit count"): with a feasible upper bound U (the hint or
a quick plan whose kits are checked to fit) the robot's and the human's work cap K; C <= U too.

**Release times** (``solve``/``run`` argument ``releases``: task id -> s, default none; docs/
formulations.md, "Release times"): the model, its scaled timeline, the hint and U take them
into account, each kit lists its tasks in release order, the closed-form shortcuts are off and
the release bound of :func:`.model.release_bound` is added; ``extra['release_makespan']`` is
the model's makespan (on the grid), on which ``gap``, ``bound`` and ``optimal`` are.

**Several stations** (docs/formulations.md, "Several stations"): the same run and model, its
station part in :mod:`.station_model`, the station-specific steps in :mod:`.station_run`.

**Trays.** The instance's tray limit is a constraint of the model (:mod:`.model`), of its
scaled timeline (:mod:`.scaling`) and of every hint.

**Time.** ``time_limit`` (default 60 s) covers everything, the warm start and packing
included: the warm start's heuristics share :data:`HINT_SHARE` (30 %) of it (greedy-ce gets
what is left of that share as its own ``time_limit``), the proven bound of
:mod:`bilevel_kit.models.relax` at most 5 % (:func:`~bilevel_kit.models.relax.for_model`), the
model run gets the rest; 1 % of the run's limit and 0.15 s are kept back (CP-SAT stops a
little after its own limit on large models). ``deterministic`` (:func:`solve`, for callers
that limit CP-SAT by ``max_deterministic_time``, docs/simulation.md#determinism): packing
calls are limited by deterministic time too (:class:`..common.Packer`), the other steps by
work (quick plans, seed cuts, cut shrinking: their number of packing calls; the kit-count LP:
its variables), every sub-step's share is the whole budget (:class:`..budget.Budget`), so
the time limit is a safety net only, and ``extra["safety_net"]`` says whether a net fired
(then the result is not reproducible). A model over the memory limit or too slow to build
is not built (:mod:`..exact.nomodel`; docs/formulations.md, "Model too large").

**Result.** ``bound`` is a proven lower bound on the makespan in seconds (the model's bound,
never below the closed-form bounds); the plan lists each kit's tasks in a precedence-feasible
order with a non-overlapping layout. The run's steps are those of :mod:`..exact.driver`; the
``extra`` keys, and where they differ from ``milp``'s, are listed in docs/formulations.md, "One
driver for cpsat and milp".
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, fields, replace
from typing import TYPE_CHECKING, Any, Literal

from ... import progress
from ...bounds import best_bound
from ...errors import UsageError
from ...instance import MAX_LENGTH, MIN_LENGTH, Instance
from ...methods import MethodOutput, Status, require_stations_support
from ...objectives import get as get_objective
from ...options import finger_room_field, keyword_run, option
from ...plan import Plan, evaluate
from .. import packing, packing_oracle
from ..budget import Budget
from ..common import (
    Johnson,
    Packer,
    assignment_cells,
    chain_groups_idx,
    johnson_plan,
    pack_time_limit,
    quick_plan,
    reduced_edges,
)
from ..exact import keys
from ..exact.driver import HINT_SHARE, check_hint, drive, without_plan
from ..exact.nomodel import CPSAT as CPSAT_NO_MODEL
from ..exact.nomodel import WHOLE, HandOff, improve
from ..exact.options import (
    SEARCH_DEFAULT,
    Fallback,
    fallback_field,
    hint_field,
    objective_field,
    search_field,
)
from ..exact.station_options import HONOURED, check_station_options, declare
from ..packing import ANY_ANGLE
from .conclude import Report, conclude, plan_of
from .context import MARGIN, Context, Model, State
from .finger_room import with_room
from .model import build, canonical, release_bound
from .proven import kit_cap, known_bound, scaled_kit_bounds, scaled_lower, strong_bound
from .scaling import Scaled, scale_times, scaled_makespan, scaled_objective
from .station_run import station_baselines, station_hand_off
from .tray import embed_scope, tray_mode
from .warm import MIN_RUN, best_heuristic_plan, closed_bound

if TYPE_CHECKING:
    from .live import Live as LiveProgress

TrayMode = Literal["auto", "embedded", "benders"]
TRAY_MODES: tuple[str, ...] = ("auto", "embedded", "benders")
#: The share of the time limit kept back from CP-SAT (with :data:`.context.MARGIN`).
KEEP_BACK = 0.01
#: CP-SAT overruns its own limit on large models (presolve): 5.5 s at 247,000 variables.
OVERRUN_S_PER_CELL = 25e-6


def _positive(owner: object, *names: str) -> None:
    for name in names:
        value = getattr(owner, name)
        if not value > 0:
            raise ValueError(f"option {name!r}: must be > 0, got {value!r}")


@dataclass(frozen=True)
class ScheduleOptions:
    """The CP-SAT model's options (the Python :func:`solve` takes these as keywords)."""

    workers: int = option(2, "CP-SAT worker threads", min=1)
    tray: TrayMode = option(  # noqa: RUF009 (a field with a str default)
        "auto", "tray packing: embedded in the model, by Benders cuts, or auto"
    )
    objective: str = objective_field()
    time_resolution: float = option(
        0.1, "time grid in s (>= 0.001), refined when times are not exact", min=0.001, max=1e4
    )
    refine_times: bool = option(True, "refine the time grid until every time is exact")
    pack_resolution: float = option(  # the instances' length range (docs/formats.md#ranges)
        1.0,
        "packing grid in mm (>= 0.01); part sizes are rounded up",
        min=MIN_LENGTH,
        max=MAX_LENGTH,
    )
    log: bool = option(False, "print CP-SAT's search log")
    fallback: Fallback = fallback_field()  # noqa: RUF009 (a field() with a str default)
    search: float = search_field()

    def __post_init__(self) -> None:
        _positive(self, "time_resolution", "pack_resolution")


@dataclass(frozen=True)
class CpsatOptions(ScheduleOptions):
    """Options of the registered method ``cpsat``."""

    hint: str = hint_field()
    finger_room: bool = finger_room_field()

    def __post_init__(self) -> None:
        super().__post_init__()
        check_hint(self.hint, ("auto", "none"))


#: What the model does with each option on several stations (docs/formulations.md, "Options
#: with several stations"): every option is honoured (:func:`declare` checks each is declared).
STATION_OPTIONS = declare(CpsatOptions, {f.name: HONOURED for f in fields(CpsatOptions)})


# ---------------------------------------------------------------------------------------------
# The registered method and the warm start
# ---------------------------------------------------------------------------------------------


def cpsat(
    instance: Instance,
    options: CpsatOptions,
    *,
    seed: int = 0,
    time_limit: float | None = None,
) -> MethodOutput:
    """Registered method ``cpsat``: :func:`run` warm-started from the plan of ``options.hint``
    (module docstring). Several assembly stations are the same run on the same model (its
    station part: :mod:`.station_model`), every option honoured (:data:`STATION_OPTIONS`)."""
    check_station_options(instance, "cpsat", options, STATION_OPTIONS)
    if options.finger_room:  # the grasp footprints packed (docs/execution.md#finger-room)
        return with_room(cpsat, instance, options, seed=seed, time_limit=time_limit)
    if not instance.stations and get_objective(options.objective).makespan_with_one_station:
        options = replace(options, objective="makespan")  # e.g. sum_completion, as milp
    instance = instance.as_one_station()  # one declared station: the S = 1 model
    one = not instance.stations
    objective = get_objective(options.objective)
    budget = Budget(time_limit)
    plan: Plan | None = None
    source = None
    hint_tl = HINT_SHARE * budget.time_limit
    live = progress.tracker(options.objective)
    live.report(bound=closed_bound(instance, objective), stage="warm start")
    kw: dict[str, Any] = {"seed": seed, "time_limit": hint_tl, "objective": options.objective}
    johnson: Johnson | None = None
    if objective.is_makespan and one:  # the closed-form check, its plan kept for the incumbent
        packer = Packer(instance, min(0.2, pack_time_limit(budget)), budget.head(0.05))
        johnson = johnson_plan(instance, packer)
    if johnson is not None and johnson.optimal:
        pass  # the run proves the Johnson-order plan optimal at once: no warm start needed
    elif options.hint == "auto":
        plan, source = best_heuristic_plan(instance, **kw)
    elif options.hint != "none":
        require_stations_support(instance, options.hint)  # one line, exit 2
        plan, source = best_heuristic_plan(instance, (options.hint,), **kw)
        if source is None:
            raise UsageError(f"cpsat: hint method {options.hint!r} gave no plan")
    if plan is not None and live.active:
        live.report(incumbent=objective.value(evaluate(instance, plan)))
    rest = max(MIN_RUN, budget.remaining())
    out = run(instance, options, seed=seed, time_limit=rest, hint=plan, johnson=johnson)
    out.extra["hint_method"] = source if out.extra["hint_used"] else None  # (its plan is the start)
    out.extra["hint_time_s"] = budget.elapsed() - out.extra.get("wall_time_s", 0.0)
    out.extra["wall_time_s"] = budget.elapsed()
    return out


def solve(
    instance: Instance,
    *,
    seed: int = 0,
    time_limit: float | None = 60.0,
    workers: int = 2,
    tray: str = "auto",
    objective: str = "makespan",
    time_resolution: float = 0.1,
    refine_times: bool = True,
    pack_resolution: float = 1.0,
    hint: Plan | None = None,
    log: bool = False,
    cpsat_params: dict[str, Any] | None = None,
    releases: Mapping[str, float] | None = None,
    fallback: str = "lns",
    search: float = SEARCH_DEFAULT,
    deterministic: bool = False,
) -> MethodOutput:
    """The Python entry: :func:`run` with the options as keywords (validated like the
    method's), ``hint`` a plan to start from, ``cpsat_params`` extra CP-SAT parameters,
    ``releases`` the release times and ``deterministic`` (module docstring, "Time")."""
    return keyword_run(run, ScheduleOptions, locals(), "cpsat")


# ---------------------------------------------------------------------------------------------
# One run
# ---------------------------------------------------------------------------------------------


def run(
    instance: Instance,
    options: ScheduleOptions,
    *,
    seed: int = 0,
    time_limit: float | None = 60.0,
    hint: Plan | None = None,
    cpsat_params: dict[str, Any] | None = None,
    releases: Mapping[str, float] | None = None,
    deterministic: bool = False,
    johnson: Johnson | None = None,
) -> MethodOutput:
    """Minimise makespan (or human idle) over all segmentations and orders (module
    docstring); ``time_limit`` (None: 60 s) covers everything, packing included. Several
    stations: :mod:`.station_model` and :mod:`.station_run`, without release times.
    ``johnson``: the Johnson-order plan :func:`cpsat` computed in its closed-form check (None:
    the run computes it), a candidate incumbent."""
    instance = instance.as_one_station()  # one declared station: the S = 1 model
    if instance.stations and releases:
        raise UsageError(
            f"{instance.source}: cpsat models release times with one assembly station only "
            "(docs/timeline.md#several-stations)"
        )
    stretch = packing_oracle.SAFETY_NET if deterministic else 1.0
    budget = Budget(time_limit, keep_back=KEEP_BACK, stretch=stretch)
    try:
        sc = scale_times(instance, options.time_resolution, options.refine_times, releases)
    except ValueError as exc:
        raise UsageError(f"cpsat: {exc}") from None
    pack_tl = pack_time_limit(budget)
    packer = Packer(
        instance, pack_tl, budget.cut(MARGIN), options.pack_resolution, deterministic=deterministic
    )
    report = Report(
        budget,
        {
            "time_resolution": sc.res,
            "times_exact": sc.exact,
            "objective": options.objective,
            keys.MASTER_SOLVES: 0,
            "cuts": 0,
            "hint_used": False,
            "hint_method": None,
        },
    )
    backend = _Cpsat(instance, options, sc, packer, report, hint, seed, cpsat_params, johnson)
    return drive(backend, options.fallback, options.search, bool(releases))


class _Cpsat:
    """The CP-SAT backend of the exact driver (:mod:`..exact.driver`): the incumbent is a
    :class:`.context.State` of kits of task indices on the scaled grid."""

    spec = CPSAT_NO_MODEL
    margin = MARGIN

    def __init__(
        self,
        instance: Instance,
        options: ScheduleOptions,
        sc: Scaled,
        packer: Packer,
        report: Report,
        hint: Plan | None,
        seed: int,
        cpsat_params: dict[str, Any] | None,
        johnson: Johnson | None = None,
    ) -> None:
        self.instance, self.options, self.sc, self.packer = instance, options, sc, packer
        self.report, self.hint, self.seed, self.cpsat_params = report, hint, seed, cpsat_params
        self.johnson = johnson  # the closed-form check's plan, when cpsat computed it
        self.budget = report.budget
        self.extra = report.extra
        self.K = 1
        self.mode = "benders"
        self.live: LiveProgress | None = None
        self.ctx: Context

    def finish(self, plan: Plan | None, status: Status, bound: float | None) -> MethodOutput:
        return self.report.finish(plan, status, bound)

    def known_bound(self) -> float:
        return known_bound(self.ctx)

    def start(self) -> State | None:
        """The incumbent (:func:`_incumbent`), the proven bound, the kit cap and tray mode."""
        instance, options, extra = self.instance, self.options, self.extra
        ctx = self.ctx = _context(instance, self.sc, options, self.packer, self.budget, extra)
        incumbent = _incumbent(ctx, self.hint, pack_time_limit(self.budget), extra, self.johnson)
        self.live = _start_live(ctx, incumbent)
        upper = None
        if incumbent is not None and ctx.minimised.is_makespan:
            upper = scaled_makespan(self.sc, incumbent)  # C <= U and the kit cap need makespan
        start = None if incumbent is None else evaluate(instance, plan_of(ctx, incumbent, None))
        self.start_ms = None if start is None else start.makespan
        strong_bound(ctx, self.start_ms, extra)
        self.K = max(kit_cap(ctx, upper), len(incumbent) if incumbent is not None else 1)
        self.mode = tray_mode(instance, options.tray, self.K, ctx.embed_scope)
        extra.update(
            tray_mode=self.mode,
            max_kits=self.K,
            upper_start=None if start is None else ctx.minimised.value(start),
        )
        return None if incumbent is None else State(incumbent, upper)

    def shortcut(self, state: State | None) -> MethodOutput | None:
        if state is None or self.start_ms is None:
            return None
        return _proven_without_model(self.ctx, state, self.report, self.start_ms)

    def cells(self) -> int:
        """The task x kit cells; with stations also the station x kit cells and the position
        pairs of the stations with two trays or more (:mod:`.station_model`)."""
        K, sc = self.K, self.sc
        pairs = sum(K * (K - 1) // 2 for t in sc.st_trays if t is not None and t >= 2)
        return assignment_cells(self.instance, K) + len(sc.st_d) * K + pairs

    def hand_off(self, state: State, limit: HandOff = WHOLE) -> State:
        """``state``, or the better plan the LNS finds from it in the time left (makespan
        objective without release times, which the LNS does not model; with stations, every
        objective: :func:`.station_run.station_hand_off`; not in a reproducible run,
        ``deterministic``, whose result must not depend on the clock)."""
        ctx = self.ctx
        assert state.kits is not None
        self.extra["improved_by"] = None
        if ctx.budget.stretch != 1.0:  # deterministic (budget.py): the LNS's start is clock-bound
            return state
        plan = plan_of(ctx, state.kits, None, ctx.packer)
        if ctx.instance.stations:
            found = station_hand_off(ctx, plan, self.seed, self.extra, limit.within(ctx.left()))
            if found is None:
                return state
            kits, layouts = found
            return State(kits, scaled_objective(ctx.sc, kits, ctx.objective), layouts=layouts)
        if not ctx.minimised.is_makespan or any(ctx.sc.rel):
            return state
        bound, within = known_bound(ctx), limit.within(ctx.left())
        better = improve(
            ctx.instance, plan, bound=bound, seed=self.seed, limit=within, extra=self.extra
        )
        if better is None:
            return state
        return self.adopt(better)

    @property
    def is_makespan(self) -> bool:
        return self.ctx.minimised.is_makespan

    def plan(self, state: State) -> Plan:
        assert state.kits is not None
        return plan_of(self.ctx, state.kits, None)

    def adopt(self, plan: Plan) -> State:
        """A better plan as the incumbent, its layouts taught to the packer: the model's final
        plan is laid out again by the packer (:func:`.conclude.plan_of`), which must not lose
        a kit the LNS laid out (at any angle, or when a packing call times out)."""
        idx = self.instance.index
        for kit in plan.kits:
            if kit.layout:
                self.packer.learn(self.instance.kit_parts(kit.tasks), kit.layout)
        kits = [[idx[t] for t in k.tasks] for k in plan.kits if k.tasks]
        layouts = [k.layout for k in plan.kits if k.tasks]
        return State(kits, scaled_makespan(self.sc, kits), layouts=layouts)

    def raise_bound(self, value: float, source: str) -> None:
        from ..relax import raised

        self.ctx.proven = raised(self.ctx.proven, value, source, self.instance)

    def conclude(self, state: State) -> MethodOutput:
        return conclude(self.ctx, None, state, self.report)

    def solve(self, state: State | None) -> MethodOutput:
        incumbent = None if state is None else state.kits
        upper = None if state is None else state.obj
        budget = self.ctx.budget
        try:
            return _solve_model(self, upper, incumbent)
        finally:  # (the model's budget ends earlier: its overrun, the LNS after it)
            self.ctx.budget = budget


def _context(
    instance: Instance,
    sc: Scaled,
    options: ScheduleOptions,
    packer: Packer,
    budget: Budget,
    extra: dict[str, Any],
) -> Context:
    """The run's context, with the interchangeable chains (symmetry breaking)."""
    n = instance.n_tasks
    sig: list[Any] = [(sc.r[i], sc.h[i], tuple(sorted(instance.tasks[i].parts))) for i in range(n)]
    if sc.station:  # chains are interchangeable on one station only
        sig = [(*sig[i], sc.station[i]) for i in range(n)]
    groups = chain_groups_idx(n, _edges(instance), sig)
    extra["symmetric_chains"] = sum(len(g) for g in groups)
    ctx = Context(instance, sc, options.objective, groups, packer, budget, options.pack_resolution)
    ctx.embed_scope = embed_scope(instance, packer)
    return ctx


def _start_live(ctx: Context, incumbent: list[list[int]] | None) -> LiveProgress | None:
    """The live progress when somebody listens (then also ``ctx.live``), with the closed-form
    bound and the incumbent reported."""
    tracker = progress.tracker(ctx.objective)
    if not tracker.active:
        return None
    from .live import Live

    ctx.live = live = Live(ctx, tracker)
    tracker.report(bound=closed_bound(ctx.instance, ctx.minimised), stage="CP-SAT")
    if incumbent is not None:
        tracker.report(incumbent=live.real(incumbent))
    return live


def _proven_without_model(
    ctx: Context, start: State, report: Report, start_ms: float
) -> MethodOutput | None:
    """The result when the incumbent ``start`` attains a closed-form bound or the release bound
    (then it is optimal and no model is built); None otherwise."""
    instance, sc, extra = ctx.instance, ctx.sc, report.extra
    incumbent, upper = start.kits, start.obj
    closed_done = start_ms <= best_bound(instance) + 1e-9 and not any(sc.rel)
    if ctx.minimised.is_makespan and closed_done:
        # the incumbent attains a closed-form bound (e.g. Johnson's makespan): optimal
        # without a model (bilevel_kit/bounds.py, (d))
        keys.no_solve(extra, keys.CLOSED_FORM_BOUND)
        return conclude(ctx, None, State(incumbent, upper, proven=True), report)
    if ctx.proven is not None and start_ms <= ctx.proven.value + 1e-9:
        # the incumbent attains the proven bound of models.relax: optimal without a model
        keys.no_solve(extra, keys.PROVEN_BOUND)
        return conclude(ctx, None, State(incumbent, upper, proven=True), report)
    if upper is not None and sc.rel and upper <= release_bound(instance, sc):
        # the incumbent attains the release bound (:func:`.model.release_bound`): optimal
        keys.no_solve(extra, keys.RELEASE_BOUND)
        state = State(incumbent, upper, upper, proven=True, lower_any=upper)
        return conclude(ctx, None, state, report)
    return None


def _solve_model(run: _Cpsat, upper: int | None, incumbent: list[list[int]] | None) -> MethodOutput:
    """Build the model with K kits (C <= ``upper``), configure CP-SAT and search (embedded or
    Benders) from the incumbent; the result."""
    from ortools.sat.python import cp_model

    ctx, options, mode, live, report = run.ctx, run.options, run.mode, run.live, run.report
    instance, extra, budget = ctx.instance, report.extra, ctx.budget
    mdl = build(
        instance,
        ctx.sc,
        K=run.K,
        upper=upper,
        embedded=mode == "embedded",
        objective=options.objective,
        pack_res=options.pack_resolution,
        groups=ctx.groups,
        kit_bounds=scaled_kit_bounds(ctx),
        lower=scaled_lower(ctx),
    )
    extra["build_time_s"] = budget.elapsed()
    ctx.budget = budget.cut(extra["model_cells"] * OVERRUN_S_PER_CELL)  # CP-SAT's overrun
    solver = cp_model.CpSolver()
    solver.parameters.num_workers = max(1, options.workers)
    solver.parameters.random_seed = run.seed
    solver.parameters.log_search_progress = options.log
    for key, value in (run.cpsat_params or {}).items():
        setattr(solver.parameters, key, value)
    if live is not None:
        live.mdl = mdl
        ctx.callback = live.attach(solver, solutions_are_plans=mode == "embedded")
        live.bound_valid = mode != "embedded" or ctx.embed_scope == ANY_ANGLE
    state = _search(ctx, mdl, solver, mode, incumbent)
    extra.update(state.info)
    keys.solved(extra, keys.status_word(state.status_name), state.status_name)
    extra["cuts"] = mdl.n_cuts
    if state.kits is None:
        return without_plan(run, state.infeasible, state.scope)
    return conclude(ctx, mdl, state, report)


def _edges(instance: Instance) -> list[tuple[int, int]]:
    idx = instance.index
    return [(idx[a], idx[b]) for a, b in reduced_edges(instance)]


def _search(
    ctx: Context, mdl: Model, solver: Any, mode: str, incumbent: list[list[int]] | None
) -> State:
    """The embedded solve or the Benders loop."""
    if mode == "embedded":
        from .embedded import run_embedded

        for key, value in packing.SAFE_NO_OVERLAP_2D.items():
            setattr(solver.parameters, key, value)
        return run_embedded(ctx, mdl, solver, incumbent)
    from .benders import run_benders

    return run_benders(ctx, mdl, solver, incumbent)


def _incumbent(
    ctx: Context,
    hint: Plan | None,
    pack_tl: float,
    extra: dict[str, Any],
    johnson: Johnson | None = None,
) -> list[list[int]] | None:
    """The best of the hint (if its kits fit), the topological order's quick plan and the
    Johnson order's (``johnson``: computed already, by :func:`cpsat`'s closed-form check), in
    canonical chain order; ties go to the hint, then the topological order's plan."""
    instance, packer = ctx.instance, ctx.packer
    ids = ctx.ids
    idx = instance.index
    candidates: list[list[list[int]]] = []
    hk = None
    if hint is not None and sorted(hint.task_order) == sorted(ids):
        from ...validate import check

        if not check(instance, hint):  # its layouts are valid: its kits fit, at any angle
            for kit in hint.kits:
                packer.learn(instance.kit_parts(kit.tasks), kit.layout)
        kits = [[idx[t] for t in k.tasks] for k in hint.kits if k.tasks]
        if all(packer.fits([ids[i] for i in kit]) for kit in kits):
            candidates.append(kits)
            hk = kits
    if ctx.sc.station:  # several stations: the baselines (a quick plan would mix stations)
        candidates += station_baselines(instance)
    elif ctx.minimised.is_makespan and not any(ctx.sc.rel):  # (releases: not a bound of them)
        if johnson is None:
            johnson = johnson_plan(instance, packer.sub(min(0.2, pack_tl), ctx.budget.head(0.05)))
        if johnson.optimal:  # optimal by the closed-form bound: the run ends at once
            assert johnson.kits is not None
            return canonical([[idx[t] for t in k] for k in johnson.kits], ctx.groups)
    if not ctx.sc.station:
        # the next 10 % of what is left (the hint's check can spend the first 10 % on large plans)
        qp = quick_plan(instance, packer.sub(min(0.2, pack_tl), ctx.budget.next(0.1)))
        if qp is not None:
            candidates.append([[idx[t] for t in k] for k in qp])
        if johnson is not None and johnson.kits is not None:
            candidates.append([[idx[t] for t in k] for k in johnson.kits])
    if not candidates:
        return None
    best = min(candidates, key=lambda ks: scaled_objective(ctx.sc, ks, ctx.objective))
    extra["hint_used"] = best is hk  # the hint's plan is the incumbent (ties: the hint)
    return canonical(best, ctx.groups)
