r"""The exact whole-horizon schedule as a CP-SAT model (registered method ``cpsat``).

**Variables.** Kit positions k = 1..K (K <= n, the number of tasks; trimmed by an upper bound,
see below). ``x[i,k]`` = task i is in kit k, ``y[i,k] = [p_i <= k]`` its order encoding,
``p_i = sum_k k x[i,k]`` its kit, ``u_k`` = kit k is used. Task i can only be in the first
``n - |descendants(i)|`` kits (every earlier kit needs a task that is not a descendant).

**Constraints.**

* every task in exactly one kit; precedence ``p_i <= p_j`` and ``y[j,k] => y[i,k]`` for every
  edge i -> j of the transitive reduction (inside a kit the human follows a topological order
  of the kit's tasks, which the returned plan lists);
* symmetry breaking: ``x[i,k] => u_k``, ``u_k => OR_i x[i,k]``, ``u_k >= u_{k+1}`` (used kits
  first, no empty kit before a used one), ``sum_k u_k >= m_min`` (area bound); interchangeable
  precedence chains (same tasks, same predecessors of the head and successors of the tail,
  e.g. the four legs of one table) have their kit vectors ``(p_{c_1}, p_{c_2}, ...)`` in
  lexicographic order (relabelling the chains maps any plan to one that satisfies it);
* the timeline of docs/timeline.md, exactly, with scaled integer times (below)::

      R_k = o_R u_k + sum_i r_i x[i,k]          H_k = o_H u_k + sum_i h_i x[i,k]
      A_k = A_{k-1} + R_k + d u_k               (arrival; the robot is busy during delivery)
      E_k >= A_k + H_k,  E_k >= E_{k-1} + H_k   (human end = max(arrival, previous end) + H_k)
      C = E_K

  Unused kits sit at the end and add nothing; E_k only needs ``>=``, since the objective
  pushes it down to the max.
* the tray: ``sum_i a_i x[i,k] <= W H`` (grid areas) always, and either

  - ``embedded``: per kit and part an optional rectangle (present iff its task is in the kit;
    two alternatives, 0 and 90 degrees, for rotatable non-square parts) and one
    ``add_no_overlap_2d`` per kit; or
  - ``benders`` (logic-based Benders): the master has the area relaxation only; each kit of an
    incumbent is packed by :mod:`~bilevel_kit.layout.cpsat_packing`; a part multiset M that is
    proven not to fit is shrunk to a minimal non-fitting one and cut from *every* kit as
    ``OR_t (c_{t,k} <= M_t - 1)`` with ``c_{t,k}`` the number of parts of type t in kit k
    (every super-multiset fails too, so the cut removes no feasible plan). The master is
    re-solved until its optimum packs (then it is optimal for the full problem) or the time
    is up; kits that do not fit are split greedily to keep an incumbent.

  ``auto`` uses ``embedded`` when the number of optional (part, kit) rectangles is at most
  :data:`AUTO_EMBEDDED_MAX_RECTS` (300: one table, 28 parts x at most 9 kits; two tables took
  9 s embedded against 1.3 s with Benders) and the instance does not enforce reachability,
  else ``benders``.

  With ``reachability`` enabled, every part centre must lie in a reachable cell of the
  instance's reach map (:mod:`bilevel_kit.reachability`): an element constraint maps the centre
  to its cell and a table constraint allows the reachable cells, in the packer and (for
  present parts) in the embedded model.

  "Fits" means: an axis-aligned (0/90 degree) layout on the packing grid of
  :mod:`~bilevel_kit.layout.cpsat_packing` (sizes rounded up). "optimal" and the model's bound
  are with respect to such plans; the closed-form bounds of :mod:`bilevel_kit.bounds`, which
  the bound never undercuts, hold for every plan. Embedded models run with
  :data:`~.cpsat_packing.SAFE_NO_OVERLAP_2D` (an OR-Tools 9.15 workaround).

**Objective.** ``makespan``: minimise C. ``human_idle``: minimise :math:`C - \sum_k H_k =
C - o_H \sum_k u_k - \sum_i h_i`; with o_H = 0 this is makespan minus a constant (same
optimum); with o_H > 0 it trades makespan against the number of kits.

**Time scaling.** Times become integers at ``time_resolution`` s (default 0.1 s). When the
instance's times are not multiples of it, the grid is refined to the coarsest divisor
``time_resolution / q`` (q in :data:`_REFINE`, down to 1/1000) on which all of them are
exact; if none exists the times are rounded *down*. Makespan is non-decreasing in every
duration (a max-plus expression), so with rounded-down times the model's optimum and bound are
lower bounds for the real instance: the reported bound is valid. The reported makespan is
always recomputed by :func:`bilevel_kit.plan.evaluate` on the real times, and ``optimal`` is
claimed only when the model is exact or that makespan meets the bound.

**Kit count.** With a feasible upper bound U (the hint or a quick greedy plan whose kits are
checked to fit), every plan at least as good has :math:`m (o_R + d) \le U - \sum r_i - o_H -
\min_{snk} h_i` and :math:`m\, o_H \le U - \min_{src} r_i - o_R - d - \sum h_i`, which
caps K; C <= U is added too.
"""

