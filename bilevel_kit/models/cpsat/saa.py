r"""The exact sample-average (SAA) model: one plan, one timeline per scenario
(docs/formulations.md#stochastic-human-times-sample-average-approximation).

The kit assignment of the CP-SAT schedule model (:mod:`.model`: ``x[i,k]``, the order
encoding, precedence, used kits first) carries ``S`` copies of its timeline, one per scenario
``s`` with that scenario's human times ``h_i^s`` (:mod:`bilevel_kit.stochastic`), each built
by the same :func:`.model._timeline`; the objective is :math:`\min \sum_s C^s` (the sample
average times ``S``). Every timeline constraint is monotone, so for fixed kits each copy's
least solution is that scenario's true timeline (docs/timeline.md), as in the one-scenario
model. Not added: the symmetry breaking of interchangeable chains (chains with the same mean
times differ per scenario) and the closed-form bounds of the mean times.

**CVaR** (``alpha`` given, docs/formulations.md#cvar-of-the-makespan): Rockafellar-Uryasev's
linear form, :math:`\min\, p S \eta + q \sum_s z_s` with :math:`z_s \ge C^s - \eta`,
:math:`z_s \ge 0` and :math:`1 - \alpha' = p / q`, i.e. :math:`p S` times
:math:`\eta + \frac{1}{(1-\alpha')S}\sum_s z_s`. :math:`\alpha'` is ``alpha`` as a fraction of
denominator at most :data:`ALPHA_DENOMINATOR`, never above it (CVaR is non-decreasing in the
level, so the bound stays a lower bound; a decimal ``alpha`` such as 0.9 is exact). An integer
:math:`\eta` loses nothing: for fixed kits the minimum is attained at an order statistic
of the (integer) :math:`C^s`.

**Tray.** The area relaxation and the part counts of :mod:`.model`; the kits of each master
solution are checked by the packing oracle and a kit that does not fit is cut for every kit
position (:func:`.tray.add_cut`), as in ``cpsat``'s logic-based Benders. A cut the oracle
could not prove (its answer unknown) leaves the bound without proof.

**Times** are scaled to integers on ``resolution`` s and rounded down (:mod:`.scaling`): the
makespan is non-decreasing in every duration, so the model's bound is a lower bound of the
real sample average; the value of the returned plan is always recomputed with the real times
by :func:`bilevel_kit.stochastic.expected_makespan` (the one evaluator).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field, replace
from fractions import Fraction
from typing import Any

import numpy as np

from ...instance import Instance
from ...plan import Kit, Placement, Plan
from ...stochastic import cvar_makespan, expected_makespan
from .. import packing_oracle
from ..budget import Budget
from ..common import Packer, kit_order, pack_time_limit
from .context import Model
from .model import _assignment, _timeline, _tray, _used_kits, extract_kits
from .scaling import scale_times
from .tray import add_cut

#: The time grid of the scaled scenario times (s).
RESOLUTION = 0.001
#: The largest denominator of the model's CVaR level (module docstring).
ALPHA_DENOMINATOR = 1000


def model_alpha(alpha: float) -> Fraction:
    """``alpha`` as a fraction of denominator <= :data:`ALPHA_DENOMINATOR`, never above it."""
    frac = Fraction(alpha).limit_denominator(ALPHA_DENOMINATOR)
    if frac > Fraction(alpha):
        frac = Fraction(math.floor(alpha * ALPHA_DENOMINATOR), ALPHA_DENOMINATOR)
    return frac


@dataclass
class SaaOutcome:
    """The best kits found (task ids) and their layouts, their real sample average ``value``
    (s), the model's ``bound`` on the sample average of every plan (s; None: no proof),
    whether the kits are proven optimal for the scenarios, and the loop's counters."""

    kits: list[tuple[str, ...]] | None
    #: each kit's layout (None: the packing oracle found none in time)
    layouts: list[tuple[Placement, ...] | None] | None
    value: float | None
    bound: float | None
    proven: bool
    info: dict[str, Any] = field(default_factory=dict)


def _build(
    instance: Instance, scenarios: np.ndarray, resolution: float, alpha: float | None = None
) -> tuple[Model, int]:
    """The model of the module docstring (K = n kit positions: every plan) and the divisor of
    its objective: the scaled objective over it is the sample average (``alpha`` None) or the
    CVaR at level :func:`model_alpha` (s / resolution)."""
    from ortools.sat.python import cp_model

    m = cp_model.CpModel()
    K = instance.n_tasks
    sc = scale_times(instance, resolution, refine=False)
    x, _, _ = _assignment(m, instance, K)
    used = _used_kits(m, instance, x, K)
    timelines = [
        _timeline(m, replace(sc, h=[math.floor(v / sc.res + 1e-9) for v in row]), x, used, K, None)
        for row in scenarios.tolist()
    ]
    ends = [end[-1] for _, _, end in timelines]
    total, divisor = sum(ends), len(ends)
    if alpha is not None:  # Rockafellar-Uryasev (module docstring)
        tail = 1 - model_alpha(alpha)
        top = max(max(e.proto.domain) for e in ends)  # the horizon of each C^s
        eta = m.new_int_var(0, top, "eta")
        zs = [m.new_int_var(0, top, f"z{s}") for s in range(len(ends))]
        for z, e in zip(zs, ends, strict=True):
            m.add(z >= e - eta)
        divisor = tail.numerator * len(ends)
        total = divisor * eta + tail.denominator * sum(zs)
    m.minimize(total)
    _, arrive, end = timelines[0]
    mdl = Model(m, K, x, used, arrive, end, total)
    _tray(instance, mdl, False, 1.0)
    mdl.obj_const = 0
    return mdl, divisor


