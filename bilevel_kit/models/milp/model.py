r"""The MILP schedule model (docs/formulations.md), a position-based batching MILP in Pyomo.

**Variables.** Kit positions k = 0..K-1. ``x[i,k]`` = task i is in kit k (only for
:math:`k < n - |\mathrm{desc}(i)|`, since every earlier kit needs a task that is not a
descendant of i), ``u[k]`` = kit k is used, ``E[k]`` = the human's end of kit k (continuous).

**Constraints.**

* assignment :math:`\sum_k x_{ik} = 1`; linking :math:`x_{ik} \le u_k \le \sum_i x_{ik}`;
  symmetry :math:`u_{k+1} \le u_k` (used kits first), :math:`\sum_k u_k \ge m_{\min}` (area);
* precedence, for every edge a -> b of the transitive reduction, in the disaggregated form
  :math:`\sum_{k' \le k} x_{b k'} \le \sum_{k' \le k} x_{a k'}` for all k (it implies
  :math:`\sum_k k\,x_{ak} \le \sum_k k\,x_{bk}` and has a stronger LP relaxation);
  inside a kit the human follows a topological order, which the returned plan lists;
* interchangeable precedence chains (same task data, same predecessors of the head and
  successors of the tail, e.g. the legs of one table) have lexicographically ordered kit
  vectors :math:`(p_{c_1}, .., p_{c_L})` (relabelling the chains maps any plan to one that
  satisfies it), written as one linear inequality: positions are < K, so lex order is the order
  of :math:`\sum_j K^{L-j} p_{c_j}` (a prefix of the chain when :math:`K^{L-1} > 10^6`); the
  heads' order is also added in the disaggregated form;
* the timeline of docs/timeline.md, exactly::

      R_k = o_R u_k + sum_i r_i x[i,k]        H_k = o_H u_k + sum_i h_i x[i,k]
      A_k = sum_{k' <= k} (R_k' + d u_k')     (arrival; the robot is busy while delivering)
      E_k >= A_k + H_k,   E_k >= E_{k-1} + H_k,   C = E_{K-1}

  An unused kit has R = H = 0 and adds no d and no overhead, so it adds no time; E only
  needs ``>=`` because the objective pushes C down to the max. With T trays (the instance's
  tray limit) the robot start of kit k > T is a variable ``S_k`` and the arrivals become
  :math:`A_k = S_k + R_k + d u_k` with

      S_k >= A_{k-1},   S_k >= E_{k-T} - H_{k-T} + o_H u_k

  (docs/timeline.md: the tray of kit k - T is back o_H after the human started it, at
  E - H). Every constraint is monotone, so the least solution is the true timeline; the
  ``o_H u_k`` term replaces a big-M: on an unused kit the bound is the human start of kit
  k - T, at most the last used kit's end, so unused trailing kits cannot inflate C. No big-M
  is needed here; the variable bound
  :math:`E_k \le M = \sum_i (r_i + h_i) + K (o_R + o_H + d)` (a schedule without any
  overlap, valid for every number of trays) is derived from the data, and ``C <= U`` with U
  the makespan of a quick feasible plan;
* the closed-form bounds of :mod:`bilevel_kit.bounds` on C, also with the model's own kit count
  :math:`m = \sum_k u_k` in place of :math:`m_{\min}` (redundant, they lift the LP bound;
  with one tray the robot bound includes the wait :math:`(m - 1) o_H` for the tray), among
  them the flow-shop bound (d) as the two lines :math:`C \ge c_l + s_l m` of
  :func:`bilevel_kit.bounds.johnson_lines` (Johnson's makespan of the tasks and m overhead
  jobs; exact on the Johnson special case: d = 0, no overheads, no precedence);
* the tray's area relaxation :math:`\sum_i a_i x_{ik} \le W H` (areas on the packing grid of
  :mod:`~bilevel_kit.models.packing`, sizes rounded up, tray down) and the no-good cuts
  of :func:`add_cut`: :math:`\bigvee_t c_{tk} \le M_t - 1` with
  :math:`c_{tk} = \sum_i n_{it} x_{ik}` the number of parts of type t in kit k, linearised
  with one binary :math:`\lambda_{tkc}` per (type, kit, threshold) as
  :math:`c_{tk} \le (c - 1) + (N_t - c + 1)(1 - \lambda_{tkc})` (big-M :math:`N_t - c + 1`
  from the total count :math:`N_t` of type t) and :math:`\sum_{t \in M} \lambda_{t k M_t}
  \ge 1`. Every super-multiset of M fails too, so no feasible plan is cut off.

**Objective.** The registry's expression (:mod:`bilevel_kit.objectives`): ``makespan``:
minimise C. ``human_idle``: minimise :math:`C - o_H \sum_k u_k` (= human idle + the constant
:math:`\sum_i h_i`).

The incumbent is passed to the solver as a MIP start (:func:`set_start`), after relabelling
its chains into the lexicographic order the model requires (:func:`canonical_kits`).

**Several stations** (docs/timeline.md#several-stations; docs/formulations.md). One station is
the S = 1 case: everything above is the model, and the variables and constraints below appear
only when the instance declares ``stations``. K = n kit positions; ``z[s,k]`` = kit k is for
station s (one per used kit, every task of the kit on it: a kit never mixes stations). With
continuous robot starts ``S_k`` and human ends ``E_k``::

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
positions j..k-1; human starts of a station are non-decreasing, so the earlier ones add
nothing). The ``o_H,s`` of the one-tray rule is inside ``G``: written as
``S_k >= G[s,k-1] + o_H,s`` with ``G`` the human start, the first kit of s at a position
k >= 1 waited for a tray that was never out and the master proved a worse plan optimal
(issue 35, item 1; tests/models/test_milp_stations.py). Every constraint is a lower bound, so
the timeline is the least solution; every variable is bounded by the horizon U
(:meth:`bilevel_kit.objectives.Objective.horizon`), so ``M = U + sum_i h_i + max_s o_H,s`` is
valid. No chain symmetry is broken (equal chains on two stations are not interchangeable);
``sum_k u_k`` is at least the area bound and the number of stations. The objective is the
registry's expression on C, the completions ``sum_s F[s,K-1]`` and the overheads
``sum_s o_H,s sum_k z[s,k]`` (the human's work depends on the kit counts).
"""

