"""The instance data model: the dataclasses, the expanded (all-units) view and the constants.

An :class:`Instance` holds one product (or a mix) as tasks with a precedence graph, the part
types the robot kits for them, the tray and the paper's weights; ``units`` copies are built one
after another, and :attr:`Instance.tasks` / :attr:`Instance.precedence` are the expanded view
every solver, the evaluator and the checker work on. Reading a file is :mod:`.parser`'s job.
"""

from __future__ import annotations

import math
from collections import Counter
from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field, replace
from functools import cached_property
from typing import Any

from ..errors import InstanceError
from .ranges import MAX_TIME, MAX_WEIGHT, check_size, parse_trays

FORMAT = "bilevel-kit/1"

#: Defaults of the paper's weights W1..W7 (the paper publishes none; docs/errata.md).
#: Units: W1 per precedence violation (only used when precedence is a penalty, not a hard
#: constraint), W2 seconds per task in the next kit, W3/W4 per second of robot/human mismatch,
#: W5 seconds per millimetre of kit fitness, W6 millimetres of fitness per mm^2 of overlap,
#: W7 seconds per unavailable part.
DEFAULT_WEIGHTS: dict[str, float] = {
    "W1": 1000.0,
    "W2": 1.0,
    "W3": 1.0,
    "W4": 1.0,
    "W5": 0.001,
    "W6": 10.0,
    "W7": 30.0,
}
DEFAULT_HORIZON = 5
#: Seconds a failed feeder takes to repair when the supply gives no ``repair_time``.
DEFAULT_REPAIR_TIME = 30.0


class _Rectangle:
    """The area of a tray or a part: width x height (mm^2)."""

    width: float
    height: float

    @property
    def area(self) -> float:
        return self.width * self.height


@dataclass(frozen=True)
class Tray(_Rectangle):
    width: float
    height: float


@dataclass(frozen=True)
class PartType(_Rectangle):
    """A kind of part; ``rotatable`` parts may lie at any angle on the tray."""

    id: str
    width: float
    height: float
    pick_time: float
    rotatable: bool = True
    name: str = ""
    #: The file's pick time when ``pick_time`` comes from the Sawyer motion model.
    nominal_pick_time: float | None = None
    #: Width of the feature a parallel gripper closes on (mm); ``None``: the smaller side
    #: (docs/execution.md#the-gripper).
    grasp_width: float | None = None


@dataclass(frozen=True)
class Task:
    """One assembly task: the human assembles it from the parts the robot kits for it."""

    id: str
    name: str
    parts: tuple[tuple[str, int], ...]
    human_mean: float
    human_sd: float = 0.0
    robot_time: float | None = None
    product: str = ""
    unit: int = 1
    base_id: str = ""
    #: The assembly station (docs/timeline.md#several-stations): the file's ``station`` field
    #: on a base task, the resolved station on an expanded one; "" without ``stations``.
    station: str = ""


@dataclass(frozen=True)
class Supply:
    """Feeder of one part type for the simulator: Poisson arrivals, exponential failures."""

    mat: float
    mttf: float | None = None
    repair_time: float = DEFAULT_REPAIR_TIME

    @property
    def cycle(self) -> float:
        """The mean time between arrivals, failures included: ``MAT * (1 + repair / MTTF)`` (a
        failure costs the repair time and starts the wait over; exact for this process)."""
        if self.mttf is None:
            return self.mat
        return self.mat * (1.0 + self.repair_time / self.mttf)


@dataclass(frozen=True)
class AssemblyStation:
    """One assembly station served by the robot (docs/timeline.md#several-stations): its own
    delivery time, trays and per-kit human overhead (``None``: the instance's), and the
    products (``"table"``) or product units (``"table@2"``) whose tasks it builds."""

    id: str
    delivery_time: float | None = None
    trays: int | None = None
    kit_overhead_human: float | None = None
    serves: tuple[str, ...] = ()

    def to_dict(self) -> dict[str, Any]:
        doc: dict[str, Any] = {"id": self.id}
        if self.delivery_time is not None:
            doc["delivery_time"] = self.delivery_time
        if self.trays is not None:
            doc["trays"] = self.trays
        if self.kit_overhead_human is not None:
            doc["kit_overhead_human"] = self.kit_overhead_human
        if self.serves:
            doc["serves"] = list(self.serves)
        return doc


@dataclass(frozen=True)
class StationParams:
    """A station's resolved timeline parameters: ``d_s``, ``o_H`` of the station and the
    number of trays that binds (``None``: never)."""

    delivery_time: float
    kit_overhead_human: float
    tray_limit: int | None


