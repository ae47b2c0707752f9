r"""Every objective a result's ``status`` may refer to, in one registry.

Each :class:`Objective` declares how it is evaluated from a plan's
:class:`~bilevel_kit.plan.Timeline` (the one evaluator, docs/timeline.md), where a result states
its value, bound and gap, how the gap is formed, and whether a stated bound is a claim about
every valid plan (so that any other valid plan's value may refute it). The ones the exact
models minimise are subclasses that also own their closed-form bound (made of the makespan
bounds of :mod:`bilevel_kit.bounds`), the models' horizon ``C <= U``, and their expression in
the models, written once on :class:`ModelTerms` for CP-SAT, Pyomo and plain numbers alike,
so that no module compares objective names. The checker (:mod:`bilevel_kit.validate`),
``compare``'s cross-method consistency test (:mod:`bilevel_kit.experiments.compare`) and the
brute-force tests iterate over :data:`OBJECTIVES`: an objective added here is checked
everywhere without a special case; a method declares the ones it minimises on its spec
(:class:`bilevel_kit.methods.MethodSpec`, docs/extending.md#adding-an-objective).
:data:`OBJECTIVES` is a :class:`~bilevel_kit.registry.Registry` like the methods', so a
plugin's registration function adds an objective with :func:`register`, and ``cpsat`` and
``milp`` minimise every modelled one (:func:`model_objectives`) by its expression.

The objectives (docs/timeline.md#metrics, docs/timeline.md#several-stations,
docs/formulations.md):

.. math::

    \text{makespan} = \max_s C_s, \qquad
    \text{sum\_completion} = \sum_s C_s, \qquad
    \text{human\_idle} = \sum_s \Bigl(C_s - \sum_{k \text{ at } s} H_k\Bigr)

with :math:`C_s` the end of station ``s``'s last kit (one station: the makespan), and the
paper's J (docs/formulations.md#exact-bilevel-milp-over-kit-columns), which also needs the
lower level's kit values and so is not a function of the timeline: its value is stated, never
recomputed, and its bound and gap are checked against that stated value; and
``expected_makespan``, the sample average of the makespan over scenarios of the human times
(docs/formulations.md#stochastic-human-times-sample-average-approximation, ``lns -p
objective=expected_makespan``), stated like J because it is a function of the plan *and* its
scenarios: the checker holds its bound and gap against the stated value, and the mean-time
makespan optimum bounds the true expectation of every plan from below (Jensen), which
:mod:`bilevel_kit.stochastic` and the SAA brute-force test use; and ``cvar_makespan``, the
CVaR at level alpha of the makespan over the same scenarios
(docs/formulations.md#cvar-of-the-makespan, ``lns -p objective=cvar_makespan -p alpha=A``),
stated and checked like ``expected_makespan``.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

from .errors import UsageError
from .registry import Registry

if TYPE_CHECKING:
    from .instance import Instance
    from .plan import Timeline


#: A closed-form makespan bound of an instance; each station's own, with its instance.
Bound = Callable[["Instance"], float]
StationBounds = Callable[["Instance"], "list[tuple[Instance, float]]"]


def relative_gap(value: float | None, bound: float | None) -> float | None:
    """The one gap formula, ``(value - bound) / value`` clipped at 0 (docs/timeline.md#terms):
    0 when proven optimal; None when either is unknown or the value is not positive."""
    if value is None or bound is None or value <= 0:
        return None
    return max(0.0, (value - bound) / value)


def _signed_gap(value: float, bound: float) -> float | None:
    """``|J - bound| / max(1, |J|)``: J may be negative (``plan_objective_J_gap``)."""
    return abs(value - bound) / max(1.0, abs(value))


@dataclass(frozen=True)
class ModelTerms:
    """What an objective is made of in an exact model (docs/formulations.md), as CP-SAT or
    Pyomo expressions or as plain numbers (a plan's value on the model's own scale), so that
    one :meth:`Objective.expression` serves both back-ends and the incumbents' values:
    ``makespan`` C; ``completions`` the sum of the stations' completions (C with one
    station), built on first use because with several stations it adds variables;
    ``overhead`` the human's kit overheads ``sum_s o_H,s m_s``."""

    makespan: Any
    completions: Callable[[], Any]
    overhead: Callable[[], Any]

    @classmethod
    def one_station(cls, makespan: Any, overhead: Callable[[], Any]) -> ModelTerms:
        """One station: the completions are the makespan."""
        return cls(makespan, lambda: makespan, overhead)


