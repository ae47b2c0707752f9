"""Instance data model, loading and validation (format ``bilevel-kit/1``).

Lengths are in millimetres, times in seconds. An instance describes one product (or a mix of
products) as tasks with a precedence graph, the part types the robot kits for them, the tray, the
delivery time and the paper's weights. ``units`` copies of the product are built one after
another; :attr:`Instance.tasks` and :attr:`Instance.precedence` are the expanded (all-units) view
that every solver, the evaluator and the checker work on.

Loading validates the structure with a JSON Schema (:func:`schema`) and then the semantics
(unknown references, duplicates, cycles, parts larger than the tray). Every problem raises
:class:`~bilevel_kit.errors.InstanceError`, whose message names the file and the JSON path.

The package keeps one responsibility per module: :mod:`.model` (the dataclasses and the
expanded view), :mod:`.ranges` (the sane ranges of the numbers), :mod:`.json_schema` (the
schema) and :mod:`.parser` (documents in); every name is imported from here.
"""

from __future__ import annotations

from .builder import InstanceBuilder
from .json_schema import schema
from .model import (
    DEFAULT_HORIZON,
    DEFAULT_REPAIR_TIME,
    DEFAULT_WEIGHTS,
    FORMAT,
    AssemblyStation,
    Instance,
    PartType,
    StationParams,
    Supply,
    Task,
    Tray,
    topological_order,
)
from .parser import document, from_dict, load, loads, read_json
from .ranges import (
    ID_PATTERN,
    MAX_LENGTH,
    MAX_PACK_PARTS,
    MAX_PARTS,
    MAX_TASKS,
    MAX_TIME,
    MAX_WEIGHT,
    MIN_LENGTH,
    check_lengths,
    check_size,
    parse_trays,
)

__all__ = [
    "DEFAULT_HORIZON",
    "DEFAULT_REPAIR_TIME",
    "DEFAULT_WEIGHTS",
    "FORMAT",
    "ID_PATTERN",
    "MAX_LENGTH",
    "MAX_PACK_PARTS",
    "MAX_PARTS",
    "MAX_TASKS",
    "MAX_TIME",
    "MAX_WEIGHT",
    "MIN_LENGTH",
    "AssemblyStation",
    "Instance",
    "InstanceBuilder",
    "PartType",
    "StationParams",
    "Supply",
    "Task",
    "Tray",
    "check_lengths",
    "check_size",
    "document",
    "from_dict",
    "load",
    "loads",
    "parse_trays",
    "read_json",
    "schema",
    "topological_order",
]
