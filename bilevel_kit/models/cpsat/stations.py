r"""``cpsat`` on an instance with several assembly stations (docs/timeline.md#several-stations).

A model of its own, beside the one-station model of :mod:`.model` (which it leaves alone):
kit positions k = 1..K (K = n), ``x[i,k]`` = task i in kit k, ``u_k`` = kit k used (used kits
first), ``z[s,k]`` = kit k is for station s (one per used kit, and every task of the kit on
it: a kit never mixes stations). With integer (scaled) times::

    R_k = o_R u_k + sum_i r_i x[i,k]       D_k = sum_s d_s z[s,k]
    H_k = sum_s o_H,s z[s,k] + sum_i h_i x[i,k]
    S_k >= A_{k-1},  A_k = S_k + R_k + D_k,  E_k >= A_k + H_k
    E_k >= E_j + H_k                       if z[s,j] and z[s,k], j < k (the station's human)
    S_k >= E_j - H_j + o_H,s               if z[s,j], z[s,k] and at least T_s kits of s lie in
                                           positions j..k-1 (its T_s-th previous kit or earlier)
    C >= E_k,  p_a <= p_b for every edge a -> b (p_i the kit of task i)

Every constraint is monotone, so for fixed kits the least solution is the timeline and the
objective (the makespan C) is pushed down to it, as in :mod:`.model`. The tray's geometry is
handled as by Benders: the kits of a solution are checked with the packing oracle, a kit that
does not fit cuts every kit position holding that task set, and the model is solved again; the
area relaxation (``sum_i a_i x[i,k] <= W H``, true areas) is in the model from the start.

"optimal" is claimed only with an optimal model, exact times on the integer grid and every cut
proven for parts at any angle (else the verdict is ``optimal_axis_aligned``, as for one
station). The hint and the upper bound ``C <= U`` come from the better of the baselines
(which interleave stations by earliest need); that plan is returned when no better one is
found.
The objective is the makespan C, the sum of the stations' completions ``C_s >= E_k`` (kits k
of s), or that sum less ``sum_s o_H,s m_s`` (the total human idle less the constant
``sum_i h_i``: the registry's expression), with ``U`` the objective's horizon
(docs/formulations.md); without stations ``sum_completion`` is the one-station makespan.
``tray`` mode is always the Benders loop here.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import replace
from typing import Any

from ...bounds import best_bound, objective_extra
from ...instance import Instance
from ...methods import MethodOutput, Status
from ...objectives import ModelTerms, is_top_level
from ...objectives import get as get_objective
from ...plan import Kit, Plan, evaluate
from ...stations import objective_of
from .. import packing_oracle, stoppable
from ..budget import Budget, check_model_memory
from ..common import Packer, kit_order, scope_claims
from ..packing import ANY_ANGLE, AXIS_ALIGNED

#: Integer time scales tried in turn; the first that makes every time exact is used.
SCALES = (1, 2, 4, 5, 10, 20, 100, 1000)
#: Peak memory per x/pair variable of this model (bytes), as :mod:`.method`'s per cell.
BYTES_PER_CELL = 6_000


def time_scale(values: list[float]) -> tuple[int, bool]:
    """The first scale of :data:`SCALES` that makes every value an integer, and whether one
    did (else the largest, with rounding)."""
    for s in SCALES:
        if all(abs(v * s - round(v * s)) <= 1e-9 * max(1.0, abs(v * s)) for v in values):
            return s, True
    return SCALES[-1], False


def solve_stations(
    instance: Instance,
    options: Any,
    *,
    seed: int = 0,
    time_limit: float | None = None,
    one: Callable[..., MethodOutput] | None = None,
) -> MethodOutput:
    """The stations model of the module docstring, solved within ``time_limit``; without
    stations the sum of the completions is the makespan: ``one`` (the one-station ``cpsat``,
    passed in so that this module does not import :mod:`.method`) solves it."""
    if not instance.stations:  # ``one``: the one-station model
        assert one is not None
        options = replace(options, objective="makespan")
        return one(instance, options, seed=seed, time_limit=time_limit)
    from ...heuristics.baselines import single_task, whole_assembly

    budget = Budget(time_limit)
    objective = options.objective
    n, S = instance.n_tasks, len(instance.station_ids)
    check_model_memory("cpsat", n * n * (S + 1), BYTES_PER_CELL, "task x kit x station cells")
    packer = Packer(instance, max(0.2, 0.05 * budget.time_limit), budget)
    hint = _warm_start(instance, single_task(instance).plan, whole_assembly, objective)
    upper = get_objective(objective).horizon(instance, evaluate(instance, hint))
    closed = best_bound(instance)
    extra: dict[str, Any] = {"tray_mode": "benders", "objective": objective, "max_kits": n}
    cuts: list[tuple[frozenset[int], str | None]] = []
    best: Plan = hint
    proven, bound_model = False, None
    while not budget.expired():
        model, scale, exact = _build(instance, upper, closed, cuts, best, objective)
        extra.update(time_scale=scale, times_exact=exact)
        status, kits, lower = _run(model, options, seed, budget)
        extra["cpsat_status"] = status
        if kits is None:
            proven = status == "INFEASIBLE"  # nothing better than the warm start
            bound_model = upper * scale if proven else lower
            break
        plan, bad = _lay_out(instance, packer, kits)
        if bad:
            cuts += bad
            continue
        assert plan is not None
        if _value(instance, plan, objective) < _value(instance, best, objective):
            best = plan
        proven = status == "OPTIMAL"
        bound_model = lower
        break
    return _conclude(instance, best, proven, bound_model, closed, cuts, extra)


def _value(instance: Instance, plan: Plan, objective: str) -> float:
    return objective_of(evaluate(instance, plan), objective)


def _warm_start(instance: Instance, single: Plan | None, whole: Any, objective: str) -> Plan:
    """The better of the baselines' plans for ``objective`` (Whole Assembly only when its kits
    fit)."""
    from ...errors import KitDoesNotFit

    assert single is not None
    try:
        other = whole(instance).plan
    except KitDoesNotFit:
        return single
    better = _value(instance, other, objective) < _value(instance, single, objective)
    return other if better else single


def _build(
    instance: Instance,
    upper: float,
    closed: float,
    cuts: list[tuple[frozenset[int], str | None]],
    hint: Plan,
    objective: str,
) -> tuple[Any, int, bool]:
    """The CP-SAT model (module docstring) with ``C <= upper`` and ``C >= closed``, hinted
    with the kits of ``hint``, minimising ``objective``."""
    from ortools.sat.python import cp_model

    tasks = instance.tasks
    n = len(tasks)
    ids = instance.station_ids
    prm = instance.station_params
    r = [instance.robot_time(t.id) for t in tasks]
    h = [instance.human_time(t.id) for t in tasks]
    times = [*r, *h, instance.kit_overhead_robot]
    times += [v for p in prm.values() for v in (p.delivery_time, p.kit_overhead_human)]
    scale, exact = time_scale(times)

    def q(v: float) -> int:
        return round(v * scale)

    m = cp_model.CpModel()
    K = n
    x = [[m.new_bool_var(f"x{i}_{k}") for k in range(K)] for i in range(n)]
    u = [m.new_bool_var(f"u{k}") for k in range(K)]
    z = {s: [m.new_bool_var(f"z{s}_{k}") for k in range(K)] for s in ids}
    where = [ids.index(t.station) for t in tasks]
    _hint(m, instance, hint, x, u, z)
    for i in range(n):
        m.add_exactly_one(x[i])
    for k in range(K):
        m.add(sum(z[s][k] for s in ids) == u[k])
        m.add_bool_or([x[i][k] for i in range(n)]).only_enforce_if(u[k])
        for i in range(n):
            m.add_implication(x[i][k], z[ids[where[i]]][k])
        if k:
            m.add_implication(u[k], u[k - 1])
    p = [sum(k * x[i][k] for k in range(K)) for i in range(n)]
    idx = instance.index
    for a, b in instance.precedence:
        m.add(p[idx[a]] <= p[idx[b]])
    _area(m, instance, x)
    for members, _ in cuts:
        for k in range(K):
            m.add(sum(x[i][k] for i in members) <= len(members) - 1)
    hz = q(upper) + 1
    C = m.new_int_var(math.ceil(closed * scale - 1e-6), hz, "C")
    R = [
        q(instance.kit_overhead_robot) * u[k] + sum(q(r[i]) * x[i][k] for i in range(n))
        for k in range(K)
    ]
    D = [sum(q(prm[s].delivery_time) * z[s][k] for s in ids) for k in range(K)]
    H = [
        sum(q(prm[s].kit_overhead_human) * z[s][k] for s in ids)
        + sum(q(h[i]) * x[i][k] for i in range(n))
        for k in range(K)
    ]
    S = [m.new_int_var(0, hz, f"S{k}") for k in range(K)]
    A = [m.new_int_var(0, hz, f"A{k}") for k in range(K)]
    E = [m.new_int_var(0, hz, f"E{k}") for k in range(K)]
    for k in range(K):
        m.add(S[k] >= (A[k - 1] if k else 0))
        m.add(A[k] == S[k] + R[k] + D[k])
        m.add(E[k] >= A[k] + H[k])
        m.add(E[k] <= C)
    _station_rules(m, instance, z, S, E, H, q)
    m.minimize(_objective(m, instance, (z, E, C, hz), q, objective))
    return (m, x, C), scale, exact


def _objective(m: Any, instance: Instance, zec: Any, q: Any, objective: str) -> Any:
    """The registry's expression of ``objective`` (``zec``: the variables z, E, C and the
    horizon) on C, the completions ``C_s >= E_k`` (kits k of s; variables made only when it
    needs them) and the overheads ``sum_s o_H,s m_s``."""
    z, E, C, hz = zec
    prm = instance.station_params

    def completions() -> Any:
        done = {s: m.new_int_var(0, hz, f"C_{s}") for s in z}
        for s, zs in z.items():
            for k, e in enumerate(E):
                m.add(done[s] >= e).only_enforce_if(zs[k])
        return sum(done.values())

    def overhead() -> Any:
        return sum(q(prm[s].kit_overhead_human) * v for s, zs in z.items() for v in zs)

    return get_objective(objective).expression(ModelTerms(C, completions, overhead))


def _hint(m: Any, instance: Instance, plan: Plan, x: Any, u: Any, z: Any) -> None:
    """Hint the kits of ``plan`` (a valid plan: a complete first solution)."""
    at = {t: k for k, kit in enumerate(plan.kits) for t in kit.tasks}
    for i, t in enumerate(instance.tasks):
        for k, v in enumerate(x[i]):
            m.add_hint(v, at[t.id] == k)
    for k in range(len(u)):
        station = instance.station_of(plan.kits[k].tasks[0]) if k < len(plan.kits) else None
        m.add_hint(u[k], station is not None)
        for s, zs in z.items():
            m.add_hint(zs[k], s == station)


def _station_rules(m: Any, instance: Instance, z: Any, S: Any, E: Any, H: Any, q: Any) -> None:
    """Each station's human does its kits in order; its trays come back (module docstring)."""
    K = len(S)
    prm = instance.station_params
    for s, zs in z.items():
        trays = prm[s].tray_limit
        count = [sum(zs[:k]) for k in range(K + 1)]  # kits of s before position k
        for k in range(1, K):
            for j in range(k):
                m.add(E[k] >= E[j] + H[k]).only_enforce_if([zs[j], zs[k]])
                if trays is None:
                    continue
                far = m.new_bool_var("")
                m.add(count[k] - count[j] <= trays - 1).only_enforce_if(far.Not())
                back = E[j] - H[j] + q(prm[s].kit_overhead_human)
                m.add(S[k] >= back).only_enforce_if([zs[j], zs[k], far])


