r"""The CP-SAT schedule model (docs/formulations.md), on the integer times of :mod:`.scaling`.

One station is the S = 1 case: with several stations :mod:`.station_model` replaces the
timeline, bounds and objective below (the assignment, used kits, chains and tray are these);
with one, nothing of it is built.

**Variables.** Kit positions k = 1..K (K <= n, the number of tasks; trimmed by an upper bound,
see :mod:`.method`). ``x[i,k]`` = task i is in kit k, ``y[i,k] = [p_i <= k]`` its order
encoding, ``p_i = sum_k k x[i,k]`` its kit, ``u_k`` = kit k is used. Task i can only be in the
first ``n - |descendants(i)|`` kits (every earlier kit needs a task that is not a descendant).

**Constraints.**

* every task in exactly one kit; precedence ``p_i <= p_j`` and ``y[j,k] => y[i,k]`` for every
  edge i -> j of the transitive reduction (inside a kit the human follows a topological order
  of the kit's tasks, which the returned plan lists);
* symmetry breaking: ``x[i,k] => u_k``, ``u_k => OR_i x[i,k]``, ``u_k >= u_{k+1}`` (used kits
  first, no empty kit before a used one), ``sum_k u_k >= m_min`` (area bound); interchangeable
  precedence chains (same tasks, same predecessors of the head and successors of the tail,
  e.g. the four legs of one table) have their kit vectors ``(p_{c_1}, p_{c_2}, ...)`` in
  lexicographic order (relabelling the chains maps any plan to one that satisfies it);
* the timeline of docs/timeline.md, exactly, with scaled integer times::

      R_k = o_R u_k + sum_i r_i x[i,k]          H_k = o_H u_k + sum_i h_i x[i,k]
      A_k = S_k + R_k + d u_k                   (arrival; the robot is busy during delivery)
      A_k >= rel_i x[i,k] + sum_{j: rel_j >= rel_i} r_j x[j,k] + d u_k   (release times)
      S_k = A_{k-1}                             (k <= T, or unlimited trays)
      S_k >= A_{k-1},  S_k >= E_{k-T} - H_{k-T} + o_H u_k      (k > T: T trays)
      E_k >= A_k + H_k,  E_k >= E_{k-1} + H_k   (human end = max(arrival, previous end) + H_k)
      C = E_K

  With release times (:mod:`.scaling`: task i is not picked before rel_i, releases raised to the
  ancestors') the first line is ``A_k >= S_k + R_k + d u_k`` plus the release line per task i with
  rel_i > 0: the robot picks a kit in the order of release, so its pick end is the one-machine
  optimum with release dates (exact; without releases the model is the one above, unchanged). Unused
  kits sit at the end and add nothing; E_k and S_k only need ``>=``: every constraint is monotone,
  so for fixed kits the least solution is the true timeline and the objective pushes C down to it.
  The tray rule (docs/timeline.md: the robot starts kit k once the tray of kit k - T is back, o_H
  after the human started that kit, at E_{k-T} - H_{k-T}) needs no big-M: on a used kit it is the
  rule itself; on an unused kit k it reads ``S_k >= human start of kit k - T``, which is at most the
  last used kit's end, and so are ``A_k = S_k`` and ``E_k`` (induction), so unused trailing kits
  cannot inflate C. The closed-form bounds
  of :mod:`bilevel_kit.bounds` on C are added on the scaled times (redundant, they help the
  search; with one tray also the one-tray robot bound with the model's own kit count), the
  flow-shop bound (d) as :math:`C \ge c_l + s_l \sum_k u_k` for the two lines of
  :func:`bilevel_kit.bounds.johnson_lines` (exact on the Johnson special case), and
  ``C <= U`` for an upper bound U;
* the tray: ``sum_i a_i x[i,k] <= W H`` (grid areas) always, plus either the embedded
  rectangles of :mod:`.tray` or, for logic-based Benders, the part counts ``c_{t,k}`` that the
  no-good cuts of :func:`.tray.add_cut` use.

**Objective.** ``makespan``: minimise C. ``human_idle``: minimise :math:`C - \sum_k H_k =
C - o_H \sum_k u_k - \sum_i h_i`; with o_H = 0 this is makespan minus a constant (same
optimum); with o_H > 0 it trades makespan against the number of kits.
"""

from __future__ import annotations

