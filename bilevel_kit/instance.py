"""Instance data model, loading and validation (format ``bilevel-kit/1``).

Lengths are in millimetres, times in seconds. An instance describes one product (or a mix of
products) as tasks with a precedence graph, the part types the robot kits for them, the tray, the
delivery time and the paper's weights. ``units`` copies of the product are built one after
another; :attr:`Instance.tasks` and :attr:`Instance.precedence` are the expanded (all-units) view
that every solver, the evaluator and the checker work on.

Loading validates the structure with a JSON Schema (:func:`schema`) and then the semantics
(unknown references, duplicates, cycles, parts larger than the tray). Every problem raises
:class:`~bilevel_kit.errors.InstanceError`, whose message names the file and the JSON path.
"""

from __future__ import annotations

import math
from collections import Counter
from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field, replace
from functools import cached_property
from pathlib import Path
from typing import Any

from . import jsonio
from .errors import InstanceError
from .jsonio import ErrorType, validate_document

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

#: Sane ranges of an instance's numbers (docs/formats.md#ranges): lengths in
#: [MIN_LENGTH, MAX_LENGTH] mm, times in [0, MAX_TIME] s, weights in [0, MAX_WEIGHT]. Outside
#: them the geometry's 1e-6 mm tolerance and the checker's time tolerance lose their meaning.
MIN_LENGTH = 0.01
MAX_LENGTH = 1e5
MAX_TIME = 1e7
MAX_WEIGHT = 1e6
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


@dataclass(frozen=True)
class Supply:
    """Feeder of one part type for the simulator: Poisson arrivals, exponential failures."""

    mat: float
    mttf: float | None = None
    repair_time: float = DEFAULT_REPAIR_TIME


@dataclass(frozen=True)
class Instance:
    """A kitting problem. Fields mirror the JSON format; see :func:`schema`."""

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
    #: Sawyer station geometry (:class:`bilevel_kit.sawyer.Station`), None if not given.
    station: Any = None
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
    source: str = "<memory>"

    # -- the expanded (all-units) view -------------------------------------------------------
    @cached_property
    def tasks(self) -> tuple[Task, ...]:
        """All tasks of all units; ids get an ``@u`` suffix when ``units > 1``."""
        if self.units == 1:
            return tuple(replace(t, base_id=t.base_id or t.id) for t in self.base_tasks)
        return tuple(
            replace(t, id=f"{t.id}@{u}", name=f"{t.name} (unit {u})", unit=u, base_id=t.id)
            for u in range(1, self.units + 1)
            for t in self.base_tasks
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
            changes["units"] = int(units)
        return replace(self, **changes) if changes else self

    @property
    def tray_limit(self) -> int | None:
        """The number of trays that binds, ``None`` when the robot is never held back (no
        limit, or at least as many trays as tasks, hence as kits)."""
        if self.trays is None or self.trays >= self.n_tasks:
            return None
        return self.trays

    def station_fields(self) -> dict[str, Any]:
        """The document fields of the robot's station and of the reachability rule
        (docs/formats.md), those that are set: shared by every writer of instance documents."""
        doc: dict[str, Any] = {}
        if self.station is not None:
            doc["station"] = self.station.to_dict()
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
            }
            for p in self.part_types.values()
        ]
        tasks = []
        for t in self.base_tasks:
            d: dict[str, Any] = {"id": t.id, "name": t.name}
            if t.product and t.product != self.name:
                d["product"] = t.product
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
        doc.update(self.station_fields())
        if self.robot_times != "pick_time":
            doc["robot_times"] = self.robot_times
        return doc


# ---------------------------------------------------------------------------------------------
# Graph helpers
# ---------------------------------------------------------------------------------------------


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