def _area(m: Any, instance: Instance, x: list[list[Any]]) -> None:
    """A kit's parts' true areas fit the tray's (a relaxation valid at any angle; areas in
    hundredths of mm^2, rounded down for parts and up for the tray)."""
    area = [
        math.floor(100 * sum(instance.part_types[p].area * c for p, c in t.parts))
        for t in instance.tasks
    ]
    cap = math.ceil(100 * instance.tray.area)
    for k in range(len(x)):
        terms = [area[i] * x[i][k] for i in range(len(x)) if area[i]]
        if terms:
            m.add(sum(terms) <= cap)


def _run(
    built: Any, options: Any, seed: int, budget: Budget
) -> tuple[str, list[list[int]] | None, float | None]:
    """Solve; the status name, the kits (task indices) of the best solution and the proven
    lower bound on C in scaled units."""
    from ortools.sat.python import cp_model

    model, x, _ = built
    solver = cp_model.CpSolver()
    solver.parameters.max_time_in_seconds = max(0.05, budget.remaining())
    solver.parameters.num_workers = max(1, options.workers)
    solver.parameters.random_seed = seed
    solver.parameters.log_search_progress = bool(options.log)
    status = stoppable.solve(solver, model)  # Ctrl-C and SIGTERM stop it (docs/cli.md)
    name = solver.status_name(status)
    if status not in (cp_model.OPTIMAL, cp_model.FEASIBLE):
        return name, None, None
    kits: dict[int, list[int]] = {}
    for i, xs in enumerate(x):
        for k, v in enumerate(xs):
            if solver.boolean_value(v):
                kits.setdefault(k, []).append(i)
    return name, [kits[k] for k in sorted(kits)], solver.best_objective_bound