from __future__ import annotations

import itertools
import math
import time
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

from ..bounds import best_bound, min_kits
from ..instance import Instance
from ..layout import cpsat_packing as packing
from ..methods import gap as relative_gap
from ..plan import Kit, Placement, Plan, evaluate
from .common import Packer, chain_groups_idx, kit_order, quick_plan, reduced_edges

TRAY_MODES = ("auto", "embedded", "benders")
OBJECTIVES = ("makespan", "human_idle")
#: ``auto`` embeds the tray when the model has at most this many optional (part, kit) rectangles.
AUTO_EMBEDDED_MAX_RECTS = 300
#: Divisors tried to make every time an exact multiple of the time grid.
_REFINE = (1, 2, 4, 5, 10, 20, 25, 50, 100, 200, 250, 500, 1000)
#: Seconds kept back from the time limit for extraction and packing the final layouts.
_MARGIN = 0.15


# ---------------------------------------------------------------------------------------------
# Data preparation
# ---------------------------------------------------------------------------------------------


@dataclass
class _Scaled:
    """Integer times: ``value_s = round_or_floor(value / res)``."""

    res: float
    exact: bool
    r: list[int]
    h: list[int]
    d: int
    o_r: int
    o_h: int


def scale_times(instance: Instance, resolution: float, refine: bool = True) -> _Scaled:
    """Integer times on the coarsest exact grid ``resolution / q`` (else floored at
    ``resolution``); see the module docstring."""
    ids = [t.id for t in instance.tasks]
    values = (
        [instance.robot_time(i) for i in ids]
        + [instance.human_time(i) for i in ids]
        + [instance.delivery_time, instance.kit_overhead_robot, instance.kit_overhead_human]
    )
    res, exact = resolution, False
    for q in _REFINE if refine else (1,):
        cand = resolution / q
        if packing.is_grid_exact(values, cand):
            res, exact = cand, True
            break

    def sc(v: float) -> int:
        return round(v / res) if exact else math.floor(v / res + 1e-9)

    return _Scaled(
        res=res,
        exact=exact,
        r=[sc(instance.robot_time(i)) for i in ids],
        h=[sc(instance.human_time(i)) for i in ids],
        d=sc(instance.delivery_time),
        o_r=sc(instance.kit_overhead_robot),
        o_h=sc(instance.kit_overhead_human),
    )


def _scaled_makespan(sc: _Scaled, kits: Sequence[Sequence[int]]) -> int:
    """The section-2 timeline on scaled integer times (kits of task indices)."""
    arrive = end = 0
    for kit in kits:
        arrive += sc.o_r + sum(sc.r[i] for i in kit) + sc.d
        end = max(arrive, end) + sc.o_h + sum(sc.h[i] for i in kit)
    return end


def _canonical(kits: list[list[int]], groups: list[list[list[int]]]) -> list[list[int]]:
    """Relabel interchangeable chains so that their kit vectors are in lexicographic order
    (the symmetry-breaking constraints of the model); makespan and kit contents unchanged."""
    pos = {i: k for k, kit in enumerate(kits) for i in kit}
    new = dict(pos)
    for group in groups:
        vectors = sorted(tuple(pos[i] for i in chain) for chain in group)
        for chain, vec in zip(group, vectors, strict=True):
            for i, k in zip(chain, vec, strict=True):
                new[i] = k
    out: list[list[int]] = [[] for _ in kits]
    for i in sorted(new):
        out[new[i]].append(i)
    return out


# ---------------------------------------------------------------------------------------------
# The model
# ---------------------------------------------------------------------------------------------


@dataclass
class _Model:
    model: Any
    K: int
    x: list[dict[int, Any]]
    used: list[Any]
    arrive: list[Any]
    end: list[Any]
    C: Any
    obj_const: int = 0
    rects: dict[tuple[int, int], list[tuple[str, int, Any, Any, Any]]] = field(default_factory=dict)
    counts: dict[tuple[str, int], Any] = field(default_factory=dict)
    cut_lits: dict[tuple[str, int, int], Any] = field(default_factory=dict)
    n_cuts: int = 0