def _find_cycle(nodes: list[str], edges: Iterable[tuple[str, str]]) -> list[str] | None:
    """One directed cycle as a node list (first node repeated at the end), or None."""
    succ: dict[str, list[str]] = {n: [] for n in nodes}
    for a, b in edges:
        succ[a].append(b)
    color = dict.fromkeys(nodes, 0)  # 0 new, 1 on stack, 2 done
    for root in nodes:
        if color[root]:
            continue
        stack: list[tuple[str, int]] = [(root, 0)]
        path: list[str] = [root]
        color[root] = 1
        while stack:
            node, i = stack[-1]
            if i < len(succ[node]):
                stack[-1] = (node, i + 1)
                nxt = succ[node][i]
                if color[nxt] == 1:
                    return [*path[path.index(nxt) :], nxt]
                if color[nxt] == 0:
                    color[nxt] = 1
                    stack.append((nxt, 0))
                    path.append(nxt)
            else:
                color[node] = 2
                stack.pop()
                path.pop()
    return None


# ---------------------------------------------------------------------------------------------
# JSON Schema and loading
# ---------------------------------------------------------------------------------------------

_NONNEG = {"type": "number", "minimum": 0, "maximum": MAX_TIME}  # times (s)
_POS = {"type": "number", "exclusiveMinimum": 0, "maximum": MAX_TIME}  # times > 0 (s)
#: lengths (mm); the lower limit MIN_LENGTH is checked after the schema, with its reason
_LENGTH = {"type": "number", "exclusiveMinimum": 0, "maximum": MAX_LENGTH}
_ID = {"type": "string", "minLength": 1, "pattern": "^[A-Za-z0-9_.:-]+$"}


def schema() -> dict[str, Any]:
    """JSON Schema (draft 2020-12) of the instance format ``bilevel-kit/1``."""
    weight_props = {
        k: {"type": "number", "minimum": 0, "maximum": MAX_WEIGHT, "description": f"default {v}"}
        for k, v in DEFAULT_WEIGHTS.items()
    }
    return {
        "$schema": "https://json-schema.org/draft/2020-12/schema",
        "$id": "https://bilevel-kit/schemas/instance-1.json",
        "title": "bilevel-kit instance",
        "description": "A just-in-time kitting problem. Lengths in mm, times in s.",
        "type": "object",
        "required": ["format", "name", "tray", "part_types", "tasks"],
        "additionalProperties": False,
        "properties": {
            "format": {"const": FORMAT},
            "name": {"type": "string", "minLength": 1},
            "description": {"type": "string"},
            "assumptions": {
                "type": "array",
                "items": {"type": "string"},
                "description": "Every number that had to be assumed, and why.",
            },
            "tray": {
                "type": "object",
                "required": ["width", "height"],
                "additionalProperties": False,
                "properties": {"width": _LENGTH, "height": _LENGTH},
            },
            "delivery_time": {**_NONNEG, "default": 0.0, "description": "d in the paper (s)"},
            "kit_overhead": {
                "type": "object",
                "additionalProperties": False,
                "properties": {
                    "robot": {**_NONNEG, "default": 0.0, "description": "robot time per kit"},
                    "human": {**_NONNEG, "default": 0.0, "description": "human time per kit"},
                },
            },
            "part_types": {
                "type": "array",
                "minItems": 1,
                "items": {
                    "type": "object",
                    "required": ["id", "width", "height", "pick_time"],
                    "additionalProperties": False,
                    "properties": {
                        "id": _ID,
                        "name": {"type": "string"},
                        "width": _LENGTH,
                        "height": _LENGTH,
                        "pick_time": _NONNEG,
                        "rotatable": {"type": "boolean", "default": True},
                    },
                },
            },
            "tasks": {
                "type": "array",
                "minItems": 1,
                "items": {
                    "type": "object",
                    "required": ["id", "parts", "human_time"],
                    "additionalProperties": False,
                    "properties": {
                        "id": {**_ID, "pattern": "^[A-Za-z0-9_.:-]+$"},
                        "name": {"type": "string"},
                        "product": {"type": "string", "minLength": 1},
                        "parts": {
                            "type": "array",
                            "items": {
                                "type": "object",
                                "required": ["type", "count"],
                                "additionalProperties": False,
                                "properties": {
                                    "type": {"type": "string"},
                                    "count": {"type": "integer", "minimum": 1},
                                },
                            },
                        },
                        "human_time": {
                            "type": "object",
                            "required": ["mean"],
                            "additionalProperties": False,
                            "properties": {"mean": _NONNEG, "sd": {**_NONNEG, "default": 0.0}},
                        },
                        "robot_time": {
                            **_NONNEG,
                            "description": "override of the sum of the parts' pick times",
                        },
                    },
                },
            },
            "precedence": {
                "type": "array",
                "items": {
                    "type": "array",
                    "prefixItems": [{"type": "string"}, {"type": "string"}],
                    "minItems": 2,
                    "maxItems": 2,
                },
                "description": "edges [a, b]: task a must be finished before task b starts",
            },
            "weights": {
                "type": "object",
                "additionalProperties": False,
                "properties": weight_props,
            },
            "horizon": {"type": "integer", "minimum": 1, "default": DEFAULT_HORIZON},
            "trays": {
                "type": ["integer", "null"],
                "minimum": 1,
                "default": None,
                "description": "kit trays in circulation: the robot starts kit k only when the "
                "tray of kit k - trays is back, i.e. once the human has retrieved its parts "
                "(the paper's study: 1); absent or null: unlimited",
            },
            "supply": {
                "type": "object",
                "description": "per part type: Poisson arrivals (mean inter-arrival MAT), "
                "exponential time to failure (MTTF) and a fixed repair time",
                "additionalProperties": {
                    "type": "object",
                    "required": ["mat"],
                    "additionalProperties": False,
                    "properties": {
                        "mat": _POS,
                        "mttf": _POS,
                        "repair_time": {**_NONNEG, "default": DEFAULT_REPAIR_TIME},
                    },
                },
            },
            "units": {"type": "integer", "minimum": 1, "default": 1},
            "station": _station_schema(),
            "reachability": {
                "type": "boolean",
                "default": False,
                "description": "enforce Sawyer reachability of every placement (uses 'station', "
                "or the default station)",
            },
            "reach_resolution": {**_LENGTH, "default": 10.0, "description": "reach map cell (mm)"},
            "robot_times": {
                "enum": ["pick_time", "motion"],
                "default": "pick_time",
                "description": "'motion': pick times from the Sawyer motion model",
            },
        },
    }


