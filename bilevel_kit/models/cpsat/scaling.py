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


@dataclass
class Clock:
    """The timeline's state after a run of kits (docs/timeline.md#several-stations; one
    station is station 0 with the instance's ``d``, ``o_H`` and trays), and the only place its
    per-kit recursion is written: ``arrive`` the last arrival; per station index ``done`` (its
    human's end), ``starts`` (the human starts of its kits, oldest first, only the last ``T_s``
    kept: no later time depends on the others) and ``kits`` (its used kits). The timelines
    below step it from the start; lns's exact windows step it from a prefix's end
    (bilevel_kit/models/lns/clock.py)."""

    arrive: int
    done: list[int]
    starts: list[list[int]]
    kits: list[int]

    @classmethod
    def start(cls, sc: Scaled) -> Clock:
        n = max(1, len(sc.st_d))
        return cls(0, [0] * n, [[] for _ in range(n)], [0] * n)

    def copy(self) -> Clock:
        return Clock(self.arrive, list(self.done), [list(s) for s in self.starts], list(self.kits))

    def step(self, sc: Scaled, kit: Sequence[int]) -> tuple[int, int, int]:
        """Deliver ``kit`` (task indices) after the kits so far; its robot start, arrival and
        human end. An empty kit (a model's unused position) is the least solution of that
        model's constraints on it: with one station a kit of no duration that still waits for
        a tray (:meth:`_unused`), with several stations nothing at all (start, arrival and end
        the previous arrival)."""
        if not kit:
            return self._unused(sc)
        if sc.station:
            s = sc.station[kit[0]]
            d, o_h, trays = sc.st_d[s], sc.st_oh[s], sc.st_trays[s]
        else:  # one station: the instance's own
            s, d, o_h, trays = 0, sc.d, sc.o_h, sc.trays
        mine = self.starts[s]
        start = self.arrive
        if trays is not None and len(mine) >= trays:  # its T_s-th previous kit's tray is back
            start = max(start, mine[-trays] + o_h)
        self.arrive = pick_end(sc, start, kit) + d
        human_start = max(self.arrive, self.done[s])
        mine.append(human_start)
        if trays is not None and len(mine) > trays:
            del mine[0]
        self.done[s] = human_start + o_h + sum(sc.h[i] for i in kit)
        self.kits[s] += 1
        return start, self.arrive, self.done[s]

    def _unused(self, sc: Scaled) -> tuple[int, int, int]:
        """An empty position. One station: it takes a tray back (without ``o_H``: no parts to
        take off), arrives when it starts, and its human start joins the tray window, as the
        one-station model's unused positions do (:mod:`.model`)."""
        if sc.station:
            return self.arrive, self.arrive, self.arrive
        mine, trays = self.starts[0], sc.trays
        if trays is not None and len(mine) >= trays:
            self.arrive = max(self.arrive, mine[-trays])
        self.done[0] = max(self.arrive, self.done[0])
        mine.append(self.done[0])
        if trays is not None and len(mine) > trays:
            del mine[0]
        return self.arrive, self.arrive, self.done[0]


def clock_after(sc: Scaled, kits: Sequence[Sequence[int]]) -> Clock:
    """The :class:`Clock` after ``kits`` from the start."""
    clock = Clock.start(sc)
    for kit in kits:
        clock.step(sc, kit)
    return clock


def scaled_timeline(sc: Scaled, kits: Sequence[Sequence[int]]) -> list[tuple[int, int, int]]:
    """Robot start, arrival and human end of every kit position on scaled times, with the tray
    and station rules (docs/timeline.md); empty kits as :meth:`Clock.step` says."""
    clock = Clock.start(sc)
    return [clock.step(sc, kit) for kit in kits]


def stations_timeline(
    sc: Scaled, kits: Sequence[Sequence[int]]
) -> tuple[list[tuple[int, int, int]], dict[int, int]]:
    """:func:`scaled_timeline` with several stations (docs/timeline.md#several-stations; a
    kit's station is its tasks'), and the completion of each station with kits (the end of
    its last kit)."""
    clock = Clock.start(sc)
    rows = [clock.step(sc, kit) for kit in kits]
    return rows, {s: done for s, done in enumerate(clock.done) if clock.kits[s]}


def scaled_makespan(sc: Scaled, kits: Sequence[Sequence[int]]) -> int:
    """The timeline of docs/timeline.md on scaled integer times (kits of task indices): the
    latest station's human end (0 for no kits)."""
    return max(clock_after(sc, kits).done)


def scaled_objective(sc: Scaled, kits: Sequence[Sequence[int]], objective: str) -> int:
    """Scaled objective of a plan, as the model minimises it (the registry's
    :meth:`~bilevel_kit.objectives.Objective.expression`: the human idle without its
    constant -sum h)."""
    clock = clock_after(sc, kits)
    if sc.station:
        overhead = sum(o_h * n for o_h, n in zip(sc.st_oh, clock.kits, strict=True))
        terms = ModelTerms(max(clock.done), lambda: sum(clock.done), lambda: overhead)
    else:  # (every position, as the one-station model counts them)
        terms = ModelTerms.one_station(clock.done[0], lambda: sc.o_h * len(kits))
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