from __future__ import annotations

import functools
import itertools
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

from ... import bounds
from ...bounds import end_tasks, johnson_lines, kit_slacks, lower_bounds, min_kits, tray_wait
from ...instance import Instance, StationParams, topological_order
from ...objectives import ModelTerms, is_top_level
from ...objectives import get as get_objective
from ...plan import Kit, Plan, Timeline, evaluate
from .. import packing
from ..common import (
    assignment_cells,
    chain_groups,
    kit_order,
    kit_positions,
    reduced_edges,
    relabel_chains,
)
from .solver import TOL

human_order = kit_order  # the human's order inside a kit (one definition: common.py)
#: :func:`bilevel_kit.bounds.objective_extra` with the master's bounds (for every plan, for
#: 0/90-degree plans) on its own scale, the constant ``sum_i h_i`` dropped for the human idle.
objective_extra = functools.partial(bounds.objective_extra, model_scale=True)


def objective_value(instance: Instance, kits: Sequence[Sequence[str]], objective: str) -> float:
    """The model's objective of a plan (the registry's expression on its makespan and its
    ``o_H`` times its kit count); with several stations the stations master's
    (:func:`model_objective`)."""
    tl = evaluate(instance, Plan(tuple(Kit(tuple(k)) for k in kits)))
    if instance.stations:
        return model_objective(instance, tl, objective)
    o_h = instance.params_of().kit_overhead_human
    terms = ModelTerms.one_station(tl.makespan, lambda: o_h * len(kits))
    return get_objective(objective).expression(terms)


def model_objective(instance: Instance, tl: Timeline, objective: str) -> float:
    """The master's objective of a plan's timeline with several stations: the
    registry's :meth:`~bilevel_kit.objectives.Objective.model_value` (for ``human_idle`` the
    total idle plus the constant ``sum_i h_i`` it drops)."""
    return get_objective(objective).model_value(instance, tl)


@dataclass
class Master:
    """The Pyomo model with what the Benders loop needs: ``x`` (task, kit) -> binary,
    ``counts`` (type, kit) -> part-count expression, ``total`` parts per type and ``lam`` the
    cut binaries (type, kit, threshold)."""

    model: Any
    K: int
    ids: list[str]
    x: dict[tuple[int, int], Any]
    counts: dict[tuple[str, int], Any] = field(default_factory=dict)
    total: dict[str, int] = field(default_factory=dict)
    lam: dict[tuple[str, int, int], Any] = field(default_factory=dict)
    n_cuts: int = 0


