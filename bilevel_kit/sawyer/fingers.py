"""The work cell's parallel gripper: its stroke and fingers (docs/execution.md#the-gripper).

A module of its own, without the feasibility pass of :mod:`.gripper`, so that the work cell
(and through it the instance schema) can hold a gripper without importing the instance.
Lengths in mm.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

from .errors import WorkCellError

#: The URDF's electric gripper fingers: each finger joint travels 0..20.833 mm.
URDF_STROKE_MAX = 2 * 20.833


@dataclass(frozen=True)
class Gripper:
    """A parallel gripper: the fingers' opening range and their size (mm)."""

    #: Smallest and largest distance between the fingers' inner faces.
    stroke_min: float = 0.0
    stroke_max: float = URDF_STROKE_MAX
    #: Length of a finger below the gripper body (included in the work cell's ``tool_offset``).
    finger_length: float = 75.0
    #: Side of a finger's square pad, seen from above.
    finger_width: float = 12.0
    #: Opening beyond the grasp width when approaching, and squeeze below it when holding.
    clearance: float = 2.0

    def __post_init__(self) -> None:
        for name in ("stroke_min", "stroke_max", "finger_length", "finger_width", "clearance"):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, int | float):
                raise WorkCellError(f"gripper.{name}: expected a number, got {value!r}")
            if not math.isfinite(value) or value < 0:
                raise WorkCellError(f"gripper.{name}: expected a finite number >= 0, got {value!r}")
            object.__setattr__(self, name, float(value))
        if self.stroke_max <= self.stroke_min:
            raise WorkCellError(
                f"gripper.stroke_max: {self.stroke_max:g} mm must exceed stroke_min "
                f"({self.stroke_min:g} mm)"
            )
        if self.finger_width <= 0:
            raise WorkCellError("gripper.finger_width: expected a number > 0")

    @property
    def grasp_range(self) -> tuple[float, float]:
        """The grasp widths this gripper holds, clearance included (mm)."""
        return (self.stroke_min + self.clearance, self.stroke_max - self.clearance)

    def to_dict(self) -> dict[str, float]:
        return {name: getattr(self, name) for name in GRIPPER_KEYS}

    @classmethod
    def from_dict(cls, doc: Any) -> Gripper:
        """Build from a work cell's ``gripper`` object; missing keys take the URDF's fingers."""
        if not isinstance(doc, Mapping):
            raise WorkCellError("work_cell.gripper: expected an object")
        unknown = sorted(set(doc) - set(GRIPPER_KEYS))
        if unknown:
            raise WorkCellError(f"work_cell.gripper: unknown key(s) {', '.join(unknown)}")
        try:
            return cls(**doc)
        except WorkCellError as exc:
            raise WorkCellError(f"work_cell.{exc}") from None


#: The URDF's fingers (the work cell's default).
DEFAULT_GRIPPER = Gripper()

GRIPPER_KEYS = ("stroke_min", "stroke_max", "finger_length", "finger_width", "clearance")


def gripper_schema() -> dict[str, Any]:
    """JSON-schema fragment of the work cell's ``gripper`` object."""
    d = DEFAULT_GRIPPER
    length = {"type": "number", "minimum": 0}
    what = {
        "stroke_min": "smallest distance between the fingers' inner faces (mm)",
        "stroke_max": "largest distance between the fingers' inner faces (mm)",
        "finger_length": "a finger's length below the gripper body (mm)",
        "finger_width": "side of a finger's square pad seen from above (mm)",
        "clearance": "opening beyond the grasp width, and squeeze below it (mm)",
    }
    return {
        "type": "object",
        "description": "the parallel gripper (default: the URDF's electric gripper fingers)",
        "additionalProperties": False,
        "properties": {
            k: {**length, "default": getattr(d, k), "description": what[k]} for k in GRIPPER_KEYS
        },
    }