@dataclass(frozen=True)
class Objective:
    """One objective: its ``name`` (``status_objective``, ``-p objective=``), how it is
    evaluated and stated, what a bound on it promises, and (the modelled ones, subclasses
    below) its closed-form bound, its exact models' expression and horizon."""

    name: str
    #: Words for messages ("the sum of the stations' completions").
    label: str
    #: Its value on a timeline (s); None: not a function of the timeline (J).
    evaluate: Callable[[Timeline], float] | None
    #: Keys holding its value, bound and gap in a solution file of format 1, first found wins:
    #: in its ``extra``, or (``top_level``) its own ``objective``, ``bound``, ``gap``. A result
    #: and a file of format 2 state them as ``objective``, ``bound``, ``gap`` of the objective
    #: they name (docs/formats.md#format-1).
    value_keys: tuple[str, ...]
    bound_keys: tuple[str, ...]
    gap_keys: tuple[str, ...]
    #: The gap from its value and its bound.
    gap: Callable[[float, float], float | None] = relative_gap
    #: A stated bound is a lower bound on its value over every valid plan (any method's).
    bound_holds_for_every_plan: bool = True
    #: ``cpsat`` and ``milp`` minimise it (``-p objective=``).
    modelled: bool = True
    #: Absolute tolerance (in its unit) of "optimal => bound equals value" on top of
    #: :data:`bilevel_kit.validate.TIME_TOL`, relative to ``max(1, |value|)``: 0 where the
    #: methods copy the value into the bound, the MILP's relative tolerance (1e-6) for J.
    rel_tol: float = 0.0
    #: The result's own ``objective``, ``bound`` and ``gap`` are about it (the makespan):
    #: a method's ``bound`` and the models' proven bounds speak of it.
    top_level: bool = False
    #: A function of the plan and scenarios of the human times (the SAA of ``lns``).
    scenarios: bool = False
    #: What it is, in one line, where a list or a status line first shows it (J).
    meaning: str | None = None

    @property
    def is_makespan(self) -> bool:
        """It is the makespan: the makespan's closed-form and proven bounds
        (:mod:`bilevel_kit.bounds`, :mod:`bilevel_kit.models.relax`) are bounds on it, an
        incumbent's value is the exact models' horizon ``C <= U`` and kit cap, and the LNS
        minimises it (docs/formulations.md). The exact drivers' closed-form shortcut and LNS
        hand-off apply only then."""
        return False

    @property
    def makespan_with_one_station(self) -> bool:
        """With one station it equals the makespan (docs/timeline.md#several-stations), so a
        one-station run of ``cpsat`` or ``milp`` minimises the makespan instead."""
        return self.is_makespan

    def value(self, timeline: Timeline) -> float | None:
        """The objective on ``timeline``; None when it is not a function of it."""
        return None if self.evaluate is None else self.evaluate(timeline)

    def stated(
        self, fields: Mapping[str, Any], extra: Mapping[str, Any]
    ) -> tuple[Any, Any, Any, bool]:
        """The value, bound and gap a result states (its own ``fields`` or its ``extra``; None:
        not stated) and whether it has a gap key at all (its null then claims no gap)."""
        source = fields if self.top_level else extra

        def first(keys: tuple[str, ...]) -> Any:
            return next((source[k] for k in keys if source.get(k) is not None), None)

        has_gap = any(k in source for k in self.gap_keys)
        return first(self.value_keys), first(self.bound_keys), first(self.gap_keys), has_gap

    def _not_modelled(self, what: str) -> ValueError:
        return ValueError(f"{self.name!r} has no {what}: no exact model minimises it")

    def bound(self, instance: Instance, makespan: Bound, stations: StationBounds) -> float:
        """A closed-form lower bound on it over every plan (s), made of the makespan bounds of
        :mod:`bilevel_kit.bounds` (which passes them in, :func:`~bilevel_kit.bounds.
        objective_bound`): ``makespan`` of an instance, ``stations`` each station's own."""
        raise self._not_modelled("closed-form bound")

    def horizon(self, instance: Instance, timeline: Timeline) -> float:
        """A bound on the makespan of every plan at least as good as ``timeline``'s for it: the
        exact models' ``C <= U``."""
        raise self._not_modelled("horizon")

    def expression(self, terms: ModelTerms) -> Any:
        """What the exact models minimise: it, less :meth:`dropped` (docs/formulations.md)."""
        raise self._not_modelled("model expression")

    def makespan_bound(self, instance: Instance, bound: float, kits: int) -> float | None:
        """A lower bound on the makespan of every plan of a one-station ``instance`` that
        ``bound``, a lower bound on this objective over every plan (s), implies, given that
        every plan has at least ``kits`` kits (:func:`bilevel_kit.bounds.min_kits`); None:
        none (the exact drivers then keep the closed-form makespan bound)."""
        return None

    def dropped(self, human: Sequence[Any]) -> Any:
        """The constant the models' :meth:`expression` leaves out, from the tasks' human times
        ``human`` (s, or the model's integer grid): value = model value less it."""
        return 0

    def model_value(self, instance: Instance, timeline: Timeline) -> float:
        """A plan's value on the models' scale (:meth:`expression`), from its timeline."""
        value = self.value(timeline)
        if value is None:
            raise ValueError(f"{self.name!r} is not a function of the timeline")
        return value + self.dropped(human_times(instance))