@dataclass
class _Data:
    """Instance data the builder needs: times, the kit range ``ub[i]`` of each task, the
    (task, kit) keys of ``x`` and the tasks that may sit in each kit."""

    ids: list[str]
    idx: dict[str, int]
    r: list[float]
    h: list[float]
    o_r: float
    ub: list[int]
    keys: list[tuple[int, int]]
    at_k: list[list[int]]

    @classmethod
    def of(cls, instance: Instance, K: int) -> _Data:
        ids = [t.id for t in instance.tasks]
        ub = kit_positions(instance, K)
        keys = [(i, k) for i in range(len(ids)) for k in range(ub[i])]
        at_k: list[list[int]] = [[] for _ in range(K)]
        for i, k in keys:
            at_k[k].append(i)
        return cls(
            ids=ids,
            idx=instance.index,
            r=[instance.robot_time(t) for t in ids],
            h=[instance.human_time(t) for t in ids],
            o_r=instance.kit_overhead_robot,
            ub=ub,
            keys=keys,
            at_k=at_k,
        )


def build(
    instance: Instance,
    K: int,
    upper: float | None,
    objective: str,
    lower: float | None = None,
) -> Master:
    """The master model of the module docstring with K kit positions (``upper``: C <= U;
    ``lower``: C >= L, a proven makespan bound, for the makespan objective); the station
    variables only with several stations (then ``upper`` is required: the horizon of every
    variable and of the big-M). The per-count bounds of :mod:`bilevel_kit.models.relax`,
    which ``cpsat`` adds, made HiGHS up to 3x slower on 12-task flow shops (5.6 s against
    15.6 s), the single bound did not."""
    import pyomo.environ as pyo

    data = _Data.of(instance, K)
    m = pyo.ConcreteModel(name="milp_schedule")
    m.x = pyo.Var(data.keys, domain=pyo.Binary)
    m.u = pyo.Var(range(K), domain=pyo.Binary)
    if instance.stations:
        if upper is None:
            raise ValueError("the stations master needs the incumbent's horizon U")
        hz = upper * (1 + 1e-9) + 1e-6
        _station_variables(m, instance, K, hz, lower or 0.0)
    else:
        one = instance.params_of()  # one station: d and o_H (several: per station, below)
        big_m = (
            sum(data.r) + sum(data.h) + K * (data.o_r + one.kit_overhead_human + one.delivery_time)
        )
        m.E = pyo.Var(range(K), bounds=(0.0, big_m))
    m.u[0].fix(1)
    m.cons = pyo.ConstraintList()
    _assignment(m, instance, data, K)
    _precedence(m, instance, data, K)
    if instance.stations:
        _station_timeline(m, instance, data, K, hz)
        m.obj = pyo.Objective(expr=_station_objective(m, instance, K, objective))
    else:
        _timeline(m, instance, data, K, upper, objective)
        if lower is not None and is_top_level(objective) and math.isfinite(lower) and lower > 0:
            m.cons.add(m.E[K - 1] >= lower)
    master = Master(m, K, data.ids, {key: m.x[key] for key in data.keys})
    _tray(master, instance, data)
    return master


def _assignment(m: Any, instance: Instance, data: _Data, K: int) -> None:
    """Every task in one kit; used kits first, at least ``m_min`` of them; with several
    stations a used kit on one station with all its tasks, at least one kit per station."""
    add = m.cons.add
    ids = range(len(instance.station_ids))
    where = [instance.station_ids.index(t.station) for t in instance.tasks]
    for i in range(len(data.ids)):
        add(sum(m.x[i, k] for k in range(data.ub[i])) == 1)
    for k in range(K):
        if instance.stations:
            add(sum(m.z[s, k] for s in ids) == m.u[k])
        for i in data.at_k[k]:
            add(m.x[i, k] <= (m.z[where[i], k] if instance.stations else m.u[k]))
        add(m.u[k] <= sum(m.x[i, k] for i in data.at_k[k]))
        if k:
            add(m.u[k] <= m.u[k - 1])
    least = max(min_kits(instance), len(ids)) if instance.stations else min_kits(instance)
    add(sum(m.u[k] for k in range(K)) >= min(K, least))


