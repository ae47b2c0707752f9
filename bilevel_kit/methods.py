"""The method registry and the one result contract every solver returns.

A method is a function ``fn(instance, options, *, seed, time_limit) -> MethodOutput`` whose
``options`` is an instance of the method's own frozen options dataclass. Both are registered
here by name and import path, so the CLI looks methods up without importing heavy back-ends
(OR-Tools, Pyomo ...) until one is used, and a new method is one :func:`register` call (from
this package, a test, or a plugin: docs/extending.md).
:func:`solve` validates the loose ``key=value`` options centrally
(:func:`bilevel_kit.options.parse_options`): an unknown key or a bad value is a
:class:`~bilevel_kit.errors.UsageError` naming the method and the key.

:func:`solve` wraps a method call: it times it, evaluates the plan with the one timeline
evaluator, attaches the closed-form lower bound, computes the gap and (optionally) runs the
independent checker.
"""

from __future__ import annotations

import contextlib
import enum
import math
import time
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field, replace
from typing import Any

from .errors import PluginError, UsageError, one_line
from .instance import Instance
from .interrupt import checkpoint
from .objectives import (
    MODEL_OBJECTIVES,
    OBJECTIVES,
    is_top_level,
    model_objectives,
    relative_gap,
)
from .options import Registered, import_target
from .plan import Plan, Timeline, evaluate
from .progress import Sink, reporting
from .registry import Registry
from .validate import timeline_params


class Status(enum.StrEnum):
    """What a solve proved about its plan (with respect to the method's objective)."""

    OPTIMAL = "optimal"
    FEASIBLE = "feasible"
    INFEASIBLE = "infeasible"
    UNKNOWN = "unknown"


STATUSES = tuple(s.value for s in Status)

#: Where a method states the value, bound and gap of the objective it minimised, when that is
#: not the makespan, in its output's ``extra`` (the one scheme; solution files of format 1 used
#: the registry's keys, :attr:`bilevel_kit.objectives.Objective.value_keys`).
OBJECTIVE_KEYS = ("objective_value", "objective_bound", "objective_gap")


@dataclass(frozen=True)
class MethodOutput:
    """What a method function returns; :func:`solve` turns it into a :class:`Result`.

    ``bound`` is a proven lower bound on the makespan in seconds (or ``None``); ``extra`` holds
    the method's own diagnostics, each key documented in the method's module docstring.
    ``status_objective`` names the objective ``status`` speaks of: ``makespan`` unless the
    method optimised another one (``human_idle``, or bilevel-milp's paper objective ``J``), in
    which case "optimal" does not mean a zero makespan gap, and ``extra`` states that
    objective's value, bound and gap under :data:`OBJECTIVE_KEYS` (:func:`solve` makes them
    the result's ``objective``, ``bound`` and ``gap``).
    """

    plan: Plan | None
    status: Status
    bound: float | None = None
    extra: dict[str, Any] = field(default_factory=dict)
    status_objective: str = "makespan"

    def __post_init__(self) -> None:
        try:
            object.__setattr__(self, "status", Status(self.status))
        except ValueError:
            raise ValueError(f"unknown status {self.status!r}") from None


@dataclass
class Result:
    """A solve: status, the optimised objective's value, bound and gap, wall time, seed and
    parameters.

    ``objective``, ``bound`` and ``gap`` are about the objective the method minimised,
    ``objective_name`` (a name of :data:`bilevel_kit.objectives.OBJECTIVES`, the one ``status``
    refers to): ``gap`` is that objective's gap of the two (``(objective - bound) / objective``
    for the makespan). The makespan is one metric among the others (``metrics["makespan"]``,
    :attr:`makespan`), with its own ``makespan_bound`` (the method's, or the closed-form bounds
    of :mod:`bilevel_kit.bounds`) and ``makespan_gap``; with the default objective the two
    sets of numbers are the same (docs/formats.md#solutions).
    """

    method: str
    status: Status
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
    #: The objective minimised: ``objective``, ``bound``, ``gap`` and ``status`` are about it.
    objective_name: str = "makespan"
    #: Delivery time, kit overheads and trays the timeline was computed with.
    timeline_params: dict[str, Any] = field(default_factory=dict)
    #: A lower bound on the makespan over every plan (s), and the makespan's gap to it; the
    #: same as ``bound`` and ``gap`` when the objective is the makespan (left None there).
    makespan_bound: float | None = None
    makespan_gap: float | None = None

    def __post_init__(self) -> None:
        if is_top_level(self.objective_name) and self.makespan_bound is None:
            self.makespan_bound = self.bound
        if is_top_level(self.objective_name) and self.makespan_gap is None:
            self.makespan_gap = self.gap

    @property
    def status_objective(self) -> str:
        """The objective ``status`` refers to: :attr:`objective_name`."""
        return self.objective_name

    @property
    def makespan(self) -> float | None:
        """The plan's makespan (s), whichever objective was minimised."""
        return self.timeline.makespan if self.timeline is not None else None

    @property
    def status_text(self) -> str:
        """``status``, with the objective it refers to when that is not the makespan."""
        if is_top_level(self.objective_name):
            return str(self.status)
        return f"{self.status} (for {self.objective_name})"

    @property
    def metrics(self) -> dict[str, float | int] | None:
        return self.timeline.metrics() if self.timeline is not None else None


