"""Integer times for the CP-SAT schedule model, and the timeline on them.

CP-SAT works on integers, so times become multiples of ``time_resolution`` s (default 0.1 s).
When the instance's times are not multiples of it, the grid is refined to the coarsest divisor
``time_resolution / q`` (q in :data:`bilevel_kit.models.relax.REFINE`, down to 1/1000) on
which all of them are exact; if none exists the times are rounded *down*. Makespan is
non-decreasing in every duration (a max-plus expression, docs/timeline.md), so with
rounded-down times the model's optimum and bound are lower bounds for the real instance: the
reported bound stays valid. The reported makespan is always recomputed by
:func:`bilevel_kit.plan.evaluate` on the real times, and ``optimal`` is claimed only when the
model is exact or that makespan meets the bound.

**Release times** (optional, docs/formulations.md): task i cannot be picked before
``rel_i``; releases are first raised to their ancestors' (the robot picks a kit's tasks in a
topological order, so a task waits for its predecessors' parts too), then scaled like the
other times (rounded down when not on the grid, which keeps every bound valid). Within a kit
the robot picks in the order of release (a topological order, releases being monotone along
precedence), so the kit's pick end is ``max(S + o_R + sum r, max_i (rel_i + sum_{j: rel_j >=
rel_i} r_j))`` (the optimum of one machine with release dates); all zero: the timeline
without releases.

This timeline stays apart from :func:`bilevel_kit.plan.evaluate` for speed (integer times,
unused kit positions, releases) and is held to it by property tests (docs/timeline.md).
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field

from ...instance import Instance
from ...objectives import ModelTerms
from ...objectives import get as get_objective
from ...plan import Plan, evaluate
from .. import packing


@dataclass
class Scaled:
    """Integer times ``value_s = round_or_floor(value / res)`` (``exact``: rounding is exact).

    ``r``, ``h``: robot and human time of each task (file order); ``d`` delivery; ``o_r``,
    ``o_h`` the per-kit overheads; ``trays`` the binding tray limit
    (:attr:`~bilevel_kit.instance.Instance.tray_limit`, None: unlimited); ``rel`` the release
    time of each task, raised to its ancestors' (empty: no releases, module docstring).
    """

    res: float
    exact: bool
    r: list[int]
    h: list[int]
    d: int
    o_r: int
    o_h: int
    trays: int | None = None
    rel: list[int] = field(default_factory=list)
    #: Several stations (docs/timeline.md#several-stations; empty: one): each task's station
    #: (an index into ``station_ids``) and per station its delivery, human overhead and trays.
    station: list[int] = field(default_factory=list)
    st_d: list[int] = field(default_factory=list)
    st_oh: list[int] = field(default_factory=list)
    st_trays: list[int | None] = field(default_factory=list)


def scale_times(
    instance: Instance,
    resolution: float,
    refine: bool = True,
    releases: Mapping[str, float] | None = None,
) -> Scaled:
    """Integer times on the coarsest exact grid ``resolution / q`` of the durations (else
    floored at ``resolution``); ``releases`` (task id -> s, missing: 0) are scaled on that grid
    (``exact`` also needs them on it); see the module docstring."""
    from ..relax import REFINE, time_grid

    ids = [t.id for t in instance.tasks]
    # the delivery times and overheads the timeline uses, each station's (Instance.params_of):
    # with stations the instance's own are only their defaults, and need not be on the grid
    params = [instance.params_of(s) for s in instance.station_ids]
    grid = time_grid(instance, resolution, REFINE if refine else (1,))
    res, exact = (resolution, False) if grid is None else (grid, True)

    rel = released(instance, releases)
    if any(rel):
        exact = exact and packing.is_grid_exact(rel, res)

    def sc(v: float) -> int:
        return round(v / res) if exact else math.floor(v / res + 1e-9)

    out = Scaled(
        res=res,
        exact=exact,
        r=[sc(instance.robot_time(i)) for i in ids],
        h=[sc(instance.human_time(i)) for i in ids],
        # one station: the instance's, or its declared one's; several: the least (the values
        # the one-station bounds may use as a relaxation) and no tray limit
        d=min(sc(p.delivery_time) for p in params),
        o_r=sc(instance.kit_overhead_robot),
        o_h=min(sc(p.kit_overhead_human) for p in params),
        trays=params[0].tray_limit if len(params) == 1 else None,
        rel=[sc(v) for v in rel] if any(rel) else [],
    )
    if len(params) > 1:
        ids = list(instance.station_ids)
        out.station = [ids.index(t.station) for t in instance.tasks]
        out.st_d = [sc(p.delivery_time) for p in params]
        out.st_oh = [sc(p.kit_overhead_human) for p in params]
        out.st_trays = [p.tray_limit for p in params]
    return out


def released(instance: Instance, releases: Mapping[str, float] | None) -> list[float]:
    """Each task's release (file order) raised to its ancestors' (module docstring)."""
    if not releases:
        return [0.0] * instance.n_tasks
    unknown = sorted(set(releases) - set(instance.index))
    if unknown:
        raise ValueError(f"releases of unknown tasks {unknown[:3]}")
    bad = [t for t, v in releases.items() if not (math.isfinite(v) and v >= 0)]
    if bad:
        raise ValueError(f"releases must be finite and >= 0, not for {sorted(bad)[:3]}")
    anc = instance.ancestors
    return [
        max([releases.get(t.id, 0.0)] + [releases.get(a, 0.0) for a in anc[t.id]])
        for t in instance.tasks
    ]


def pick_end(sc: Scaled, start: int, kit: Sequence[int]) -> int:
    """When the robot has picked a used kit that it starts at ``start`` (module docstring)."""
    end = start + sc.o_r + sum(sc.r[i] for i in kit)
    if sc.rel:
        for i in kit:
            if sc.rel[i] > start:
                end = max(end, sc.rel[i] + sum(sc.r[j] for j in kit if sc.rel[j] >= sc.rel[i]))
    return end


def scaled_timeline(sc: Scaled, kits: Sequence[Sequence[int]]) -> list[tuple[int, int, int]]:
    """Robot start, arrival and human end of every kit position on scaled times, with the tray
    rule (docs/timeline.md); empty kits (unused trailing positions) take no time and need no
    tray, which is exactly the least solution of the model's constraints on them. Several
    stations: :func:`stations_timeline`."""
    if sc.station:
        return stations_timeline(sc, kits)[0]
    out: list[tuple[int, int, int]] = []
    hs: list[int] = []  # human starts
    arrive = end = 0
    for k, kit in enumerate(kits):
        used = bool(kit)
        start = arrive
        if sc.trays is not None and k >= sc.trays:
            start = max(start, hs[k - sc.trays] + sc.o_h * used)
        arrive = pick_end(sc, start, kit) + sc.d if used else start
        hk = sc.o_h + sum(sc.h[i] for i in kit) if used else 0
        hs.append(max(arrive, end))
        end = hs[-1] + hk
        out.append((start, arrive, end))
    return out


def stations_timeline(
    sc: Scaled, kits: Sequence[Sequence[int]]
) -> tuple[list[tuple[int, int, int]], dict[int, int]]:
    """:func:`scaled_timeline` with several stations (docs/timeline.md#several-stations; a
    kit's station is its tasks'), and each station's completion (the end of its last kit).
    An unused position takes no time: its start, arrival and end are the previous arrival,
    the least solution of the model's constraints on it."""
    out: list[tuple[int, int, int]] = []
    starts: dict[int, list[int]] = {}  # each station's human starts
    done: dict[int, int] = {}  # each station's last end
    arrive = 0
    for kit in kits:
        if not kit:
            out.append((arrive, arrive, arrive))
            continue
        s = sc.station[kit[0]]
        mine = starts.setdefault(s, [])
        start, trays = arrive, sc.st_trays[s]
        if trays is not None and len(mine) >= trays:  # its T_s-th previous kit's tray is back
            start = max(start, mine[-trays] + sc.st_oh[s])
        arrive = pick_end(sc, start, kit) + sc.st_d[s]
        mine.append(max(arrive, done.get(s, 0)))
        done[s] = mine[-1] + sc.st_oh[s] + sum(sc.h[i] for i in kit)
        out.append((start, arrive, done[s]))
    return out, done


