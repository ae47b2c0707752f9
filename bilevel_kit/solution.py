"""Solution files (format ``bilevel-kit-solution/2``): the result of one solve, as JSON.

Keys other tools can rely on: ``method``, ``status``, ``objective`` {``name``, ``value``,
``bound``, ``gap``} (the objective the method minimised, the one ``status`` refers to),
``makespan`` {``value``, ``bound``, ``gap``} (s), ``seed``, ``params``, ``wall_time_s``,
``metrics`` {``makespan``, ``human_idle``, ``robot_idle``, ``n_kits``} and ``kits``
[{``tasks``, ``robot_start``, ``robot_end``, ``arrive``, ``human_start``, ``human_end``,
``layout`` [{``part``, ``type``, ``x``, ``y``, ``theta``, ``w``, ``h``}]}]; with several
stations also each kit's ``station`` and ``station_metrics`` {station: {``completion``,
``human_idle``, ``n_kits``}}. Lengths in mm, angles in degrees, times in s. ``overrides``: the
instance overrides the plan was solved with (``--units``, ``--trays``, ...), which
``bilevel-kit check`` applies again (docs/formats.md). ``work_cell`` {``path``, ``sha256``,
``cell``}: the work cell of ``solve --work-cell``, which ``execute`` uses (or warns about when
given another one).
Files of format 1 (a number ``objective``, ``bound`` and ``gap`` about the makespan, the
minimised objective's numbers in ``extra``) are still read and checked.
"""

from __future__ import annotations

import json
import math
from collections.abc import Mapping
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

from . import atomic
from .errors import SolutionError
from .instance import Instance
from .jsonio import read_json, validate_document
from .methods import Result
from .objectives import OBJECTIVES, is_top_level
from .plan import Kit, KitTimes, Placement, Plan
from .validate import Claims, Violation, check

FORMAT = "bilevel-kit-solution/2"
#: The previous format, still read: its ``objective``, ``bound`` and ``gap`` are the makespan's.
FORMAT_1 = "bilevel-kit-solution/1"
_TIME_KEYS = ("robot_start", "robot_end", "arrive", "human_start", "human_end")
_METRIC_KEYS = ("makespan", "human_idle", "robot_idle", "n_kits")
#: per station, with several stations (:meth:`bilevel_kit.plan.Timeline.station_metrics`)
_STATION_KEYS = ("completion", "human_idle", "n_kits")


def _jsonable(value: Any) -> Any:
    """Parameters as plain JSON (non-finite floats become null, unknown objects strings)."""
    if isinstance(value, float):
        return value if math.isfinite(value) else None
    if value is None or isinstance(value, bool | int | str):
        return value
    if isinstance(value, dict):
        return {str(k): _jsonable(v) for k, v in value.items()}
    if isinstance(value, list | tuple):
        return [_jsonable(v) for v in value]
    if hasattr(value, "item"):  # numpy scalars
        return _jsonable(value.item())
    return str(value)


def result_to_dict(
    result: Result,
    overrides: Mapping[str, Any] | None = None,
    work_cell: Mapping[str, Any] | None = None,
) -> dict[str, Any]:
    """The JSON document of a :class:`~bilevel_kit.methods.Result`; ``overrides`` (the
    instance overrides it was solved with) is recorded so that the checker can rebuild the
    same instance, and ``work_cell`` (:func:`bilevel_kit.sawyer.workcell.cell_record`) so
    that ``execute`` runs the plan in the cell it was solved in."""
    kits = []
    tl = result.timeline
    if result.plan is not None and tl is not None:
        stations = tl.kit_stations or ("",) * len(tl.kits)
        for kit, times, s in zip(result.plan.kits, tl.kits, stations, strict=True):
            kits.append(
                {
                    "tasks": list(kit.tasks),
                    **({"station": s} if s else {}),
                    **{k: getattr(times, k) for k in _TIME_KEYS},
                    "layout": [p.to_dict() for p in kit.layout],
                }
            )
    doc: dict[str, Any] = {
        "format": FORMAT,
        "instance": result.instance,
        "method": result.method,
        "status": result.status,
        "objective": {
            "name": result.objective_name,
            "value": result.objective,
            "bound": result.bound,
            "gap": result.gap,
        },
        "timeline_params": result.timeline_params,
        "makespan": {
            "value": result.makespan,
            "bound": result.makespan_bound,
            "gap": result.makespan_gap,
        },
        "seed": result.seed,
        "params": _jsonable(result.params),
        "wall_time_s": result.wall_time_s,
        "metrics": result.metrics,
        "kits": kits,
        # per station: a checked claim of its own below, not an unchecked extra
        "extra": _jsonable({k: v for k, v in result.extra.items() if k != "station_metrics"}),
    }
    if result.extra.get("station_metrics"):
        doc["station_metrics"] = _jsonable(result.extra["station_metrics"])
    if overrides:
        doc["overrides"] = _jsonable(dict(overrides))
    if work_cell:
        doc["work_cell"] = _jsonable(dict(work_cell))
    return doc