def _net_cut(solver: Any, status: Any, det_limit: float) -> bool:
    """Did CP-SAT stop on its wall-clock limit (the safety net) rather than on a proof
    (optimal, infeasible) or on ``det_limit``, its deterministic time (inf: none)? Stopped by
    that limit, its deterministic time reaches it (docs/robust.md#the-study)."""
    from ortools.sat.python import cp_model

    if status in (cp_model.OPTIMAL, cp_model.INFEASIBLE, cp_model.MODEL_INVALID):
        return False
    return bool(solver.deterministic_time < det_limit - 1e-6)


def _hint(mdl: Model, instance: Instance, kits: Sequence[Sequence[str]]) -> None:
    where = {t: k for k, kit in enumerate(kits) for t in kit}
    for i, xs in enumerate(mdl.x):
        for k, v in xs.items():
            mdl.model.add_hint(v, where.get(instance.tasks[i].id) == k)
    for k, u in enumerate(mdl.used):
        mdl.model.add_hint(u, k < len(kits))


def solve_saa(
    instance: Instance,
    scenarios: np.ndarray,
    *,
    time_limit: float,
    start: Plan | None = None,
    seed: int = 0,
    workers: int = 1,
    resolution: float = RESOLUTION,
    deterministic_time: float | None = None,
    alpha: float | None = None,
) -> SaaOutcome:
    """Minimise the sample average of the makespan (``alpha`` None) or its CVaR at level
    ``alpha`` over every plan (module docstring) within ``time_limit`` s, hinted with
    ``start``; the better of ``start`` and the model's plan.
    ``deterministic_time``: CP-SAT's deterministic time over all its solves (one worker: a
    reproducible run, docs/simulation.md#determinism), the time limit its safety net, whose
    firing ``info["saa_safety_net"]`` records (:func:`_net_cut`, docs/robust.md#the-study)."""
    from ortools.sat.python import cp_model

    budget = Budget(time_limit)
    nets_before = packing_oracle.safety_nets()
    if instance.stations:
        raise ValueError("the SAA model covers one assembly station")
    mdl, divisor = _build(instance, scenarios, resolution, alpha)

    def value_of(plan: Plan) -> float:  # the one evaluator (bilevel_kit/stochastic.py)
        if alpha is None:
            return expected_makespan(instance, plan, scenarios)
        return cvar_makespan(instance, plan, scenarios, alpha)

    packer = Packer(
        instance, pack_time_limit(budget), budget, deterministic=deterministic_time is not None
    )
    best: tuple[float, list[tuple[str, ...]] | None] = (math.inf, None)
    if start is not None:
        kits0 = [k.tasks for k in start.kits if k.tasks]
        for kit in start.kits:
            if kit.layout:
                packer.learn(instance.kit_parts(kit.tasks), kit.layout)
        best = (value_of(start), kits0)
        _hint(mdl, instance, kits0)
    ids = [t.id for t in instance.tasks]
    info: dict[str, Any] = {
        "saa_cuts": 0,
        "saa_unproven_cuts": 0,
        "saa_iterations": 0,
        "saa_status": None,
        "saa_deterministic_time": 0.0,
    }
    bound_valid, proven, cut = True, False, False
    bound: float | None = None
    while budget.remaining(0.05) > 0.05:
        solver = cp_model.CpSolver()
        solver.parameters.max_time_in_seconds = budget.remaining(0.05)
        solver.parameters.num_workers = workers
        left = math.inf
        if deterministic_time is not None:
            left = deterministic_time - info["saa_deterministic_time"]
            if left <= 0:
                break
            solver.parameters.max_deterministic_time = left
        solver.parameters.random_seed = seed
        status = solver.solve(mdl.model)
        cut = cut or _net_cut(solver, status, left)
        info["saa_deterministic_time"] += solver.deterministic_time
        info["saa_iterations"] += 1
        info["saa_status"] = solver.status_name(status)
        if status not in (cp_model.OPTIMAL, cp_model.FEASIBLE):
            break
        kits = [kit_order(instance, [ids[i] for i in k]) for k in extract_kits(mdl, solver)]
        misfits = [k for k in kits if packer.fits(k) is not True]
        if not misfits:
            plan = Plan(tuple(Kit(k) for k in kits))
            found = value_of(plan)
            if found < best[0]:
                best = (found, kits)
            if bound_valid:
                scaled = solver.best_objective_bound
                bound = scaled * resolution / divisor  # not refined: the grid is it
            proven = status == cp_model.OPTIMAL and bound_valid
            break
        for k in misfits:
            verdict = packer.verdict(dict(instance.kit_parts(k)))
            bound_valid = bound_valid and verdict.fits is False
            info["saa_unproven_cuts"] += verdict.fits is None
            add_cut(mdl, dict(instance.kit_parts(k)))
            info["saa_cuts"] += 1
        if best[1] is not None:
            mdl.model.clear_hints()
            _hint(mdl, instance, best[1])
    else:  # the clock ran out with cuts added and work left: the net cut the run
        cut = True
    if deterministic_time is not None:
        info["saa_safety_net"] = cut or packing_oracle.safety_nets() > nets_before
    value: float | None = best[0] if best[1] is not None else None
    if bound is not None and value is not None:
        bound = min(bound, value)
    layouts = None if best[1] is None else [packer.layout(k) for k in best[1]]
    return SaaOutcome(best[1], layouts, value, bound, proven, info)
