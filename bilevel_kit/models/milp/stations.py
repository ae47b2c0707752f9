r"""``milp`` on an instance with several assembly stations (docs/timeline.md#several-stations).

A master of its own, beside the one-station model of :mod:`.model` (which it leaves alone),
solved by the same Benders loop (:mod:`.method`). Kit positions k = 0..K-1 (K = n),
``x[i,k]`` = task i in kit k, ``u[k]`` = kit k used (used kits first), ``z[s,k]`` = kit k is
for station s (one per used kit, and every task of the kit on it: a kit never mixes
stations). With continuous robot starts ``S_k`` and human ends ``E_k``::

    R_k = o_R u_k + sum_i r_i x[i,k]     D_k = sum_s d_s z[s,k]
    H_k = sum_s o_H,s z[s,k] + sum_i h_i x[i,k]
    S_k >= A_{k-1},  A_k = S_k + R_k + D_k,  E_k >= A_k + H_k,  C >= E_k

Each station's human and trays are followed by two running values per station and position,
``F[s,k]`` (the end of s's last kit at or before k) and ``G[s,k]`` (the time its tray is
back, o_H,s after its human start; 0 while s has no kit)::

    F[s,k] >= F[s,k-1],  F[s,k] >= E_k - M (1 - z[s,k])
    E_k >= F[s,k-1] + H_k - M (1 - z[s,k])                       (s's human, in order)
    G[s,k] >= G[s,k-1],  G[s,k] >= E_k - H_k + o_H,s - M (1 - z[s,k])
    S_k >= G[s,k-1] - M (1 - z[s,k])                             (one tray: T_s = 1)
    S_k >= E_j - H_j + o_H,s - M (3 - z[s,j] - z[s,k] - f[s,j,k])   (T_s >= 2, j < k)
    sum_{j<=q<k} z[s,q] <= T_s - 1 + K f[s,j,k]

(with ``T_s >= 2`` the binary ``f[s,j,k]`` must be 1 when at least ``T_s`` kits of s lie in
positions j..k-1, i.e. j is the ``T_s``-th previous kit of s or earlier; human starts of a
station are non-decreasing, so the earlier ones add nothing). The ``o_H,s`` of the one-tray
rule is inside ``G``: written as ``S_k >= G[s,k-1] + o_H,s`` with ``G`` the human start, the
first kit of s at a position k >= 1 waited for a tray that was never out (``G = 0``): the
robot start was at least ``o_H,s`` though it is ``A_{k-1}`` (docs/timeline.md#several-stations:
the second term is absent while s has fewer than ``T_s`` kits out), a master that priced
such plans too high and proved a worse one optimal (issue 35, item 1;
tests/models/test_milp_stations.py). Every constraint is a lower
bound, so every solution's C is at least its plan's makespan and the timeline itself is a
solution: the optimum is the optimal makespan. Every variable is bounded by the incumbent's
makespan U (``C <= U``), so ``M = U + sum_i h_i + max_s o_H,s`` is valid.

Precedence is disaggregated as in :mod:`.model` (no chain symmetry: equal chains on two
stations are not interchangeable); ``sum_k u_k`` is at least the area bound and the number of
stations. The tray's area relaxation and the no-good cuts are :mod:`.model`'s. The incumbent
and ``U`` are the better of the baselines' plans (which interleave stations by earliest need).
The objective is the makespan ``C``, the sum of the completions ``sum_s F[s,K-1]``, or the
total human idle less the constant ``sum_i h_i``, ``sum_s F[s,K-1] - sum_s o_H,s sum_k
z[s,k]`` (exactly: the human's work depends on the kit counts), with ``U`` from
:meth:`bilevel_kit.objectives.Objective.horizon` (docs/formulations.md); ``hint`` is refused,
and ``tray`` is always the Benders loop from the area relaxation, as in cpsat's stations
model (seeding the cuts of every pair of tasks that does not fit, ``tray=auto`` for one
station, adds cuts proven for 0/90-degree layouts only, so 14 of the 24 random instances of
tests/models/test_milp_stations.py were then proven optimal only among such plans, against 4
without them).
"""

from __future__ import annotations

import functools
from collections.abc import Sequence
from typing import Any

from ... import bounds
from ...bounds import min_kits
from ...errors import KitDoesNotFit, UsageError
from ...instance import Instance, StationParams
from ...objectives import ModelTerms
from ...objectives import get as get_objective
from ...plan import Plan, evaluate
from ...stations import objective_of
from .model import Master, _Data, _tray, model_objective

