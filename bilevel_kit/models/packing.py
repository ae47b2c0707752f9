r"""Tray packing with CP-SAT: does a kit fit, and which layout is the most usable.

**Grid.** Lengths are mapped to integers at ``resolution`` mm (default 1 mm). Part sizes are
rounded *up* and the tray *down*, so a grid-feasible layout is truly non-overlapping and inside
the tray: each part is drawn centred in its (possibly slightly larger) grid cell. When every
size is a multiple of the resolution the grid is exact: integer sizes admit an integer-position
packing whenever any packing exists (bottom-left compaction), so "infeasible" is then a proof
for 0/90-degree layouts. Otherwise "infeasible" means "not at this resolution". Every
infeasible answer records in ``extra["proof"]`` whether it is a proof (an exact grid without
reachability, or a reason that holds at true sizes: a part larger than the tray, more part
area than tray area, or an any-angle test of :mod:`.packing_bounds`) and in
``extra["proof_scope"]`` which layouts it rules out (:data:`ANY_ANGLE`: every layout the
checker accepts, parts at any angle; :data:`AXIS_ALIGNED`: the layouts whose parts lie at 0
or 90 degrees, docs/formulations.md#what-optimal-means).
``bilevel-kit pack`` reports the others as "no layout on this grid";
:func:`exact_resolution` gives the grid on which every size is exact, which the oracle
(:mod:`.packing_oracle`) uses to confirm such an answer.

**Model.** Every part has a lower-left corner (x, y). A rotatable, non-square part has two
optional rectangles, one per orientation (0 and 90 degrees), whose presence literals are
``not rot`` and ``rot``; the end variable of each optional interval lives in [0, W] (resp.
[0, H]), which keeps a present orientation inside the tray. One ``add_no_overlap_2d`` over all
rectangles forbids overlap. Identical parts (same type) are interchangeable, so their corners
are ordered lexicographically, :math:`(x_a, y_a) <_{lex} (x_b, y_b)` (two non-overlapping
rectangles never share a lower-left corner, so the order is strict and loses no layout).

**Before search** (both objectives): the cheap infeasibility tests of
:mod:`bilevel_kit.models.packing_bounds` (a part larger than the tray, area, incompatible pairs,
tall parts, dual-feasible-function bounds) answer "infeasible" without a model; deciding, the
shelf packer and then the maximal-rectangles packer (:mod:`.maxrects`) answer "feasible".

**Decision model** (``objective="feasible"``): one redundant ``add_cumulative`` per axis on the
same intervals (the parts crossing any vertical line have heights summing to at most H, and
symmetrically), the classic relaxation of 2D packing; it is what decides zero-waste kits, where
every line is full (docs/formulations.md#cp-sat-packing, bench/results/packing.md). CP-SAT's
parameters come from :data:`DECISION_PARAMS` on top of :data:`SAFE_NO_OVERLAP_2D`.

**Fitness.** The paper's kit fitness (eq. 11 with the sign fix of docs/errata.md) is
:math:`f = D_{diff} - D_{same} - W_6 Z` with Euclidean centre distances. Overlap is a hard
constraint here, so Z = 0 and ``w6`` only enters the reported true fitness. CP-SAT needs a
linear objective, so the model maximises the **L1 surrogate**

.. math:: \tilde f = \sum_{Q(a) \ne Q(b)} (|\Delta x| + |\Delta y|)
                  - \sum_{Q(a) = Q(b)} (|\Delta x| + |\Delta y|)

(absolute values via ``add_abs_equality``, centres on a half-grid so everything is integer).
Since :math:`\|v\|_2 \le \|v\|_1 \le \sqrt 2 \|v\|_2` the surrogate ranks layouts like the
true fitness up to that factor; :class:`PackResult` reports both the surrogate optimum (and its
bound) and the true Euclidean fitness of the returned layout (:func:`bilevel_kit.fitness.
layout_fitness`, exact Z).

**Reachability.** Given a reach map (:mod:`bilevel_kit.reachability`), every centre must lie in
a reachable cell: the centre's cell column and row follow from the half-grid centre (linear
when a cell is a whole number of half-grid units, else an element constraint) and a table of
reachable cells, or one column span per row when the rows are contiguous, allows them
(:mod:`.packing_reach`).

**Limits.** By default the CP-SAT solve is limited by wall-clock ``time_limit`` (less the time
already spent): a heavily loaded machine may then leave a kit undecided that an idle one
decides. With ``deterministic_time`` it is limited by CP-SAT's deterministic time
(``max_deterministic_time``) with one worker, so the answer is a function of the inputs
whatever the load, and ``time_limit`` only caps that solve as a wall-clock safety net that
fires on a pathologically loaded machine (``extra["safety_net"]``: the solve was stopped by
it, not by its deterministic limit). ``extra["deterministic_time"]`` is the solve's
deterministic time (0 without a solve); docs/simulation.md#determinism.

**Oracle.** :mod:`.packing_oracle` answers "does this part multiset fit" with memoisation and
says what a "no" proves.
"""