def write(
    path: str | Path,
    result: Result,
    overrides: Mapping[str, Any] | None = None,
    work_cell: Mapping[str, Any] | None = None,
) -> None:
    """Write a solution file atomically; a non-finite number is refused (it is not JSON)."""
    try:
        doc = result_to_dict(result, overrides, work_cell)
        text = json.dumps(doc, indent=2, allow_nan=False)
    except ValueError:
        raise SolutionError(
            str(path), "$", "non-finite number in the result; not written"
        ) from None
    atomic.write_text(path, text + "\n")


_NUM = {"type": "number"}
_OPT_NUM = {"type": ["number", "null"]}
#: The instance overrides a solution records (the override options of solve and compare).
_OVERRIDES = {
    "type": "object",
    "description": "the instance overrides the plan was solved with; check applies them",
    "additionalProperties": False,
    "properties": {
        "delivery_time": {"type": "number", "minimum": 0},
        "weights": {"type": "object", "additionalProperties": {"type": "number", "minimum": 0}},
        "horizon": {"type": "integer", "minimum": 1},
        "units": {"type": "integer", "minimum": 1},
        "trays": {"oneOf": [{"type": "integer", "minimum": 1}, {"const": "unlimited"}]},
    },
}


#: The work cell a plan was solved in (``solve --work-cell``), for ``execute``.
_WORK_CELL = {
    "type": "object",
    "description": "the work cell the plan was solved in: its path as given, the SHA-256 of "
    "its canonical JSON, and its content; execute uses it",
    "required": ["path", "sha256", "cell"],
    "additionalProperties": False,
    "properties": {
        "path": {"type": "string"},
        "sha256": {"type": "string", "pattern": "^[0-9a-f]{64}$"},
        "cell": {"type": "object"},
    },
}


def schema(version: str = FORMAT) -> dict[str, Any]:
    """JSON Schema of a solution file of format ``version`` (what :func:`read` requires).
    Every key the writer stores is typed, and no other key is allowed: the checker recomputes
    each number it is given, so a misspelt or foreign key cannot pass unnoticed."""
    placement = {
        "type": "object",
        "required": ["part", "type", "x", "y", "theta", "w", "h"],
        "additionalProperties": False,
        "properties": {
            "part": {"type": "string"},
            "type": {"type": "string"},
            **{k: _NUM for k in ("x", "y", "theta", "w", "h")},
        },
    }
    kit = {
        "type": "object",
        "required": ["tasks", "layout"],
        "additionalProperties": False,
        "properties": {
            "tasks": {"type": "array", "items": {"type": "string"}},
            "station": {"type": "string", "description": "the kit's station, with stations"},
            "layout": {"type": "array", "items": placement},
            **{k: _NUM for k in _TIME_KEYS},
        },
    }
    metrics = {
        "type": ["object", "null"],
        "required": list(_METRIC_KEYS),
        "additionalProperties": False,
        "properties": {
            **{k: _NUM for k in _METRIC_KEYS[:-1]},
            "n_kits": {"type": "integer", "minimum": 0},
        },
    }
    return {
        "$schema": "https://json-schema.org/draft/2020-12/schema",
        "title": "bilevel-kit solution",
        "type": "object",
        "required": ["format", "method", "status", "kits"],
        "additionalProperties": False,
        "properties": {
            "format": {"const": version},
            "instance": {"type": "string"},
            "method": {"type": "string"},
            "status": {"enum": ["optimal", "feasible", "infeasible", "unknown"]},
            **(_claims_1() if version == FORMAT_1 else _claims_2()),
            "timeline_params": {
                "type": "object",
                "description": "delivery_time, kit_overhead and trays the times were computed for",
                "required": ["delivery_time", "kit_overhead", "trays"],
                "additionalProperties": False,
                "properties": {
                    "delivery_time": {"type": "number", "minimum": 0},
                    "kit_overhead": {
                        "type": "object",
                        "required": ["robot", "human"],
                        "additionalProperties": False,
                        "properties": {
                            "robot": {"type": "number", "minimum": 0},
                            "human": {"type": "number", "minimum": 0},
                        },
                    },
                    "trays": {"type": ["integer", "null"], "minimum": 1},
                    "stations": {
                        "type": "array",
                        "items": {"type": "object"},
                        "description": "the instance's stations, when it declares them",
                    },
                },
            },
            "seed": {"type": "integer", "minimum": 0},
            "params": {"type": "object"},
            "wall_time_s": {"type": "number", "minimum": 0},
            "metrics": metrics,
            "station_metrics": {
                "type": "object",
                "description": "per station, with several stations",
                "additionalProperties": {
                    "type": "object",
                    "required": list(_STATION_KEYS),
                    "additionalProperties": False,
                    "properties": {
                        "completion": _NUM,
                        "human_idle": _NUM,
                        "n_kits": {"type": "integer", "minimum": 0},
                    },
                },
            },
            "kits": {"type": "array", "items": kit},
            "extra": {"type": "object"},
            "overrides": _OVERRIDES,
            "work_cell": _WORK_CELL,
        },
    }