#: :func:`bilevel_kit.bounds.objective_extra` with the master's bounds (for every plan, for
#: 0/90-degree plans) on its own scale, the constant ``sum_i h_i`` dropped for the human idle.
objective_extra = functools.partial(bounds.objective_extra, model_scale=True)


def incumbent(
    instance: Instance, objective: str, hint: str
) -> tuple[list[list[str]] | None, float | None, float | None, int]:
    """The better of the baselines' plans for ``objective`` as kits, its master objective
    (:func:`.model.model_objective`), the horizon ``U``
    (:meth:`bilevel_kit.objectives.Objective.horizon`) and the kit cap K = n; a
    UsageError for a hint."""
    from ...heuristics.baselines import single_task, whole_assembly

    if hint != "none":
        raise UsageError(
            "milp: with several stations only hint=none is modelled (docs/timeline.md)"
        )
    plans: list[Plan] = []
    for method in (single_task, whole_assembly):
        try:
            out = method(instance)
        except KitDoesNotFit:
            continue
        assert out.plan is not None
        plans.append(out.plan)
    if not plans:  # every task fits alone (checked before), so single-task always plans
        raise KitDoesNotFit(f"{instance.source}: no baseline plan for the milp incumbent")
    best = min(plans, key=lambda p: objective_of(evaluate(instance, p), objective))
    tl = evaluate(instance, best)
    kits = [list(k.tasks) for k in best.kits]
    upper = get_objective(objective).horizon(instance, tl)
    return kits, model_objective(instance, tl, objective), upper, instance.n_tasks


def model_cells(instance: Instance, K: int) -> int:
    """The model's size in task x kit cells, with its station and tray-pair binaries."""
    pairs = sum(1 for p in instance.station_params.values() if (p.tray_limit or 0) >= 2)
    return instance.n_tasks * K + len(instance.station_ids) * K * (2 + K * pairs)


def build(
    instance: Instance, K: int, upper: float, lower: float, objective: str = "makespan"
) -> Master:
    """The master of the module docstring with K kit positions, ``lower <= C <= upper``,
    minimising ``objective``."""
    import pyomo.environ as pyo

    data = _Data.of(instance, K)
    ids = range(len(instance.station_ids))  # station positions index the variables
    hz = upper * (1 + 1e-9) + 1e-6
    m = pyo.ConcreteModel(name="milp_stations")
    m.x = pyo.Var(data.keys, domain=pyo.Binary)
    m.u = pyo.Var(range(K), domain=pyo.Binary)
    m.z = pyo.Var(ids, range(K), domain=pyo.Binary)
    m.S = pyo.Var(range(K), bounds=(0.0, hz))
    m.E = pyo.Var(range(K), bounds=(0.0, hz))
    m.F = pyo.Var(ids, range(K), bounds=(0.0, hz))
    m.G = pyo.Var(ids, range(K), bounds=(0.0, hz))
    m.C = pyo.Var(bounds=(max(0.0, min(lower, upper)), hz))
    m.u[0].fix(1)
    m.cons = pyo.ConstraintList()
    _assignment(m, instance, data, K)
    _precedence(m, instance, data)
    _timeline(m, instance, data, K, hz)
    m.obj = pyo.Objective(expr=_objective(m, instance, K, objective), sense=pyo.minimize)
    master = Master(m, K, data.ids, {key: m.x[key] for key in data.keys})
    _tray(master, instance, data)
    return master


def _objective(m: Any, instance: Instance, K: int, objective: str) -> Any:
    """The registry's expression of ``objective`` on C, the completions ``F[s,K-1]`` and the
    overheads ``sum_s o_H,s m_s``."""
    ids = range(len(instance.station_ids))
    prm = [instance.station_params[s] for s in instance.station_ids]
    terms = ModelTerms(
        m.C,
        lambda: sum(m.F[s, K - 1] for s in ids),
        lambda: sum(prm[s].kit_overhead_human * m.z[s, k] for s in ids for k in range(K)),
    )
    return get_objective(objective).expression(terms)


def _assignment(m: Any, instance: Instance, data: _Data, K: int) -> None:
    """Every task in one kit, a used kit on one station with all its tasks, used kits first."""
    add = m.cons.add
    ids = range(len(instance.station_ids))
    where = [instance.station_ids.index(t.station) for t in instance.tasks]
    for i in range(len(data.ids)):
        add(sum(m.x[i, k] for k in range(data.ub[i])) == 1)
    for k in range(K):
        add(sum(m.z[s, k] for s in ids) == m.u[k])
        for i in data.at_k[k]:
            add(m.x[i, k] <= m.z[where[i], k])
        add(m.u[k] <= sum(m.x[i, k] for i in data.at_k[k]))
        if k:
            add(m.u[k] <= m.u[k - 1])
    add(sum(m.u[k] for k in range(K)) >= min(K, max(min_kits(instance), len(ids))))


