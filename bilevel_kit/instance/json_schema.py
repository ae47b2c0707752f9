"""The JSON Schema (draft 2020-12) of the instance format ``bilevel-kit/1`` (docs/formats.md).

The schema checks the structure; the parser then checks what a schema cannot say (unknown
references, duplicates, cycles, parts larger than the tray). ``bilevel-kit schema`` prints
:func:`schema`, and docs/formats.md's field tables follow it. Each part of the document has
its own builder below, in the order the properties appear in the schema.
"""

from __future__ import annotations

from typing import Any

from .model import DEFAULT_HORIZON, DEFAULT_REPAIR_TIME, DEFAULT_WEIGHTS, FORMAT
from .ranges import (
    ID_PATTERN,
    MAX_LENGTH,
    MAX_PARTS,
    MAX_TASKS,
    MAX_TIME,
    MAX_WEIGHT,
    SERVES_PATTERN,
)

_NONNEG = {"type": "number", "minimum": 0, "maximum": MAX_TIME}  # times (s)
_POS = {"type": "number", "exclusiveMinimum": 0, "maximum": MAX_TIME}  # times > 0 (s)
#: lengths (mm, also the pack files'); the lower limit MIN_LENGTH is checked after the schema,
#: with its reason
LENGTH = {"type": "number", "exclusiveMinimum": 0, "maximum": MAX_LENGTH}
#: ids (also the pack files')
ID = {"type": "string", "minLength": 1, "pattern": ID_PATTERN}


def schema() -> dict[str, Any]:
    """JSON Schema (draft 2020-12) of the instance format ``bilevel-kit/1``."""
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
            "generated_by": {
                "type": "string",
                "description": "the command that made this instance (bilevel-kit generate ...)",
            },
            "tray": _tray_schema(),
            "delivery_time": {**_NONNEG, "default": 0.0, "description": "d in the paper (s)"},
            "kit_overhead": _kit_overhead_schema(),
            "part_types": {"type": "array", "minItems": 1, "items": _part_type_schema()},
            "tasks": {"type": "array", "minItems": 1, "items": _task_schema()},
            "precedence": _precedence_schema(),
            "weights": _weights_schema(),
            "horizon": {
                "type": "integer",
                "minimum": 1,
                "maximum": MAX_TASKS,
                "default": DEFAULT_HORIZON,
            },
            "trays": _trays_schema(),
            "stations": _stations_schema(),
            "supply": _supply_schema(),
            "units": {"type": "integer", "minimum": 1, "maximum": MAX_TASKS, "default": 1},
            "work_cell": _work_cell_schema(),
            **_robot_schema(),
        },
    }


def _tray_schema() -> dict[str, Any]:
    return {
        "type": "object",
        "required": ["width", "height"],
        "additionalProperties": False,
        "properties": {"width": LENGTH, "height": LENGTH},
    }


def _kit_overhead_schema() -> dict[str, Any]:
    return {
        "type": "object",
        "additionalProperties": False,
        "properties": {
            "robot": {**_NONNEG, "default": 0.0, "description": "robot time per kit"},
            "human": {**_NONNEG, "default": 0.0, "description": "human time per kit"},
        },
    }


def _part_type_schema() -> dict[str, Any]:
    """One entry of ``part_types``."""
    return {
        "type": "object",
        "required": ["id", "width", "height", "pick_time"],
        "additionalProperties": False,
        "properties": {
            "id": ID,
            "name": {"type": "string"},
            "width": LENGTH,
            "height": LENGTH,
            "pick_time": _NONNEG,
            "rotatable": {"type": "boolean", "default": True},
            "grasp_width": {
                **LENGTH,
                "description": "width of the feature a parallel gripper closes on (mm), at "
                "most the smaller side; default: the smaller side",
            },
        },
    }


def _task_schema() -> dict[str, Any]:
    """One entry of ``tasks``: its parts (type and count) and its human time."""
    part_request = {
        "type": "object",
        "required": ["type", "count"],
        "additionalProperties": False,
        "properties": {
            "type": {"type": "string"},
            "count": {"type": "integer", "minimum": 1, "maximum": MAX_PARTS},
        },
    }
    return {
        "type": "object",
        "required": ["id", "parts", "human_time"],
        "additionalProperties": False,
        "properties": {
            "id": ID,
            "name": {"type": "string"},
            "product": {"type": "string", "minLength": 1},
            "station": {
                **ID,
                "description": "the assembly station of the task (one of 'stations'); "
                "default: the station serving its product unit",
            },
            "parts": {"type": "array", "items": part_request},
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
    }


def _precedence_schema() -> dict[str, Any]:
    return {
        "type": "array",
        "items": {
            "type": "array",
            "prefixItems": [{"type": "string"}, {"type": "string"}],
            "minItems": 2,
            "maxItems": 2,
        },
        "description": "edges [a, b]: task a must be finished before task b starts",
    }


def _weights_schema() -> dict[str, Any]:
    """W1..W7, each described by its default (:data:`~bilevel_kit.instance.DEFAULT_WEIGHTS`)."""
    return {
        "type": "object",
        "additionalProperties": False,
        "properties": {
            k: {
                "type": "number",
                "minimum": 0,
                "maximum": MAX_WEIGHT,
                "description": f"default {v}",
            }
            for k, v in DEFAULT_WEIGHTS.items()
        },
    }


def _trays_schema() -> dict[str, Any]:
    return {
        "type": ["integer", "null"],
        "minimum": 1,
        "default": None,
        "description": "kit trays in circulation: the robot starts kit k only when the "
        "tray of kit k - trays is back, i.e. once the human has retrieved its parts "
        "(the paper's study: 1); absent or null: unlimited",
    }


def _stations_schema() -> dict[str, Any]:
    """Assembly stations served by the one robot (docs/timeline.md#several-stations)."""
    return {
        "type": "array",
        "minItems": 1,
        "description": "assembly stations served by the robot; absent: one station holding "
        "every task",
        "items": {
            "type": "object",
            "required": ["id"],
            "additionalProperties": False,
            "properties": {
                "id": ID,
                "delivery_time": {**_NONNEG, "description": "d_s (s); default: delivery_time"},
                "trays": {
                    "type": "integer",
                    "minimum": 1,
                    "description": "T_s, trays of this station; default: trays",
                },
                "kit_overhead_human": {
                    **_NONNEG,
                    "description": "o_H of this station's human (s); default: kit_overhead.human",
                },
                "serves": {
                    "type": "array",
                    "items": {"type": "string", "minLength": 1, "pattern": SERVES_PATTERN},
                    "description": "products ('table') or product units ('table@2') whose "
                    "tasks the station builds",
                },
            },
        },
    }


def _supply_schema() -> dict[str, Any]:
    """Per part type, the simulator's feeder (docs/simulation.md)."""
    return {
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
    }


def _work_cell_schema() -> dict[str, Any]:
    from ..sawyer.cell import work_cell_schema

    return work_cell_schema()


def _robot_schema() -> dict[str, Any]:
    """The properties of the Sawyer's reachability rule and of its motion-model times."""
    return {
        "reachability": {
            "type": "boolean",
            "default": False,
            "description": "enforce Sawyer reachability of every placement (uses 'work_cell', "
            "or the default work cell)",
        },
        "reach_resolution": {**LENGTH, "default": 10.0, "description": "reach map cell (mm)"},
        "robot_times": {
            "enum": ["pick_time", "motion"],
            "default": "pick_time",
            "description": "'motion': pick times from the Sawyer motion model",
        },
    }
