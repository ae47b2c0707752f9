"""An independent reference timeline for the tests, written from docs/timeline.md alone.

It imports nothing of the package's evaluator (``bilevel_kit.plan``), its objectives or its
scaled timelines: a plan is a list of kits of task ids, and the times are plain numbers
(:class:`Times`; :func:`times_of` reads them from an instance's documented fields). The rule,
line by line from docs/timeline.md ("The rule", "Trays in circulation", "Several stations"),
with the release times of docs/formulations.md (CP-SAT schedule, "Release times"):

- ``R_k = o_R + sum r_i``, ``H_k = o_H,s + sum h_i``, ``s`` the station of kit ``k``;
- ``robot_start_k = max(arrive_{k-1}, human_start_j + o_H,s)``, ``j`` the ``T_s``-th previous
  kit of station ``s`` (the term absent while ``s`` has fewer than ``T_s`` kits out, or
  without a tray limit), ``arrive_0 = 0``;
- the robot then picks: ``robot_end_k = robot_start_k + R_k``; with releases, after ``o_R`` it
  picks the kit's tasks in the order of their release raised to their ancestors', each not
  before its release;
- ``arrive_k = robot_end_k + d_s``; ``human_start_k = max(arrive_k, human_end`` of ``s``'s
  previous kit), ``human_end_k = human_start_k + H_k``; task ``i`` of kit ``k`` starts
  ``o_H,s`` after ``human_start_k`` plus the human times of the kit's tasks before it;
- ``C_s`` the human end of ``s``'s last kit (0 without kits), makespan ``max_s C_s``, sum of
  completions ``sum_s C_s``, human idle ``sum_s (C_s - sum_{k at s} H_k)``, robot idle
  ``C - sum_k (R_k + d_s(k))``.

Without ``stations`` the instance is one station holding every task with its ``d``, ``trays``
and ``o_H``.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from functools import partial


@dataclass(frozen=True)
class Station:
    """A station's delivery time ``d_s``, human overhead ``o_H,s`` and trays (None: no limit)."""

    delivery: float
    overhead_human: float
    trays: int | None = None


@dataclass(frozen=True)
class Times:
    """Everything the timeline reads, as plain numbers keyed by task id."""

    o_r: float
    r: Mapping[str, float]
    h: Mapping[str, float]
    stations: Mapping[str, Station]
    #: each task's station (a key of ``stations``)
    station_of: Mapping[str, str]
    #: release times already raised to the ancestors' (missing: 0)
    release: Mapping[str, float] = field(default_factory=dict)


@dataclass(frozen=True)
class KitTimes:
    station: str
    robot_start: float
    robot_end: float
    arrive: float
    human_start: float
    human_end: float


@dataclass(frozen=True)
class RefTimeline:
    kits: tuple[KitTimes, ...]
    task_start: dict[str, float]
    task_end: dict[str, float]
    #: ``C_s`` and ``sum_{k at s} H_k`` of every station (0 for a station without kits)
    completion: dict[str, float]
    human_work_at: dict[str, float]
    robot_work: float

    @property
    def makespan(self) -> float:
        return max(self.completion.values(), default=0.0)

    @property
    def sum_completion(self) -> float:
        return sum(self.completion.values())

    @property
    def human_work(self) -> float:
        return sum(self.human_work_at.values())

    @property
    def human_idle(self) -> float:
        return sum(self.completion[s] - self.human_work_at[s] for s in self.completion)

    @property
    def robot_idle(self) -> float:
        return self.makespan - self.robot_work

    def objective(self, name: str) -> float:
        """``makespan``, ``sum_completion`` or ``human_idle``
        (docs/timeline.md#several-stations)."""
        return float(getattr(self, name))


def times_of(
    inst,
    releases: Mapping[str, float] | None = None,
    *,
    robot_times: Mapping[str, float] | None = None,
    human_times: Mapping[str, float] | None = None,
) -> Times:
    """The numbers of an instance, from its documented fields (docs/formats.md): ``r_i`` the
    sum of the pick times of the task's parts unless it sets ``robot_time``, ``h_i`` its mean
    human time; each station's fields default to the instance's (docs/timeline.md)."""
    r, h, where = {}, {}, {}
    for t in inst.tasks:
        picks = sum(inst.part_types[p].pick_time * n for p, n in t.parts)
        r[t.id] = t.robot_time if t.robot_time is not None else picks
        h[t.id] = t.human_mean
        where[t.id] = t.station if inst.stations else ""
    if robot_times is not None:
        r.update(robot_times)
    if human_times is not None:
        h.update(human_times)
    if not inst.stations:
        stations = {"": Station(inst.delivery_time, inst.kit_overhead_human, inst.trays)}
    else:
        stations = {
            s.id: Station(
                inst.delivery_time if s.delivery_time is None else s.delivery_time,
                inst.kit_overhead_human if s.kit_overhead_human is None else s.kit_overhead_human,
                inst.trays if s.trays is None else s.trays,
            )
            for s in inst.stations
        }
    return Times(inst.kit_overhead_robot, r, h, stations, where, raised(inst, releases or {}))


def raised(inst, releases: Mapping[str, float]) -> dict[str, float]:
    """Each release raised to its ancestors' (docs/formulations.md, "Release times"): the
    transitive predecessors come from the instance's edges, walked here."""
    if not releases:
        return {}
    preds: dict[str, set[str]] = {t.id: set() for t in inst.tasks}
    for a, b in inst.precedence:
        preds[b].add(a)
    out: dict[str, float] = {}

    def rel(t: str) -> float:
        if t not in out:
            out[t] = max([releases.get(t, 0.0)] + [rel(a) for a in preds[t]])
        return out[t]

    for t in preds:
        rel(t)
    return out