def _build(
    instance: Instance,
    sc: _Scaled,
    *,
    K: int,
    upper: int | None,
    embedded: bool,
    objective: str,
    pack_res: float,
    groups: list[list[list[int]]],
) -> _Model:
    from ortools.sat.python import cp_model

    ids = [t.id for t in instance.tasks]
    n = len(ids)
    idx = instance.index
    m = cp_model.CpModel()

    # kit positions; p_i <= n - |descendants(i)| since every earlier kit needs a task
    n_desc = [0] * n
    for t in ids:
        for a in instance.ancestors[t]:
            n_desc[idx[a]] += 1
    ub = [min(K, n - n_desc[i]) for i in range(n)]
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
    edges = [(idx[a], idx[b]) for a, b in reduced_edges(instance)]
    for a, b in edges:
        m.add(p[a] <= p[b])
        for k in range(min(ub[a], ub[b]) - 1):
            m.add_implication(y[b][k], y[a][k])

    # symmetry breaking: used kits first; interchangeable chains in lexicographic order
    members: list[list[Any]] = [[] for _ in range(K)]
    for i in range(n):
        for k, v in x[i].items():
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
    for group in groups:
        for c1, c2 in itertools.pairwise(group):
            _add_lex_leq(m, [p[i] for i in c1], [p[i] for i in c2])

    # timeline
    hz = sum(sc.r) + sum(sc.h) + K * (sc.o_r + sc.o_h + sc.d)
    if upper is not None:
        hz = min(hz, upper)
    arrive, end = [], []
    for k in range(K):
        R = sc.o_r * used[k] + sum(sc.r[i] * x[i][k] for i in range(n) if k in x[i])
        Hk = sc.o_h * used[k] + sum(sc.h[i] * x[i][k] for i in range(n) if k in x[i])
        a = m.new_int_var(0, hz, f"A{k}")
        e = m.new_int_var(0, hz, f"E{k}")
        m.add(a == (arrive[-1] if k else 0) + R + sc.d * used[k])
        m.add(e >= a + Hk)
        if k:
            m.add(e >= end[-1] + Hk)
        arrive.append(a)
        end.append(e)
    C = end[-1]
    # closed-form bounds on scaled times (redundant, they help the search)
    has_pred = {b for _, b in edges}
    has_succ = {a for a, _ in edges}
    mk = min(K, min_kits(instance))
    lb_human = (
        min(sc.r[i] for i in range(n) if i not in has_pred)
        + sc.o_r
        + sc.d
        + sum(sc.h)
        + mk * sc.o_h
    )
    lb_robot = (
        sum(sc.r)
        + mk * (sc.o_r + sc.d)
        + sc.o_h
        + min(sc.h[i] for i in range(n) if i not in has_succ)
    )
    m.add(max(lb_human, lb_robot) <= C)
    out = _Model(m, K, x, used, arrive, end, C)
    if objective == "makespan":
        m.minimize(C)
    else:
        m.minimize(C - sc.o_h * sum(used))
        out.obj_const = -sum(sc.h)

    # tray: area relaxation in grid units (valid for both modes)
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
        from ..reachability import reach_grid

        reach = reach_grid(instance)
        tables = None if reach is None else packing.reach_tables(reach, W, Hh, pack_res)
        _embed_tray(instance, out, W, Hh, gsize, tables)
    else:
        total = instance.kit_parts(ids)
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
                    out.counts[(t, k)] = cnt
    return out


def _embed_tray(
    instance: Instance,
    mdl: _Model,
    W: int,
    H: int,
    gsize: dict[str, tuple[int, int]],
    tables: packing.ReachTables | None,
) -> None:
    """Per kit: optional rectangles (both orientations when allowed) + add_no_overlap_2d;
    with a reach map, every present centre in a reachable cell."""
    m = mdl.model
    per_kit_x: list[list[Any]] = [[] for _ in range(mdl.K)]
    per_kit_y: list[list[Any]] = [[] for _ in range(mdl.K)]
    for i, task in enumerate(instance.tasks):
        for k, present in mdl.x[i].items():
            rects = []
            for ptype, cnt in task.parts:
                w, h = gsize[ptype]
                turn = instance.part_types[ptype].rotatable and w != h and h <= W and w <= H
                stay = w <= W and h <= H
                lo_w, lo_h = (min(w, h), min(w, h)) if turn else ((w, h) if stay else (h, w))
                prev = None
                for j in range(cnt):
                    xv = m.new_int_var(0, W - lo_w, "")
                    yv = m.new_int_var(0, H - lo_h, "")
                    m.add(xv == 0).only_enforce_if(present.Not())
                    m.add(yv == 0).only_enforce_if(present.Not())
                    if turn and stay:
                        a0 = m.new_bool_var("")
                        a1 = m.new_bool_var("")
                        m.add(a0 + a1 == present)
                        alts = ((w, h, a0), (h, w, a1))
                        rot: Any = (a0, a1)
                        cx2, cy2 = 2 * xv + w * a0 + h * a1, 2 * yv + h * a0 + w * a1
                        parked = (0, 0)  # absent: x = y = 0 and no orientation
                    else:
                        sx, sy = (w, h) if stay else (h, w)
                        alts = ((sx, sy, present),)
                        rot = 0 if stay else 1
                        cx2, cy2 = 2 * xv + sx, 2 * yv + sy
                        parked = (sx, sy)
                    if tables is not None:
                        packing.add_reach(m, tables, cx2, cy2, W, H, present, parked)
                    for sx, sy, lit in alts:
                        xe = m.new_int_var(0, W, "")
                        ye = m.new_int_var(0, H, "")
                        per_kit_x[k].append(m.new_optional_interval_var(xv, sx, xe, lit, ""))
                        per_kit_y[k].append(m.new_optional_interval_var(yv, sy, ye, lit, ""))
                    if prev is not None:  # identical copies of one task: lexicographic order
                        packing.add_lex_less(m, prev, (xv, yv), enforce=(present,))
                    prev = (xv, yv)
                    rects.append((ptype, j, xv, yv, rot))
            mdl.rects[(i, k)] = rects
    for k in range(mdl.K):
        if per_kit_x[k]:
            m.add_no_overlap_2d(per_kit_x[k], per_kit_y[k])