def _station_schema() -> dict[str, Any]:
    from .sawyer.station import station_schema

    return station_schema()


def read_json(path: str | Path, error: ErrorType = InstanceError) -> Any:
    """Parse a JSON file strictly (see :func:`bilevel_kit.jsonio.read_json`)."""
    return jsonio.read_json(path, error)


def document(
    name: str,
    part_types: list[dict[str, Any]],
    tasks: list[dict[str, Any]],
    *,
    tray: tuple[float, float] = (100.0, 100.0),
    delivery_time: float = 1.0,
    overhead: tuple[float, float] = (1.0, 1.0),
    precedence: list[list[str]] | None = None,
    **fields: Any,
) -> dict[str, Any]:
    """A minimal instance document (docs/formats.md) in the usual key order; ``overhead`` is
    (robot, human) in seconds, ``fields`` any further top-level field (``trays`` ...)."""
    return {
        "format": FORMAT,
        "name": name,
        "tray": {"width": tray[0], "height": tray[1]},
        "delivery_time": delivery_time,
        "kit_overhead": {"robot": overhead[0], "human": overhead[1]},
        "part_types": part_types,
        "tasks": tasks,
        "precedence": [] if precedence is None else precedence,
        **fields,
    }


def from_dict(doc: Any, source: str = "<memory>") -> Instance:
    """Validate a parsed JSON document and build the :class:`Instance`."""
    if isinstance(doc, dict) and "format" in doc and doc["format"] != FORMAT:
        raise InstanceError(
            source,
            "$.format",
            f"unsupported format {doc['format']!r}; this version reads {FORMAT!r}",
        )
    validate_document(doc, source, schema(), InstanceError)

    def fail(path: str, msg: str) -> InstanceError:
        return InstanceError(source, path, msg)

    tray = Tray(float(doc["tray"]["width"]), float(doc["tray"]["height"]))
    check_lengths(doc["tray"], "$.tray", source)
    check_lengths(doc, "$", source, ("reach_resolution",))

    part_types: dict[str, PartType] = {}
    for i, p in enumerate(doc["part_types"]):
        if p["id"] in part_types:
            raise fail(f"$.part_types[{i}].id", f"duplicate part type id {p['id']!r}")
        check_lengths(p, f"$.part_types[{i}]", source)
        pt = PartType(
            id=p["id"],
            width=float(p["width"]),
            height=float(p["height"]),
            pick_time=float(p["pick_time"]),
            rotatable=bool(p.get("rotatable", True)),
            name=p.get("name", ""),
        )
        fits = pt.width <= tray.width and pt.height <= tray.height
        if pt.rotatable:
            fits = fits or (pt.height <= tray.width and pt.width <= tray.height)
        if not fits:
            orient = "either axis-aligned orientation" if pt.rotatable else "its fixed orientation"
            raise fail(
                f"$.part_types[{i}]",
                f"part {pt.id!r} ({pt.width:g} x {pt.height:g} mm) "
                f"does not fit the {tray.width:g} x {tray.height:g} mm tray in {orient}",
            )
        part_types[pt.id] = pt

    name = doc["name"]
    tasks: list[Task] = []
    seen: set[str] = set()
    for i, t in enumerate(doc["tasks"]):
        if t["id"] in seen:
            raise fail(f"$.tasks[{i}].id", f"duplicate task id {t['id']!r}")
        if "@" in t["id"]:
            raise fail(f"$.tasks[{i}].id", "'@' is reserved for unit suffixes")
        seen.add(t["id"])
        parts: list[tuple[str, int]] = []
        for j, req in enumerate(t["parts"]):
            if req["type"] not in part_types:
                raise fail(f"$.tasks[{i}].parts[{j}].type", f"unknown part type {req['type']!r}")
            if any(req["type"] == q for q, _ in parts):
                raise fail(
                    f"$.tasks[{i}].parts[{j}].type",
                    f"part type {req['type']!r} listed twice; give one count",
                )
            parts.append((req["type"], int(req["count"])))
        ht = t["human_time"]
        tasks.append(
            Task(
                id=t["id"],
                name=t.get("name", t["id"]),
                parts=tuple(parts),
                human_mean=float(ht["mean"]),
                human_sd=float(ht.get("sd", 0.0)),
                robot_time=float(t["robot_time"]) if "robot_time" in t else None,
                product=t.get("product", name),
                base_id=t["id"],
            )
        )

    edges: list[tuple[str, str]] = []
    edge_set: set[tuple[str, str]] = set()
    for k, (a, b) in enumerate(doc.get("precedence", [])):
        for side, tid in ((0, a), (1, b)):
            if tid not in seen:
                raise fail(f"$.precedence[{k}][{side}]", f"unknown task {tid!r}")
        if a == b:
            raise fail(f"$.precedence[{k}]", f"task {a!r} cannot precede itself")
        if (a, b) not in edge_set:
            edge_set.add((a, b))
            edges.append((a, b))
    cycle = _find_cycle([t.id for t in tasks], edges)
    if cycle is not None:
        raise fail("$.precedence", "precedence cycle " + " -> ".join(cycle))

    supply: dict[str, Supply] = {}
    for ptype, s in doc.get("supply", {}).items():
        if ptype not in part_types:
            raise fail(f"$.supply.{ptype}", f"unknown part type {ptype!r}")
        supply[ptype] = Supply(
            mat=float(s["mat"]),
            mttf=float(s["mttf"]) if "mttf" in s else None,
            repair_time=float(s.get("repair_time", DEFAULT_REPAIR_TIME)),
        )

    station = None
    if "station" in doc:
        from .sawyer.station import Station, StationError

        try:
            station = Station.from_dict(doc["station"])
        except StationError as exc:
            raise fail("$.station", str(exc)) from None
    robot_times = doc.get("robot_times", "pick_time")
    if robot_times == "motion":
        part_types = _motion_pick_times(part_types, station, tray, source)

    overhead = doc.get("kit_overhead", {})
    return Instance(
        name=name,
        tray=tray,
        delivery_time=float(doc.get("delivery_time", 0.0)),
        kit_overhead_robot=float(overhead.get("robot", 0.0)),
        kit_overhead_human=float(overhead.get("human", 0.0)),
        part_types=part_types,
        base_tasks=tuple(tasks),
        base_precedence=tuple(edges),
        weights={**DEFAULT_WEIGHTS, **{k: float(v) for k, v in doc.get("weights", {}).items()}},
        horizon=int(doc.get("horizon", DEFAULT_HORIZON)),
        supply=supply,
        units=int(doc.get("units", 1)),
        description=doc.get("description", ""),
        assumptions=tuple(doc.get("assumptions", ())),
        station=station,
        reachability=bool(doc.get("reachability", False)),
        reach_resolution=float(doc.get("reach_resolution", 10.0)),
        robot_times=robot_times,
        trays=parse_trays(doc.get("trays"), source) if doc.get("trays") is not None else None,
        source=source,
    )