import itertools
from collections.abc import Iterator, Mapping, Sequence
from typing import Any

from ...bounds import end_tasks, human_robot, johnson_lines, min_kits
from ...instance import Instance
from ...objectives import ModelTerms
from ...objectives import get as get_objective
from .. import packing
from ..common import kit_positions, reduced_edges, relabel_chains
from .context import Model
from .scaling import Scaled, scaled_makespan, scaled_timeline


def build(
    instance: Instance,
    sc: Scaled,
    *,
    K: int,
    upper: int | None,
    embedded: bool,
    objective: str,
    pack_res: float,
    groups: list[list[list[int]]],
    kit_bounds: Mapping[int, int] | None = None,
    lower: int | None = None,
) -> Model:
    r"""The model of the module docstring with K kit positions (``upper``: C <= U);
    ``kit_bounds``: m -> a lower bound on the scaled makespan of every plan of exactly m kits
    (the kit-count LP of :mod:`bilevel_kit.models.relax`), added as
    :math:`C \ge \sum_m L_m (u_{m-1} - u_m)`; ``lower``: several stations, C >= L, a lower
    bound on the scaled makespan of every plan (:func:`.proven.scaled_lower`)."""
    from ortools.sat.python import cp_model

    m = cp_model.CpModel()
    x, p, y = _assignment(m, instance, K)
    used = _used_kits(m, instance, x, K)
    for group in groups:
        for c1, c2 in itertools.pairwise(group):
            add_lex_leq(m, [p[i] for i in c1], [p[i] for i in c2])
    if sc.station:  # several stations: their variables, timeline and objective
        from .station_model import build_stations

        out = build_stations(m, instance, sc, x, used, upper, objective)
        if lower is not None:
            m.add(lower <= out.C)
        out.order = (p, y)  # (hinted: a complete hint, :func:`.station_model.hint_stations`)
        out.parts = [tuple(t.parts) for t in instance.tasks]
        _tray(instance, out, embedded, pack_res)
        return out
    start, arrive, end = _timeline(m, sc, x, used, K, upper)
    C = end[-1]
    m.add(_closed_form_bound(instance, sc, K) <= C)
    if any(sc.rel):  # (without releases the model is unchanged)
        m.add(release_bound(instance, sc) <= C)
    out = Model(m, K, x, used, arrive, end, C, start=start)
    _one_tray_bound(instance, sc, out)
    for c, slope in johnson_lines(sc.r, sc.h, sc.o_r + sc.d, sc.o_h):  # bound (d), m = sum u
        m.add(c + slope * sum(used) <= C)
    if kit_bounds:  # exactly m kits used <=> u_{m-1} and not u_m
        terms = [
            v * (used[k - 1] - (used[k] if k < K else 0))
            for k, v in kit_bounds.items()
            if 1 <= k <= K and v > 0
        ]
        if terms:
            m.add(sum(terms) <= C)
    obj = get_objective(objective)  # what it minimises, less a constant (docs/formulations.md)
    m.minimize(obj.expression(ModelTerms.one_station(C, lambda: sc.o_h * sum(used))))
    out.obj_const = -obj.dropped(sc.h)
    _tray(instance, out, embedded, pack_res)
    return out


def _assignment(
    m: Any, instance: Instance, K: int
) -> tuple[list[dict[int, Any]], list[Any], list[list[Any]]]:
    """``x[i][k]``, the kit ``p_i`` of every task and the order encoding ``y[i][k]``, with
    precedence on the reduced graph."""
    n = instance.n_tasks
    idx = instance.index
    ub = kit_positions(instance, K)  # p_i <= n - |descendants(i)|: every later kit needs a task
    # x[i][k] = [p_i == k] and the order encoding y[i][k] = [p_i <= k]; precedence as the
    # implications y[b][k] => y[a][k] (stronger propagation and LP than p_a <= p_b alone)
    x = [{k: m.new_bool_var(f"x{i}_{k}") for k in range(ub[i])} for i in range(n)]
    y = [[m.new_bool_var(f"y{i}_{k}") for k in range(ub[i] - 1)] for i in range(n)]
    p = []
    for i in range(n):
        m.add_exactly_one(x[i].values())
        for k in range(ub[i]):
            below = y[i][k - 1] if k else 0
            at_or_below = y[i][k] if k < ub[i] - 1 else 1
            m.add(x[i][k] == at_or_below - below)
            if 0 < k < ub[i] - 1:
                m.add_implication(y[i][k - 1], y[i][k])
        pi = m.new_int_var(0, ub[i] - 1, f"p{i}")
        m.add(pi == sum(k * v for k, v in x[i].items()))
        p.append(pi)
    for ia, ib in [(idx[a], idx[b]) for a, b in reduced_edges(instance)]:
        m.add(p[ia] <= p[ib])
        for k in range(min(ub[ia], ub[ib]) - 1):
            m.add_implication(y[ib][k], y[ia][k])
    return x, p, y