def _precedence(m: Any, instance: Instance, data: _Data, K: int) -> None:
    """Precedence and the chains' symmetry breaking (module docstring; none with several
    stations: equal chains on two stations are not interchangeable)."""
    add = m.cons.add
    idx, ub = data.idx, data.ub

    def before(a: int, b: int) -> None:
        # disaggregated: y_b(k) <= y_a(k) with y_i(k) = sum_{k' <= k} x[i,k']
        for k in range(min(ub[a], ub[b]) - 1):
            add(sum(m.x[b, q] for q in range(k + 1)) <= sum(m.x[a, q] for q in range(k + 1)))

    for a_id, b_id in reduced_edges(instance):
        before(idx[a_id], idx[b_id])
    if instance.stations:
        return

    # symmetry: interchangeable chains in lexicographic order of their kit vectors, as one
    # linear inequality (positions < K, so lex order = order of sum_j K^(L-1-j) p_{c_j}),
    # plus the heads' order in the disaggregated (LP-stronger) form
    def pos(i: int) -> Any:
        return sum(k * m.x[i, k] for k in range(1, ub[i]))

    for group in chain_groups(instance):
        chains = sorted([idx[t] for t in c] for c in group)
        length = len(chains[0])
        while length > 1 and K ** (length - 1) > 1e6:  # a lex prefix is valid too
            length -= 1
        for c1, c2 in itertools.pairwise(chains):
            add(sum(K ** (length - 1 - j) * (pos(c1[j]) - pos(c2[j])) for j in range(length)) <= 0)
            before(c1[0], c2[0])


def _timeline(
    m: Any, instance: Instance, data: _Data, K: int, upper: float | None, objective: str
) -> None:
    """The timeline, the closed-form bounds on C, ``C <= U`` and the objective."""
    import pyomo.environ as pyo

    add = m.cons.add
    one = instance.params_of()  # one station (several: :func:`_station_timeline`)
    r, h, o_r = data.r, data.h, data.o_r
    d, o_h, trays = one.delivery_time, one.kit_overhead_human, one.tray_limit
    if trays is not None and trays < K:
        m.S = pyo.Var(range(trays, K), bounds=(0.0, m.E[0].ub))  # robot starts (tray rule)
    arrive: Any = 0.0
    human: list[Any] = []
    for k in range(K):
        R = o_r * m.u[k] + sum(r[i] * m.x[i, k] for i in data.at_k[k])
        Hk = o_h * m.u[k] + sum(h[i] * m.x[i, k] for i in data.at_k[k])
        if trays is not None and k >= trays:
            # the tray of kit k - T is back o_H after its human start E - H (docs/timeline.md)
            add(m.S[k] >= arrive)
            add(m.S[k] >= m.E[k - trays] - human[k - trays] + o_h * m.u[k])
            arrive = m.S[k]
        arrive = arrive + R + d * m.u[k]
        add(m.E[k] >= arrive + Hk)
        if k:
            add(m.E[k] >= m.E[k - 1] + Hk)
        human.append(Hk)
    cmax = m.E[K - 1]
    lb = lower_bounds(instance)
    add(cmax >= max(lb["human"], lb["robot"], lb["flow"]))
    # the same bounds with the model's own kit count m = sum_k u_k (valid for integer plans:
    # the last kit holds a sink, the first a source; see :mod:`bilevel_kit.bounds`)
    sources, sinks = end_tasks(instance)
    n_used = sum(m.u[k] for k in range(K))
    w = tray_wait(instance)  # one tray: the robot waits o_H per kit after the first
    add(cmax >= sum(r) + (o_r + d + w) * n_used - w + o_h + min(h[i] for i in sinks))
    add(cmax >= min(r[i] for i in sources) + o_r + d + sum(h) + o_h * n_used)
    # the flow-shop bound (d) of :mod:`bilevel_kit.bounds` with the model's own kit count
    for c, slope in johnson_lines(r, h, o_r + d, o_h):
        add(cmax >= c + slope * n_used)
    if upper is not None:
        add(cmax <= upper)
    terms = ModelTerms.one_station(cmax, lambda: o_h * sum(m.u[k] for k in range(K)))
    m.obj = pyo.Objective(expr=get_objective(objective).expression(terms), sense=pyo.minimize)