_GAP = {"type": ["number", "null"], "minimum": 0}


def _claims_1() -> dict[str, Any]:
    """Format 1's claims: the makespan's, and the name of the objective ``status`` is about
    (its numbers in ``extra``, under the keys the registry lists)."""
    return {
        "status_objective": {
            "type": "string",
            "description": "the objective the status refers to "
            "(makespan, human_idle, sum_completion, J)",
        },
        "objective": _OPT_NUM,
        "bound": _OPT_NUM,
        "gap": _GAP,
    }


def _claims_2() -> dict[str, Any]:
    """Format 2's claims: the minimised objective's, named, and the makespan's."""

    def block(name: bool) -> dict[str, Any]:
        return {
            "type": "object",
            "required": ["name"] if name else [],
            "additionalProperties": False,
            "properties": {
                **({"name": {"type": "string"}} if name else {}),
                "value": _OPT_NUM,
                "bound": _OPT_NUM,
                "gap": _GAP,
            },
        }

    return {
        "objective": {
            **block(True),
            "description": "the objective the method minimised (status refers to it): its "
            "name (makespan, sum_completion, human_idle, J, expected_makespan, cvar_makespan), "
            "value, bound, gap",
        },
        "makespan": {**block(False), "description": "the plan's makespan, its bound and gap (s)"},
    }


@dataclass(frozen=True)
class LoadedSolution:
    """A solution file: its plan, and what it claims (times, metrics, objective, bound, gap,
    status), all of which the checker recomputes; ``number_faults``: the numbers the strict
    reader refused (:class:`_Numbers`), violations of their own."""

    document: dict[str, Any]
    plan: Plan
    reported_kits: tuple[KitTimes, ...] | None
    reported_metrics: dict[str, float] | None
    claims: Claims = field(default_factory=Claims)
    number_faults: tuple[Violation, ...] = ()
    #: per station, and each kit's stated station (None where not stated), with stations
    reported_stations: dict[str, dict[str, float]] | None = None
    reported_kit_stations: tuple[str | None, ...] | None = None

    @property
    def overrides(self) -> dict[str, Any]:
        """The instance overrides the file records (empty for files written without any)."""
        return dict(self.document.get("overrides") or {})

    @property
    def work_cell(self) -> dict[str, Any] | None:
        """The work cell the file records (``path``, ``sha256``, ``cell``); None for files
        solved without one and for files written before the record existed."""
        record = self.document.get("work_cell")
        return None if record is None else dict(record)

    def check(self, instance: Instance) -> list[Violation]:
        """The independent checker on the plan and on every number the file states."""
        found = check(
            instance,
            self.plan,
            reported_kits=self.reported_kits,
            reported_metrics=self.reported_metrics,
            claims=self.claims,
            reported_stations=self.reported_stations,
            reported_kit_stations=self.reported_kit_stations,
        )
        return [*self.number_faults, *found]


#: The largest magnitude a number of a solution may have (lengths in mm, times in s): far
#: beyond any plan of an instance in range (docs/formats.md#ranges), and small enough that
#: the checker's sums, products and tolerances stay exact-enough floats.
MAX_NUMBER = 1e18