class Makespan(Objective):
    """``max_s C_s``: the models' C; its bound is :func:`bilevel_kit.bounds.best_bound`."""

    @property
    def is_makespan(self) -> bool:
        return True

    def bound(self, instance: Instance, makespan: Bound, stations: StationBounds) -> float:
        return makespan(instance)

    def horizon(self, instance: Instance, timeline: Timeline) -> float:
        return timeline.makespan

    def expression(self, terms: ModelTerms) -> Any:
        return terms.makespan


class SumCompletion(Objective):
    """``sum_s C_s``: each completion is at most the sum, so the sum bounds the makespan; its
    bound sums each station's own (:func:`bilevel_kit.bounds.station_bounds`)."""

    @property
    def makespan_with_one_station(self) -> bool:
        return True

    def bound(self, instance: Instance, makespan: Bound, stations: StationBounds) -> float:
        return sum(lb for _, lb in stations(instance))

    def horizon(self, instance: Instance, timeline: Timeline) -> float:
        return _sum_completion(timeline)

    def expression(self, terms: ModelTerms) -> Any:
        return terms.completions()


class HumanIdle(Objective):
    """``sum_s (C_s - sum_{k at s} H_k)``; the models drop the constant ``sum_i h_i``."""

    def bound(self, instance: Instance, makespan: Bound, stations: StationBounds) -> float:
        """The sum over the stations of ``max(o_R + d_s, LB_s - W_s)``: a station's human idles
        at least until its first kit arrives, and its idle is ``C_s`` less its work, at most
        ``W_s = sum h_i + o_H,s n_s`` (one task per kit)."""
        total = 0.0
        for one, lb in stations(instance):
            params = one.params_of()  # the station's own (station_instance)
            work = sum(human_times(one)) + params.kit_overhead_human * one.n_tasks
            total += max(instance.kit_overhead_robot + params.delivery_time, lb - work)
        return total

    def horizon(self, instance: Instance, timeline: Timeline) -> float:
        """``idle + sum_i h_i + n max_s o_H,s``: a station's completion is its idle plus its
        work."""
        o_h = max(p.kit_overhead_human for p in instance.station_params.values())
        return timeline.human_idle + sum(human_times(instance)) + o_h * instance.n_tasks

    def expression(self, terms: ModelTerms) -> Any:
        return terms.completions() - terms.overhead()

    def dropped(self, human: Sequence[Any]) -> Any:
        return sum(human)

    def makespan_bound(self, instance: Instance, bound: float, kits: int) -> float | None:
        """``C = idle + sum_i h_i + o_H m`` with ``m >= kits`` (one station)."""
        o_h = instance.params_of().kit_overhead_human
        return bound + sum(human_times(instance)) + o_h * kits


def human_times(instance: Instance) -> list[float]:
    """Every task's human time (s), in task order: what :meth:`Objective.dropped` takes."""
    return [instance.human_time(t.id) for t in instance.tasks]


def _sum_completion(timeline: Timeline) -> float:
    """``sum_s C_s`` (``station_metrics()``); with one station the makespan."""
    if not timeline.kit_stations:
        return timeline.makespan
    return sum(float(m["completion"]) for m in timeline.station_metrics().values())


#: Where a result's ``extra`` keeps an objective's value, bound and gap besides the makespan:
#: the ``value_keys``, ``bound_keys`` and ``gap_keys`` of a new objective (a plugin's too).
EXTRA_KEYS = (("objective_value",), ("objective_bound",), ("objective_gap",))

#: What J is, in one line: printed below a list or table that first shows it (``bilevel-kit
#: methods``, ``compare``'s status column "feasible (for J)", ``solve``'s status line). The
#: paper names only the kit score F (Section IV-A, Eqs. 3-7); J is the toolkit's name for F summed
#: over a plan's kits (docs/guide.md#exact-baselines-bilevel_kitmodels).
J_MEANING = (
    "J = the paper's objective: its kit score F (Eqs. 3-7, which greedy-ce minimises one kit "
    "at a time) summed over the plan's kits; lower is better, and it is not the makespan"
)

