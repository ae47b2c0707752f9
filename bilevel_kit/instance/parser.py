"""Reading instance documents: :func:`load` a file, :func:`from_dict` a parsed document.

The document is checked in two passes: its structure by the JSON Schema
(:func:`~bilevel_kit.instance.json_schema.schema`), then its meaning (unknown references,
duplicates, cycles, parts larger than the tray, lengths below the floor), section by section in
the order of the file. The first problem raises :class:`~bilevel_kit.errors.InstanceError`,
whose message names the file and the JSON path.
"""

from __future__ import annotations

import sys
from collections.abc import Iterable, Mapping
from dataclasses import replace
from pathlib import Path
from typing import Any

from .. import jsonio
from ..errors import InstanceError
from ..jsonio import ErrorType, validate_document
from .json_schema import schema
from .model import (
    DEFAULT_HORIZON,
    DEFAULT_REPAIR_TIME,
    DEFAULT_WEIGHTS,
    FORMAT,
    AssemblyStation,
    Instance,
    PartType,
    Supply,
    Task,
    Tray,
)
from .ranges import check_lengths, check_reach_cells, check_size, parse_trays

#: The former name of the ``work_cell`` section, still read with a notice (docs/formats.md).
OLD_WORK_CELL_KEY = "station"
#: Sources whose old ``station`` section was announced already (one notice per file a run).
_ANNOUNCED: set[str] = set()


def read_json(path: str | Path, error: ErrorType = InstanceError) -> Any:
    """Parse a JSON file strictly (see :func:`bilevel_kit.jsonio.read_json`)."""
    return jsonio.read_json(path, error)


def load(path: str | Path) -> Instance:
    """Load and validate an instance file."""
    return from_dict(read_json(path, InstanceError), str(path))


def loads(text: str, source: str) -> Instance:
    """Validate the text of the instance file ``source`` (read elsewhere: a cell carries its
    instance's text to the worker, docs/cluster.md); errors name ``source`` as :func:`load`'s."""
    return from_dict(jsonio.parse_json(text, source, InstanceError), source)


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
    doc, old = _renamed_work_cell(doc, source)
    _check_structure(doc, source, old)
    tray = Tray(float(doc["tray"]["width"]), float(doc["tray"]["height"]))
    check_lengths(doc["tray"], "$.tray", source)
    check_lengths(doc, "$", source, ("reach_resolution",))
    part_types = _part_types(doc["part_types"], tray, source)
    name = doc["name"]
    tasks = _tasks(doc["tasks"], part_types, name, source)
    check_size(len(tasks), int(doc.get("units", 1)), source)
    edges = _precedence(doc.get("precedence", []), [t.id for t in tasks], source)
    supply = _supply(doc.get("supply", {}), part_types, source)
    work_cell = _work_cell(doc, source, part_types, old)
    if doc.get("reachability", False):  # the reach map is built: its size is checked first
        check_reach_cells(tray.width, tray.height, float(doc.get("reach_resolution", 10.0)), source)
    robot_times = doc.get("robot_times", "pick_time")
    if robot_times == "motion":
        part_types = _motion_pick_times(part_types, work_cell, tray, source)
    overhead = doc.get("kit_overhead", {})
    stations = _stations(doc, tasks, source)
    inst = Instance(
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
        generated_by=doc.get("generated_by", ""),
        work_cell=work_cell,
        reachability=bool(doc.get("reachability", False)),
        reach_resolution=float(doc.get("reach_resolution", 10.0)),
        robot_times=robot_times,
        trays=parse_trays(doc.get("trays"), source) if doc.get("trays") is not None else None,
        stations=stations,
        source=source,
    )
    if stations:
        _check_station_tasks(inst, source)
    _check_some_task_needs_a_kit(inst, source)
    return inst


def _check_some_task_needs_a_kit(inst: Instance, source: str) -> None:
    """A part-less task rides in a neighbouring kit of its station, so every station with
    tasks needs one task with parts or robot time (docs/timeline.md#part-less-tasks)."""
    for station in inst.station_ids if inst.stations else [""]:
        tasks = [t.id for t in inst.tasks if not station or t.station == station]
        if tasks and not any(inst.needs_kit(t) for t in tasks):
            on = f" of station {station!r}" if station else ""
            raise InstanceError(
                source,
                "$.tasks",
                f"every task{on} has no parts and no robot_time: a part-less task rides in a "
                "neighbouring kit, so at least one task needs parts (docs/timeline.md)",
            )