from __future__ import annotations

import itertools
import math
import time
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, Protocol

from ..geometry import TOL, cells_available, cells_needed, exact_step
from ..instance import DEFAULT_WEIGHTS, PartType
from ..plan import Placement
from .packing_reach import ReachTables, add_reach, corners_reachable, reach_tables

if TYPE_CHECKING:
    from ..reachability import ReachGrid


#: Proof scopes of an infeasible answer (module docstring, "Grid"): no layout at all, parts at
#: any angle (what the checker accepts) ...
ANY_ANGLE = "any angle"
#: ... or no layout whose parts lie at 0 or 90 degrees (a layout at other angles may exist).
AXIS_ALIGNED = "0/90 degrees"
#: The finest exact grid :func:`exact_resolution` offers: a tray side of at most this many
#: grid units (finer grids are "absurd": the answer stays unproven).
MAX_EXACT_UNITS = 1_000_000

#: OR-Tools 9.15 workaround. With its default ``no_overlap_2d_boolean_relations_limit`` (10),
#: CP-SAT sometimes (about 3% of seeds with 2-8 workers) reported OPTIMAL for a worse
#: objective than a known feasible one on our embedded schedule models (optional rectangles
#: sharing start variables). Setting the presolve limit to 0 removed every such run in our
#: stress tests (hundreds of seeds), so every no-overlap-2D model here sets it.
SAFE_NO_OVERLAP_2D = {"no_overlap_2d_boolean_relations_limit": 0}


#: CP-SAT parameters of the decision model (``objective="feasible"``), on top of
#: :data:`SAFE_NO_OVERLAP_2D`; chosen on a training half of bench/data/packing and checked on
#: the other half (bench/results/packing.md).
DECISION_PARAMS: dict[str, Any] = {}

#: Add one redundant cumulative per axis to the decision model.
REDUNDANT_CUMULATIVE = True


class _Rect(Protocol):
    @property
    def width(self) -> float: ...

    @property
    def height(self) -> float: ...


@dataclass(frozen=True)
class PackResult:
    """Outcome of :func:`pack`.

    ``status``: ``optimal`` (fitness proven optimal for the surrogate), ``feasible`` (a layout,
    not proven optimal; always the answer of the ``feasible`` objective), ``infeasible`` (proven
    at this grid) or ``unknown`` (time limit). ``surrogate_objective`` and ``bound`` are the L1
    surrogate (mm) of the layout and the solver's proven upper bound on it (``fitness`` only);
    ``true_fitness`` is the Euclidean :math:`D_{diff} - D_{same} - W_6 Z` of the layout.
    """

    status: str
    layout: tuple[Placement, ...] | None
    wall_time_s: float
    surrogate_objective: float | None = None
    true_fitness: float | None = None
    bound: float | None = None
    extra: dict[str, Any] = field(default_factory=dict)


