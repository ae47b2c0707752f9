"""The incumbent of ``milp`` with several assembly stations (docs/timeline.md#several-stations;
docs/formulations.md, "Options with several stations"): the best plan, for the run's
objective, of the baselines and the ``hint`` methods (``auto``, the default: greedy-ce too;
``none``: the baselines alone, as ``cpsat``'s), within the warm start's share of the time limit.

Why greedy-ce: the better baseline alone was the incumbent before, and at a time limit (or
when the model was too large to build) ``milp`` returned it, 20-24 % above greedy-ce's plan
(issue 37: an in-tree of 90 tasks on 3 stations, 1728 s against 1434 s). The incumbent is the
MIP start and ``C <= U``, so ``milp``'s plan is never worse than greedy-ce's; when the model
will not be built the warm start has the whole time limit (:func:`warm_share`).
"""

from __future__ import annotations

from typing import Any, Protocol

from ...errors import KitDoesNotFit, UsageError
from ...instance import Instance
from ...objectives import get as get_objective
from ...plan import Kit, Plan, evaluate
from ..budget import Budget
from ..common import Packer
from ..exact.driver import HINT_SHARE
from ..exact.nomodel import HandOff, NoModelSpec
from ..exact.station_lns import station_lns
from ..exact.warm import WarmRule, best_heuristic_plan, hint_methods
from .model import model_cells, model_objective
from .options import MilpOptions
from .solver import TOL


class Run(Protocol):
    """What the warm start reads and writes of the milp driver's run (``.method._Run``, which
    imports this module: a protocol, not an import, so there is no cycle)."""

    instance: Instance
    options: MilpOptions
    budget: Budget
    packer: Packer  # it learns the incumbent's layouts
    extra: dict[str, Any]  # the result's ``extra`` (``hint_method``, skipped warm starts)
    seed: int
    inc_obj: float | None  # the incumbent's master objective
    upper: float | None  # the horizon U

    @property
    def spec(self) -> NoModelSpec: ...  # the model's measured costs

    @property
    def margin(self) -> float: ...  # seconds kept back from the time limit


#: The heuristics whose best plan is the incumbent with several stations (all take them) and
#: ``hint=none`` (``auto``, the default, adds greedy-ce: :func:`..exact.warm.hint_methods`).
STATION_METHODS = ("single-task", "whole-assembly")
#: Seconds per task kept back for a heuristic's run past its own ``time_limit``: greedy-ce's
#: was +0.5-1.4 s at 1,000 tasks (:data:`..exact.warm.HINT_OVERRUN_S_PER_TASK`, whose 0.01 s
#: per task left greedy-ce 0.8 s of a 10 s run on 900 tasks on 3 stations, and its plan
#: 1,000 s above its own at 10 s).
OVERRUN_S_PER_TASK = {"greedy-ce": 0.002}
#: The warm-start rule with several stations (:class:`..exact.warm.WarmRule`): the overrun
#: above, no method skipped for lack of time (each gets at least ``MIN_RUN``) and a plan better
#: only beyond the solver's tolerance; kept apart from ``cpsat``'s rule because the station
#: results of issue 37 (and the tests' expected incumbents) were measured with it.
RULE = WarmRule(OVERRUN_S_PER_TASK, kernel_load_s=0.0, min_run=None, tol=TOL)


def check_station_hint(instance: Instance, hint: str) -> None:
    """A ``hint`` method that does not model several stations is a one-line UsageError (exit 2)
    with stations: its plan would be silently missing from the incumbent."""
    from ...methods import get_method

    if not instance.stations or hint in ("auto", "none") or get_method(hint).supports_stations:
        return
    raise UsageError(
        f"{instance.source}: milp does not use option 'hint={hint}' with several assembly "
        f"stations ({hint} does not model them); drop it or use hint=none or a method that "
        "supports stations (docs/timeline.md#several-stations)"
    )


def station_incumbent(
    r: Run, seed: int
) -> tuple[list[list[str]] | None, float | None, float | None, int]:
    """The best of :data:`STATION_METHODS` and the ``hint`` methods for the objective (its
    layouts taught to the packer), its master objective (:func:`.model.model_objective`), the
    horizon U (:meth:`bilevel_kit.objectives.Objective.horizon`) and the kit cap K = n;
    ``extra["hint_method"]`` names the method whose plan it is."""
    instance, objective, hint = r.instance, r.options.objective, r.options.hint
    methods = STATION_METHODS + tuple(m for m in hint_methods(hint) if m not in STATION_METHODS)
    time_limit = warm_share(r) * r.budget.remaining(r.margin)
    plan, name = best_heuristic_plan(instance, methods, seed, time_limit, objective, RULE, r.extra)
    if plan is None:  # every task fits alone (checked before), so single-task always plans
        raise KitDoesNotFit(f"{instance.source}: no heuristic plan for the milp incumbent")
    r.extra["hint_method"] = name
    _learn(r, plan)
    tl = evaluate(instance, plan)
    kits = [list(k.tasks) for k in plan.kits if k.tasks]
    upper = get_objective(objective).horizon(instance, tl)
    return kits, model_objective(instance, tl, objective), upper, max(instance.n_tasks, len(kits))


def station_hand_off(r: Run, inc: list[list[str]], limit: HandOff) -> list[list[str]]:
    """Several stations: ``inc`` or the better plan of ``lns``'s station search from it within
    ``limit`` for the objective (:func:`..exact.station_lns.station_lns`; its layouts taught
    to the packer, its master objective and horizon U the run's)."""
    kits = []
    for kit in inc:  # (the incumbent's kits are in human order)
        layout = r.packer.layout(kit)
        if layout is None and r.instance.kit_parts(kit):
            return inc
        kits.append(Kit(tuple(kit), layout or ()))
    objective = r.options.objective
    found = station_lns(
        r.instance, Plan(tuple(kits)), objective, seed=r.seed, limit=limit, extra=r.extra
    )
    if found is None:
        return inc
    _learn(r, found)
    tl = evaluate(r.instance, found)
    r.inc_obj = model_objective(r.instance, tl, objective)
    r.upper = get_objective(objective).horizon(r.instance, tl)
    return [list(k.tasks) for k in found.kits if k.tasks]


def warm_share(r: Run) -> float:
    """The share of the time left for the warm start: :data:`HINT_SHARE` of the time limit,
    or all of it when the model of K = n positions will not be built anyway (over the memory
    limit, or its estimated build time above :data:`..budget.BUILD_SHARE` of what the warm
    start leaves): then the warm start's plan is the result, and greedy-ce given less time
    than on its own would leave tasks in kits of their own (a 200-task sparse instance on 2
    stations needs more than 10 s)."""
    from ..budget import BUILD_SHARE, memory_refusal

    spec, left = r.spec, r.budget.remaining(r.margin)
    if left <= 0:
        return 0.0
    share = min(1.0, HINT_SHARE * r.budget.time_limit / left)
    cells = model_cells(r.instance, r.instance.n_tasks)
    what = "task x kit variables"
    if memory_refusal(spec.owner, cells, spec.bytes_per_cell, what) is not None:
        return 1.0
    return 1.0 if cells * spec.build_s_per_cell > BUILD_SHARE * left * (1 - share) else share


def _learn(r: Run, plan: Plan) -> None:
    """The plan's layouts (a heuristic's, perhaps at any angle) taught to the run's packer,
    which lays out the result's kits."""
    for kit in plan.kits:
        if kit.layout:
            r.packer.learn(r.instance.kit_parts(kit.tasks), kit.layout)