#: Cached views of :class:`Instance` that depend only on its tasks, units, stations and
#: precedence, so a copy that changes none of these shares them.
GRAPH_VIEWS = (
    "tasks",
    "served_by",
    "precedence",
    "task_by_id",
    "index",
    "predecessors",
    "ancestors",
)


@dataclass(frozen=True)
class Instance:
    """A kitting problem. Fields mirror the JSON format; see
    :func:`~bilevel_kit.instance.json_schema.schema`."""

    name: str
    tray: Tray
    delivery_time: float
    kit_overhead_robot: float
    kit_overhead_human: float
    part_types: Mapping[str, PartType]
    base_tasks: tuple[Task, ...]
    base_precedence: tuple[tuple[str, str], ...]
    weights: Mapping[str, float] = field(default_factory=lambda: dict(DEFAULT_WEIGHTS))
    horizon: int = DEFAULT_HORIZON
    supply: Mapping[str, Supply] = field(default_factory=dict)
    units: int = 1
    description: str = ""
    assumptions: tuple[str, ...] = ()
    #: The command that made a generated instance (``bilevel-kit generate ...``), else "".
    generated_by: str = ""
    #: The Sawyer work cell's geometry (:class:`bilevel_kit.sawyer.WorkCell`, the file's
    #: ``work_cell`` section), None if not given; the assembly stations are ``stations``.
    work_cell: Any = None
    #: Enforce Sawyer reachability of every placement (packers, CE and the checker).
    reachability: bool = False
    #: Cell size (mm) of the reach map that defines reachability.
    reach_resolution: float = 10.0
    #: ``"pick_time"``: robot times from the parts' pick times; ``"motion"``: each part's pick
    #: time is the Sawyer motion model's mean pick-and-place time over the reachable tray.
    robot_times: str = "pick_time"
    #: Kit trays in circulation (the study's protocol: 1); ``None``: unlimited, the robot may
    #: run ahead of the human (docs/timeline.md).
    trays: int | None = None
    #: Assembly stations (docs/timeline.md#several-stations); empty: one station, every task.
    stations: tuple[AssemblyStation, ...] = ()
    source: str = "<memory>"

    # -- the expanded (all-units) view -------------------------------------------------------
    @cached_property
    def tasks(self) -> tuple[Task, ...]:
        """All tasks of all units; ids get an ``@u`` suffix when ``units > 1``."""
        if self.units == 1:
            return tuple(
                replace(t, base_id=t.base_id or t.id, station=self._station_for(t, 1))
                for t in self.base_tasks
            )
        return tuple(
            replace(
                t,
                id=f"{t.id}@{u}",
                name=f"{t.name} (unit {u})",
                unit=u,
                base_id=t.id,
                station=self._station_for(t, u),
            )
            for u in range(1, self.units + 1)
            for t in self.base_tasks
        )

    def _station_for(self, task: Task, unit: int) -> str:
        """A task's station: its own field, else the station serving its product unit, else
        the one serving its product ("" when none does, which the parser refuses)."""
        if not self.stations or task.station:
            return task.station
        served = self.served_by
        return served.get(f"{task.product}@{unit}", served.get(task.product, ""))

    @cached_property
    def served_by(self) -> dict[str, str]:
        """``serves`` entries (product or ``product@unit``) -> station id."""
        return {key: s.id for s in self.stations for key in s.serves}

    @property
    def station_ids(self) -> tuple[str, ...]:
        """The stations' ids in file order; ``("",)`` for the one implicit station."""
        return tuple(s.id for s in self.stations) if self.stations else ("",)

    def station_of(self, task_id: str) -> str:
        """The station of an (expanded) task; "" without ``stations``."""
        return self.task_by_id[task_id].station

    @cached_property
    def station_params(self) -> dict[str, StationParams]:
        """Each station's ``d_s``, ``o_H`` and binding tray count (docs/timeline.md); without
        ``stations`` the one station "" has the instance's own. The one source of these
        numbers: every timeline, bound and model reads them here, through :meth:`params_of`
        (docs/formats.md, "Stations")."""
        if not self.stations:
            return {"": StationParams(self.delivery_time, self.kit_overhead_human, self.tray_limit)}
        count = Counter(t.station for t in self.tasks)
        out = {}
        for s in self.stations:
            trays = s.trays if s.trays is not None else self.trays
            out[s.id] = StationParams(
                self.delivery_time if s.delivery_time is None else s.delivery_time,
                self.kit_overhead_human if s.kit_overhead_human is None else s.kit_overhead_human,
                None if trays is None or trays >= count[s.id] else trays,
            )
        return out

    def params_of(self, station: str | None = None) -> StationParams:
        """The ``d_s``, ``o_H,s`` and binding trays of ``station`` (:attr:`station_params`).
        ``None``: the one station's, for code that models one station (a station's own
        instance, :func:`station_instance`, or :meth:`as_one_station`); refused with several,
        whose fields may differ per station (docs/timeline.md#several-stations)."""
        if station is not None:
            return self.station_params[station]
        if len(self.station_ids) > 1:
            raise ValueError(
                f"{self.source}: {len(self.station_ids)} stations have parameters of their own: "
                "read one station's (Instance.params_of(station))"
            )
        return self.station_params[self.station_ids[0]]

    def as_one_station(self) -> Instance:
        """With exactly one declared station, the same instance without ``stations`` and with
        that station's ``d``, ``o_H`` and trays as its own: the S = 1 case, which every method
        solves in its place (same tasks, ids and graph; docs/timeline.md#several-stations).
        Otherwise the instance itself."""
        if len(self.stations) != 1:
            return self
        spec = self.stations[0]
        params = self.station_params[spec.id]
        return replace(
            self,
            base_tasks=tuple(replace(t, station="") for t in self.base_tasks),
            delivery_time=params.delivery_time,
            kit_overhead_human=params.kit_overhead_human,
            trays=spec.trays if spec.trays is not None else self.trays,
            stations=(),
        )

    @cached_property
    def precedence(self) -> tuple[tuple[str, str], ...]:
        """Edges of the expanded graph.

        Within a unit the product's own edges; between units, every sink of product p in unit
        u precedes every source of p in unit u+1, which (transitively) makes every task of unit
        u precede every task of the same product in unit u+1.
        """
        if self.units == 1:
            return self.base_precedence
        succ = {t.id: 0 for t in self.base_tasks}
        pred = {t.id: 0 for t in self.base_tasks}
        for a, b in self.base_precedence:
            succ[a] += 1
            pred[b] += 1
        products: dict[str, list[Task]] = {}
        for t in self.base_tasks:
            products.setdefault(t.product, []).append(t)
        if self.stations:
            return self._station_precedence(products, succ, pred)
        edges: list[tuple[str, str]] = []
        for u in range(1, self.units + 1):
            edges += [(f"{a}@{u}", f"{b}@{u}") for a, b in self.base_precedence]
            if u == self.units:
                continue
            for members in products.values():
                sinks = [t.id for t in members if succ[t.id] == 0]
                sources = [t.id for t in members if pred[t.id] == 0]
                edges += [(f"{s}@{u}", f"{r}@{u + 1}") for s in sinks for r in sources]
        return tuple(edges)

    def _station_precedence(
        self, products: dict[str, list[Task]], succ: dict[str, int], pred: dict[str, int]
    ) -> tuple[tuple[str, str], ...]:
        """The expanded edges with stations: the product's own edges in every unit, and the
        units of a product chained station by station (the sinks of its tasks on station s in
        one unit precede their sources on s in the next unit that has any): stations are
        independent (docs/timeline.md#several-stations)."""
        edges = [
            (f"{a}@{u}", f"{b}@{u}")
            for u in range(1, self.units + 1)
            for a, b in self.base_precedence
        ]
        for members in products.values():
            last: dict[str, list[str]] = {}  # station -> sinks of its latest unit
            for u in range(1, self.units + 1):
                groups: dict[str, list[Task]] = {}
                for t in members:
                    groups.setdefault(self._station_for(t, u), []).append(t)
                for st, group in groups.items():
                    sources = [f"{t.id}@{u}" for t in group if pred[t.id] == 0]
                    edges += [(s, r) for s in last.get(st, []) for r in sources]
                    last[st] = [f"{t.id}@{u}" for t in group if succ[t.id] == 0]
        return tuple(edges)

    @cached_property
    def task_by_id(self) -> dict[str, Task]:
        return {t.id: t for t in self.tasks}

    @cached_property
    def index(self) -> dict[str, int]:
        """Position of each task id in :attr:`tasks` (the deterministic tie-break order)."""
        return {t.id: i for i, t in enumerate(self.tasks)}

    @cached_property
    def predecessors(self) -> dict[str, frozenset[str]]:
        """Direct predecessors of each task in the expanded graph."""
        pred: dict[str, set[str]] = {t.id: set() for t in self.tasks}
        for a, b in self.precedence:
            pred[b].add(a)
        return {k: frozenset(v) for k, v in pred.items()}

    @cached_property
    def ancestors(self) -> dict[str, frozenset[str]]:
        """All (transitive) predecessors of each task."""
        out: dict[str, frozenset[str]] = {}
        for tid in topological_order(self):
            acc: set[str] = set()
            for p in self.predecessors[tid]:
                acc.add(p)
                acc |= out[p]
            out[tid] = frozenset(acc)
        return out

    # -- durations and parts -----------------------------------------------------------------
    def robot_time(self, task_id: str) -> float:
        """Robot kitting time of a task: its override, else the sum of its parts' pick times."""
        t = self.task_by_id[task_id]
        if t.robot_time is not None:
            return t.robot_time
        return sum(self.part_types[p].pick_time * n for p, n in t.parts)

    def needs_kit(self, task_id: str) -> bool:
        """Whether a task gives the robot work: parts, or a robot time above 0. A task
        without either (*part-less*) needs no kit of its own: it rides in a neighbouring kit
        of its station (docs/timeline.md#part-less-tasks)."""
        return bool(self.task_by_id[task_id].parts) or self.robot_time(task_id) > 0

    def human_time(self, task_id: str) -> float:
        """Expected human assembly time of a task."""
        return self.task_by_id[task_id].human_mean

    def kit_parts(self, task_ids: Iterable[str]) -> Counter[str]:
        """Multiset of part types (type -> count) that a kit holding these tasks needs."""
        c: Counter[str] = Counter()
        for tid in task_ids:
            for p, n in self.task_by_id[tid].parts:
                c[p] += n
        return c

    @property
    def n_tasks(self) -> int:
        return len(self.tasks)

    # -- variants ----------------------------------------------------------------------------
    def with_overrides(
        self,
        *,
        delivery_time: float | None = None,
        weights: Mapping[str, float] | None = None,
        horizon: int | None = None,
        units: int | None = None,
        trays: int | str | None = None,
    ) -> Instance:
        """A copy with some fields replaced (the CLI's ``--d``, ``--weights``, ``--trays`` ...).

        ``trays="unlimited"`` lifts the tray limit; ``None`` leaves every field as it is.
        """
        changes: dict[str, Any] = {}
        if trays is not None:
            changes["trays"] = parse_trays(trays, self.source)
        if delivery_time is not None:
            if not math.isfinite(delivery_time) or not 0 <= delivery_time <= MAX_TIME:
                raise InstanceError(
                    self.source, "$.delivery_time", f"must be a number in [0, {MAX_TIME:g}] s"
                )
            changes["delivery_time"] = float(delivery_time)
        if weights:
            unknown = set(weights) - set(DEFAULT_WEIGHTS)
            if unknown:
                raise InstanceError(
                    self.source, "$.weights", f"unknown weight(s) {', '.join(sorted(unknown))}"
                )
            for k, v in weights.items():
                if not (math.isfinite(v) and 0 <= v <= MAX_WEIGHT):
                    raise InstanceError(
                        self.source, f"$.weights.{k}", f"must be a number in [0, {MAX_WEIGHT:g}]"
                    )
            changes["weights"] = {**self.weights, **{k: float(v) for k, v in weights.items()}}
        if horizon is not None:
            if horizon < 1:
                raise InstanceError(self.source, "$.horizon", "must be >= 1")
            changes["horizon"] = int(horizon)
        if units is not None:
            if units < 1:
                raise InstanceError(self.source, "$.units", "must be >= 1")
            check_size(len(self.base_tasks), int(units), self.source)
            changes["units"] = int(units)
        out = replace(self, **changes) if changes else self
        if out is not self and "units" not in changes:
            for name in GRAPH_VIEWS:  # same tasks and graph: no re-expansion (linear in tasks)
                if name in self.__dict__:
                    out.__dict__[name] = self.__dict__[name]
        lost = [t.id for t in out.tasks if not t.station] if out.stations else []
        if lost:  # docs/timeline.md#several-stations: every task on a station
            raise InstanceError(
                self.source, "$.units", f"task {lost[0]!r} is on no station with these units"
            )
        return out

    @property
    def tray_limit(self) -> int | None:
        """The number of trays that binds, ``None`` when the robot is never held back (no
        limit, or at least as many trays as tasks, hence as kits)."""
        if self.trays is None or self.trays >= self.n_tasks:
            return None
        return self.trays

    def work_cell_fields(self) -> dict[str, Any]:
        """The document fields of the robot's work cell and of the reachability rule
        (docs/formats.md), those that are set: shared by every writer of instance documents."""
        doc: dict[str, Any] = {}
        if self.work_cell is not None:
            doc["work_cell"] = self.work_cell.to_dict()
        if self.reachability:
            doc["reachability"] = True
            doc["reach_resolution"] = self.reach_resolution
        return doc

    def to_dict(self) -> dict[str, Any]:
        """The JSON document of this instance (the base tasks, not the expansion)."""
        doc: dict[str, Any] = {"format": FORMAT, "name": self.name}
        if self.description:
            doc["description"] = self.description
        if self.assumptions:
            doc["assumptions"] = list(self.assumptions)
        if self.generated_by:
            doc["generated_by"] = self.generated_by
        doc["tray"] = {"width": self.tray.width, "height": self.tray.height}
        doc["delivery_time"] = self.delivery_time
        doc["kit_overhead"] = {"robot": self.kit_overhead_robot, "human": self.kit_overhead_human}
        doc["part_types"] = [
            {
                "id": p.id,
                **({"name": p.name} if p.name else {}),
                "width": p.width,
                "height": p.height,
                "pick_time": p.pick_time if p.nominal_pick_time is None else p.nominal_pick_time,
                "rotatable": p.rotatable,
                **({"grasp_width": p.grasp_width} if p.grasp_width is not None else {}),
            }
            for p in self.part_types.values()
        ]
        tasks = []
        for t in self.base_tasks:
            d: dict[str, Any] = {"id": t.id, "name": t.name}
            if t.product and t.product != self.name:
                d["product"] = t.product
            if t.station:
                d["station"] = t.station
            d["parts"] = [{"type": p, "count": n} for p, n in t.parts]
            d["human_time"] = {"mean": t.human_mean, "sd": t.human_sd}
            if t.robot_time is not None:
                d["robot_time"] = t.robot_time
            tasks.append(d)
        doc["tasks"] = tasks
        doc["precedence"] = [list(e) for e in self.base_precedence]
        doc["weights"] = dict(self.weights)
        doc["horizon"] = self.horizon
        if self.trays is not None:
            doc["trays"] = self.trays
        if self.stations:
            doc["stations"] = [s.to_dict() for s in self.stations]
        if self.supply:
            doc["supply"] = {
                k: {
                    "mat": s.mat,
                    **({"mttf": s.mttf} if s.mttf is not None else {}),
                    "repair_time": s.repair_time,
                }
                for k, s in self.supply.items()
            }
        doc["units"] = self.units
        doc.update(self.work_cell_fields())
        if self.robot_times != "pick_time":
            doc["robot_times"] = self.robot_times
        return doc