# ---------------------------------------------------------------------------------------------
# Grid helpers
# ---------------------------------------------------------------------------------------------


def grid_up(v: float, resolution: float) -> int:
    """Size in grid units, rounded up (a part never shrinks beyond the tolerance of
    docs/timeline.md#packing-tolerance)."""
    return cells_needed(v, resolution)


def grid_down(v: float, resolution: float) -> int:
    """Tray size in grid units, rounded down (the tray never grows beyond the tolerance)."""
    return cells_available(v, resolution)


def is_grid_exact(values: Sequence[float], resolution: float) -> bool:
    """True when every value is a multiple of ``resolution`` (up to float noise)."""
    return all(abs(v / resolution - round(v / resolution)) < 1e-6 for v in values)


def exact_resolution(
    values: Sequence[float], max_units: int | None = MAX_EXACT_UNITS
) -> float | None:
    """The coarsest grid (mm) of which every value is a multiple (152.4, 12.7 and 300 give
    0.1; :func:`~bilevel_kit.geometry.exact_step`), None when there is none or the largest
    value would span more than ``max_units`` units (module docstring, "Grid")."""
    return exact_step(values, max_units)


# ---------------------------------------------------------------------------------------------
# The shelf heuristic
# ---------------------------------------------------------------------------------------------


def _shelf(
    sizes: Sequence[tuple[int, int, bool]], W: int, H: int
) -> list[tuple[int, int, bool]] | None:
    """A fast "yes" from the toolkit's shelf packer (:func:`~bilevel_kit.heuristics.shelf.
    shelf_pack`) run in grid units, so its answer holds for the rounded-up sizes."""
    from ..heuristics.shelf import shelf_pack
    from ..instance import Tray

    items = [
        (str(j), PartType(id=str(j), width=w, height=h, pick_time=0.0, rotatable=r))
        for j, (w, h, r) in enumerate(sizes)
    ]
    layout = shelf_pack(Tray(float(W), float(H)), items)
    if layout is None:
        return None
    out: list[tuple[int, int, bool]] = [(0, 0, False)] * len(sizes)
    for p in layout:
        j = int(p.part)
        rot = abs(p.theta - 90.0) < 1e-9
        w, h, _ = sizes[j]
        ww, hh = (h, w) if rot else (w, h)
        out[j] = (round(p.x - ww / 2.0), round(p.y - hh / 2.0), rot)
    return out


# ---------------------------------------------------------------------------------------------
# The CP-SAT packing model
# ---------------------------------------------------------------------------------------------


def pack(
    tray: _Rect,
    items: Sequence[tuple[str, PartType]],
    *,
    objective: str = "feasible",
    resolution: float = 1.0,
    time_limit: float = 10.0,
    workers: int = 2,
    seed: int = 0,
    w6: float | None = None,
    log: bool = False,
    reach: ReachGrid | None = None,
    deterministic_time: float | None = None,
) -> PackResult:
    """Place ``items`` ((part id, part type) pairs) on ``tray`` without overlap.

    ``objective="feasible"`` decides whether they fit (the shelf heuristic answers first when it
    can); ``"fitness"`` maximises the L1 surrogate of the kit fitness (module docstring).
    ``reach`` (a :class:`~bilevel_kit.reachability.ReachGrid`, see
    :func:`bilevel_kit.reachability.reach_grid`) keeps every centre in a reachable cell.
    ``deterministic_time`` (module docstring, "Limits"): limit CP-SAT by deterministic time
    with one worker, a reproducible answer; ``time_limit`` is then a wall-clock safety net on
    the CP-SAT solve.
    """
    if objective not in ("feasible", "fitness"):
        raise ValueError(f"objective must be 'feasible' or 'fitness', not {objective!r}")
    if not (math.isfinite(resolution) and resolution > 0):
        raise ValueError(f"resolution must be a finite number of mm > 0, not {resolution!r}")
    t0 = time.perf_counter()
    grid = _grid(tray, items, resolution, reach)
    extra: dict[str, Any] = {
        "resolution": resolution,
        "grid_exact": grid.exact,
        "objective": objective,
    }
    done = _Done(items, grid, DEFAULT_WEIGHTS["W6"] if w6 is None else w6, t0, extra)
    early = _before_search(tray, items, grid, objective, done)
    if early is not None:
        return early
    model, parts = _build(items, grid, objective)
    params: dict[str, Any] = {
        "num_workers": max(1, workers),
        "random_seed": seed,
        "log_search_progress": log,
    }
    left = time_limit - (time.perf_counter() - t0)
    if deterministic_time is not None:  # reproducible: one worker, the net on the solve alone
        params.update(num_workers=1, max_deterministic_time=max(0.0, deterministic_time))
        left = time_limit
    solver, st = _solve(model, objective, left, params)
    extra["deterministic_time"] = solver.deterministic_time
    if deterministic_time is not None:  # stopped by the safety net, not its own limit?
        cut_short = solver.status_name(st) not in ("OPTIMAL", "INFEASIBLE")
        extra["safety_net"] = cut_short and solver.deterministic_time < 0.999 * deterministic_time
    return _answer(tray, items, grid, objective, solver, st, parts, done)