def _precedence(m: Any, instance: Instance, data: _Data) -> None:
    """``sum_{q<=k} x[b,q] <= sum_{q<=k} x[a,q]`` for every edge a -> b (the disaggregated
    form of :mod:`.model`)."""
    from ..common import reduced_edges

    idx, ub = data.idx, data.ub
    for a_id, b_id in reduced_edges(instance):
        a, b = idx[a_id], idx[b_id]
        for k in range(min(ub[a], ub[b]) - 1):
            m.cons.add(sum(m.x[b, q] for q in range(k + 1)) <= sum(m.x[a, q] for q in range(k + 1)))


def _timeline(m: Any, instance: Instance, data: _Data, K: int, hz: float) -> None:
    """The shared robot, each station's human and trays (module docstring)."""
    add = m.cons.add
    prm = [instance.station_params[s] for s in instance.station_ids]
    ids = range(len(prm))
    big = hz + sum(data.h) + max(p.kit_overhead_human for p in prm)
    H: list[Any] = []
    arrive: Any = 0.0
    for k in range(K):
        R = data.o_r * m.u[k] + sum(data.r[i] * m.x[i, k] for i in data.at_k[k])
        D = sum(prm[s].delivery_time * m.z[s, k] for s in ids)
        H.append(
            sum(prm[s].kit_overhead_human * m.z[s, k] for s in ids)
            + sum(data.h[i] * m.x[i, k] for i in data.at_k[k])
        )
        add(m.S[k] >= arrive)
        arrive = m.S[k] + R + D
        add(m.E[k] >= arrive + H[k])
        add(m.E[k] <= m.C)
        for s in ids:
            off = big * (1 - m.z[s, k])
            add(m.F[s, k] >= m.E[k] - off)
            add(m.G[s, k] >= m.E[k] - H[k] + prm[s].kit_overhead_human - off)
            if k:
                add(m.F[s, k] >= m.F[s, k - 1])
                add(m.G[s, k] >= m.G[s, k - 1])
                add(m.E[k] >= m.F[s, k - 1] + H[k] - off)
    for s in ids:
        _trays(m, prm[s], s, H, big)


def _trays(m: Any, params: StationParams, s: int, H: list[Any], big: float) -> None:
    """The tray rule of station ``s`` (its position): through ``G`` (the tray is back, ``o_H``
    included) with one tray, pairwise with more."""
    import pyomo.environ as pyo

    K = len(H)
    trays, o_h = params.tray_limit, params.kit_overhead_human
    if trays is None:
        return
    add = m.cons.add
    for k in range(1, K):
        if trays == 1:
            add(m.S[k] >= m.G[s, k - 1] - big * (1 - m.z[s, k]))
            continue
        for j in range(k):
            f = pyo.Var(domain=pyo.Binary)
            m.add_component(f"f_{s}_{j}_{k}", f)
            add(sum(m.z[s, q] for q in range(j, k)) <= trays - 1 + K * f)
            add(m.S[k] >= m.E[j] - H[j] + o_h - big * (3 - m.z[s, j] - m.z[s, k] - f))


def set_start(master: Master, instance: Instance, kits: Sequence[Sequence[str]]) -> None:
    """Load a plan's kits, stations and tray binaries (a MIP start; HiGHS completes the
    continuous values)."""
    m = master.model
    if len(kits) > master.K:
        return
    where = {t: k for k, kit in enumerate(kits) for t in kit}
    for (i, k), v in master.x.items():
        v.set_value(float(where[master.ids[i]] == k), skip_validation=True)
    station = [instance.station_ids.index(instance.station_of(kit[0])) for kit in kits]
    for k in range(master.K):
        if k:
            m.u[k].set_value(float(k < len(kits)), skip_validation=True)
        for s in range(len(instance.station_ids)):
            m.z[s, k].set_value(float(k < len(kits) and station[k] == s), skip_validation=True)
    for s, sid in enumerate(instance.station_ids):
        trays = instance.station_params[sid].tray_limit
        if trays is None or trays < 2:
            continue
        for k in range(1, master.K):
            for j in range(k):
                count = sum(1 for q in range(j, min(k, len(kits))) if station[q] == s)
                f = getattr(m, f"f_{s}_{j}_{k}")
                f.set_value(float(count >= trays), skip_validation=True)
    for (t, k, c), var in master.lam.items():
        have = instance.kit_parts(kits[k]).get(t, 0) if k < len(kits) else 0
        var.set_value(float(have <= c - 1), skip_validation=True)