def _used_kits(m: Any, instance: Instance, x: list[dict[int, Any]], K: int) -> list[Any]:
    """``u_k``: used kits first, at least ``m_min`` of them (symmetry breaking)."""
    members: list[list[Any]] = [[] for _ in range(K)]
    for xs in x:
        for k, v in xs.items():
            members[k].append(v)
    used = [m.new_bool_var(f"u{k}") for k in range(K)]
    for k in range(K):
        for v in members[k]:
            m.add_implication(v, used[k])
        m.add_bool_or(members[k]).only_enforce_if(used[k])
        if k:
            m.add_implication(used[k], used[k - 1])
    m.add(used[0] == 1)
    m.add(sum(used) >= min(K, min_kits(instance)))
    return used


def _timeline(
    m: Any, sc: Scaled, x: list[dict[int, Any]], used: list[Any], K: int, upper: int | None
) -> tuple[list[Any], list[Any], list[Any]]:
    """Robot start ``S_k`` (None where it is the previous arrival), arrival ``A_k`` and human
    end ``E_k`` of every kit position (module docstring)."""
    n = len(x)
    hz = max(sc.rel, default=0) + sum(sc.r) + sum(sc.h) + K * (sc.o_r + sc.o_h + sc.d)
    if upper is not None:
        hz = min(hz, upper)
    trays = sc.trays
    start: list[Any] = []
    arrive: list[Any] = []
    end: list[Any] = []
    human: list[Any] = []
    for k in range(K):
        R = sc.o_r * used[k] + sum(sc.r[i] * x[i][k] for i in range(n) if k in x[i])
        Hk = sc.o_h * used[k] + sum(sc.h[i] * x[i][k] for i in range(n) if k in x[i])
        a = m.new_int_var(0, hz, f"A{k}")
        e = m.new_int_var(0, hz, f"E{k}")
        prev = arrive[-1] if k else 0
        if trays is not None and k >= trays:
            # the tray of kit k - T is back o_H after its human start E - H (docs/timeline.md)
            s = m.new_int_var(0, hz, f"S{k}")
            m.add(s >= prev)
            m.add(s >= end[k - trays] - human[k - trays] + sc.o_h * used[k])
            _arrival(m, sc, x, k, a, s + R + sc.d * used[k], used[k])
        else:
            s = None
            _arrival(m, sc, x, k, a, prev + R + sc.d * used[k], used[k])
        m.add(e >= a + Hk)
        if k:
            m.add(e >= end[-1] + Hk)
        start.append(s)
        arrive.append(a)
        end.append(e)
        human.append(Hk)
    return start, arrive, end


def _arrival(
    m: Any, sc: Scaled, x: list[dict[int, Any]], k: int, a: Any, least: Any, u: Any
) -> None:
    """``A_k = least`` (start + R_k + d); with release times ``A_k >= least`` and, per task i
    released after 0, ``A_k >= rel_i x[i,k] + sum_{j: rel_j >= rel_i} r_j x[j,k] + d u_k``
    (module docstring; implied by the first when i is not in kit k)."""
    if not any(sc.rel):
        m.add(a == least)
        return
    m.add(a >= least)
    for i, xs in enumerate(x):
        if sc.rel[i] > 0 and k in xs:
            later = [
                sc.r[j] * x[j][k] for j in range(len(x)) if k in x[j] and sc.rel[j] >= sc.rel[i]
            ]
            m.add(a >= sc.rel[i] * xs[k] + sum(later) + sc.d * u)


def _closed_form_bound(instance: Instance, sc: Scaled, K: int) -> int:
    """The human and robot bounds of :mod:`bilevel_kit.bounds` on scaled times."""
    mk = min(K, min_kits(instance))
    kit = (sc.o_r, sc.d, sc.o_h, tray_wait(sc))
    return max(human_robot((sc.r, sc.h), kit, end_tasks(instance), mk))