def _add_lex_leq(m: Any, u: Sequence[Any], v: Sequence[Any]) -> None:
    """u <=lex v for equal-length vectors of integer variables."""
    eq_prev = None
    for t, (a, b) in enumerate(zip(u, v, strict=True)):
        cond = [] if eq_prev is None else [eq_prev]
        if t == len(u) - 1:
            m.add(a <= b).only_enforce_if(cond)
            break
        eq = m.new_bool_var("")
        m.add(a == b).only_enforce_if(eq)
        m.add(a < b).only_enforce_if([*cond, eq.Not()])
        if eq_prev is not None:
            m.add_implication(eq, eq_prev)
        eq_prev = eq


def _add_cut(mdl: _Model, counts: dict[str, int]) -> None:
    """Forbid the multiset ``counts`` (and every super-multiset) in every kit."""
    m = mdl.model
    for k in range(mdl.K):
        lits = []
        trivially_ok = False
        for t, c in counts.items():
            var = mdl.counts.get((t, k))
            if var is None:
                trivially_ok = True  # this kit can never hold a part of type t
                break
            key = (t, k, c)
            if key not in mdl.cut_lits:
                lit = m.new_bool_var("")
                m.add(var <= c - 1).only_enforce_if(lit)
                mdl.cut_lits[key] = lit
            lits.append(mdl.cut_lits[key])
        if not trivially_ok:
            m.add_bool_or(lits)
    mdl.n_cuts += 1


