"""The packing oracle: does a part multiset fit the tray, and what does a "no" prove?

:func:`fit_verdict` answers with memoisation (monotone: sub-multisets of a fitting one fit,
super-multisets of a non-fitting one do not), then the packer of :mod:`.packing`: its
pre-search tests, the shelf heuristic on the grid, then CP-SAT. A "yes" comes with a layout
that the checker accepts (grid sizes are rounded up). A "no" is given only with a proof, and
says which layouts it rules out (:data:`~.packing.ANY_ANGLE` or
:data:`~.packing.AXIS_ALIGNED`, docs/formulations.md#what-optimal-means):

* the packing grid says "no" but is not exact (some size is not a multiple of it): the answer
  is confirmed on the coarsest exact grid (:func:`.packing.exact_resolution`, e.g. 0.1 mm for
  the table's 152.4 x 12.7 mm legs) with the time left, where a layout is a "yes" and
  "infeasible" a proof for 0/90-degree layouts; without an exact grid (or with a reach map,
  where no grid answer is a proof) the answer stays unknown: ``None``, never "no";
* a proof at true sizes (more part area than tray area) rules out every layout, at any angle;
  so does any proof when no part of the multiset may rotate (such parts lie at 0 or 180
  degrees); every other proof rules out the 0/90-degree layouts only, since parts at other
  angles can fit where no axis-aligned layout does.

**Limits.** A call is limited by wall-clock ``time_limit`` (the default; a kit undecided
within it is "unknown", which callers treat as "does not fit", so a heavily loaded machine can
change a verdict) or, with ``deterministic_time``, by CP-SAT's deterministic time with one
worker (:func:`.packing.pack`, "Limits"): then the verdict is the same whatever the load, and
``time_limit`` is only a wall-clock safety net per solve. An unknown answer is memoised per
kind of limit: one of a wall-clock limit is never taken for one of a deterministic limit (nor
one the safety net cut short), so it never turns a reproducible call's answer into "unknown".
:data:`DET_PER_S` converts a wall limit into deterministic units
(docs/simulation.md#determinism).

The exact models cut a kit only on a "no" (``Fit.fits is False``) and claim optimality for
every layout only when each "no" they used has the scope :data:`~.packing.ANY_ANGLE`.
"""

from __future__ import annotations

import math
import time
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

from ..instance import Instance, PartType
from ..plan import Placement
from .packing import ANY_ANGLE, AXIS_ALIGNED, PackResult, exact_resolution, is_grid_exact, pack

if TYPE_CHECKING:
    from ..reachability import ReachGrid
    from .packing import _Rect

#: Layout of a multiset by part type: per type, a list of (x, y, theta) centres.
TypedLayout = dict[str, list[tuple[float, float, float]]]

#: Why an answer is unknown: the time limit (a longer one may decide), or no exact grid to
#: confirm a "no" of the packing grid on (more time does not help).
WHY_TIME = "time limit"
WHY_GRID = "no layout on the packing grid, not confirmed on an exact grid"
#: The kinds of limit of a packing call (module docstring, "Limits"): wall-clock seconds, or
#: CP-SAT's deterministic time with one worker (reproducible whatever the machine load).
WALL, DET = "wall", "deterministic"
#: Deterministic units a reproducible call gets per second of the wall limit it replaces.
#: Measured with one worker on bench/data/packing (load 2.5 on 2 cores): decided solves ran
#: 0.05-0.2 units per wall second, those cut at 0.5 s reached 0.06-0.11 units; so a call
#: decides at least what the wall limit decided on such a machine (docs/simulation.md).
DET_PER_S = 0.25
#: The wall-clock safety net of a reproducible call: this many times the limit it replaces.
SAFETY_NET = 10.0


def deterministic_limits(seconds: float) -> tuple[float, float]:
    """A wall limit of ``seconds`` as (deterministic time, wall-clock safety net) of a
    reproducible call (:data:`DET_PER_S`, :data:`SAFETY_NET`)."""
    return DET_PER_S * seconds, SAFETY_NET * seconds


@dataclass(frozen=True)
class Fit:
    """The oracle's answer: ``fits`` True (with ``layout``), False (proven, ``scope`` says for
    which layouts) or None (unknown, ``why``)."""

    fits: bool | None
    layout: TypedLayout | None = None
    scope: str | None = None
    why: str | None = None


