"""Plans (ordered kits with tray layouts) and the one timeline evaluator (docs/timeline.md).

For kits k = 1..m in delivery order::

    R_k = o_R + sum_{i in S_k} r_i            H_k = o_H + sum_{i in S_k} h_i
    robot_start_1 = 0
    robot_start_k = max(arrive_{k-1}, human_start_{k-T} + o_H)     (T = trays; k > T)
    robot_start_k = arrive_{k-1}                                    (k <= T, or no limit)
    robot_end_k = robot_start_k + R_k,       arrive_k = robot_end_k + d
    human_start_k = max(arrive_k, human_end_{k-1}),  human_end_k = human_start_k + H_k
    C = human_end_m,  human idle = C - sum_k H_k,  robot idle = C - sum_k (R_k + d)

The robot pushes the tray, so it is busy while it delivers. With ``T`` trays in circulation
(the paper's study: one) the tray of kit k - T comes back once the human has retrieved its
parts, ``o_H`` after starting it; the robot cannot start kit k before. Robot idle counts
delivery as robot work.
With several assembly stations (docs/timeline.md#several-stations) ``d``, ``o_H``, ``T`` and
"the previous kit" of the human and of the tray rule are those of the kit's station; the
robot is shared, so ``arrive_{k-1}`` is the previous kit of any station.
Every solver, the checker, the simulator and the plots go through :func:`evaluate`.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, fields, replace

from .instance import Instance


@dataclass(frozen=True)
class Placement:
    """One part on the tray: footprint centre (x, y) in mm from the tray's lower-left corner,
    rotation ``theta`` in degrees counter-clockwise, unrotated footprint ``w`` x ``h`` in mm."""

    part: str
    type: str
    x: float
    y: float
    theta: float
    w: float
    h: float

    def to_dict(self) -> dict[str, str | float]:
        """The JSON form used by solution and layout files."""
        return {f.name: getattr(self, f.name) for f in fields(self)}


@dataclass(frozen=True)
class Kit:
    """One tray: its tasks in the order the human does them, and its layout."""

    tasks: tuple[str, ...]
    layout: tuple[Placement, ...] = ()


@dataclass(frozen=True)
class Plan:
    """Kits in delivery order."""

    kits: tuple[Kit, ...]

    @property
    def task_order(self) -> list[str]:
        return [t for k in self.kits for t in k.tasks]


@dataclass(frozen=True)
class KitTimes:
    robot_start: float
    robot_end: float
    arrive: float
    human_start: float
    human_end: float


@dataclass(frozen=True)
class Timeline:
    """The evaluated schedule of a plan and its metrics."""

    kits: tuple[KitTimes, ...]
    task_start: Mapping[str, float]
    task_end: Mapping[str, float]
    makespan: float
    human_idle: float
    robot_idle: float
    human_work: float
    robot_work: float
    #: each kit's station, with several stations (docs/timeline.md#several-stations); empty
    #: for one station
    kit_stations: tuple[str, ...] = ()

    @classmethod
    def from_work(
        cls,
        kits: Sequence[KitTimes],
        task_start: Mapping[str, float],
        task_end: Mapping[str, float],
        makespan: float,
        human_work: float,
        robot_work: float,
    ) -> Timeline:
        """A timeline whose idle times are the makespan less each side's work (the module
        docstring); the evaluator and the simulator's log both build theirs this way."""
        return cls(
            tuple(kits),
            dict(task_start),
            dict(task_end),
            makespan,
            makespan - human_work,
            makespan - robot_work,
            human_work,
            robot_work,
        )

    @property
    def n_kits(self) -> int:
        return len(self.kits)

    def station_metrics(self) -> dict[str, dict[str, float | int]]:
        """Per station: its completion time, its human's idle time (completion less the
        human's work there) and its kits; empty for one station (the four metrics say it)."""
        out: dict[str, dict[str, float | int]] = {}
        if not self.kit_stations:
            return out
        for kt, s in zip(self.kits, self.kit_stations, strict=True):
            m = out.setdefault(s, {"completion": 0.0, "human_idle": 0.0, "n_kits": 0})
            m["human_idle"] = float(m["human_idle"]) - (kt.human_end - kt.human_start)
            m["completion"] = max(m["completion"], kt.human_end)
            m["n_kits"] = int(m["n_kits"]) + 1
        for m in out.values():
            m["human_idle"] = float(m["completion"]) + float(m["human_idle"])
        return out

    def metrics(self) -> dict[str, float | int]:
        return {
            "makespan": self.makespan,
            "human_idle": self.human_idle,
            "robot_idle": self.robot_idle,
            "n_kits": self.n_kits,
        }