def scaled_makespan(sc: Scaled, kits: Sequence[Sequence[int]]) -> int:
    """The timeline of docs/timeline.md on scaled integer times (kits of task indices)."""
    if sc.station:
        return max(stations_timeline(sc, kits)[1].values(), default=0)
    tl = scaled_timeline(sc, kits)
    return tl[-1][2] if tl else 0


def scaled_objective(sc: Scaled, kits: Sequence[Sequence[int]], objective: str) -> int:
    """Scaled objective of a plan, as the model minimises it (the registry's
    :meth:`~bilevel_kit.objectives.Objective.expression`: the human idle without its
    constant -sum h)."""
    if sc.station:
        done = stations_timeline(sc, kits)[1]
        overhead = sum(sc.st_oh[sc.station[k[0]]] for k in kits if k)
        terms = ModelTerms(
            max(done.values(), default=0), lambda: sum(done.values()), lambda: overhead
        )
        return get_objective(objective).expression(terms)
    c = scaled_makespan(sc, kits)
    terms = ModelTerms.one_station(c, lambda: sc.o_h * len(kits))
    return get_objective(objective).expression(terms)


def released_makespan(
    instance: Instance, plan: Plan, releases: Mapping[str, float], resolution: float = 0.1
) -> float:
    """A plan's makespan with release times (module docstring), on the time grid of
    ``resolution`` (refined); without releases exactly :func:`bilevel_kit.plan.evaluate`'s."""
    if not any(releases.values()):
        return evaluate(instance, plan).makespan
    sc = scale_times(instance, resolution, True, releases)
    idx = instance.index
    return scaled_makespan(sc, [[idx[t] for t in k.tasks] for k in plan.kits]) * sc.res