@dataclass
class _FitCache:
    """Known answers for one (tray, part types, resolution): monotone in the multiset, so a
    sub-multiset of a fitting one fits, and a super-multiset of a non-fitting one does not
    (with the same scope)."""

    fits: list[tuple[dict[str, int], TypedLayout]] = field(default_factory=list)
    nofit: list[tuple[dict[str, int], str]] = field(default_factory=list)
    #: (multiset, limit kind) -> (the limit tried, in that kind's unit: s or deterministic
    #: units; why unknown): a wall-clock unknown never stands for a deterministic one
    unknown: dict[tuple[frozenset[tuple[str, int]], str], tuple[float, str]] = field(
        default_factory=dict
    )
    solves: int = 0
    #: reproducible solves a wall-clock safety net cut short (docs/simulation.md#determinism)
    nets: int = 0


_CACHES: dict[tuple[Any, ...], _FitCache] = {}


def _cache_for(
    tray: _Rect, part_types: Mapping[str, PartType], resolution: float, reach: ReachGrid | None
) -> _FitCache:
    key = (
        tray.width,
        tray.height,
        resolution,
        tuple(sorted((p.id, p.width, p.height, p.rotatable) for p in part_types.values())),
        None
        if reach is None
        else (reach.reachable.tobytes(), reach.reachable.shape, reach.cell_size),
    )
    return _CACHES.setdefault(key, _FitCache())


def pack_solves() -> int:
    """Packing solves so far, over every cache (a run reports its own by difference)."""
    return sum(c.solves for c in _CACHES.values())


def safety_nets() -> int:
    """Reproducible packing solves cut by their wall-clock safety net so far, over every cache
    (a run reports its own by difference: then its answers are not reproducible)."""
    return sum(c.nets for c in _CACHES.values())


def _leq(a: Mapping[str, int], b: Mapping[str, int]) -> bool:
    return all(b.get(k, 0) >= n for k, n in a.items())


def _known(
    cache: _FitCache, counts: dict[str, int], part_types: Mapping[str, PartType], tray: _Rect
) -> Fit | None:
    """The answer the cache implies (monotonicity), the strongest scope first; None if none."""
    for known, layout in cache.fits:
        if _leq(counts, known):
            return Fit(True, {k: layout[k][:n] for k, n in counts.items()})
    scopes = {scope for known, scope in cache.nofit if _leq(known, counts)}
    if ANY_ANGLE in scopes:
        return Fit(False, scope=ANY_ANGLE)
    if scopes:  # more part area than tray area would prove more
        area = sum(part_types[k].area * n for k, n in counts.items())
        return Fit(False, scope=ANY_ANGLE if area > tray.width * tray.height else AXIS_ALIGNED)
    return None


def fit_verdict(
    tray: _Rect,
    part_types: Mapping[str, PartType],
    counts: Mapping[str, int],
    *,
    time_limit: float = 2.0,
    resolution: float = 1.0,
    workers: int = 2,
    seed: int = 0,
    reach: ReachGrid | None = None,
    deterministic_time: float | None = None,
) -> Fit:
    """Whether a part multiset fits (module docstring), memoised; an unknown answer is retried
    only with a longer limit of the same kind (and never when no exact grid can confirm it).
    ``deterministic_time`` (module docstring, "Limits"): CP-SAT limited by deterministic time
    with one worker, ``time_limit`` the wall-clock safety net of each solve."""
    counts = {k: int(n) for k, n in counts.items() if n > 0}
    cache = _cache_for(tray, part_types, resolution, reach)
    known = _known(cache, counts, part_types, tray)
    if known is not None:
        return known
    det = deterministic_time is not None
    kind, budget = (WALL, time_limit) if deterministic_time is None else (DET, deterministic_time)
    key = frozenset(counts.items())
    tried = cache.unknown.get((key, kind))
    if tried is not None and tried[0] >= budget:
        return Fit(None, why=tried[1])
    from ..heuristics.shelf import kit_items

    items = kit_items(part_types, counts)
    cache.solves += 1
    t0 = time.perf_counter()
    kw: dict[str, Any] = {"workers": 1 if det else workers, "seed": seed, "reach": reach}
    kw["deterministic_time"] = deterministic_time
    res = pack(tray, items, resolution=resolution, time_limit=time_limit, **kw)
    why = WHY_TIME
    if res.status == "infeasible" and not res.extra.get("proof"):
        # a "no" of this grid alone: confirm it on the exact grid, with the time left
        exact = None if reach is not None else _exact_grid(tray, items)
        left = time_limit - (time.perf_counter() - t0)
        if det:  # the deterministic time left; the safety net: the whole wall limit again
            left = budget - res.extra.get("deterministic_time", 0.0)
            kw["deterministic_time"] = left
        if exact is None:
            why = WHY_GRID
        elif left > (1e-4 if det else 0.01):
            res = pack(tray, items, resolution=exact, time_limit=time_limit if det else left, **kw)
    fit = _record(cache, counts, res)
    if fit is None:
        if res.extra.get("safety_net"):  # the wall clock stopped it: no deterministic answer
            kind, budget = WALL, time_limit
            cache.nets += 1
        cache.unknown[(key, kind)] = (budget if why == WHY_TIME else math.inf, why)
        return Fit(None, why=why)
    return fit