def _renamed_work_cell(doc: Any, source: str) -> tuple[Any, bool]:
    """``doc`` with an old ``station`` section (the work cell's geometry, not an assembly
    station) renamed ``work_cell`` in place, and whether it was: a one-line notice on stderr,
    once per file. Both keys at once is an :class:`InstanceError`."""
    if not isinstance(doc, dict) or OLD_WORK_CELL_KEY not in doc:
        return doc, False
    if "work_cell" in doc:
        raise InstanceError(
            source,
            f"$.{OLD_WORK_CELL_KEY}",
            "the work cell is given twice: 'station' is the former name of 'work_cell' "
            "(docs/formats.md#the-work-cell-section); keep 'work_cell' only",
        )
    if source not in _ANNOUNCED:
        _ANNOUNCED.add(source)
        print(
            f"bilevel-kit: notice: {source}: the 'station' section (the work cell's geometry) "
            "is now named 'work_cell'; read as 'work_cell' (docs/formats.md#the-work-cell-section)",
            file=sys.stderr,
            flush=True,
        )
    return {("work_cell" if k == OLD_WORK_CELL_KEY else k): v for k, v in doc.items()}, True


def _check_structure(doc: Any, source: str, old: bool = False) -> None:
    """The format tag first (a clearer message than the schema's for a newer file), then the
    JSON Schema; ``old``: the work cell came as ``station``, which the errors name."""
    if isinstance(doc, dict) and "format" in doc and doc["format"] != FORMAT:
        raise InstanceError(
            source,
            "$.format",
            f"unsupported format {doc['format']!r}; this version reads {FORMAT!r}",
        )
    try:
        validate_document(doc, source, schema(), InstanceError)
    except InstanceError as exc:
        if not (old and exc.path.startswith("$.work_cell")):
            raise
        path = f"$.{OLD_WORK_CELL_KEY}" + exc.path.removeprefix("$.work_cell")
        raise InstanceError(source, path, exc.detail) from None


def _part_types(entries: list[dict[str, Any]], tray: Tray, source: str) -> dict[str, PartType]:
    """The part types by id: unique ids, lengths above the floor, each fitting the tray."""
    part_types: dict[str, PartType] = {}
    for i, p in enumerate(entries):
        if p["id"] in part_types:
            raise InstanceError(
                source, f"$.part_types[{i}].id", f"duplicate part type id {p['id']!r}"
            )
        check_lengths(p, f"$.part_types[{i}]", source)
        pt = PartType(
            id=p["id"],
            width=float(p["width"]),
            height=float(p["height"]),
            pick_time=float(p["pick_time"]),
            rotatable=bool(p.get("rotatable", True)),
            name=p.get("name", ""),
            grasp_width=None if p.get("grasp_width") is None else float(p["grasp_width"]),
        )
        _check_fits(pt, tray, f"$.part_types[{i}]", source)
        if pt.grasp_width is not None and pt.grasp_width > min(pt.width, pt.height):
            raise InstanceError(
                source,
                f"$.part_types[{i}].grasp_width",
                f"{pt.grasp_width:g} mm exceeds the smaller side of part {pt.id!r} "
                f"({pt.width:g} x {pt.height:g} mm), across which the fingers close",
            )
        part_types[pt.id] = pt
    return part_types


def _check_fits(pt: PartType, tray: Tray, where: str, source: str) -> None:
    """A part must fit the tray axis-aligned (either way round when it may rotate), up to the
    packers' and the checker's tolerance (:func:`~bilevel_kit.geometry.length_fits`): else no
    kit holding it has a layout."""
    from ..geometry import length_fits

    def fits_as(w: float, h: float) -> bool:
        return length_fits(w, tray.width) and length_fits(h, tray.height)

    fits = fits_as(pt.width, pt.height) or (pt.rotatable and fits_as(pt.height, pt.width))
    if not fits:
        orient = "either axis-aligned orientation" if pt.rotatable else "its fixed orientation"
        raise InstanceError(
            source,
            where,
            f"part {pt.id!r} ({pt.width:g} x {pt.height:g} mm) "
            f"does not fit the {tray.width:g} x {tray.height:g} mm tray in {orient}",
        )


