"""A work-cell file: the work cell's geometry, its gripper and the parts' grasp widths,
declared outside the product file (docs/execution.md#the-work-cell).

An instance file describes the product and its kitting problem; the cell a lab kits it in
(where the tray lies, which fingers the gripper carries, which feature of a part the fingers
close on) is a property of the lab. A work-cell file is a JSON object whose keys are any key
of an instance's ``work_cell`` section (docs/formats.md), ``gripper`` included, plus
``grasp_widths`` (part type -> mm) and a free ``description``; applying it merges the geometry
keys over the instance's work cell (or the default one) and replaces the part types'
``grasp_width``. The instance is then rebuilt from its document, so everything derived from the
geometry (the motion model's pick times with ``robot_times: "motion"``, the reach map) follows
the file.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

from ..errors import DocumentError, InstanceError
from .cell import WorkCell, error_path, work_cell_schema
from .errors import WorkCellError

if TYPE_CHECKING:  # pragma: no cover - typing only
    from ..instance import Instance


class WorkCellFileError(DocumentError):
    """A work-cell file is malformed or does not fit the instance; names file and field."""


#: Keys of a work-cell file besides the ``work_cell`` section's.
CELL_KEYS = ("description", "grasp_widths")


@dataclass(frozen=True)
class WorkCellFile:
    """A parsed work-cell file: the geometry keys it overrides (``work_cell`` section keys)
    and the grasp widths it declares."""

    source: str
    geometry: Mapping[str, Any]
    grasp_widths: Mapping[str, float]
    description: str = ""


def parse_work_cell(doc: Any, source: str = "<memory>") -> WorkCellFile:
    """Validate a work-cell document: known keys, a geometry that builds, positive widths."""
    if not isinstance(doc, Mapping):
        raise WorkCellFileError(source, "$", "expected an object")
    known = set(work_cell_schema()["properties"]) | set(CELL_KEYS)
    unknown = sorted(set(doc) - known)
    if unknown:
        raise WorkCellFileError(
            source, f"$.{unknown[0]}", f"unknown key (known: {', '.join(sorted(known))})"
        )
    geometry = {k: v for k, v in doc.items() if k not in CELL_KEYS}
    try:
        WorkCell.from_dict(geometry)
    except WorkCellError as exc:
        field, detail = error_path(exc)
        raise WorkCellFileError(source, "$" + field, detail) from None
    widths = doc.get("grasp_widths", {})
    if not isinstance(widths, Mapping):
        raise WorkCellFileError(source, "$.grasp_widths", "expected an object part type -> mm")
    for name, value in widths.items():
        ok = isinstance(value, int | float) and not isinstance(value, bool)
        if not ok or not math.isfinite(value) or value <= 0:
            raise WorkCellFileError(
                source, f"$.grasp_widths.{name}", f"expected a number > 0 (mm), got {value!r}"
            )
    description = doc.get("description", "")
    if not isinstance(description, str):
        raise WorkCellFileError(source, "$.description", "expected a string")
    return WorkCellFile(source, geometry, {k: float(v) for k, v in widths.items()}, description)


def load_work_cell(path: str | Path) -> WorkCellFile:
    """Read and validate a work-cell file."""
    from ..jsonio import read_json

    return parse_work_cell(read_json(path, WorkCellFileError), str(path))


def apply_work_cell(instance: Instance, cell: WorkCellFile) -> Instance:
    """``instance`` in the work cell: the file's geometry keys merged over the instance's work
    cell (or the default one), its grasp widths on the part types. Unknown part types and a
    grasp width wider than the part's smaller side are :class:`WorkCellFileError` naming the
    file. The instance is rebuilt from its document: apply the cell before
    ``with_overrides``."""
    from ..instance import from_dict

    unknown = sorted(set(cell.grasp_widths) - set(instance.part_types))
    if unknown:
        name = unknown[0]
        where = f"$.grasp_widths.{name}"
        raise WorkCellFileError(cell.source, where, f"no part type {name!r} in {instance.source}")
    doc = instance.to_dict()
    for i, pt in enumerate(doc["part_types"]):
        width = cell.grasp_widths.get(pt["id"])
        if width is None:
            continue
        if width > min(pt["width"], pt["height"]):
            raise WorkCellFileError(
                cell.source,
                f"$.grasp_widths.{pt['id']}",
                f"{width:g} mm exceeds the smaller side of part {pt['id']!r} "
                f"({pt['width']:g} x {pt['height']:g} mm), across which the fingers close",
            )
        doc["part_types"][i] = {**pt, "grasp_width": width}
    if cell.geometry:
        base = (instance.work_cell or WorkCell()).to_dict()
        doc["work_cell"] = {**base, **cell.geometry}
    try:
        out = from_dict(doc, instance.source)
    except InstanceError as exc:  # e.g. a bin of an unknown part type, a slot out of reach
        inside = exc.path.startswith("$.work_cell")
        field = "$" + exc.path.removeprefix("$.work_cell") if inside else "$"
        raise WorkCellFileError(cell.source, field, f"{exc.detail} ({instance.source})") from None
    return out


def cell_document(cell: WorkCellFile) -> dict[str, Any]:
    """The work cell as a document :func:`parse_work_cell` reads back to the same cell."""
    doc: dict[str, Any] = {**cell.geometry}
    if cell.grasp_widths:
        doc["grasp_widths"] = dict(cell.grasp_widths)
    if cell.description:
        doc["description"] = cell.description
    return doc


def cell_digest(cell: WorkCellFile) -> str:
    """SHA-256 of the cell's canonical JSON: equal for equal content, whatever the file's
    layout, key order or path."""
    import hashlib
    import json

    text = json.dumps(cell_document(cell), sort_keys=True, separators=(",", ":"))
    return hashlib.sha256(text.encode("utf-8")).hexdigest()


def cell_record(cell: WorkCellFile) -> dict[str, Any]:
    """What a solution file records of the work cell it was solved in (docs/formats.md):
    the file's path as given, the content's digest and the content itself, so that
    ``execute`` can use it without the file and tell a different cell apart."""
    return {"path": cell.source, "sha256": cell_digest(cell), "cell": cell_document(cell)}


def recorded_cell(record: Mapping[str, Any], source: str) -> WorkCellFile:
    """The work cell a solution file records (``source`` names the file), validated as a
    work-cell file is; a content that does not match its digest is :class:`WorkCellFileError`."""
    cell = parse_work_cell(record["cell"], f"{source} (work_cell.cell)")
    if cell_digest(cell) != record["sha256"]:
        raise WorkCellFileError(source, "$.work_cell.sha256", "does not match the recorded cell")
    return cell