@dataclass(frozen=True)
class _Grid:
    """The tray (W x H) and the parts' ``sizes`` (w, h, rotatable) in grid units (module
    docstring, "Grid"); ``exact``: every size a multiple of the resolution; ``tables``: the reach
    map on this grid, if any."""

    W: int
    H: int
    sizes: list[tuple[int, int, bool]]
    exact: bool
    resolution: float
    tables: ReachTables | None


def _grid(
    tray: _Rect, items: Sequence[tuple[str, PartType]], resolution: float, reach: ReachGrid | None
) -> _Grid:
    W, H = grid_down(tray.width, resolution), grid_down(tray.height, resolution)
    sizes = [
        (grid_up(pt.width, resolution), grid_up(pt.height, resolution), pt.rotatable)
        for _, pt in items
    ]
    exact = is_grid_exact(
        [tray.width, tray.height] + [v for _, pt in items for v in (pt.width, pt.height)],
        resolution,
    )
    tables = None if reach is None else reach_tables(reach, W, H, resolution)
    return _Grid(W, H, sizes, exact, resolution, tables)


@dataclass(frozen=True)
class _Done:
    """How :func:`pack` ends: grid corners (x, y, rotated) become the layout, with its true
    fitness and the wall time since ``t0``."""

    items: Sequence[tuple[str, PartType]]
    grid: _Grid
    w6: float
    t0: float
    extra: dict[str, Any]

    def __call__(
        self, status: str, corners_: Sequence[tuple[int, int, bool]] | None, **kw: Any
    ) -> PackResult:
        from ..fitness import layout_fitness

        g = self.grid
        layout = (
            None if corners_ is None else _to_layout(self.items, g.sizes, corners_, g.resolution)
        )
        true_fit = None if layout is None else layout_fitness(layout, self.w6)
        wall = time.perf_counter() - self.t0
        return PackResult(status, layout, wall, true_fitness=true_fit, extra=self.extra, **kw)