def _lay_out(
    instance: Instance, packer: Packer, kits: list[list[int]]
) -> tuple[Plan | None, list[tuple[frozenset[int], str | None]]]:
    """The plan of ``kits`` with layouts, or the cuts of the kits that do not fit (with the
    proof's scope; None: unknown within the packing time)."""
    out, bad = [], []
    for kit in kits:
        tasks = kit_order(instance, [instance.tasks[i].id for i in kit])
        fit = packer.verdict(dict(instance.kit_parts(tasks)))
        if fit.fits:
            layout = packing_oracle.typed_to_placements(instance, tasks, fit.layout or {})
            out.append(Kit(tasks, layout))
        else:
            bad.append((frozenset(kit), fit.scope if fit.fits is False else None))
    return (None if bad else Plan(tuple(out))), bad


def _conclude(
    instance: Instance,
    plan: Plan,
    proven: bool,
    bound_model: float | None,
    closed: float,
    cuts: list[tuple[frozenset[int], str | None]],
    extra: dict[str, Any],
) -> MethodOutput:
    """The status and bounds the run proved (module docstring)."""
    makespan = evaluate(instance, plan).makespan
    scopes = {scope for _, scope in cuts}
    scope = None if None in scopes else AXIS_ALIGNED if AXIS_ALIGNED in scopes else ANY_ANGLE
    exact = bool(extra.get("times_exact"))
    model_s = None if bound_model is None else bound_model / extra["time_scale"]
    optimal_axis = proven and exact and scope is not None
    optimal = optimal_axis and scope == ANY_ANGLE
    bound_axis = max(closed, model_s) if model_s is not None and exact and scope else closed
    bound = makespan if optimal else (bound_axis if scope == ANY_ANGLE else closed)
    objective = extra["objective"]
    if not is_top_level(objective):  # the model's bound is on that objective, not the makespan
        bound = bound_axis = closed
        # a proof only on exact times and for the plans of the cuts' scope
        low = model_s if model_s is not None and exact and scope is not None else None
        lows = (low if scope == ANY_ANGLE else None, low)
        proofs = (optimal, optimal_axis)
        extra.update(objective_extra(instance, plan, objective, lows, proofs, model_scale=True))
    extra.update(
        cuts=len(cuts),
        makespan=makespan,
        optimal_axis_aligned=optimal_axis,
        bound_axis_aligned=makespan if optimal_axis else bound_axis,
        bound_closed_form=closed,
        **scope_claims(scope),
    )
    status = Status.OPTIMAL if optimal else Status.FEASIBLE
    return MethodOutput(plan, status, min(bound, makespan), extra, status_objective=objective)