def _tasks(
    entries: list[dict[str, Any]], part_types: Mapping[str, PartType], product: str, source: str
) -> list[Task]:
    """The base tasks: unique ids without ``@`` (reserved for unit suffixes), known parts."""
    tasks: list[Task] = []
    seen: set[str] = set()
    for i, t in enumerate(entries):
        if t["id"] in seen:
            raise InstanceError(source, f"$.tasks[{i}].id", f"duplicate task id {t['id']!r}")
        if "@" in t["id"]:
            raise InstanceError(source, f"$.tasks[{i}].id", "'@' is reserved for unit suffixes")
        seen.add(t["id"])
        ht = t["human_time"]
        tasks.append(
            Task(
                id=t["id"],
                name=t.get("name", t["id"]),
                parts=_task_parts(t["parts"], part_types, f"$.tasks[{i}]", source),
                human_mean=float(ht["mean"]),
                human_sd=float(ht.get("sd", 0.0)),
                robot_time=float(t["robot_time"]) if "robot_time" in t else None,
                product=t.get("product", product),
                base_id=t["id"],
                station=t.get("station", ""),
            )
        )
    return tasks


def _task_parts(
    requests: list[dict[str, Any]], part_types: Mapping[str, PartType], where: str, source: str
) -> tuple[tuple[str, int], ...]:
    """A task's ``(type, count)`` pairs: known types, each listed once."""
    parts: list[tuple[str, int]] = []
    for j, req in enumerate(requests):
        if req["type"] not in part_types:
            raise InstanceError(
                source, f"{where}.parts[{j}].type", f"unknown part type {req['type']!r}"
            )
        if any(req["type"] == q for q, _ in parts):
            raise InstanceError(
                source,
                f"{where}.parts[{j}].type",
                f"part type {req['type']!r} listed twice; give one count",
            )
        parts.append((req["type"], int(req["count"])))
    return tuple(parts)


def _precedence(pairs: list[list[str]], task_ids: list[str], source: str) -> list[tuple[str, str]]:
    """The edges in file order without repeats: known tasks, no self-loop, no cycle."""
    known = set(task_ids)
    edges: list[tuple[str, str]] = []
    edge_set: set[tuple[str, str]] = set()
    for k, (a, b) in enumerate(pairs):
        for side, tid in ((0, a), (1, b)):
            if tid not in known:
                raise InstanceError(source, f"$.precedence[{k}][{side}]", f"unknown task {tid!r}")
        if a == b:
            raise InstanceError(source, f"$.precedence[{k}]", f"task {a!r} cannot precede itself")
        if (a, b) not in edge_set:
            edge_set.add((a, b))
            edges.append((a, b))
    cycle = _find_cycle(task_ids, edges)
    if cycle is not None:
        raise InstanceError(source, "$.precedence", "precedence cycle " + " -> ".join(cycle))
    return edges


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


def _stations(
    doc: Mapping[str, Any], tasks: list[Task], source: str
) -> tuple[AssemblyStation, ...]:
    """The assembly stations (docs/timeline.md#several-stations): unique ids; each ``serves``
    entry a known product or ``product@unit`` with ``1 <= unit <= units``, served once; a
    task's ``station`` field names a declared station."""
    entries = doc.get("stations", [])
    ids: set[str] = set()
    served: set[str] = set()
    products = {t.product for t in tasks}
    units = int(doc.get("units", 1))
    out = []
    for i, e in enumerate(entries):
        if e["id"] in ids:
            raise InstanceError(source, f"$.stations[{i}].id", f"duplicate station id {e['id']!r}")
        ids.add(e["id"])
        for j, key in enumerate(e.get("serves", [])):
            product, at, unit = key.partition("@")  # the schema's SERVES_PATTERN held
            bad = product not in products or (
                bool(at) and not (unit.isascii() and unit.isdigit() and 1 <= int(unit) <= units)
            )
            where = f"$.stations[{i}].serves[{j}]"
            if bad:
                raise InstanceError(
                    source,
                    where,
                    f"{key!r} is no product ({', '.join(sorted(products))}) "
                    f"nor product@unit with unit in 1..{units}",
                )
            if key in served:
                raise InstanceError(source, where, f"{key!r} is served by two stations")
            served.add(key)
        out.append(
            AssemblyStation(
                id=e["id"],
                delivery_time=float(e["delivery_time"]) if "delivery_time" in e else None,
                trays=int(e["trays"]) if "trays" in e else None,
                kit_overhead_human=(
                    float(e["kit_overhead_human"]) if "kit_overhead_human" in e else None
                ),
                serves=tuple(e.get("serves", [])),
            )
        )
    for i, t in enumerate(tasks):
        if t.station and t.station not in ids:
            known = ", ".join(sorted(ids)) if ids else "none: the file declares no stations"
            raise InstanceError(
                source, f"$.tasks[{i}].station", f"unknown station {t.station!r} (known: {known})"
            )
    return tuple(out)