@dataclass(frozen=True)
class MethodSpec(Registered):
    """A registered method (see :class:`~bilevel_kit.options.Registered`).

    ``prepare``: the import path of a function run once before the method's clock starts
    (:func:`solve`), e.g. a compile that must not be charged to the time limit; it takes an
    optional ``notify`` callable and returns the seconds it spent (None: nothing to do).
    ``in_default``: whether ``compare``'s default set of methods (``--methods default``, the
    README's main job) includes it; ``--methods all`` runs every method.
    ``supports_stations``: it plans for several assembly stations
    (docs/timeline.md#several-stations); :func:`solve` refuses an instance with stations
    otherwise.
    ``objectives``: the objectives of :mod:`bilevel_kit.objectives` it minimises, its default
    first; an ``objective`` option is held to them (docs/extending.md#adding-a-method).
    ``modelled_objectives``: it also minimises every other modelled objective of the registry
    by the objective's model expression (``cpsat``, ``milp``), a plugin's too
    (:meth:`objective_names`)."""

    options: str  # every method declares its options class
    prepare: str | None = None
    in_default: bool = True
    supports_stations: bool = False
    objectives: tuple[str, ...] = ("makespan",)
    modelled_objectives: bool = False

    def objective_names(self) -> tuple[str, ...]:
        """The objectives it minimises: the declared ones, its default first, then (with
        ``modelled_objectives``) the registry's other modelled ones, read now so that the
        plugins' are among them."""
        if not self.modelled_objectives:
            return self.objectives
        more = tuple(o for o in model_objectives() if o not in self.objectives)
        return self.objectives + more

    def parse(self, params: Mapping[str, Any]) -> Any:
        """The options, validated (:meth:`~bilevel_kit.options.Registered.parse`), with an
        ``objective`` option among :meth:`objective_names`."""
        options = super().parse(params)
        chosen = getattr(options, "objective", None)
        names = self.objective_names()
        if isinstance(chosen, str) and chosen not in names:
            raise UsageError(
                f"method {self.name!r}: option 'objective': must be one of "
                f"{', '.join(repr(o) for o in names)}, got {chosen!r}"
            )
        return options

    def load(self) -> Callable[..., MethodOutput]:
        """The method's function; a plugin's is guarded (:func:`_plugin_call`)."""
        plugin = REGISTRY.plugin_of(self.name)
        if plugin is None:
            fn: Callable[..., MethodOutput] = import_target(self.target)
            return fn
        return _plugin_call(plugin, self.name, _plugin_import(plugin, self.name, self.target))

    def options_class(self) -> type:
        plugin = REGISTRY.plugin_of(self.name)
        if plugin is None or not self.options:
            return super().options_class()
        cls: type = _plugin_import(plugin, self.name, self.options)
        return cls

    def run_prepare(self, notify: Callable[[str], None] | None = None) -> float | None:
        """The method's ``prepare`` step (seconds spent, None when it has none)."""
        if self.prepare is None:
            return None
        plugin = REGISTRY.plugin_of(self.name)
        if plugin is None:
            seconds: float | None = import_target(self.prepare)(notify)
            return seconds
        step = _plugin_import(plugin, self.name, self.prepare)
        try:
            return step(notify)
        except (KeyboardInterrupt, UsageError):
            raise
        except BaseException as exc:  # a plugin's failure is one line naming it
            what = f"prepare step failed: {_named(exc)}"
            raise _plugin_failure(plugin, self.name, what) from None


def _plugin_failure(plugin: str, method: str, what: str) -> PluginError:
    return PluginError(one_line(f"plugin {plugin!r}: method {method!r} {what}"))


