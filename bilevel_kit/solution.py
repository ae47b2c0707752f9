"""Solution files (format ``bilevel-kit-solution/1``): the result of one solve, as JSON.

Keys other tools can rely on: ``method``, ``status``, ``objective`` (makespan, s), ``bound``,
``gap``, ``seed``, ``params``, ``wall_time_s``, ``metrics`` {``makespan``, ``human_idle``,
``robot_idle``, ``n_kits``} and ``kits`` [{``tasks``, ``robot_start``, ``robot_end``,
``arrive``, ``human_start``, ``human_end``, ``layout`` [{``part``, ``type``, ``x``, ``y``,
``theta``, ``w``, ``h``}]}]. Lengths in mm, angles in degrees, times in s.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from . import atomic
from .errors import SolutionError
from .instance import read_json, validate_document
from .methods import Result
from .plan import Kit, KitTimes, Placement, Plan

FORMAT = "bilevel-kit-solution/1"
_TIME_KEYS = ("robot_start", "robot_end", "arrive", "human_start", "human_end")


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


def result_to_dict(result: Result) -> dict[str, Any]:
    """The JSON document of a :class:`~bilevel_kit.methods.Result`."""
    kits = []
    if result.plan is not None and result.timeline is not None:
        for kit, times in zip(result.plan.kits, result.timeline.kits, strict=True):
            kits.append(
                {
                    "tasks": list(kit.tasks),
                    **{k: getattr(times, k) for k in _TIME_KEYS},
                    "layout": [p.to_dict() for p in kit.layout],
                }
            )
    return {
        "format": FORMAT,
        "instance": result.instance,
        "method": result.method,
        "status": result.status,
        "status_objective": result.status_objective,
        "objective": result.objective,
        "bound": result.bound,
        "gap": result.gap,
        "seed": result.seed,
        "params": _jsonable(result.params),
        "wall_time_s": result.wall_time_s,
        "metrics": result.metrics,
        "kits": kits,
        "extra": _jsonable(result.extra),
    }


def write(path: str | Path, result: Result) -> None:
    """Write a solution file atomically."""
    atomic.write_text(path, json.dumps(result_to_dict(result), indent=2) + "\n")


_NUM = {"type": "number"}


def schema() -> dict[str, Any]:
    """JSON Schema of a solution file (what :func:`read` requires)."""
    placement = {
        "type": "object",
        "required": ["part", "type", "x", "y", "theta", "w", "h"],
        "properties": {
            "part": {"type": "string"},
            "type": {"type": "string"},
            **{k: _NUM for k in ("x", "y", "theta", "w", "h")},
        },
    }
    kit = {
        "type": "object",
        "required": ["tasks", "layout"],
        "properties": {
            "tasks": {"type": "array", "items": {"type": "string"}},
            "layout": {"type": "array", "items": placement},
            **{k: _NUM for k in _TIME_KEYS},
        },
    }
    return {
        "$schema": "https://json-schema.org/draft/2020-12/schema",
        "title": "bilevel-kit solution",
        "type": "object",
        "required": ["format", "method", "status", "kits"],
        "properties": {
            "format": {"const": FORMAT},
            "method": {"type": "string"},
            "status": {"enum": ["optimal", "feasible", "infeasible", "unknown"]},
            "status_objective": {
                "type": "string",
                "description": "the objective the status refers to (makespan, human_idle, J)",
            },
            "objective": {"type": ["number", "null"]},
            "bound": {"type": ["number", "null"]},
            "metrics": {"type": ["object", "null"]},
            "kits": {"type": "array", "items": kit},
        },
    }


@dataclass(frozen=True)
class LoadedSolution:
    """A solution file: its plan, and the times and metrics it reports (for the checker)."""

    document: dict[str, Any]
    plan: Plan
    reported_kits: tuple[KitTimes, ...] | None
    reported_metrics: dict[str, float] | None


def from_dict(doc: Any, source: str = "<memory>") -> LoadedSolution:
    validate_document(doc, source, schema(), SolutionError)
    kits = []
    times = []
    for kd in doc["kits"]:
        layout = tuple(
            Placement(
                p["part"],
                p["type"],
                float(p["x"]),
                float(p["y"]),
                float(p["theta"]),
                float(p["w"]),
                float(p["h"]),
            )
            for p in kd["layout"]
        )
        kits.append(Kit(tuple(kd["tasks"]), layout))
        if all(k in kd for k in _TIME_KEYS):
            times.append(KitTimes(*(float(kd[k]) for k in _TIME_KEYS)))
    reported = tuple(times) if len(times) == len(kits) and kits else None
    return LoadedSolution(doc, Plan(tuple(kits)), reported, doc.get("metrics"))


def read(path: str | Path) -> LoadedSolution:
    """Load a solution file; malformed files raise :class:`SolutionError` naming the field."""
    return from_dict(read_json(path, SolutionError), str(path))