def _before_search(
    tray: _Rect,
    items: Sequence[tuple[str, PartType]],
    grid: _Grid,
    objective: str,
    done: _Done,
) -> PackResult | None:
    """The answers without a model (module docstring, "Before search"): no parts, the
    pre-search tests of :mod:`.packing_bounds`, and (deciding) the shelf heuristic."""
    if not items:
        return done(
            "feasible" if objective == "feasible" else "optimal",
            [],
            surrogate_objective=0.0 if objective == "fitness" else None,
            bound=0.0 if objective == "fitness" else None,
        )
    from .packing_bounds import infeasibility_reason

    why = infeasibility_reason(grid.sizes, grid.W, grid.H)
    if why is not None:
        # the tests ignore reachability, which only removes layouts: on an exact grid the
        # answer is a proof with or without a reach map
        done.extra["reason"] = why
        scope = _true_size_scope(tray, items)
        if grid.exact and why == "area":
            scope = ANY_ANGLE  # the grid areas are the true areas
        _set_proof(done.extra, items, grid.exact or scope is not None, scope)
        return done("infeasible", None)
    if objective == "feasible":
        shelf = _shelf(grid.sizes, grid.W, grid.H)
        if shelf is not None and corners_reachable(grid.tables, shelf, grid.sizes):
            done.extra["reason"] = "shelf heuristic"
            return done("feasible", shelf)
        from .maxrects import maxrects_pack

        rects = maxrects_pack(grid.sizes, grid.W, grid.H)
        if rects is not None and corners_reachable(grid.tables, rects, grid.sizes):
            done.extra["reason"] = "maxrects heuristic"
            return done("feasible", rects)
    return None


@dataclass
class _Parts:
    """The model's variables per part: lower-left corner, rotation (a 0/1 constant or a
    literal); and its rectangles per axis with their sizes on that axis."""

    xs: list[Any] = field(default_factory=list)
    ys: list[Any] = field(default_factory=list)
    rots: list[Any] = field(default_factory=list)
    x_iv: list[Any] = field(default_factory=list)
    y_iv: list[Any] = field(default_factory=list)
    x_sizes: list[int] = field(default_factory=list)
    y_sizes: list[int] = field(default_factory=list)


def _build(
    items: Sequence[tuple[str, PartType]], grid: _Grid, objective: str
) -> tuple[Any, _Parts]:
    """The CP-SAT packing model of the module docstring ("Model", "Decision model",
    "Fitness", "Reachability")."""
    from ortools.sat.python import cp_model

    W, H, sizes = grid.W, grid.H, grid.sizes
    model = cp_model.CpModel()
    parts = _place_parts(model, grid)
    model.add_no_overlap_2d(parts.x_iv, parts.y_iv)
    if objective == "feasible" and REDUNDANT_CUMULATIVE:
        # redundant: the parts crossing any vertical line stack to at most H, and those
        # crossing a horizontal line to at most W (tight for zero-waste kits)
        model.add_cumulative(parts.x_iv, parts.y_sizes, H)
        model.add_cumulative(parts.y_iv, parts.x_sizes, W)
    # centres on the half grid: 2 cx = 2 x + (w or h)
    xs, ys, rots = parts.xs, parts.ys, parts.rots
    cx2 = [2 * xs[j] + w + (h - w) * rots[j] for j, (w, h, _) in enumerate(sizes)]
    cy2 = [2 * ys[j] + h + (w - h) * rots[j] for j, (w, h, _) in enumerate(sizes)]
    if grid.tables is not None:
        for j in range(len(items)):
            add_reach(model, grid.tables, cx2[j], cy2[j], W, H)

    # identical parts: lexicographic order of lower-left corners
    groups: dict[str, list[int]] = {}
    for j, (_, pt) in enumerate(items):
        groups.setdefault(pt.id, []).append(j)
    for members in groups.values():
        for a, b in itertools.pairwise(members):
            add_lex_less(model, (xs[a], ys[a]), (xs[b], ys[b]))

    if objective == "fitness":
        terms = []
        for a in range(len(items)):
            for b in range(a + 1, len(items)):
                sign = -1 if items[a][1].id == items[b][1].id else 1
                for ca, cb, lim in ((cx2[a], cx2[b], 2 * W), (cy2[a], cy2[b], 2 * H)):
                    dv = model.new_int_var(0, lim, "")
                    model.add_abs_equality(dv, ca - cb)
                    terms.append(sign * dv)
        model.maximize(sum(terms))
    return model, parts