#: The registry, by name: the built-in objectives, then those plugins add (:func:`register`).
OBJECTIVES: Registry[Objective] = Registry("objective")
_BUILTINS = (
    Makespan(
        "makespan",
        "the makespan",
        lambda tl: tl.makespan,
        ("objective",),
        ("bound",),
        ("gap",),
        top_level=True,
    ),
    SumCompletion(
        "sum_completion", "the sum of the stations' completions", _sum_completion, *EXTRA_KEYS
    ),
    HumanIdle(
        "human_idle",
        "the total human idle",
        lambda tl: tl.human_idle,
        ("objective_value",),
        ("objective_bound", "idle_bound"),  # idle_bound: the one-station models' key
        ("objective_gap",),
    ),
    Objective(
        "expected_makespan",
        "the sample-average makespan over the scenarios of the human times",
        None,  # a function of the plan and its scenarios, not of one timeline
        ("expected_makespan",),
        ("expected_makespan_bound",),
        ("expected_makespan_gap",),
        # a bound speaks of the result's own scenarios; another method's plan is held
        # against it only on the same scenarios (bilevel_kit/stochastic.py)
        bound_holds_for_every_plan=False,
        modelled=False,
        rel_tol=1e-4,  # scenario times rounded down on a 1 ms grid (docs/formulations.md)
        scenarios=True,
    ),
    Objective(
        "J",
        "the paper's objective J",
        None,
        ("plan_objective_J",),
        ("plan_objective_J_bound",),
        ("plan_objective_J_gap",),
        gap=_signed_gap,
        modelled=False,
        rel_tol=1e-6,
        meaning=J_MEANING,
    ),
    Objective(
        "cvar_makespan",
        "the CVaR of the makespan over the scenarios of the human times",
        None,  # like expected_makespan: a function of the plan, its scenarios and alpha
        ("cvar_makespan",),
        ("cvar_makespan_bound",),
        ("cvar_makespan_gap",),
        bound_holds_for_every_plan=False,
        modelled=False,
        rel_tol=1e-4,  # the same 1 ms grid as expected_makespan (docs/formulations.md)
        scenarios=True,
    ),
)
for _builtin in _BUILTINS:
    # set directly: the paper's "J" predates the registry's lower-case names (registry.py)
    OBJECTIVES[_builtin.name] = _builtin

#: The built-in objectives ``cpsat`` and ``milp`` take (``-p objective=``), the makespan
#: first; :func:`model_objectives` adds the plugins'.
MODEL_OBJECTIVES: tuple[str, ...] = tuple(o.name for o in _BUILTINS if o.modelled)


def register(objective: Objective) -> None:
    """Add ``objective`` (a plugin's, docs/extending.md#adding-an-objective) under its name:
    a lower-case name not yet taken (:data:`bilevel_kit.registry.NAME_PATTERN`), else a
    :class:`~bilevel_kit.errors.UsageError`. A modelled one must define its closed-form
    bound, horizon and model expression (a subclass of :class:`Objective`)."""
    if not isinstance(objective, Objective):
        raise UsageError(f"objective {objective!r} is not a bilevel_kit.objectives.Objective")
    if objective.modelled:
        missing = [
            m
            for m in ("bound", "horizon", "expression")
            if getattr(type(objective), m) is getattr(Objective, m)
        ]
        if missing:
            raise UsageError(
                f"objective {objective.name!r} is modelled but does not define {', '.join(missing)}"
            )
    OBJECTIVES.add(objective)


def model_objectives() -> tuple[str, ...]:
    """Every objective the exact models minimise by its expression (:attr:`Objective.modelled`),
    the plugins' too, the makespan first: what ``cpsat`` and ``milp`` take."""
    return tuple(n for n, o in OBJECTIVES.items() if o.modelled)


def scenario_objectives() -> tuple[str, ...]:
    """The objectives that are functions of scenarios of the human times
    (:attr:`Objective.scenarios`): the ones that read ``lns``'s scenario options."""
    return tuple(n for n, o in OBJECTIVES.items() if o.scenarios)


def is_top_level(name: str) -> bool:
    """Whether objective ``name`` is the makespan, whose numbers a result also states as
    ``makespan_bound``, ``makespan_gap`` (:attr:`Objective.top_level`; an unknown name is
    not)."""
    obj = OBJECTIVES.get(name)
    return obj is not None and obj.top_level


def get(name: str) -> Objective:
    """The registered objective ``name``; KeyError naming the known ones."""
    try:
        return OBJECTIVES[name]
    except KeyError:
        raise KeyError(f"unknown objective {name!r} (known: {', '.join(OBJECTIVES)})") from None


def evaluated() -> list[Objective]:
    """The objectives that are functions of the timeline (the brute forces' and ``compare``'s)."""
    return [o for o in OBJECTIVES.values() if o.evaluate is not None]