def _hint(
    mdl: _Model,
    sc: _Scaled,
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
    arrive = end = 0
    for k in range(mdl.K):
        kit = kits[k] if k < len(kits) else []
        m.add_hint(mdl.used[k], bool(kit))
        if kit:
            arrive += sc.o_r + sum(sc.r[i] for i in kit) + sc.d
            end = max(arrive, end) + sc.o_h + sum(sc.h[i] for i in kit)
        m.add_hint(mdl.arrive[k], arrive)
        m.add_hint(mdl.end[k], end)
    if not mdl.rects:
        return
    for (i, k), rects in mdl.rects.items():
        here = where.get(i) == k and corners is not None and i in corners
        for ptype, j, xv, yv, rot in rects:
            cx, cy, turned = corners[i][(ptype, j)] if here else (0, 0, False)
            m.add_hint(xv, cx)
            m.add_hint(yv, cy)
            if isinstance(rot, tuple):
                m.add_hint(rot[0], here and not turned)
                m.add_hint(rot[1], here and turned)


def _grid_corners(
    instance: Instance, kits: Sequence[Sequence[int]], packer: Packer
) -> dict[int, dict[tuple[str, int], tuple[int, int, bool]]] | None:
    """Lower-left grid corners of every part of a plan, from the packing oracle's layouts;
    identical copies of one task get their corners in lexicographic order (as the model
    requires). None when some kit has no known layout."""
    res = packer.res
    out: dict[int, dict[tuple[str, int], tuple[int, int, bool]]] = {}
    for kit in kits:
        ok, typed = packer.counts(dict(instance.kit_parts([instance.tasks[i].id for i in kit])))
        if not ok or typed is None:
            return None
        slot = dict.fromkeys(typed, 0)
        for i in kit:
            out[i] = {}
            for ptype, cnt in instance.tasks[i].parts:
                pt = instance.part_types[ptype]
                w, h = packing.grid_up(pt.width, res), packing.grid_up(pt.height, res)
                mine = []
                for _ in range(cnt):
                    x, y, theta = typed[ptype][slot[ptype]]
                    slot[ptype] += 1
                    turned = abs(theta - 90.0) < 1e-9
                    ww, hh = (h, w) if turned else (w, h)
                    mine.append((round(x / res - ww / 2.0), round(y / res - hh / 2.0), turned))
                for j, c in enumerate(sorted(mine)):
                    out[i][(ptype, j)] = c
    return out


def _extract_kits(mdl: _Model, solver: Any) -> list[list[int]]:
    kits: dict[int, list[int]] = {}
    for i, xs in enumerate(mdl.x):
        for k, v in xs.items():
            if solver.boolean_value(v):
                kits.setdefault(k, []).append(i)
    return [kits[k] for k in sorted(kits)]


def _embedded_layouts(
    instance: Instance, mdl: _Model, solver: Any, kits: list[list[int]], res: float
) -> list[tuple[Placement, ...]]:
    """Placements of each kit from the embedded rectangles (centred in their grid cells)."""
    out = []
    ids = [t.id for t in instance.tasks]
    for kit in kits:
        k = next(k for k, v in mdl.x[kit[0]].items() if solver.boolean_value(v))
        layout = []
        for i in kit:
            for ptype, j, xv, yv, rot in mdl.rects[(i, k)]:
                pt = instance.part_types[ptype]
                w = packing.grid_up(pt.width, res)
                h = packing.grid_up(pt.height, res)
                r = solver.boolean_value(rot[1]) if isinstance(rot, tuple) else bool(rot)
                ww, hh = (h, w) if r else (w, h)
                layout.append(
                    Placement(
                        part=f"{ids[i]}:{ptype}:{j + 1}",
                        type=ptype,
                        x=(2 * solver.value(xv) + ww) * res / 2.0,
                        y=(2 * solver.value(yv) + hh) * res / 2.0,
                        theta=90.0 if r else 0.0,
                        w=pt.width,
                        h=pt.height,
                    )
                )
        out.append(tuple(layout))
    return out


# ---------------------------------------------------------------------------------------------
# The method
# ---------------------------------------------------------------------------------------------


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
) -> Any:
    """Minimise makespan (or human idle) over all segmentations and orders (module
    docstring).

    Returns a :class:`bilevel_kit.methods.MethodOutput`: ``bound`` is a proven lower bound on
    the makespan in seconds (the model's bound, never below the closed-form bounds), the plan
    lists each kit's tasks in a precedence-feasible order with a non-overlapping layout, and
    ``extra`` holds ``gap``, ``tray_mode``, ``benders_iterations``, ``cuts``, the time grid and
    solver statistics. ``time_limit`` (default 60 s) covers everything, packing included.
    """
    t0 = time.perf_counter()
    from ortools.sat.python import cp_model

    from ..methods import MethodOutput

    time_limit = 60.0 if time_limit is None else float(time_limit)
    # CP-SAT stops a little after its own limit on large models: keep 0.15 s + 1 % back
    deadline = t0 + time_limit - 0.01 * time_limit
    if tray not in TRAY_MODES:
        raise ValueError(f"tray must be one of {TRAY_MODES}, not {tray!r}")
    if objective not in OBJECTIVES:
        raise ValueError(f"objective must be one of {OBJECTIVES}, not {objective!r}")
    ids = [t.id for t in instance.tasks]
    n = len(ids)
    idx = instance.index
    sc = scale_times(instance, time_resolution, refine_times)
    pack_tl = max(0.2, min(2.0, 0.05 * time_limit))
    packer = Packer(instance, pack_tl, deadline - _MARGIN, pack_resolution)
    solves_before = sum(c.solves for c in packing._CACHES.values())
    extra: dict[str, Any] = {
        "time_resolution": sc.res,
        "times_exact": sc.exact,
        "objective": objective,
        "benders_iterations": 0,
        "cuts": 0,
        "hint_used": False,
    }

    def finish(plan: Plan | None, status: str, bound: float | None) -> Any:
        extra["pack_solves"] = sum(c.solves for c in packing._CACHES.values()) - solves_before
        extra["wall_time_s"] = time.perf_counter() - t0
        return MethodOutput(plan, status, bound, extra)

    unfit = packer.task_not_fitting()  # then no plan exists
    if unfit is not None:
        extra["reason"] = f"the parts of task {unfit!r} alone do not fit the tray"
        return finish(None, "infeasible", None)

    edges = [(idx[a], idx[b]) for a, b in reduced_edges(instance)]
    sig = [(sc.r[i], sc.h[i], tuple(sorted(instance.tasks[i].parts))) for i in range(n)]
    groups = chain_groups_idx(n, edges, sig)
    extra["symmetric_chains"] = sum(len(g) for g in groups)

    # incumbent and upper bound: the hint (if its kits fit) and a quick plan
    candidates: list[list[list[int]]] = []
    if hint is not None and sorted(hint.task_order) == sorted(ids):
        hk = [[idx[t] for t in k.tasks] for k in hint.kits if k.tasks]
        if all(packer.fits([ids[i] for i in k]) for k in hk):
            candidates.append(hk)
            extra["hint_used"] = True
    qp = quick_plan(
        instance,
        Packer(instance, min(0.2, pack_tl), min(deadline, t0 + 0.1 * time_limit), pack_resolution),
    )
    if qp is not None:
        candidates.append([[idx[t] for t in k] for k in qp])
    incumbent = None
    if candidates:
        incumbent = _canonical(min(candidates, key=lambda ks: _obj_of(sc, ks, objective)), groups)
    upper = None
    if incumbent is not None and objective == "makespan":
        upper = _scaled_makespan(sc, incumbent)  # C <= U and the kit cap need makespan

    K = n
    if upper is not None:
        has_pred = {b for _, b in edges}
        has_succ = {a for a, _ in edges}
        if sc.o_r + sc.d > 0:
            slack = upper - sum(sc.r) - sc.o_h - min(sc.h[i] for i in range(n) if i not in has_succ)
            K = min(K, max(1, slack // (sc.o_r + sc.d)))
        if sc.o_h > 0:
            slack = (
                upper
                - min(sc.r[i] for i in range(n) if i not in has_pred)
                - sc.o_r
                - sc.d
                - sum(sc.h)
            )
            K = min(K, max(1, slack // sc.o_h))
    K = max(K, len(incumbent) if incumbent is not None else 1)
    n_rects = sum(c for t in instance.tasks for _, c in t.parts) * K
    mode = tray
    if mode == "auto":
        small = n_rects <= AUTO_EMBEDDED_MAX_RECTS and not instance.reachability
        mode = "embedded" if small else "benders"
    extra.update(
        tray_mode=mode,
        max_kits=K,
        upper_start=None
        if incumbent is None
        else evaluate(instance, _plan_of(instance, incumbent, None)).makespan,
    )

    mdl = _build(
        instance,
        sc,
        K=K,
        upper=upper,
        embedded=mode == "embedded",
        objective=objective,
        pack_res=pack_resolution,
        groups=groups,
    )
    extra["build_time_s"] = time.perf_counter() - t0
    solver = cp_model.CpSolver()
    solver.parameters.num_workers = max(1, workers)
    solver.parameters.random_seed = seed
    solver.parameters.log_search_progress = log
    for key, value in (cpsat_params or {}).items():
        setattr(solver.parameters, key, value)
    if mode == "embedded":
        for key, value in packing.SAFE_NO_OVERLAP_2D.items():
            setattr(solver.parameters, key, value)
        state = _run_embedded(instance, sc, mdl, solver, objective, incumbent, packer, deadline)
    else:
        state = _run_benders(
            instance, sc, mdl, solver, objective, incumbent, packer, deadline, groups
        )
    extra.update(state.info)
    extra["cpsat_status"] = state.status_name
    extra["cuts"] = mdl.n_cuts
    if state.kits is None:
        if state.infeasible:
            return finish(None, "infeasible", None)
        return finish(None, "unknown", best_bound(instance))

    plan = _plan_of(instance, state.kits, state.layouts, packer)
    real = evaluate(instance, plan)
    closed = best_bound(instance)
    lower = state.lower
    lower_s = None if lower is None else round(lower * sc.res, 9)  # a multiple of res >= 1e-4
    idle_bound = None
    if objective == "makespan":
        bound_s = closed if lower_s is None else max(closed, lower_s)
        status = (
            "optimal"
            if state.proven and (sc.exact or real.makespan <= bound_s + 1e-6)
            else "feasible"
        )
    else:
        if lower is not None and sc.exact:
            idle_bound = round((lower + mdl.obj_const) * sc.res, 9)
        w_min = (
            sum(instance.human_time(i) for i in ids)
            + min_kits(instance) * instance.kit_overhead_human
        )
        bound_s = closed if idle_bound is None else max(closed, idle_bound + w_min)
        status = "optimal" if state.proven and sc.exact else "feasible"
        extra["idle_bound"] = idle_bound
    missing = [k for k in plan.kits if not k.layout and instance.kit_parts(k.tasks)]
    if missing:  # a kit without a layout (packing timed out at the very end): not a valid plan
        extra["reason"] = "no layout for some kit within the time limit"
        return finish(None, "unknown", bound_s)
    extra.update(
        gap=relative_gap(real.makespan, bound_s) or 0.0,
        makespan=real.makespan,
        human_idle=real.human_idle,
        n_kits=len(plan.kits),
        bound_closed_form=closed,
        bound_model=lower_s,
        scaled_optimal=state.proven,
    )
    return finish(plan, status, bound_s)


def _plan_of(
    instance: Instance,
    kits: Sequence[Sequence[int]],
    layouts: Sequence[tuple[Placement, ...]] | None,
    packer: Packer | None = None,
) -> Plan:
    """Kits of task indices -> a Plan (human order = topological order inside each kit)."""
    out = []
    for kk, kit in enumerate(kits):
        tasks = kit_order(instance, [instance.tasks[i].id for i in kit])
        layout: tuple[Placement, ...] = ()
        if layouts is not None:
            layout = layouts[kk]
        elif packer is not None:
            ok, typed = packer.counts(dict(instance.kit_parts(tasks)))
            if ok and typed is not None:
                layout = packing.typed_to_placements(instance, tasks, typed)
        out.append(Kit(tasks, layout))
    return Plan(tuple(out))


def _obj_of(sc: _Scaled, kits: Sequence[Sequence[int]], objective: str) -> int:
    """Scaled objective of a plan (human idle without its constant -sum h)."""
    c = _scaled_makespan(sc, kits)
    return c if objective == "makespan" else c - sc.o_h * len(kits)


@dataclass
class _State:
    """What a run ends with: the best kits (objective ``obj``), the proven lower bound
    ``lower`` (scaled objective units), whether ``obj`` is proven optimal."""

    kits: list[list[int]] | None
    obj: int | None
    lower: int | None = None
    proven: bool = False
    infeasible: bool = False
    layouts: list[tuple[Placement, ...]] | None = None
    status_name: str = "UNKNOWN"
    info: dict[str, Any] = field(default_factory=dict)


def _run_embedded(
    instance: Instance,
    sc: _Scaled,
    mdl: _Model,
    solver: Any,
    objective: str,
    incumbent: list[list[int]] | None,
    packer: Packer,
    deadline: float,
) -> _State:
    from ortools.sat.python import cp_model

    state = _State(incumbent, None if incumbent is None else _obj_of(sc, incumbent, objective))
    if incumbent is not None:
        _hint(mdl, sc, incumbent, _grid_corners(instance, incumbent, packer))
    left = deadline - time.perf_counter() - _MARGIN
    if left <= 0.01:
        return state
    # a large embedded model (10 tables: 7e4 variables, 1e5 constraints, 40 s of presolve)
    # overran its CP-SAT limit by 2.2 s of 57 s: keep 4 % more back here
    solver.parameters.max_time_in_seconds = 0.96 * left
    st = solver.solve(mdl.model)
    state.status_name = solver.status_name(st)
    if st in (cp_model.OPTIMAL, cp_model.FEASIBLE):
        kits = _extract_kits(mdl, solver)
        obj = round(solver.objective_value)
        if state.obj is None or obj <= state.obj:
            state.kits, state.obj = kits, obj
            state.layouts = _embedded_layouts(instance, mdl, solver, kits, packer.res)
        state.lower = math.ceil(solver.best_objective_bound - 1e-6)
        state.proven = st == cp_model.OPTIMAL
    elif st == cp_model.INFEASIBLE:
        # C <= U holds for the incumbent, so this only happens without one
        state.infeasible = incumbent is None
        state.proven = incumbent is not None
        state.lower = state.obj
    return state


def _run_benders(
    instance: Instance,
    sc: _Scaled,
    mdl: _Model,
    solver: Any,
    objective: str,
    incumbent: list[list[int]] | None,
    packer: Packer,
    deadline: float,
    groups: list[list[list[int]]],
) -> _State:
    """Logic-based Benders: master (area relaxation + no-good cuts) <-> packing of each kit."""
    from ortools.sat.python import cp_model

    ids = [t.id for t in instance.tasks]
    state = _State(incumbent, None if incumbent is None else _obj_of(sc, incumbent, objective))
    unproven = 0
    seen: set[frozenset[tuple[str, int]]] = set()

    def left() -> float:
        return deadline - time.perf_counter() - _MARGIN

    def cut(counts: dict[str, int], proven: bool) -> bool:
        mini = (
            packer.minimal_nofit(counts, time.perf_counter() + max(0.0, left() / 4))
            if proven
            else counts
        )
        key = frozenset(mini.items())
        if key in seen:
            return False
        seen.add(key)
        _add_cut(mdl, mini)
        return True

    # seed cuts: every pair of (distinct part multisets of) tasks that does not fit together
    seed_until = time.perf_counter() + max(0.0, 0.1 * left())
    reps = list({frozenset(instance.kit_parts([t]).items()): t for t in ids}.values())
    for a, b in itertools.combinations_with_replacement(range(len(reps)), 2):
        if time.perf_counter() > seed_until:
            break
        counts = dict(instance.kit_parts([reps[a], reps[b]]))
        if packer.counts(counts)[0] is False:
            cut(counts, True)
    it = 0
    while left() > 0.01:
        it += 1
        if state.kits is not None:
            _hint(mdl, sc, state.kits)
        solver.parameters.max_time_in_seconds = left()
        st = solver.solve(mdl.model)
        state.status_name = solver.status_name(st)
        if st == cp_model.INFEASIBLE:
            # the master holds C <= U, so without an unproven cut the incumbent is optimal
            state.infeasible = state.kits is None and unproven == 0
            if state.kits is not None and unproven == 0:
                state.proven, state.lower = True, state.obj
            break
        if st not in (cp_model.OPTIMAL, cp_model.FEASIBLE):
            break
        if unproven == 0:  # after an unproven cut the master bound is no proof
            bound = math.ceil(solver.best_objective_bound - 1e-6)
            state.lower = bound if state.lower is None else max(state.lower, bound)
        kits = _extract_kits(mdl, solver)
        verdicts = []
        for kit in kits:
            counts = dict(instance.kit_parts([ids[i] for i in kit]))
            ok = packer.counts(counts)[0]
            if ok is None:  # a hard packing: one more try with a longer limit
                ok = packer.counts(
                    counts, max(packer.pack_tl, min(10 * packer.pack_tl, left() / 3))
                )[0]
            verdicts.append(ok)
        if all(v is True for v in verdicts):
            obj = round(solver.objective_value)
            if state.obj is None or obj <= state.obj:
                state.kits, state.obj = kits, obj
            state.proven = (st == cp_model.OPTIMAL and unproven == 0) or (
                state.lower is not None and state.lower >= state.obj
            )
            if state.proven:
                state.lower = state.obj
            break  # optimal, or the master ran out of time on a packable incumbent
        new = 0
        for kit, ok in zip(kits, verdicts, strict=True):
            if ok is not True:
                counts = dict(instance.kit_parts([ids[i] for i in kit]))
                added = cut(counts, ok is False)
                new += added
                unproven += int(added and ok is None)
        # repair: split the kits that do not fit; keep the better incumbent
        repaired: list[list[int]] = []
        for kit in kits:
            parts = packer.split(list(kit_order(instance, [ids[i] for i in kit])))
            if parts is None:
                repaired = []
                break
            repaired += [[instance.index[t] for t in q] for q in parts]
        if repaired:
            repaired = _canonical(repaired, groups)
            obj = _obj_of(sc, repaired, objective)
            if state.obj is None or obj < state.obj:
                state.kits, state.obj = repaired, obj
        if state.obj is not None and state.lower is not None and state.lower >= state.obj:
            state.proven = True
            break
        if not new:
            break  # nothing new to cut (only possible with unknown packings)
    state.info = {"benders_iterations": it, "unproven_cuts": unproven}
    return state


HINT_METHODS = ("single-task", "whole-assembly", "greedy-ce")


def best_heuristic_plan(
    instance: Instance, methods: Sequence[str] = HINT_METHODS, seed: int = 0
) -> tuple[Plan | None, str | None]:
    """The plan of lowest makespan among heuristic methods (a warm start for exact models);
    methods that cannot lay out a kit are skipped."""
    from ..errors import BilevelKitError
    from ..methods import get_method
    from ..plan import evaluate

    best: tuple[float, Plan, str] | None = None
    for name in methods:
        try:
            out = get_method(name).load()(instance, seed=seed)
        except BilevelKitError:
            continue
        if out.plan is None:
            continue
        ms = evaluate(instance, out.plan).makespan
        if best is None or ms < best[0]:
            best = (ms, out.plan, name)
    return (best[1], best[2]) if best else (None, None)


def solve_method(
    instance: Instance,
    *,
    seed: int = 0,
    time_limit: float | None = None,
    hint: str = "auto",
    **options: Any,
) -> Any:
    """Registered method ``cpsat``: :func:`solve` warm-started from the best heuristic plan.

    ``hint``: ``"auto"`` (best of single-task, whole-assembly and greedy-ce), a method name,
    or ``"none"``. The heuristics' time counts in the method's wall time, not in
    ``time_limit``. Other options go to :func:`solve` (``workers``, ``tray``, ``objective``,
    ``time_resolution``, ``pack_resolution`` ...).
    """
    from ..errors import UsageError

    allowed = {
        "workers",
        "tray",
        "objective",
        "time_resolution",
        "refine_times",
        "pack_resolution",
        "log",
    }
    bad = sorted(set(options) - allowed)
    if bad:
        raise UsageError(
            f"cpsat: unknown option(s) {', '.join(bad)}; options are hint, "
            f"{', '.join(sorted(allowed))}"
        )
    if options.get("tray", "auto") not in TRAY_MODES:
        raise UsageError(f"cpsat: tray must be one of {', '.join(TRAY_MODES)}")
    if options.get("objective", "makespan") not in OBJECTIVES:
        raise UsageError(f"cpsat: objective must be one of {', '.join(OBJECTIVES)}")
    plan: Plan | None = None
    source = None
    if hint == "auto":
        plan, source = best_heuristic_plan(instance, seed=seed)
    elif hint != "none":
        plan, source = best_heuristic_plan(instance, (hint,), seed=seed)
        if source is None:
            raise UsageError(f"cpsat: hint method {hint!r} gave no plan")
    out = solve(instance, seed=seed, time_limit=time_limit, hint=plan, **options)
    out.extra["hint_method"] = source
    return out