def _place_parts(model: Any, grid: _Grid) -> _Parts:
    """Each part's corner, rotation and rectangles: two optional rectangles (one per
    orientation) for a rotatable, non-square part that fits both ways, else one fixed one."""
    W, H = grid.W, grid.H
    parts = _Parts()
    for j, (w, h, r) in enumerate(grid.sizes):
        can_turn = r and w != h and h <= W and w <= H
        can_stay = w <= W and h <= H
        lo_w = min(w, h) if can_turn else (w if can_stay else h)
        lo_h = min(w, h) if can_turn else (h if can_stay else w)
        x = model.new_int_var(0, W - lo_w, f"x{j}")
        y = model.new_int_var(0, H - lo_h, f"y{j}")
        parts.xs.append(x)
        parts.ys.append(y)
        if can_turn and can_stay:
            rot = model.new_bool_var(f"rot{j}")
            for size_x, size_y, lit in ((w, h, rot.Not()), (h, w, rot)):
                xe = model.new_int_var(0, W, f"xe{j}")
                ye = model.new_int_var(0, H, f"ye{j}")
                parts.x_iv.append(model.new_optional_interval_var(x, size_x, xe, lit, f"ix{j}"))
                parts.y_iv.append(model.new_optional_interval_var(y, size_y, ye, lit, f"iy{j}"))
                parts.x_sizes.append(size_x)
                parts.y_sizes.append(size_y)
            parts.rots.append(rot)
        else:
            turned = not can_stay
            sx, sy = (h, w) if turned else (w, h)
            parts.x_iv.append(model.new_fixed_size_interval_var(x, sx, f"ix{j}"))
            parts.y_iv.append(model.new_fixed_size_interval_var(y, sy, f"iy{j}"))
            parts.x_sizes.append(sx)
            parts.y_sizes.append(sy)
            parts.rots.append(1 if turned else 0)
    return parts


def _solve(
    model: Any, objective: str, time_left: float, params: Mapping[str, Any]
) -> tuple[Any, Any]:
    """CP-SAT on the model for what is left of the time limit; the solver and its status."""
    from ortools.sat.python import cp_model

    solver = cp_model.CpSolver()
    solver.parameters.max_time_in_seconds = max(0.01, time_left)
    for key, value in params.items():
        setattr(solver.parameters, key, value)
    solver.parameters.no_overlap_2d_boolean_relations_limit = 0  # see SAFE_NO_OVERLAP_2D
    if objective == "feasible":
        for key, value in DECISION_PARAMS.items():
            setattr(solver.parameters, key, value)
    from .stoppable import solve  # Ctrl-C and SIGTERM stop it (docs/cli.md)

    return solver, solve(solver, model)


def _answer(
    tray: _Rect,
    items: Sequence[tuple[str, PartType]],
    grid: _Grid,
    objective: str,
    solver: Any,
    st: Any,
    parts: _Parts,
    done: _Done,
) -> PackResult:
    """The result of a CP-SAT solve: its layout, or why there is none (and whether that is a
    proof, module docstring "Grid")."""
    from ortools.sat.python import cp_model

    done.extra["cpsat_status"] = solver.status_name(st)
    if st == cp_model.INFEASIBLE:
        scope = _true_size_scope(tray, items)
        _set_proof(done.extra, items, (grid.exact and grid.tables is None) or bool(scope), scope)
        return done("infeasible", None)
    if st not in (cp_model.OPTIMAL, cp_model.FEASIBLE):
        return done("unknown", None)
    rots = parts.rots
    sol = [
        (
            solver.value(parts.xs[j]),
            solver.value(parts.ys[j]),
            bool(solver.value(rots[j])) if not isinstance(rots[j], int) else bool(rots[j]),
        )
        for j in range(len(items))
    ]
    if objective == "feasible":
        return done("feasible", sol)
    half = grid.resolution / 2.0
    return done(
        "optimal" if st == cp_model.OPTIMAL else "feasible",
        sol,
        surrogate_objective=solver.objective_value * half,
        bound=solver.best_objective_bound * half,
    )