def check_lengths(
    obj: Mapping[str, Any],
    where: str,
    source: str,
    keys: tuple[str, ...] = ("width", "height"),
    error: ErrorType = InstanceError,
) -> None:
    """The lengths ``keys`` of ``obj`` at least :data:`MIN_LENGTH` mm: far below it, a part is
    smaller than the geometry's tolerance and overlaps are measured in rounding noise."""
    for key in keys:
        if key in obj and obj[key] < MIN_LENGTH:
            raise error(
                source,
                f"{where}.{key}",
                f"{obj[key]:g} mm is below the smallest length {MIN_LENGTH:g} mm (docs/formats.md)",
            )


def parse_trays(value: Any, source: str = "<memory>") -> int | None:
    """A tray count: an integer >= 1, or ``None``/``"unlimited"``/``"none"`` for no limit."""
    if value is None or (isinstance(value, str) and value.lower() in ("unlimited", "none")):
        return None
    if isinstance(value, str):
        try:
            value = float(value)
        except ValueError:
            raise InstanceError(
                source, "$.trays", f"must be an integer >= 1 or unlimited, got {value!r}"
            ) from None
    if (
        isinstance(value, bool)
        or not isinstance(value, int | float)
        or not math.isfinite(value)
        or value != int(value)
        or value < 1
    ):
        raise InstanceError(
            source, "$.trays", f"must be an integer >= 1 or unlimited, got {value!r}"
        )
    return int(value)


def _motion_pick_times(
    part_types: dict[str, PartType], station: Any, tray: Tray, source: str
) -> dict[str, PartType]:
    """Pick times from the Sawyer motion model: the mean pick-and-place time of each type over
    the reachable cells of the tray (the layout is not known when times are planned)."""
    from .sawyer import DEFAULT_STATION, UnreachableError, tray_average_time

    st = station or DEFAULT_STATION
    out = {}
    for pid, pt in part_types.items():
        try:
            t = tray_average_time(st, pid, tray.width, tray.height)
        except UnreachableError as exc:
            raise InstanceError(source, "$.robot_times", str(exc)) from None
        out[pid] = replace(pt, pick_time=t, nominal_pick_time=pt.pick_time)
    return out


def load(path: str | Path) -> Instance:
    """Load and validate an instance file."""
    return from_dict(read_json(path, InstanceError), str(path))