def _station_variables(m: Any, instance: Instance, K: int, hz: float, lower: float) -> None:
    """The station variables (module docstring): ``z``, the robot starts ``S``, the human ends
    ``E``, the running ``F`` and ``G``, and ``C`` in ``[lower, U]``."""
    import pyomo.environ as pyo

    ids = range(len(instance.station_ids))  # station positions index the variables
    m.z = pyo.Var(ids, range(K), domain=pyo.Binary)
    m.S = pyo.Var(range(K), bounds=(0.0, hz))
    m.E = pyo.Var(range(K), bounds=(0.0, hz))
    m.F = pyo.Var(ids, range(K), bounds=(0.0, hz))
    m.G = pyo.Var(ids, range(K), bounds=(0.0, hz))
    m.C = pyo.Var(bounds=(max(0.0, min(lower, hz)), hz))


def _station_objective(m: Any, instance: Instance, K: int, objective: str) -> Any:
    """The registry's expression of ``objective`` on C, the completions ``F[s,K-1]`` and the
    overheads ``sum_s o_H,s m_s``."""
    ids = range(len(instance.station_ids))
    prm = [instance.params_of(s) for s in instance.station_ids]
    terms = ModelTerms(
        m.C,
        lambda: sum(m.F[s, K - 1] for s in ids),
        lambda: sum(prm[s].kit_overhead_human * m.z[s, k] for s in ids for k in range(K)),
    )
    return get_objective(objective).expression(terms)


def _station_timeline(m: Any, instance: Instance, data: _Data, K: int, hz: float) -> None:
    """The shared robot, each station's human and trays (module docstring)."""
    add = m.cons.add
    prm = [instance.params_of(s) for s in instance.station_ids]
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
        _station_trays(m, prm[s], s, H, big)


def _station_trays(m: Any, params: StationParams, s: int, H: list[Any], big: float) -> None:
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


def model_cells(instance: Instance, K: int) -> int:
    """The model's size in task x kit cells (:func:`..common.assignment_cells`), with several
    stations the station and tray-pair binaries too (its size grows with them)."""
    if not instance.stations:
        return assignment_cells(instance, K)
    pairs = sum(1 for p in instance.station_params.values() if (p.tray_limit or 0) >= 2)
    return instance.n_tasks * K + len(instance.station_ids) * K * (2 + K * pairs)


def _tray(master: Master, instance: Instance, data: _Data) -> None:
    """The area relaxation on the packing grid (the oracle's notion of "fits") and the part
    counts per (type, kit) that the cuts use."""
    m, K = master.model, master.K
    tray = instance.tray
    W = packing.grid_down(tray.width, 1.0)
    H = packing.grid_down(tray.height, 1.0)
    garea = {
        p.id: packing.grid_up(p.width, 1.0) * packing.grid_up(p.height, 1.0)
        for p in instance.part_types.values()
    }
    area = [sum(garea[p] * c for p, c in t.parts) for t in instance.tasks]
    if sum(area) > W * H:
        for k in range(K):
            terms = [area[i] * m.x[i, k] for i in data.at_k[k] if area[i]]
            if terms:
                m.cons.add(sum(terms) <= W * H)
    master.total = dict(instance.kit_parts(data.ids))
    for t in instance.part_types:
        for k in range(K):
            terms = [
                c * m.x[i, k] for i in data.at_k[k] for q, c in instance.tasks[i].parts if q == t
            ]
            if terms:
                master.counts[(t, k)] = sum(terms)


def add_cut(master: Master, counts: Mapping[str, int]) -> None:
    """Forbid the multiset ``counts`` (and every super-multiset) in every kit."""
    import pyomo.environ as pyo

    m = master.model
    for k in range(master.K):
        lits: list[Any] = []
        for t, c in counts.items():
            expr = master.counts.get((t, k))
            if expr is None:
                lits = []
                break  # kit k can never hold a part of type t: the cut holds there
            key = (t, k, c)
            if key not in master.lam:
                name = f"lam_{len(master.lam)}"
                var = pyo.Var(domain=pyo.Binary)
                m.add_component(name, var)
                m.cons.add(expr <= (c - 1) + (master.total[t] - c + 1) * (1 - var))
                master.lam[key] = var
            lits.append(master.lam[key])
        if lits:
            m.cons.add(sum(lits) >= 1)
    master.n_cuts += 1