def _exact_grid(tray: _Rect, items: Sequence[tuple[str, PartType]]) -> float | None:
    """The coarsest grid on which the tray and these parts are exact (None: none, or absurd)."""
    values = [tray.width, tray.height] + [v for _, pt in items for v in (pt.width, pt.height)]
    res = exact_resolution(values)
    return res if res is not None and is_grid_exact(values, res) else None


def _record(cache: _FitCache, counts: dict[str, int], res: PackResult) -> Fit | None:
    """A packer's answer, memoised: a layout or a proven "no"; None when it is neither."""
    if res.status == "infeasible" and res.extra.get("proof"):
        scope = res.extra.get("proof_scope") or AXIS_ALIGNED
        cache.nofit.append((counts, scope))
        return Fit(False, scope=scope)
    if res.layout is None:
        return None
    typed: TypedLayout = {}
    for p in res.layout:
        typed.setdefault(p.type, []).append((p.x, p.y, p.theta))
    cache.fits.append((counts, typed))
    return Fit(True, typed)


def kit_fits(
    instance: Instance,
    part_counts: Mapping[str, int],
    time_limit: float = 2.0,
    *,
    resolution: float = 1.0,
) -> bool | None:
    """Cheap memoised oracle: do these parts (type -> count) fit on the instance's tray?
    False only with a proof (:func:`fit_verdict` tells its scope)."""
    return kit_verdict(instance, part_counts, time_limit, resolution).fits


def kit_verdict(
    instance: Instance, counts: Mapping[str, int], time_limit: float, resolution: float = 1.0
) -> Fit:
    """:func:`fit_verdict` on the instance's tray and part types, within the robot's reach."""
    from ..reachability import reach_grid

    return fit_verdict(
        instance.tray,
        instance.part_types,
        counts,
        time_limit=time_limit,
        resolution=resolution,
        reach=reach_grid(instance),
    )


def kit_layout(
    instance: Instance,
    task_ids: Sequence[str],
    *,
    time_limit: float = 2.0,
    resolution: float = 1.0,
) -> tuple[Placement, ...] | None:
    """A non-overlapping layout for the parts of these tasks (part ids ``task:type:j``), or
    None when they do not fit or the answer is unknown."""
    fit = kit_verdict(instance, instance.kit_parts(task_ids), time_limit, resolution)
    if not fit.fits or fit.layout is None:
        return None
    return typed_to_placements(instance, task_ids, fit.layout)


def typed_to_placements(
    instance: Instance, task_ids: Sequence[str], typed: TypedLayout
) -> tuple[Placement, ...]:
    """Hand out the slots of a by-type layout to the tasks' parts, in task order."""
    used = dict.fromkeys(typed, 0)
    out = []
    for tid in task_ids:
        for ptype, n in instance.task_by_id[tid].parts:
            pt = instance.part_types[ptype]
            for j in range(1, n + 1):
                x, y, theta = typed[ptype][used[ptype]]
                used[ptype] += 1
                out.append(
                    Placement(
                        part=f"{tid}:{ptype}:{j}",
                        type=ptype,
                        x=x,
                        y=y,
                        theta=theta,
                        w=pt.width,
                        h=pt.height,
                    )
                )
    return tuple(out)


def clear_cache() -> None:
    """Forget every memoised packing answer (tests, benchmarks)."""
    _CACHES.clear()
