"""Stand-alone pack files for ``bilevel-kit pack``: a tray and items, no tasks; and the layout
file ``bilevel-kit pack --out`` writes (its ``format`` tag; both formats in docs/formats.md).

Format: ``{"tray": {"width": W, "height": H}, "items": [{"id", "width", "height", "count",
"rotatable"}]}`` (mm; ``count`` default 1, ``rotatable`` default true). Loading validates with a
JSON Schema and raises :class:`~bilevel_kit.errors.InstanceError` naming the file and the path.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

from .errors import InstanceError
from .instance import (
    MAX_PACK_PARTS,
    Instance,
    PartType,
    Tray,
    check_lengths,
)
from .instance.json_schema import ID, LENGTH  # ids and lengths (mm) as in the instances
from .jsonio import read_json, validate_document

#: The ``format`` tag of layout files.
LAYOUT_FORMAT = "bilevel-kit-layout/1"


def schema() -> dict[str, Any]:
    return {
        "$schema": "https://json-schema.org/draft/2020-12/schema",
        "title": "bilevel-kit pack file",
        "type": "object",
        "required": ["tray", "items"],
        "additionalProperties": False,
        "properties": {
            "tray": {
                "type": "object",
                "required": ["width", "height"],
                "additionalProperties": False,
                "properties": {"width": LENGTH, "height": LENGTH},
            },
            "items": {
                "type": "array",
                "minItems": 1,
                "items": {
                    "type": "object",
                    "required": ["id", "width", "height"],
                    "additionalProperties": False,
                    "properties": {
                        "id": ID,
                        "width": LENGTH,
                        "height": LENGTH,
                        "count": {
                            "type": "integer",
                            "minimum": 1,
                            "maximum": MAX_PACK_PARTS,
                            "default": 1,
                        },
                        "rotatable": {"type": "boolean", "default": True},
                    },
                },
            },
        },
    }


def is_pack_file(doc: Any) -> bool:
    """A JSON object without ``format`` is read as a pack file (instances have ``format``), so
    a pack file that lacks ``items`` is reported as such."""
    return isinstance(doc, dict) and "format" not in doc


def load(path: str | Path) -> tuple[Instance, dict[str, int]]:
    """The pack file as a task-less :class:`Instance` (tray + part types) and the counts."""
    src = str(path)
    doc = read_json(path, InstanceError)
    validate_document(doc, src, schema(), InstanceError)
    check_lengths(doc["tray"], "$.tray", src)
    types: dict[str, PartType] = {}
    counts: dict[str, int] = {}
    for i, item in enumerate(doc["items"]):
        if item["id"] in types:
            raise InstanceError(src, f"$.items[{i}].id", f"duplicate item id {item['id']!r}")
        check_lengths(item, f"$.items[{i}]", src)
        types[item["id"]] = PartType(
            item["id"],
            float(item["width"]),
            float(item["height"]),
            0.0,
            bool(item.get("rotatable", True)),
        )
        counts[item["id"]] = int(item.get("count", 1))
    if sum(counts.values()) > MAX_PACK_PARTS:
        raise InstanceError(
            src,
            "$.items",
            f"{sum(counts.values()):,} parts in all, above the limit of {MAX_PACK_PARTS:,} "
            "(docs/formats.md#ranges)",
        )
    tray = Tray(float(doc["tray"]["width"]), float(doc["tray"]["height"]))
    inst = Instance(
        name=Path(path).stem,
        tray=tray,
        delivery_time=0.0,
        kit_overhead_robot=0.0,
        kit_overhead_human=0.0,
        part_types=types,
        base_tasks=(),
        base_precedence=(),
        source=src,
    )
    return inst, counts