def set_start(master: Master, instance: Instance, kits: Sequence[Sequence[str]]) -> None:
    """Load a plan into the master's variables (a MIP start); its kits are put into the
    canonical chain order first, so the start satisfies the symmetry constraints (several
    stations: :func:`_set_station_start`)."""
    m = master.model
    if len(kits) > master.K:
        return
    if instance.stations:
        _set_station_start(master, instance, kits)
        return
    kits = canonical_kits(instance, kits)
    where = {t: k for k, kit in enumerate(kits) for t in kit}
    for (i, k), v in master.x.items():
        v.set_value(float(where[master.ids[i]] == k), skip_validation=True)
    tl = evaluate(instance, Plan(tuple(Kit(tuple(k)) for k in kits)))
    end = arrive = 0.0
    starts: list[float] = []  # human starts (of an unused kit: its end)
    trays = instance.params_of().tray_limit
    for k in range(master.K):
        if k < len(kits):
            kt = tl.kits[k]
            start, arrive, end = kt.robot_start, kt.arrive, kt.human_end
            starts.append(kt.human_start)
        else:  # the least values of the constraints on an unused kit (module docstring)
            start = arrive
            if trays is not None and k >= trays:
                start = max(start, starts[k - trays])
            arrive = start
            starts.append(max(arrive, end))
            end = starts[-1]
        if k:
            m.u[k].set_value(float(k < len(kits)), skip_validation=True)
        m.E[k].set_value(end, skip_validation=True)
        if trays is not None and k >= trays:
            m.S[k].set_value(start, skip_validation=True)
    _set_cut_binaries(master, instance, kits)


def _set_station_start(master: Master, instance: Instance, kits: Sequence[Sequence[str]]) -> None:
    """The kits, stations and tray binaries of a plan (HiGHS completes the continuous
    values)."""
    m = master.model
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
        trays = instance.params_of(sid).tray_limit
        if trays is None or trays < 2:
            continue
        for k in range(1, master.K):
            for j in range(k):
                count = sum(1 for q in range(j, min(k, len(kits))) if station[q] == s)
                f = getattr(m, f"f_{s}_{j}_{k}")
                f.set_value(float(count >= trays), skip_validation=True)
    _set_cut_binaries(master, instance, kits)


def _set_cut_binaries(master: Master, instance: Instance, kits: Sequence[Sequence[str]]) -> None:
    """The cut binaries ``lam`` of a plan's kits."""
    for (t, k, c), var in master.lam.items():
        have = instance.kit_parts(kits[k]).get(t, 0) if k < len(kits) else 0
        var.set_value(float(have <= c - 1), skip_validation=True)


def canonical_kits(instance: Instance, kits: Sequence[Sequence[str]]) -> list[list[str]]:
    """Relabel interchangeable chains so that their kit vectors are in lexicographic order
    (what the model's symmetry constraints require); kit contents stay the same multisets."""
    new = relabel_chains({t: k for k, kit in enumerate(kits) for t in kit}, chain_groups(instance))
    out: list[list[str]] = [[] for _ in kits]
    for t in topological_order(instance):
        out[new[t]].append(t)
    return out


def extract(master: Master) -> list[list[str]]:
    kits: dict[int, list[str]] = {}
    for (i, k), v in master.x.items():
        if v.value is not None and v.value > 0.5:
            kits.setdefault(k, []).append(master.ids[i])
    return [kits[k] for k in sorted(kits)]


def kit_cap(instance: Instance, upper: float) -> int:
    """Largest kit count m of a plan with makespan <= U, from the closed-form bounds with m
    (:func:`bilevel_kit.bounds.kit_slacks`):

    .. math:: m (o_R + d + w) \\le U - \\sum r - o_H + w - \\min_{snk} h,\\qquad
              m\\, o_H \\le U - \\min_{src} r - o_R - d - \\sum h

    (w = o_H with one tray, else 0: :func:`bilevel_kit.bounds.tray_wait`).
    """
    ids = [t.id for t in instance.tasks]
    times = ([instance.robot_time(t) for t in ids], [instance.human_time(t) for t in ids])
    one = instance.params_of()  # one station (several: no kit cap, K = n)
    kit = (
        instance.kit_overhead_robot,
        one.delivery_time,
        one.kit_overhead_human,
        tray_wait(instance),
    )
    cap = len(ids)
    eps = TOL * max(1.0, upper)
    for slack, per_kit in kit_slacks(upper, times, kit, end_tasks(instance)):
        if per_kit > 0:
            cap = min(cap, max(1, math.floor((slack + eps) / per_kit)))
    return cap