def _named(exc: BaseException) -> str:
    """``Type: message`` of a plugin's exception (its type alone when it has no message)."""
    return f"{type(exc).__name__}: {exc}" if str(exc) else type(exc).__name__


def _plugin_import(plugin: str, method: str, target: str) -> Any:
    """A plugin's ``module:name``, any failure to import it a :class:`PluginError`."""
    try:
        return import_target(target)
    except Exception as exc:
        raise _plugin_failure(plugin, method, f"cannot import {target}: {exc}") from None


def _plugin_call(plugin: str, method: str, fn: Any) -> Callable[..., MethodOutput]:
    """``fn`` whose failure is one line naming the plugin (exit 1, docs/extending.md#plugins):
    an exception (not an interrupt, nor this package's own errors, which say what is wrong
    with the input), a ``SystemExit``, or a result that is no :class:`MethodOutput`."""

    def call(*args: Any, **kwargs: Any) -> MethodOutput:
        from .errors import BilevelKitError

        try:
            out = fn(*args, **kwargs)
        except (KeyboardInterrupt, BilevelKitError):
            raise
        except BaseException as exc:
            raise _plugin_failure(plugin, method, f"failed: {_named(exc)}") from None
        if not isinstance(out, MethodOutput):
            got = type(out).__name__
            raise _plugin_failure(plugin, method, f"returned {got}, not a MethodOutput")
        return out

    return call


#: Every method, built-in and from plugins (:mod:`bilevel_kit.registry`), by name.
REGISTRY: Registry[MethodSpec] = Registry("method")

#: The ``prepare`` step of every method that may run greedy-ce's compiled kernels (its own
#: or another method's warm start): compiled before the clock (docs/scaling.md#first-run).
COMPILE_KERNELS = "bilevel_kit.heuristics.warmup:compile_kernels"


def register(
    name: str,
    target: str,
    summary: str,
    options: str,
    *,
    prepare: str | None = None,
    in_default: bool = True,
    supports_stations: bool = False,
    objectives: tuple[str, ...] = ("makespan",),
    modelled_objectives: bool = False,
) -> None:
    """Add a method by import paths (``"module:function"``, ``"module:OptionsClass"``), so
    registering imports nothing; a name already registered, or an objective the registry
    (:mod:`bilevel_kit.objectives`) does not know, is a :class:`UsageError`. ``prepare``,
    ``in_default``, ``supports_stations``, ``objectives`` and ``modelled_objectives``: see
    :class:`MethodSpec`. A plugin registers its own objectives first
    (:func:`bilevel_kit.objectives.register`)."""
    unknown = [o for o in objectives if o not in OBJECTIVES]
    if unknown or not objectives:
        raise UsageError(
            f"method {name!r}: objectives must name registered ones "
            f"({', '.join(OBJECTIVES)}), got {', '.join(objectives) or 'none'}"
        )
    spec = MethodSpec(
        name,
        target,
        summary,
        options,
        prepare,
        in_default,
        supports_stations,
        tuple(objectives),
        modelled_objectives,
    )
    REGISTRY.add(spec)


def station_methods() -> frozenset[str]:
    """The registered methods (plugins' too) whose spec declares ``supports_stations``."""
    return frozenset(n for n, spec in REGISTRY.items() if spec.supports_stations)


def require_stations_support(instance: Instance, method: str) -> None:
    """Refuse (exit 2) a method whose spec does not declare ``supports_stations`` on an
    instance that has stations (its times would use the instance's ``d``, ``o_H``, trays)."""
    if instance.stations and not get_method(method).supports_stations:
        raise UsageError(
            f"{instance.source}: method {method!r} does not model several assembly stations "
            f"yet; use one of {', '.join(sorted(station_methods()))} (docs/timeline.md)"
        )


def method_names() -> list[str]:
    return list(REGISTRY)


def default_method_names() -> list[str]:
    """The methods ``--methods default`` runs: every one not registered ``in_default=False``."""
    return [name for name in REGISTRY if REGISTRY[name].in_default]


def time_limit_reached(out: MethodOutput, wall: float, time_limit: float | None) -> bool:
    """Whether a run stopped at its time limit rather than on its own: the method's own word
    (``extra["time_limit_hit"]``) where it gives one, else a run that proved nothing and used
    at least 90 % of the limit (the exact methods keep a margin back for their last steps:
    cpsat on 600 tasks at 10 s ended at 9.4 s). Every output shows it (docs/cli.md)."""
    if "time_limit_hit" in out.extra:
        return bool(out.extra["time_limit_hit"])
    if time_limit is None or out.status in (Status.OPTIMAL, Status.INFEASIBLE):
        return False
    return wall >= 0.9 * time_limit