def _true_size_scope(tray: _Rect, items: Sequence[tuple[str, PartType]]) -> str | None:
    """A reason no layout exists, grid or not, and its scope. Every test argues on the
    checker's world made exact (:func:`.packing_bounds.exact_world`: parts ``TOL`` smaller,
    the tray ``TOL`` larger): more part area than tray area, two inscribed disks without room
    (:func:`.packing_bounds.disks_collide`), a part that fits at no angle
    (:func:`.packing_bounds.fits_at_some_angle`) or band parts as wide as the tray
    (:func:`.packing_bounds.band_blocks`): :data:`ANY_ANGLE`; a part that fits the tray in
    neither 0/90-degree orientation: :data:`AXIS_ALIGNED` (a long part may still fit along the
    diagonal); None without one."""
    from .packing_bounds import (
        ANGLE_SLACK,
        band_blocks,
        disks_collide,
        exact_world,
        fits_at_some_angle,
    )

    true = [(pt.width, pt.height) for _, pt in items]
    sizes, W, H = exact_world(true, tray.width, tray.height, TOL)
    if sum(w * h for w, h in sizes) > W * H * (1 + ANGLE_SLACK):
        return ANY_ANGLE
    if disks_collide(sizes, W, H):
        return ANY_ANGLE
    if any(not fits_at_some_angle(w, h, W, H) for w, h in sizes):
        return ANY_ANGLE
    if band_blocks(true, tray.width, tray.height, TOL):
        return ANY_ANGLE
    for (w, h), (_, pt) in zip(sizes, items, strict=True):
        if not (w <= W and h <= H) and not (pt.rotatable and h <= W and w <= H):
            return AXIS_ALIGNED
    return None


def _set_proof(
    extra: dict[str, Any], items: Sequence[tuple[str, PartType]], proof: bool, scope: str | None
) -> None:
    """``extra["proof"]`` and its ``proof_scope`` (module docstring, "Grid"): a proof for
    0/90-degree layouts rules out every layout when no part may rotate (a part that may not
    rotate lies at 0 or 180 degrees, the same footprint)."""
    extra["proof"] = proof
    if not proof:
        extra["proof_scope"] = None
    elif scope == ANY_ANGLE or all(not pt.rotatable for _, pt in items):
        extra["proof_scope"] = ANY_ANGLE
    else:
        extra["proof_scope"] = AXIS_ALIGNED


def add_lex_less(
    model: Any, a: tuple[Any, Any], b: tuple[Any, Any], enforce: Sequence[Any] = ()
) -> None:
    """(a0, a1) <lex (b0, b1) (strictly), optionally only when all ``enforce`` literals hold."""
    eq = model.new_bool_var("")
    model.add(a[0] <= b[0]).only_enforce_if(list(enforce))
    model.add(a[0] == b[0]).only_enforce_if([eq, *enforce])
    model.add(a[0] < b[0]).only_enforce_if([eq.Not(), *enforce])
    model.add(a[1] < b[1]).only_enforce_if([eq, *enforce])


def _to_layout(
    items: Sequence[tuple[str, PartType]],
    sizes: Sequence[tuple[int, int, bool]],
    corners_: Sequence[tuple[int, int, bool]],
    resolution: float,
) -> tuple[Placement, ...]:
    """Grid corners -> real placements, each part centred in its grid cell."""
    out = []
    for (pid, pt), (w, h, _), (x, y, rot) in zip(items, sizes, corners_, strict=True):
        ww, hh = (h, w) if rot else (w, h)
        out.append(
            Placement(
                part=pid,
                type=pt.id,
                x=(2 * x + ww) * resolution / 2.0,
                y=(2 * y + hh) * resolution / 2.0,
                theta=90.0 if rot else 0.0,
                w=pt.width,
                h=pt.height,
            )
        )
    return tuple(out)