def tray_back(instance: Instance, kits: Sequence[KitTimes], station: str = "") -> float:
    """When a tray of ``station`` is free for its next kit, given that station's ``kits`` so
    far: 0 while fewer than ``T_s`` kits are out, else ``human_start + o_H`` of the kit
    ``T_s`` back (docs/timeline.md)."""
    params = instance.params_of(station)
    trays = params.tray_limit
    if trays is None or len(kits) < trays:
        return 0.0
    return kits[-trays].human_start + params.kit_overhead_human


def next_robot_start(instance: Instance, kits: Sequence[KitTimes]) -> float:
    """The earliest start of the robot on the kit after ``kits`` on an instance of one
    station: the previous kit has arrived and a tray is back (docs/timeline.md); with several
    stations, :meth:`TimelineBuilder.next_start`."""
    return max(kits[-1].arrive if kits else 0.0, tray_back(instance, kits))


def kit_durations(
    instance: Instance,
    tasks: Sequence[str],
    robot_times: Mapping[str, float] | None = None,
    human_times: Mapping[str, float] | None = None,
) -> tuple[float, float]:
    """(R_k, H_k) of a kit holding ``tasks``: overheads plus the tasks' robot/human times."""
    r = instance.kit_overhead_robot
    h = instance.params_of(kit_station(instance, tasks)).kit_overhead_human
    for t in tasks:
        r += robot_times[t] if robot_times is not None else instance.robot_time(t)
        h += human_times[t] if human_times is not None else instance.human_time(t)
    return r, h


def kit_station(instance: Instance, tasks: Sequence[str]) -> str:
    """The station of a kit: its first task's ("" without stations; the checker refuses a
    kit that mixes stations, ``wrong_station``, and an empty kit, timed at the first
    station)."""
    if not instance.stations:
        return ""
    return instance.station_of(tasks[0]) if tasks else instance.station_ids[0]


class TimelineBuilder:
    """The timeline evaluator, one kit at a time: :func:`evaluate` is a loop over
    :meth:`append`, and a planner that grows a plan kit by kit (greedy-ce's epochs) keeps one
    builder instead of re-evaluating the whole plan each epoch (O(m) instead of O(m^2))."""

    def __init__(
        self,
        instance: Instance,
        *,
        robot_times: Mapping[str, float] | None = None,
        human_times: Mapping[str, float] | None = None,
    ) -> None:
        self.instance = instance
        self.robot_times = robot_times
        self.human_times = human_times
        self.kits: list[KitTimes] = []
        self.kit_stations: list[str] = []
        #: each station's kits so far, in delivery order
        self.by_station: dict[str, list[KitTimes]] = {s: [] for s in instance.station_ids}
        self.task_start: dict[str, float] = {}
        self.task_end: dict[str, float] = {}
        self.robot_work = 0.0
        self.human_work = 0.0

    @property
    def human_free(self) -> float:
        """When the last human finishes the kits so far (0 before the first): with one
        station, its human's end of the last kit."""
        if self.instance.stations:
            return max(self.station_free(s) for s in self.by_station)
        return self.kits[-1].human_end if self.kits else 0.0

    def station_free(self, station: str = "") -> float:
        """When the human of ``station`` finishes its last kit so far (0 before its first)."""
        own = self.by_station[station]
        return own[-1].human_end if own else 0.0

    def next_start(self, station: str = "") -> float:
        """The earliest robot start of the next kit if it is for ``station``: the robot is
        free (the previous kit, of any station, has arrived) and a tray of ``station`` is
        back (docs/timeline.md#several-stations)."""
        free = self.kits[-1].arrive if self.kits else 0.0
        return max(free, tray_back(self.instance, self.by_station[station], station))

    def append(self, kit: Kit) -> KitTimes:
        """Add the next kit in delivery order and return its times (the module docstring)."""
        inst, human_times = self.instance, self.human_times
        station = kit_station(inst, kit.tasks)
        params = inst.params_of(station)
        r, h = kit_durations(inst, kit.tasks, self.robot_times, human_times)
        robot_start = self.next_start(station)
        robot_end = robot_start + r
        arrive = robot_end + params.delivery_time
        human_start = max(arrive, self.station_free(station))
        human_end = human_start + h
        clock = human_start + params.kit_overhead_human
        for t in kit.tasks:
            self.task_start[t] = clock
            clock += human_times[t] if human_times is not None else inst.human_time(t)
            self.task_end[t] = clock
        times = KitTimes(robot_start, robot_end, arrive, human_start, human_end)
        self.kits.append(times)
        self.kit_stations.append(station)
        self.by_station[station].append(times)
        self.robot_work += r + params.delivery_time
        self.human_work += h
        return times

    def timeline(self) -> Timeline:
        """The timeline of the kits appended so far."""
        if not self.instance.stations:
            return Timeline.from_work(
                self.kits,
                self.task_start,
                self.task_end,
                self.human_free,
                self.human_work,
                self.robot_work,
            )
        ends = [self.station_free(s) for s in self.by_station]
        return replace(
            Timeline.from_work(
                self.kits,
                self.task_start,
                self.task_end,
                max(ends),
                self.human_work,
                self.robot_work,
            ),
            human_idle=sum(ends) - self.human_work,
            kit_stations=tuple(self.kit_stations),
        )