#: The release bound enumerates the segmentations of at most this many late tasks.
RELEASE_BOUND_TASKS = 4


def release_bound(instance: Instance, sc: Scaled) -> int:
    r"""A lower bound on C from the release times (0 without). For a release value v > 0 the
    set J of tasks released at v or later (closed under successors: releases are raised to
    the ancestors') is picked after v, so

    * :math:`C \ge v - o_R + T^*(J)`, :math:`T^*(J)` the least makespan of J's tasks alone
      from time 0 without releases and without the tray's geometry (every kit of a plan
      restricted to J starts no later; its first kit's o_R may be spent before v), enumerated
      (precedence-feasible orders x cut patterns) when J has at most
      :data:`RELEASE_BOUND_TASKS` tasks;
    * else the closed-form lines on J: :math:`C \ge v + \min_{src} r_i + d + o_H + \sum_J h`
      (the first kit of J arrives, then the human does all of J) and :math:`C \ge v + \sum_J
      r + d + o_H + \min_{snk} h_i` (the robot picks all of J, then the last kit's human)."""
    if not any(sc.rel):
        return 0
    from dataclasses import replace

    plain = replace(sc, rel=[])
    edges = [(instance.index[a], instance.index[b]) for a, b in reduced_edges(instance)]
    best = 0
    for v in sorted(set(sc.rel) - {0}):
        late = [i for i in range(len(sc.rel)) if sc.rel[i] >= v]
        if len(late) <= RELEASE_BOUND_TASKS:
            least = min(scaled_makespan(plain, kits) for kits in _segmentations(late, edges))
            best = max(best, v - sc.o_r + least)
            continue
        inside = set(late)
        src = [i for i in late if not any(b == i and a in inside for a, b in edges)]
        snk = [i for i in late if not any(a == i for a, _ in edges)]
        human = v + min(sc.r[i] for i in src) + sc.d + sc.o_h + sum(sc.h[i] for i in late)
        robot = v + sum(sc.r[i] for i in late) + sc.d + sc.o_h + min(sc.h[i] for i in snk)
        best = max(best, human, robot)
    return best


def _segmentations(tasks: list[int], edges: list[tuple[int, int]]) -> Iterator[list[list[int]]]:
    """Every precedence-feasible order of ``tasks`` cut into consecutive kits."""
    for perm in itertools.permutations(tasks):
        pos = {i: k for k, i in enumerate(perm)}
        if any(a in pos and b in pos and pos[a] > pos[b] for a, b in edges):
            continue
        for mask in range(2 ** (len(perm) - 1)):
            kits: list[list[int]] = [[perm[0]]]
            for k in range(1, len(perm)):
                if mask >> (k - 1) & 1:
                    kits.append([])
                kits[-1].append(perm[k])
            yield kits


def tray_wait(sc: Scaled) -> int:
    """The one-tray robot bound's wait per kit (:func:`bilevel_kit.bounds.tray_wait`)."""
    return sc.o_h if sc.trays == 1 else 0


def _one_tray_bound(instance: Instance, sc: Scaled, mdl: Model) -> None:
    """With one tray, the one-tray robot bound of :mod:`bilevel_kit.bounds` with the model's
    own kit count ``sum_k u_k`` (redundant; it lifts the LP bound)."""
    w = tray_wait(sc)
    if not w:
        return
    last = min(sc.h[i] for i in end_tasks(instance)[1])
    n_used = sum(mdl.used)
    mdl.model.add(sum(sc.r) + (sc.o_r + sc.d + w) * n_used - w + sc.o_h + last <= mdl.C)


