"""The work cell's geometry: where the tray and the part bins are, relative to the Sawyer.

An instance's ``work_cell`` section (docs/formats.md#the-work-cell-section); not to be confused
with the assembly *stations* a robot serves (``stations``, docs/stations.md).

Units follow the instance format: lengths in **millimetres**, angles in **degrees**. All poses
are in the robot ``base`` frame (x forward, y to the robot's left, z up; origin on the
``right_j0`` axis at the top of the pedestal, about 0.91 m above the floor).

The tray frame has its origin at the tray's lower-left corner on the tray surface; its x axis
runs along the tray width and its y axis along the tray height (the directions of the
instance's ``tray.width`` / ``tray.height`` and of every placement's ``x`` / ``y``); its z axis
is the base z axis. ``tray_yaw`` is the heading of the tray x axis in the base frame.

The default work cell (:data:`DEFAULT_WORK_CELL`): a tray lying flat on a table 150 mm below the
base (a 0.76 m table next to the standard pedestal), with yaw -90 deg, so that from the robot's
point of view the tray x axis runs to the right and the y axis away from the robot. Its
lower-left corner is at (450, 300) mm, so a 600 x 400 mm tray covers x in [450, 850] mm and y
in [-300, 300] mm: centred 650 mm in front of the robot. Parts come from one bin at
(300, 550, -100) mm, to the robot's left, unless ``bins`` names a bin for their type. The tool
is the Rethink electric gripper (tip 135.62 mm beyond the flange,
``model.ELECTRIC_GRIPPER_TIP``).
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from .errors import WorkCellError
from .fingers import DEFAULT_GRIPPER, Gripper, gripper_schema

Vec3 = tuple[float, float, float]


def _vec3(value: Any, where: str) -> Vec3:
    try:
        x, y, z = (float(v) for v in value)
    except (TypeError, ValueError) as exc:
        raise WorkCellError(f"{where}: expected [x, y, z] in mm, got {value!r}") from exc
    if not all(math.isfinite(v) for v in (x, y, z)):
        raise WorkCellError(f"{where}: coordinates must be finite, got {value!r}")
    return (x, y, z)


@dataclass(frozen=True)
class WorkCell:
    """Tray pose, bins and gripper settings of the robot's work cell (mm, degrees).

    ``bins`` may be given as a mapping part type -> (x, y, z); it is stored as a sorted tuple
    of pairs so that work cells are hashable. ``grasp_yaws`` are the allowed headings of the
    gripper's x axis: measured from the tray x axis at the tray, from the base x axis at a bin.
    """

    tray_x: float = 450.0
    tray_y: float = 300.0
    tray_z: float = -150.0
    tray_yaw: float = -90.0
    bins: Any = ()
    default_bin: Vec3 = (300.0, 550.0, -100.0)
    #: Vertical distance of the approach / retreat pose above each grasp or release pose.
    approach_height: float = 100.0
    #: Height of the tool tip above the tray surface when it releases a part.
    place_height: float = 20.0
    #: Per part type, a release height replacing ``place_height`` (mapping or pairs, mm).
    place_heights: Any = ()
    grasp_yaws: tuple[float, ...] = (0.0, 90.0, 180.0, -90.0)
    #: Tool tip distance along the flange (``right_hand``) z axis.
    tool_offset: float = 135.62
    #: The parallel gripper (docs/execution.md#the-gripper); default: the URDF's fingers.
    gripper: Gripper = DEFAULT_GRIPPER

    def __post_init__(self) -> None:
        bins = self.bins
        items = bins.items() if isinstance(bins, Mapping) else bins
        norm = tuple(sorted((str(k), _vec3(v, f"bins.{k}")) for k, v in items))
        object.__setattr__(self, "bins", norm)
        heights = self.place_heights
        pairs = heights.items() if isinstance(heights, Mapping) else heights
        object.__setattr__(
            self,
            "place_heights",
            tuple(sorted((str(k), _number(v, f"place_heights.{k}")) for k, v in pairs)),
        )
        object.__setattr__(self, "default_bin", _vec3(self.default_bin, "default_bin"))
        object.__setattr__(self, "grasp_yaws", tuple(float(a) for a in self.grasp_yaws))
        for name in (
            "tray_x",
            "tray_y",
            "tray_z",
            "tray_yaw",
            "approach_height",
            "place_height",
            "tool_offset",
        ):
            value = float(getattr(self, name))
            if not math.isfinite(value):
                raise WorkCellError(f"{name} must be finite, got {value!r}")
            object.__setattr__(self, name, value)
        if not isinstance(self.gripper, Gripper):
            raise WorkCellError(f"gripper: expected a Gripper, got {self.gripper!r}")
        if not self.grasp_yaws:
            raise WorkCellError("grasp_yaws: at least one allowed gripper yaw is needed")
        if self.approach_height < 0 or self.tool_offset < 0:
            raise WorkCellError("approach_height and tool_offset must be >= 0")
        if len(set(self.grasp_yaws)) != len(self.grasp_yaws):
            raise WorkCellError("grasp_yaws: angles must be distinct")

    # --- geometry -------------------------------------------------------------------------

    @property
    def tool_offset_m(self) -> float:
        return self.tool_offset / 1000.0

    def tray_to_base(
        self, x_mm: float | np.ndarray, y_mm: float | np.ndarray, height_mm: float = 0.0
    ) -> np.ndarray:
        """Base-frame position [m] of tray point(s) (mm), ``height_mm`` above the surface.

        Scalars give shape (3,); arrays give shape (..., 3).
        """
        t = math.radians(self.tray_yaw)
        c, s = math.cos(t), math.sin(t)
        x = np.asarray(x_mm, dtype=float)
        y = np.asarray(y_mm, dtype=float)
        bx = self.tray_x + c * x - s * y
        by = self.tray_y + s * x + c * y
        bz = np.broadcast_to(self.tray_z + height_mm, bx.shape)
        return np.stack([bx, by, bz], axis=-1) / 1000.0

    def slot_yaws(self) -> tuple[float, ...]:
        """Allowed gripper headings at the tray, in the base frame (deg)."""
        return tuple(self.tray_yaw + a for a in self.grasp_yaws)

    def bin_xyz(self, part_type: str) -> Vec3:
        """Position (mm, base frame) of the bin of ``part_type`` (the default bin if none)."""
        for name, xyz in self.bins:
            if name == part_type:
                return xyz
        return self.default_bin

    def place_height_of(self, part_type: str) -> float:
        """Release height [mm] of the tool tip above the tray for ``part_type``."""
        return dict(self.place_heights).get(part_type, self.place_height)

    def bin_point(self, part_type: str) -> np.ndarray:
        """Grasp point [m, base frame] of the tool tip at the bin of ``part_type``."""
        return np.array(self.bin_xyz(part_type)) / 1000.0

    # --- serialisation --------------------------------------------------------------------

    def to_dict(self) -> dict[str, Any]:
        """The ``work_cell`` section of an instance file (see :func:`work_cell_schema`)."""
        doc: dict[str, Any] = {
            "tray_pose": {
                "x": self.tray_x,
                "y": self.tray_y,
                "z": self.tray_z,
                "yaw": self.tray_yaw,
            },
            "default_bin": list(self.default_bin),
            "approach_height": self.approach_height,
            "place_height": self.place_height,
            "grasp_yaws": list(self.grasp_yaws),
            "tool_offset": self.tool_offset,
        }
        if self.bins:
            doc["bins"] = {name: list(xyz) for name, xyz in self.bins}
        if self.place_heights:
            doc["place_heights"] = dict(self.place_heights)
        if self.gripper != DEFAULT_GRIPPER:
            doc["gripper"] = self.gripper.to_dict()
        return doc

    @classmethod
    def from_dict(cls, doc: Mapping[str, Any] | None) -> WorkCell:
        """Build from a ``work_cell`` section; missing keys take the default work cell's values.

        Raises :class:`WorkCellError` (a ``ValueError``) naming the bad key.
        """
        if doc is None:
            return cls()
        if not isinstance(doc, Mapping):
            raise WorkCellError(f"work_cell: expected an object, got {type(doc).__name__}")
        known = set(work_cell_schema()["properties"])
        unknown = sorted(set(doc) - known)
        if unknown:
            raise WorkCellError(f"work_cell: unknown key(s) {', '.join(unknown)}")
        kwargs: dict[str, Any] = {}
        pose = doc.get("tray_pose", {})
        if not isinstance(pose, Mapping):
            raise WorkCellError("work_cell.tray_pose: expected an object with x, y, z, yaw")
        for key in pose:
            if key not in ("x", "y", "z", "yaw"):
                raise WorkCellError(f"work_cell.tray_pose: unknown key {key!r}")
        for key in ("x", "y", "z", "yaw"):
            if key in pose:
                kwargs[f"tray_{key}"] = _number(pose[key], f"work_cell.tray_pose.{key}")
        if "bins" in doc:
            if not isinstance(doc["bins"], Mapping):
                raise WorkCellError("work_cell.bins: expected an object part type -> [x, y, z]")
            kwargs["bins"] = {k: _vec3(v, f"work_cell.bins.{k}") for k, v in doc["bins"].items()}
        if "place_heights" in doc:
            if not isinstance(doc["place_heights"], Mapping):
                raise WorkCellError("work_cell.place_heights: expected an object part type -> mm")
            kwargs["place_heights"] = {
                k: _number(v, f"work_cell.place_heights.{k}")
                for k, v in doc["place_heights"].items()
            }
        if "gripper" in doc:
            kwargs["gripper"] = Gripper.from_dict(doc["gripper"])
        if "default_bin" in doc:
            kwargs["default_bin"] = _vec3(doc["default_bin"], "work_cell.default_bin")
        for key in ("approach_height", "place_height", "tool_offset"):
            if key in doc:
                kwargs[key] = _number(doc[key], f"work_cell.{key}")
        if "grasp_yaws" in doc:
            yaws = doc["grasp_yaws"]
            if isinstance(yaws, str | bytes) or not isinstance(yaws, Iterable):
                raise WorkCellError("work_cell.grasp_yaws: expected a list of angles in degrees")
            kwargs["grasp_yaws"] = tuple(_number(a, "work_cell.grasp_yaws[]") for a in yaws)
        return cls(**kwargs)


def error_path(exc: WorkCellError) -> tuple[str, str]:
    """``(path inside the section, detail)`` of a geometry error, so that a file's error names
    its own key (``work_cell`` or the old ``station``): ``"work_cell.tray_pose.x: bad"`` gives
    ``(".tray_pose.x", "bad")``; a message without a field gives ``("", message)``."""
    field, sep, detail = str(exc).partition(": ")
    if not sep or " " in field:
        return "", str(exc)
    field = field.removeprefix("work_cell")
    return (field if not field or field.startswith(".") else "." + field), detail


def _number(value: Any, where: str) -> float:
    if isinstance(value, bool) or not isinstance(value, int | float) or not math.isfinite(value):
        raise WorkCellError(f"{where}: expected a finite number, got {value!r}")
    return float(value)


#: The documented default work cell (see the module docstring).
DEFAULT_WORK_CELL = WorkCell()


def work_cell_schema() -> dict[str, Any]:
    """JSON-schema fragment (draft 2020-12) of the optional ``work_cell`` section."""
    num = {"type": "number"}
    xyz = {
        "type": "array",
        "items": num,
        "minItems": 3,
        "maxItems": 3,
        "description": "[x, y, z] in mm, robot base frame",
    }
    d = DEFAULT_WORK_CELL
    return {
        "type": "object",
        "description": "Sawyer work cell geometry (mm, degrees, robot base frame: x forward, "
        "y left, z up). Every key is optional; defaults describe a tray 650 mm in front of "
        "the robot on a table 150 mm below the base.",
        "additionalProperties": False,
        "properties": {
            "tray_pose": {
                "type": "object",
                "description": "pose of the tray's lower-left corner frame; yaw = heading of "
                "the tray x (width) axis",
                "additionalProperties": False,
                "properties": {
                    "x": {**num, "default": d.tray_x},
                    "y": {**num, "default": d.tray_y},
                    "z": {**num, "default": d.tray_z},
                    "yaw": {**num, "default": d.tray_yaw},
                },
            },
            "bins": {
                "type": "object",
                "description": "part type -> grasp point of its bin",
                "additionalProperties": xyz,
            },
            "default_bin": {**xyz, "default": list(d.default_bin)},
            "approach_height": {"type": "number", "minimum": 0, "default": d.approach_height},
            "place_height": {
                **num,
                "default": d.place_height,
                "description": "tool tip height above the tray when releasing",
            },
            "place_heights": {
                "type": "object",
                "description": "part type -> tool tip height above the tray when releasing "
                "that type (mm), replacing place_height",
                "additionalProperties": num,
            },
            "grasp_yaws": {
                "type": "array",
                "items": num,
                "minItems": 1,
                "default": list(d.grasp_yaws),
                "description": "allowed gripper headings (deg) from the tray x "
                "axis at the tray and from the base x axis at a bin",
            },
            "tool_offset": {
                "type": "number",
                "minimum": 0,
                "default": d.tool_offset,
                "description": "tool tip distance beyond the flange (mm)",
            },
            "gripper": gripper_schema(),
        },
    }