def evaluate(
    instance: Instance,
    plan: Plan,
    *,
    robot_times: Mapping[str, float] | None = None,
    human_times: Mapping[str, float] | None = None,
) -> Timeline:
    """The timeline (docs/timeline.md) of ``plan`` (see the module docstring).

    ``robot_times``/``human_times`` replace the instance's expected task times (the simulator
    passes sampled durations); they must cover every task of the plan. The plan is not checked
    here: see :func:`bilevel_kit.validate.check`.
    """
    builder = TimelineBuilder(instance, robot_times=robot_times, human_times=human_times)
    for kit in plan.kits:
        builder.append(kit)
    return builder.timeline()


def kitless(instance: Instance, kit: Kit) -> bool:
    """A kit of part-less tasks only (no parts, no robot time): the checker's
    ``kit_without_parts``; :func:`fold_kitless` removes it (docs/timeline.md#part-less-tasks)."""
    known = instance.task_by_id
    return bool(kit.tasks) and all(t in known and not instance.needs_kit(t) for t in kit.tasks)


def fold_kitless(instance: Instance, plan: Plan) -> Plan:
    """``plan`` with every kit of part-less tasks merged into a neighbouring kit of its
    station: the previous one (its tasks done after that kit's), else the next one (before
    them). A part-less task needs no kit of its own (docs/timeline.md#part-less-tasks); the
    merge keeps the plan's task order within each station, hence every precedence (stations
    share no edge), and the layout of the kit it joins. A plan without such kits comes back
    unchanged (the same object)."""
    if not any(kitless(instance, k) for k in plan.kits):
        return plan
    kits: list[Kit | None] = list(plan.kits)
    stations = [kit_station(instance, k.tasks) for k in plan.kits]
    last: dict[str, int] = {}  # each station's last kit with parts so far
    for k, kit in enumerate(plan.kits):
        if not kitless(instance, kit):
            last[stations[k]] = k
        elif stations[k] in last:  # forward: after the previous kit of its station
            j = last[stations[k]]
            target = kits[j]
            assert target is not None
            kits[j], kits[k] = replace(target, tasks=target.tasks + kit.tasks), None
    following: dict[str, int] = {}  # backward: the leading ones, before the next kit
    for k in range(len(kits) - 1, -1, -1):
        cur = kits[k]
        if cur is None:
            continue
        if not kitless(instance, cur):
            following[stations[k]] = k
        elif stations[k] in following:
            j = following[stations[k]]
            target = kits[j]
            assert target is not None
            kits[j], kits[k] = replace(target, tasks=cur.tasks + target.tasks), None
    # a station without a kit with parts keeps its part-less kits for the checker to report
    return Plan(tuple(k for k in kits if k is not None))