def _tray(instance: Instance, mdl: Model, embedded: bool, pack_res: float) -> None:
    """The area relaxation in grid units (valid for both modes), then the embedded rectangles
    or the part counts the Benders cuts need."""
    from .tray import embed_tray

    m, x, K = mdl.model, mdl.x, mdl.K
    n = len(x)
    tray = instance.tray
    W = packing.grid_down(tray.width, pack_res)
    Hh = packing.grid_down(tray.height, pack_res)
    gsize = {
        pt.id: (packing.grid_up(pt.width, pack_res), packing.grid_up(pt.height, pack_res))
        for pt in instance.part_types.values()
    }
    area = [sum(gsize[t][0] * gsize[t][1] * c for t, c in task.parts) for task in instance.tasks]
    for k in range(K):
        terms = [area[i] * x[i][k] for i in range(n) if k in x[i] and area[i]]
        if terms:
            m.add(sum(terms) <= W * Hh)
    if embedded:
        from ...reachability import reach_grid

        reach = reach_grid(instance)
        tables = None if reach is None else packing.reach_tables(reach, W, Hh, pack_res)
        embed_tray(instance, mdl, W, Hh, gsize, tables)
        return
    total = instance.kit_parts([t.id for t in instance.tasks])
    for t in instance.part_types:
        for k in range(K):
            terms = [
                c * x[i][k]
                for i in range(n)
                if k in x[i]
                for q, c in instance.tasks[i].parts
                if q == t
            ]
            if terms:
                cnt = m.new_int_var(0, total[t], f"c_{t}_{k}")
                m.add(cnt == sum(terms))
                mdl.counts[(t, k)] = cnt


def add_lex_leq(m: Any, u: Sequence[Any], v: Sequence[Any]) -> None:
    """u <=lex v for equal-length vectors of integer variables."""
    eq_prev = None
    for t, (a, b) in enumerate(zip(u, v, strict=True)):
        cond: list[Any] = [] if eq_prev is None else [eq_prev]
        if t == len(u) - 1:
            m.add(a <= b).only_enforce_if(cond)
            break
        eq = m.new_bool_var("")
        m.add(a == b).only_enforce_if(eq)
        m.add(a < b).only_enforce_if([*cond, eq.Not()])
        if eq_prev is not None:
            m.add_implication(eq, eq_prev)
        eq_prev = eq


def canonical(kits: list[list[int]], groups: list[list[list[int]]]) -> list[list[int]]:
    """Relabel interchangeable chains so that their kit vectors are in lexicographic order
    (the symmetry-breaking constraints of the model); makespan and kit contents unchanged."""
    new = relabel_chains({i: k for k, kit in enumerate(kits) for i in kit}, groups)
    out: list[list[int]] = [[] for _ in kits]
    for i in sorted(new):
        out[new[i]].append(i)
    return out


def hint(
    mdl: Model,
    sc: Scaled,
    kits: Sequence[Sequence[int]],
    corners: dict[int, dict[tuple[str, int], tuple[int, int, bool]]] | None = None,
) -> None:
    """Hint a complete solution: kits, timeline and (embedded) the rectangles' corners."""
    m = mdl.model
    m.clear_hints()
    if len(kits) > mdl.K:
        return
    where = {i: k for k, kit in enumerate(kits) for i in kit}
    for i, xs in enumerate(mdl.x):
        for k, v in xs.items():
            m.add_hint(v, where.get(i) == k)
    padded = [list(kits[k]) if k < len(kits) else [] for k in range(mdl.K)]
    if sc.station:
        from .station_model import hint_stations

        hint_stations(mdl, sc, padded)
    for k, (start, arrive, end) in enumerate([] if sc.station else scaled_timeline(sc, padded)):
        m.add_hint(mdl.used[k], bool(padded[k]))
        if mdl.start and mdl.start[k] is not None:
            m.add_hint(mdl.start[k], start)
        m.add_hint(mdl.arrive[k], arrive)
        m.add_hint(mdl.end[k], end)
    if not mdl.rects:
        return
    for (i, k), rects in mdl.rects.items():
        here = where.get(i) == k and corners is not None and i in corners
        for ptype, j, xv, yv, rot in rects:
            cx, cy, turned = corners[i][(ptype, j)] if here and corners else (0, 0, False)
            m.add_hint(xv, cx)
            m.add_hint(yv, cy)
            if isinstance(rot, tuple):
                m.add_hint(rot[0], here and not turned)
                m.add_hint(rot[1], here and turned)


def extract_kits(mdl: Model, solver: Any) -> list[list[int]]:
    """The kits (task indices, in kit order) of the solver's current solution."""
    kits: dict[int, list[int]] = {}
    for i, xs in enumerate(mdl.x):
        for k, v in xs.items():
            if solver.boolean_value(v):
                kits.setdefault(k, []).append(i)
    return [kits[k] for k in sorted(kits)]