def get_method(name: str) -> MethodSpec:
    if name not in REGISTRY:
        raise UsageError(f"unknown method {name!r}; choose from {', '.join(method_names())}")
    return REGISTRY[name]


def check_seed(seed: Any) -> int:
    """Seeds are integers >= 0 (numpy's ``default_rng`` and CP-SAT refuse the rest)."""
    if isinstance(seed, bool) or not isinstance(seed, int) or seed < 0:
        raise UsageError(f"seed must be an integer >= 0, got {seed!r}")
    return seed


#: The longest time limit (about 11.6 days): the solvers' and the operating system's waits
#: take milliseconds in a C int (24.8 days at most), and no run of this toolkit is longer.
MAX_TIME_LIMIT = 1e6


def check_time_limit(time_limit: Any) -> float | None:
    """A time limit is ``None`` (the method's default) or seconds in (0, MAX_TIME_LIMIT]."""
    if time_limit is None:
        return None
    if (
        isinstance(time_limit, bool)
        or not isinstance(time_limit, int | float)
        or not math.isfinite(time_limit)
        or not 0 < time_limit <= MAX_TIME_LIMIT
    ):
        raise UsageError(
            f"time limit must be seconds > 0 and <= {MAX_TIME_LIMIT:g}, got {time_limit!r}"
        )
    return float(time_limit)


def gap(objective: float | None, bound: float | None) -> float | None:
    """Relative optimality gap (objective - bound) / objective, 0 when proven optimal: the
    one formula, :func:`bilevel_kit.objectives.relative_gap`."""
    return relative_gap(objective, bound)


def above_bound(objective: float | None, bound: float | None) -> float | None:
    """How far ``objective`` lies above ``bound``, (objective - bound) / bound: the distance
    above the optimum when ``bound`` is the proven optimum, and an upper bound on it otherwise
    (the optimum lies between the two). The lead figure of ``compare``'s table and chart
    (docs/timeline.md#terms)."""
    if objective is None or bound is None or bound <= 0:
        return None
    return max(0.0, (objective - bound) / bound)


def fold_kitless_output(instance: Instance, out: MethodOutput) -> MethodOutput:
    """``out`` with its kits of part-less tasks merged into neighbouring kits
    (:func:`bilevel_kit.plan.fold_kitless`, docs/timeline.md#part-less-tasks), for every
    method alike. Restricting the plans only raises an optimum, so every bound still holds;
    the status objective's value and gap in ``extra`` are recomputed on the folded plan, and
    "optimal" stays only when the folded plan is no worse (on one station it never is).
    ``extra["kitless_folded"]``: the number of kits merged away."""
    from .plan import fold_kitless

    if out.plan is None or (folded := fold_kitless(instance, out.plan)) is out.plan:
        return out
    extra = {**out.extra, "kitless_folded": len(out.plan.kits) - len(folded.kits)}
    obj = OBJECTIVES.get(out.status_objective)
    before = obj.value(evaluate(instance, out.plan)) if obj is not None else None
    after = obj.value(evaluate(instance, folded)) if obj is not None else None
    status = out.status
    if status == Status.OPTIMAL and (before is None or after is None or after > before + 1e-9):
        status = Status.FEASIBLE
    value_key, bound_key, gap_key = OBJECTIVE_KEYS
    if obj is not None and not obj.top_level and after is not None:
        if value_key in extra:
            extra[value_key] = after
        if gap_key in extra and extra.get(bound_key) is not None:
            extra[gap_key] = obj.gap(after, extra[bound_key])
    return MethodOutput(folded, status, out.bound, extra, status_objective=out.status_objective)