def pick_end(times: Times, start: float, kit: Sequence[str]) -> float:
    """When the robot has picked ``kit`` from ``start``: ``o_R``, then the tasks in order of
    release, each picked no earlier than its release (none: ``start + R_k``)."""
    clock = start + times.o_r
    if not times.release:
        return clock + sum(times.r[t] for t in kit)
    for t in sorted(kit, key=lambda t: times.release.get(t, 0.0)):
        clock = max(clock, times.release.get(t, 0.0)) + times.r[t]
    return clock


def step(
    st: Station,
    free: float,
    starts: Sequence[float],
    end: float,
    robot: float | Callable[[float], float],
    human: float,
) -> tuple[float, float, float, float, float]:
    """One kit of station ``st``: its robot start, robot end, arrival, human start and human
    end, given when the robot is free (``arrive_{k-1}``), the human starts of the station's
    kits so far, when its human is free, the kit's ``R_k`` (or its pick end as a function of
    the robot start, with releases) and ``H_k``."""
    robot_start = free
    if st.trays is not None and len(starts) >= st.trays:
        robot_start = max(robot_start, starts[-st.trays] + st.overhead_human)  # tray back
    robot_end = robot(robot_start) if callable(robot) else robot_start + robot
    arrive = robot_end + st.delivery
    human_start = max(arrive, end)
    return robot_start, robot_end, arrive, human_start, human_start + human


def _end(pick: Callable[[float, Sequence[str]], float], kit: Sequence[str], start: float) -> float:
    return pick(start, kit)


def timeline(
    times: Times,
    kits: Sequence[Sequence[str]],
    pick: Callable[[float, Sequence[str]], float] | None = None,
) -> RefTimeline:
    """The timeline of ``kits`` (each a non-empty sequence of one station's tasks, in the
    human's order), delivered in the given order (the module docstring); ``pick(start, kit)``,
    when given, is the robot's end on a kit it starts at ``start`` (a test's own picking)."""
    picked = partial(pick_end, times)
    out: list[KitTimes] = []
    starts: dict[str, list[float]] = {s: [] for s in times.stations}  # human starts per station
    completion = dict.fromkeys(times.stations, 0.0)
    work = dict.fromkeys(times.stations, 0.0)
    task_start: dict[str, float] = {}
    task_end: dict[str, float] = {}
    arrive = robot_work = 0.0
    for kit in kits:
        s = times.station_of[kit[0]]
        st = times.stations[s]
        robot = times.o_r + sum(times.r[t] for t in kit)
        human = st.overhead_human + sum(times.h[t] for t in kit)
        picker = pick if pick is not None else picked if times.release else None
        robot_end = robot if picker is None else partial(_end, picker, kit)
        kt = KitTimes(s, *step(st, arrive, starts[s], completion[s], robot_end, human))
        clock = kt.human_start + st.overhead_human
        for t in kit:
            task_start[t] = clock
            clock += times.h[t]
            task_end[t] = clock
        arrive = kt.arrive
        work[s] += human
        robot_work += robot + st.delivery
        completion[s] = kt.human_end
        starts[s].append(kt.human_start)
        out.append(kt)
    return RefTimeline(tuple(out), task_start, task_end, completion, work, robot_work)


def reference(inst, kits: Sequence[Sequence[str]], **kw) -> RefTimeline:
    """:func:`timeline` of ``kits`` on the numbers of ``inst`` (:func:`times_of`)."""
    return timeline(times_of(inst, **kw), kits)


def close(a: float, b: float, rel: float = 1e-9) -> bool:
    """Equal up to float rounding: the two timelines add the same numbers in other orders."""
    return abs(a - b) <= rel * max(1.0, abs(a), abs(b))


def disagreements(ref: RefTimeline, tl) -> list[str]:
    """Where the package's ``Timeline`` ``tl`` differs from the reference (empty: nowhere):
    every kit's five times, every task's start and end, the metrics, the per-station
    completion and idle, and the registry's objectives."""
    from bilevel_kit.objectives import OBJECTIVES

    bad: list[str] = []

    def same(what: str, a: float, b: float) -> None:
        if not close(a, b):
            bad.append(f"{what}: reference {a!r}, evaluator {b!r}")

    if len(ref.kits) != len(tl.kits):
        return [f"{len(ref.kits)} kits, evaluator {len(tl.kits)}"]
    names = ("robot_start", "robot_end", "arrive", "human_start", "human_end")
    for k, (a, b) in enumerate(zip(ref.kits, tl.kits, strict=True)):
        for name in names:
            same(f"kit {k} {name}", getattr(a, name), getattr(b, name))
    for t in ref.task_start:
        same(f"{t} start", ref.task_start[t], tl.task_start[t])
        same(f"{t} end", ref.task_end[t], tl.task_end[t])
    for name in ("makespan", "human_idle", "robot_idle", "human_work", "robot_work"):
        same(name, getattr(ref, name), getattr(tl, name))
    for s, m in tl.station_metrics().items():
        same(f"{s} completion", ref.completion[s], float(m["completion"]))
        same(f"{s} idle", ref.completion[s] - ref.human_work_at[s], float(m["human_idle"]))
    for name in ("makespan", "sum_completion", "human_idle"):
        same(name, ref.objective(name), OBJECTIVES[name].value(tl))
    return bad