def _check_station_tasks(inst: Instance, source: str) -> None:
    """Every task on a station, and no precedence edge between two stations (they are
    independent, docs/timeline.md#several-stations)."""
    index = {t.id: i for i, t in enumerate(inst.base_tasks)}
    for t in inst.tasks:
        if not t.station:
            unit = f" (unit {t.unit})" if inst.units > 1 else ""
            raise InstanceError(
                source,
                f"$.tasks[{index[t.base_id]}].station",
                f"task {t.base_id!r}{unit} belongs to no station: give it a 'station' or list "
                f"its product {t.product!r} in a station's 'serves'",
            )
    by_id = inst.task_by_id
    for k, (a, b) in enumerate(inst.base_precedence):
        for u in range(1, inst.units + 1):
            ta, tb = (by_id[x if inst.units == 1 else f"{x}@{u}"] for x in (a, b))
            if ta.station != tb.station:
                raise InstanceError(
                    source,
                    f"$.precedence[{k}]",
                    f"{a!r} is on station {ta.station!r}, {b!r} on {tb.station!r}: stations are "
                    "independent, so no edge may join them",
                )


def _supply(
    entries: Mapping[str, Any], part_types: Mapping[str, PartType], source: str
) -> dict[str, Supply]:
    """The simulator's feeders, by known part type (docs/simulation.md)."""
    supply: dict[str, Supply] = {}
    for ptype, s in entries.items():
        if ptype not in part_types:
            raise InstanceError(source, f"$.supply.{ptype}", f"unknown part type {ptype!r}")
        supply[ptype] = Supply(
            mat=float(s["mat"]),
            mttf=float(s["mttf"]) if "mttf" in s else None,
            repair_time=float(s.get("repair_time", DEFAULT_REPAIR_TIME)),
        )
    return supply


def _work_cell(
    doc: Mapping[str, Any], source: str, part_types: Mapping[str, PartType], old: bool
) -> Any:
    """The Sawyer work cell of the document (:class:`bilevel_kit.sawyer.WorkCell`), None if
    the document gives none; its bins must be of known part types. Errors name the file's own
    key (``old``: ``station``)."""
    if "work_cell" not in doc:
        return None
    from ..sawyer.cell import WorkCell, error_path
    from ..sawyer.errors import WorkCellError

    key = OLD_WORK_CELL_KEY if old else "work_cell"
    try:
        cell = WorkCell.from_dict(doc["work_cell"])
    except WorkCellError as exc:
        field, detail = error_path(exc)
        raise InstanceError(source, f"$.{key}{field}", detail) from None
    for name, _ in cell.bins:
        if name not in part_types:
            raise InstanceError(source, f"$.{key}.bins.{name}", f"unknown part type {name!r}")
    return cell


def _motion_pick_times(
    part_types: dict[str, PartType], work_cell: Any, tray: Tray, source: str
) -> dict[str, PartType]:
    """Pick times from the Sawyer motion model: the mean pick-and-place time of each type over
    the reachable cells of the tray (the layout is not known when times are planned)."""
    from ..sawyer import DEFAULT_WORK_CELL, UnreachableError, tray_average_time

    st = work_cell or DEFAULT_WORK_CELL
    out = {}
    for pid, pt in part_types.items():
        try:
            t = tray_average_time(st, pid, tray.width, tray.height)
        except UnreachableError as exc:
            raise InstanceError(source, "$.robot_times", str(exc)) from None
        out[pid] = replace(pt, pick_time=t, nominal_pick_time=pt.pick_time)
    return out