def solve(
    instance: Instance,
    method: str,
    *,
    seed: int = 0,
    time_limit: float | None = None,
    check: bool = False,
    progress: Sink | None = None,
    **params: Any,
) -> Result:
    """Run a registered method and return the honest :class:`Result`.

    With ``check=True`` the independent checker runs on the plan and on the result's claims
    (status, bound and gap against the makespan), and its violations are stored in
    ``result.extra["violations"]`` (an empty list means valid). ``progress``: a sink that
    receives the live incumbent, bound and gap of the exact methods (:mod:`.progress`); it
    changes nothing in the result.
    """
    from .bounds import best_bound, makespan_grid, on_grid
    from .reachability import ensure_kit_placeable

    spec = get_method(method)
    require_stations_support(instance, method)
    check_seed(seed)
    check_time_limit(time_limit)
    options = spec.parse(params)
    fn = spec.load()
    ensure_kit_placeable(instance)  # an empty reach map is a clear error, not "no kit fits"
    prepare_s = spec.run_prepare()  # e.g. a compile: never charged to the time limit
    checkpoint()  # a signal whose interrupt the prepare step lost: no run (docs/cli.md)
    t0 = time.perf_counter()
    with contextlib.nullcontext() if progress is None else reporting(progress):  # one
        # declared station is the S = 1 case (docs/timeline.md#several-stations)
        out = fn(instance.as_one_station(), options, seed=seed, time_limit=time_limit)
    wall = time.perf_counter() - t0
    out = fold_kitless_output(instance, out)
    timeline = evaluate(instance, out.plan) if out.plan is not None else None
    makespan = timeline.makespan if timeline is not None else None
    bounds = [b for b in (out.bound, best_bound(instance)) if b is not None]
    grid = makespan_grid(instance)
    makespan_bound = on_grid(max(bounds), grid) if bounds else None
    extra = dict(out.extra)
    if is_top_level(out.status_objective) and makespan is not None:
        if out.status == Status.OPTIMAL and out.bound is None:
            makespan_bound = makespan  # a proof of optimality is a bound equal to the objective
        elif out.status == Status.FEASIBLE and _meets(makespan_bound, makespan):
            out = replace(out, status=Status.OPTIMAL)  # the bound, on the makespan's grid
            extra["optimal_by_grid"] = grid
    value, bound, obj_gap = _optimised(instance, out, timeline, extra)
    if is_top_level(out.status_objective):
        value, bound, obj_gap = makespan, makespan_bound, gap(makespan, makespan_bound)
    extra["time_limit_hit"] = time_limit_reached(out, wall, time_limit)
    if prepare_s is not None:
        extra["prepare_s"] = prepare_s
    if instance.stations and timeline is not None:
        per = timeline.station_metrics()  # docs/timeline.md, in the file's station order
        extra["station_metrics"] = {s: per[s] for s in instance.station_ids if s in per}
    result = Result(
        method=method,
        status=out.status,
        plan=out.plan,
        timeline=timeline,
        objective=value,
        bound=bound,
        gap=obj_gap,
        wall_time_s=wall,
        seed=seed,
        params={"time_limit": time_limit, **params},
        instance=instance.name,
        extra=extra,
        objective_name=out.status_objective,
        timeline_params=timeline_params(instance),
        makespan_bound=makespan_bound,
        makespan_gap=gap(makespan, makespan_bound),
    )
    if check and out.plan is not None:
        from .validate import check as run_check

        # the result's own claims too: a bound above the makespan, or "optimal" with a gap,
        # is a violation like an overlap (docs/formats.md, the checker's table)
        found = run_check(instance, out.plan, claims=result_claims(result))
        extra["violations"] = [v.to_dict() for v in found]
    return result


def _meets(bound: float | None, makespan: float) -> bool:
    """A makespan bound that proves ``makespan`` optimal (within the evaluator's float noise):
    rounded up onto the makespan's grid (:func:`.bounds.makespan_grid`), a bound less than one
    step below a plan reaches it (docs/formulations.md#what-optimal-means)."""
    return bound is not None and bound >= makespan - 1e-9 * max(1.0, abs(makespan))


def _optimised(
    instance: Instance, out: MethodOutput, timeline: Timeline | None, extra: dict[str, Any]
) -> tuple[float | None, float | None, float | None]:
    """The value, bound and gap of the objective ``out`` minimised when it is not the
    makespan, taken out of ``extra`` (where the methods state them, :data:`OBJECTIVE_KEYS`)
    so that a result states them once: the value is the registry's evaluation of the
    timeline where there is one (else the method's), the bound the better of the method's and,
    for the modelled objectives, the closed-form one (:func:`bilevel_kit.bounds.
    objective_bound`), as for the makespan, and the gap the objective's own. "Optimal" with no
    bound at all stays without one: the checker names it (docs/formats.md#solutions)."""
    from .bounds import objective_bound

    obj = OBJECTIVES.get(out.status_objective)
    if obj is None or obj.top_level:
        return None, None, None
    stated, bound, _ = (extra.pop(key, None) for key in OBJECTIVE_KEYS)
    value = obj.value(timeline) if timeline is not None else None
    value = stated if obj.evaluate is None else value
    if obj.modelled and timeline is not None:
        closed = objective_bound(instance, obj.name)
        bound = closed if bound is None else max(bound, closed)
    obj_gap = obj.gap(value, bound) if value is not None and bound is not None else None
    return value, bound, obj_gap