class _Numbers:
    """The one strict reader of a solution's numbers: a JSON number (any size of integer)
    becomes a float when it is finite and at most :data:`MAX_NUMBER` in magnitude; any other
    is a ``bad_number`` violation naming its JSON path, and reads as NaN (the checks then
    skip it), never an exception."""

    def __init__(self) -> None:
        self.faults: list[Violation] = []

    def __call__(self, value: Any, where: str) -> float:
        try:
            out = float(value)
        except OverflowError:  # an integer beyond the float range
            out = math.inf
        if math.isfinite(out) and abs(out) <= MAX_NUMBER:
            return out
        digits = len(str(abs(value))) if isinstance(value, int) else None
        shown = f"a {digits}-digit integer" if digits is not None else f"{out:g}"
        self.faults.append(
            Violation("bad_number", f"{where}: {shown} is out of range (|x| <= {MAX_NUMBER:g})")
        )
        return math.nan

    def optional(self, value: Any, where: str) -> float | None:
        """A claim that may be null; a refused number reads as not stated."""
        if value is None:
            return None
        out = self(value, where)
        return None if math.isnan(out) else out


def from_dict(doc: Any, source: str = "<memory>") -> LoadedSolution:
    """Validate a parsed solution document; a kit with some but not all of the five times, or
    times on some kits only, raises :class:`SolutionError` naming the missing field."""
    version = doc.get("format") if isinstance(doc, dict) else None
    if isinstance(doc, dict) and "format" in doc and version not in (FORMAT, FORMAT_1):
        raise SolutionError(
            source, "$.format", f"expected {FORMAT!r} (or {FORMAT_1!r}), got {version!r}"
        )
    validate_document(
        doc, source, schema(FORMAT_1 if version == FORMAT_1 else FORMAT), SolutionError
    )
    num = _Numbers()
    kits = []
    times = []
    timed = [any(k in kd for k in _TIME_KEYS) for kd in doc["kits"]]
    for i, kd in enumerate(doc["kits"]):
        where = f"$.kits[{i}]"
        layout = tuple(
            Placement(
                p["part"],
                p["type"],
                *(num(p[k], f"{where}.layout[{j}].{k}") for k in ("x", "y", "theta", "w", "h")),
            )
            for j, p in enumerate(kd["layout"])
        )
        kits.append(Kit(tuple(kd["tasks"]), layout))
        if any(timed):
            missing = [k for k in _TIME_KEYS if k not in kd]
            if missing:
                raise SolutionError(
                    source,
                    f"$.kits[{i}]",
                    f"missing time field {missing[0]!r} (a solution gives all five times of "
                    "every kit, or none)",
                )
            times.append(KitTimes(*(num(kd[k], f"{where}.{k}") for k in _TIME_KEYS)))
    metrics = doc.get("metrics")
    if metrics is not None:  # a refused metric is left out (its violation says why)
        read = {k: num(v, f"$.metrics.{k}") for k, v in metrics.items()}
        metrics = {k: v for k, v in read.items() if not math.isnan(v)}
    reader = _claims_of_1 if doc["format"] == FORMAT_1 else _claims_of_2
    claims = replace(reader(doc, num), timeline=_timeline(doc.get("timeline_params"), num))
    per_station = doc.get("station_metrics")
    if per_station is not None:
        per_station = {
            s: {k: num(v, f"$.station_metrics.{s}.{k}") for k, v in m.items()}
            for s, m in per_station.items()
        }
    kit_stations = [kd.get("station") for kd in doc["kits"]]
    return LoadedSolution(
        doc,
        Plan(tuple(kits)),
        tuple(times) if times else None,
        metrics,
        claims,
        tuple(num.faults),
        per_station,
        tuple(kit_stations) if any(s is not None for s in kit_stations) else None,
    )


def _claims_of_1(doc: dict[str, Any], num: _Numbers) -> Claims:
    """A format-1 file's claims: ``objective``, ``bound``, ``gap`` the makespan's, those on
    ``status_objective`` in ``extra`` (the registry's keys)."""
    stated = {k: num.optional(doc.get(k), f"$.{k}") for k in ("objective", "bound", "gap")}
    status_objective = doc.get("status_objective", "makespan")
    claims = _stated_claims(doc["status"], doc, stated, "objective", status_objective)
    objective_claims = _objective_claims(status_objective, doc.get("extra") or {}, num)
    return replace(claims, objective_claims=objective_claims)


