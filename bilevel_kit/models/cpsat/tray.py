r"""The tray in the CP-SAT schedule model: embedded rectangles or logic-based Benders cuts.

* ``embedded``: per kit and part an optional rectangle (present iff its task is in the kit;
  two alternatives, 0 and 90 degrees, for rotatable non-square parts) and one
  ``add_no_overlap_2d`` per kit (:func:`embed_tray`); with a reach map every present centre
  lies in a reachable cell (an element constraint maps the centre to its cell and a table
  constraint allows the reachable cells, :mod:`bilevel_kit.reachability`);
* ``benders``: the master has the area relaxation only; a part multiset M proven not to fit
  is cut from *every* kit as ``OR_t (c_{t,k} <= M_t - 1)`` with ``c_{t,k}`` the number of
  parts of type t in kit k (:func:`add_cut`; every super-multiset fails too, so the cut
  removes no feasible plan).

"Fits" means an axis-aligned (0/90 degree) layout on the packing grid of
:mod:`~bilevel_kit.models.packing` (sizes rounded up), see docs/formulations.md.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

from ...instance import Instance
from ...plan import Placement
from .. import packing
from ..common import Packer
from ..packing import ANY_ANGLE, AXIS_ALIGNED
from .context import Model

#: ``auto`` embeds the tray when the model has at most this many optional (part, kit) rectangles
#: (300: one table, 28 parts x at most 9 kits; two tables took 9 s embedded against 1.3 s with
#: Benders, the one-tray table 8-10 s embedded against 4 s with Benders on a loaded machine).
AUTO_EMBEDDED_MAX_RECTS = 300

#: Lower-left grid corner and rotation of every part of a plan: task index -> (type, copy j)
#: -> (x, y, turned).
Corners = dict[int, dict[tuple[str, int], tuple[int, int, bool]]]


def embed_tray(
    instance: Instance,
    mdl: Model,
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
                        alts: tuple[tuple[int, int, Any], ...] = ((w, h, a0), (h, w, a1))
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


def embed_scope(instance: Instance, packer: Packer) -> str | None:
    """Which plans a tray embedded on ``packer``'s grid holds
    (docs/formulations.md#what-optimal-means): every plan when all the instance's parts fit
    one tray on that grid (then the model excludes no kit); else the 0/90-degree plans when
    the grid is exact (every size a multiple of it, no reach map); else None: the model's
    bound proves nothing."""
    from ...heuristics.shelf import kit_items

    every = instance.kit_parts([t.id for t in instance.tasks])
    limit = min(packer.pack_tl, 0.5)
    whole = packing.pack(
        instance.tray,
        kit_items(instance.part_types, every),
        resolution=packer.res,
        reach=packer.reach,
        **(
            packer.limits(limit)
            if packer.deterministic
            else {"time_limit": min(limit, max(0.01, packer.budget.remaining()))}
        ),
    )
    if whole.extra.get("safety_net"):  # a reproducible call cut by the wall clock: recorded
        packer.budget.net_fired()
    if whole.layout is not None:
        return ANY_ANGLE
    sizes = [instance.tray.width, instance.tray.height]
    sizes += [v for pt in instance.part_types.values() for v in (pt.width, pt.height)]
    if packer.reach is not None or not packing.is_grid_exact(sizes, packer.res):
        return None
    if all(not instance.part_types[p].rotatable for p in every):
        return ANY_ANGLE  # such parts lie at 0 or 180 degrees only
    return AXIS_ALIGNED


def tray_mode(instance: Instance, tray: str, K: int, scope: str | None) -> str:
    """``tray`` with ``auto`` resolved (module docstring); ``scope``: what an embedded tray
    would prove (:func:`embed_scope`). Embedded only when it proves optimality for every plan:
    otherwise Benders, whose cuts each carry their own proof (many hold at any angle: area,
    inscribed disks) and whose oracle confirms a misfit of an inexact grid on the exact one."""
    if tray != "auto":
        return tray
    n_rects = sum(c for t in instance.tasks for _, c in t.parts) * K
    small = n_rects <= AUTO_EMBEDDED_MAX_RECTS and not instance.reachability
    small = small and scope == ANY_ANGLE
    # with a tray limit Benders proved the one-tray table 2-2.5x faster than embedded
    # (bench/results/cpsat_trays.csv); with stations, a limit of any station (their own)
    limits = [instance.params_of(s).tray_limit for s in instance.station_ids]
    return "embedded" if small and all(t is None for t in limits) else "benders"


def add_cut(mdl: Model, counts: dict[str, int]) -> None:
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


def grid_corners(
    instance: Instance, kits: Sequence[Sequence[int]], packer: Packer
) -> Corners | None:
    """Lower-left grid corners of every part of a plan, from the packing oracle's layouts;
    identical copies of one task get their corners in lexicographic order (as the model
    requires). None when some kit has no known layout."""
    res = packer.res
    out: Corners = {}
    for kit in kits:
        fit = packer.grid_verdict(instance.kit_parts([instance.tasks[i].id for i in kit]))
        typed = fit.layout
        if not fit.fits or typed is None:
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


def embedded_layouts(
    instance: Instance, mdl: Model, solver: Any, kits: list[list[int]], res: float
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