def result_claims(result: Result) -> Any:
    """What ``result`` claims, for the checker (:class:`bilevel_kit.validate.Claims`): the
    makespan's value, bound and gap, and the minimised objective's when it is another."""
    from .validate import Claims

    top = is_top_level(result.objective_name)
    return Claims(
        status=str(result.status),
        objective=result.makespan,
        bound=result.makespan_bound,
        gap=result.makespan_gap,
        has_gap=True,
        status_objective=result.objective_name,
        objective_claims=None if top else (result.objective, result.bound, result.gap, True),
        objective_where=None if top else ("objective", "bound"),
    )


#: What both exact models (``cpsat``, ``milp``) declare: several stations, and every objective
#: with a model expression, a plugin's too (docs/extending.md).
_EXACT_MODEL: dict[str, Any] = {
    "supports_stations": True,
    "objectives": MODEL_OBJECTIVES,
    "modelled_objectives": True,
}

register(
    "single-task",
    "bilevel_kit.heuristics.baselines:single_task",
    "paper baseline: one kit per task, deterministic topological order",
    "bilevel_kit.options:NoOptions",
    supports_stations=True,
)
register(
    "whole-assembly",
    "bilevel_kit.heuristics.baselines:whole_assembly",
    "paper baseline: one kit per product unit",
    "bilevel_kit.options:NoOptions",
    supports_stations=True,
)
register(
    "greedy-ce",
    "bilevel_kit.heuristics.greedy_ce:greedy_ce",
    "the paper's bilevel heuristic: greedy rolling horizon + cross-entropy tray layout",
    "bilevel_kit.heuristics.greedy_ce:GreedyCEOptions",
    prepare=COMPILE_KERNELS,
    supports_stations=True,
)
register(
    "cpsat",
    "bilevel_kit.models.cpsat.method:cpsat",
    "exact: CP-SAT over all segmentations and orders, tray packing embedded or by Benders",
    "bilevel_kit.models.cpsat.method:CpsatOptions",
    prepare=COMPILE_KERNELS,  # its warm start runs greedy-ce
    **_EXACT_MODEL,
)
register(
    "milp",
    "bilevel_kit.models.milp.method:milp",
    "exact: the schedule as a Pyomo MILP (HiGHS by default, any Pyomo solver), tray by cuts",
    "bilevel_kit.models.milp.method:MilpOptions",
    prepare="bilevel_kit.models.milp.method:prepare",  # greedy-ce's kernels and Pyomo
    **_EXACT_MODEL,
)
register(
    "bilevel-milp",
    "bilevel_kit.models.bilevel_milp:bilevel_milp",
    "exact optimum of the paper's objective J over enumerated kits (<= 16 tasks)",
    "bilevel_kit.models.bilevel_milp:BilevelMilpOptions",
    prepare=COMPILE_KERNELS,  # its kit values and warm start run greedy-ce's CE
    # it minimises the paper's J (not the makespan) and needs 100-250 s for a proof on the
    # table: at a time limit its plan depends on the machine's speed, so the main job leaves
    # it out unless named (README)
    in_default=False,
    objectives=("J",),
)
register(
    "bbr",
    "bilevel_kit.models.bbr.method:bbr",
    "exact: branch, bound and remember over the precedence ideals (makespan)",
    "bilevel_kit.models.bbr.method:BbrOptions",
    prepare=COMPILE_KERNELS,  # its start is lns's, which runs greedy-ce
    # a new exact method beside cpsat and milp: named, not in the main job's default set
    in_default=False,
    supports_stations=True,  # the makespan only (docs/formulations.md)
)
register(
    "lns",
    "bilevel_kit.models.lns.method:lns",
    "matheuristic: large-neighbourhood search, windows of kits re-optimised exactly by CP-SAT",
    "bilevel_kit.models.lns.method:LnsOptions",
    prepare=COMPILE_KERNELS,  # its start plan is greedy-ce's
    objectives=("makespan", "expected_makespan", "cvar_makespan", "sum_completion", "human_idle"),
    supports_stations=True,  # every objective but the scenario ones (docs/stations.md)
)