def _claims_of_2(doc: dict[str, Any], num: _Numbers) -> Claims:
    """A format-2 file's claims: the ``makespan`` block's, and the ``objective`` block's on the
    objective it names. When that is the makespan, the two blocks are one claim: a number in
    either is checked (the ``objective`` block's where both state it, a ``makespan`` block
    that differs being a mismatch)."""
    own = doc.get("objective") or {"name": "makespan"}
    name = str(own["name"])
    top = is_top_level(name)
    other = doc.get("makespan") or {}
    keys = ("value", "bound", "gap")
    block = {**other, **{k: own[k] for k in keys if k in own}} if top else other

    def where(k: str) -> str:
        return f"$.objective.{k}" if top and k in own else f"$.makespan.{k}"

    stated = {k: num.optional(block.get(k), where(k)) for k in keys}
    claims = _stated_claims(doc["status"], block, stated, "value", name)
    if top:
        for k in (k for k in keys if k in other and k in own):
            theirs = num.optional(other[k], f"$.makespan.{k}")
            refused = (theirs is None) != (other[k] is None) or (
                (stated[k] is None) != (own[k] is None)
            )
            if not refused and theirs != stated[k]:  # a refused number: its own violation
                msg = f"$.makespan.{k} {other[k]!r} differs from $.objective.{k} {own[k]!r}"
                num.faults.append(Violation("objective_mismatch", msg))
        return claims
    value, bound, gap = (
        num.optional(own.get(k), f"$.objective.{k}") for k in ("value", "bound", "gap")
    )
    stated_in = ("objective.value", "objective.bound")
    return replace(
        claims, objective_claims=(value, bound, gap, "gap" in own), objective_where=stated_in
    )


def _stated_claims(
    status: str,
    block: Mapping[str, Any],
    stated: Mapping[str, float | None],
    value_key: str,
    status_objective: str,
) -> Claims:
    """The claims of one block of stated numbers (``value_key``, ``bound``, ``gap``, as read
    strictly into ``stated``), in either format; a refused number is named by the claim it
    makes (``objective`` for the value)."""
    return Claims(
        status=status,
        objective=stated[value_key],
        bound=stated["bound"],
        gap=stated["gap"],
        has_gap="gap" in block,
        status_objective=status_objective,
        refused=frozenset(
            "objective" if k == value_key else k
            for k, v in stated.items()
            if v is None and block.get(k) is not None
        ),
    )


def _objective_claims(
    name: str, extra: dict[str, Any], num: _Numbers
) -> tuple[float | None, float | None, float | None, bool] | None:
    """The value, bound and gap ``extra`` states for the objective ``name`` where the
    registry keeps them there (:mod:`bilevel_kit.objectives`), read strictly: anything but a
    number or null is a ``bad_number`` violation and reads as not stated."""
    obj = OBJECTIVES.get(name)
    if obj is None or obj.top_level:
        return None
    *stated, has_gap = obj.stated({}, extra)
    keys = (obj.value_keys, obj.bound_keys, obj.gap_keys)
    out: list[float | None] = []
    for value, names in zip(stated, keys, strict=True):
        key = next((k for k in names if extra.get(k) is not None), names[0])
        if value is not None and (isinstance(value, bool) or not isinstance(value, int | float)):
            num.faults.append(Violation("bad_number", f"$.extra.{key}: {value!r} is not a number"))
            value = None
        out.append(num.optional(value, f"$.extra.{key}"))
    return out[0], out[1], out[2], has_gap


def _timeline(params: dict[str, Any] | None, num: _Numbers) -> dict[str, Any] | None:
    """``timeline_params`` with its numbers read strictly (``trays`` stays an integer)."""
    if params is None:
        return None
    where = "$.timeline_params"
    trays = params["trays"]
    if trays is not None and math.isnan(num(trays, f"{where}.trays")):
        trays = math.nan
    return {
        "delivery_time": num(params["delivery_time"], f"{where}.delivery_time"),
        "kit_overhead": {
            k: num(params["kit_overhead"][k], f"{where}.kit_overhead.{k}")
            for k in ("robot", "human")
        },
        "trays": trays,
        **({"stations": params["stations"]} if "stations" in params else {}),
    }


def read(path: str | Path) -> LoadedSolution:
    """Load a solution file; malformed files raise :class:`SolutionError` naming the field."""
    return from_dict(read_json(path, SolutionError, long_ints=True), str(path))