def station_instance(instance: Instance, station: str) -> Instance:
    """The tasks of ``station`` as an instance of one station, with its ``d_s``, ``o_H`` and
    trays: the robot serving this station alone. Its plans' makespans are at most the
    station's completion in any plan of ``instance`` (dropping the other stations' kits only
    frees the robot earlier, and times are non-decreasing in start times), so its bounds hold
    for that completion and their max over the stations for the makespan (here, below the
    bounds and the station models that use it; :mod:`bilevel_kit.stations` exports it)."""
    if not instance.stations:
        return instance
    tasks = tuple(replace(t, station="") for t in instance.tasks if t.station == station)
    ids = {t.id for t in tasks}
    spec = next(s for s in instance.stations if s.id == station)
    params = instance.station_params[station]
    return replace(
        instance,
        name=f"{instance.name}:{station}",
        base_tasks=tasks,
        base_precedence=tuple((a, b) for a, b in instance.precedence if a in ids),
        units=1,
        delivery_time=params.delivery_time,
        kit_overhead_human=params.kit_overhead_human,
        trays=spec.trays if spec.trays is not None else instance.trays,
        stations=(),
    )


def topological_order(instance: Instance, rank: Mapping[str, int] | None = None) -> list[str]:
    """Kahn's algorithm with ties broken by ``rank`` (default: file order, the deterministic
    default order): among the ready tasks, the one of smallest rank comes first."""
    import heapq

    indeg = {t.id: 0 for t in instance.tasks}
    succ: dict[str, list[str]] = {t.id: [] for t in instance.tasks}
    for a, b in instance.precedence:
        indeg[b] += 1
        succ[a].append(b)
    pos = rank if rank is not None else {t.id: i for i, t in enumerate(instance.tasks)}
    heap = [(pos[t], t) for t, d in indeg.items() if d == 0]
    heapq.heapify(heap)
    out: list[str] = []
    while heap:
        _, t = heapq.heappop(heap)
        out.append(t)
        for s in succ[t]:
            indeg[s] -= 1
            if indeg[s] == 0:
                heapq.heappush(heap, (pos[s], s))
    return out
