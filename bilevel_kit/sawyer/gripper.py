"""The work cell's parallel gripper and the feasibility pass of every grasp and release
(docs/execution.md#the-gripper).

A parallel gripper closes two fingers across one width of a part: across the footprint's y
side or its x side, a declared ``grasp_width`` (the feature the fingers close on, e.g. a
bracket's wall) replacing the smaller side. The fingers are centred on the footprint's centre,
where the arm releases the part; among the grasps the stroke holds, the pass keeps the one
with the largest clearance.

The pass, per kit and part in layout order (the order the arm places them):

- **stroke**: the grasp width lies within ``[stroke_min + clearance, stroke_max - clearance]``
  (the fingers open ``clearance`` beyond the part to approach it and close ``clearance``
  further to hold it);
- **tray**: the open fingers, two square pads of ``finger_width`` whose inner faces are
  ``grasp width + clearance`` apart, lie within the tray at the part's slot and angle;
- **placed parts**: the pads do not overlap the footprint of any part placed before it in
  the same kit (touching is allowed: the clearance found is reported).

Lengths in mm, angles in degrees, in the tray frame of :mod:`.cell`.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from ..geometry import TOL, corners, penetration
from .fingers import DEFAULT_GRIPPER as DEFAULT_GRIPPER
from .fingers import GRIPPER_KEYS as GRIPPER_KEYS
from .fingers import URDF_STROKE_MAX as URDF_STROKE_MAX
from .fingers import Gripper as Gripper
from .fingers import gripper_schema as gripper_schema

if TYPE_CHECKING:  # pragma: no cover - typing only
    from ..instance import Instance, PartType
    from ..plan import Placement, Plan


@dataclass(frozen=True)
class GraspCheck:
    """One part's grasp and release: its widths, the fingers' clearances and the verdict."""

    kit: int
    part: str
    type: str
    grasp_width: float
    #: Distance between the open fingers' outer faces.
    span: float
    #: Smallest distance of a finger pad to the tray's edge (< 0: outside).
    tray_clearance: float
    #: Smallest distance of a finger pad to a part placed before (< 0: overlap; inf: none).
    part_clearance: float
    #: The placed part nearest to the fingers ("" when none).
    nearest: str
    #: What fails: "stroke" (no grasp within the stroke), "tray", "part", or "" (feasible).
    fault: str
    #: One line naming kit, part and widths when the grasp is not feasible, else "".
    problem: str


def grasp_axes(pt: PartType, p: Placement) -> list[tuple[float, float]]:
    """The grasps of a part as (closing direction in degrees from the tray x axis, width):
    across its y side (``h``) and across its x side (``w``); a declared ``grasp_width``
    replaces the smaller side's width (both widths of a square part)."""
    declared = getattr(pt, "grasp_width", None)
    small = min(p.w, p.h)
    out = []
    for along, side in ((p.theta + 90.0, p.h), (p.theta, p.w)):
        out.append((along, float(declared) if declared is not None and side <= small else side))
    return out


def finger_pads(
    p: Placement, along: float, width: float, gripper: Gripper
) -> tuple[np.ndarray, np.ndarray]:
    """Corners of the two open finger pads releasing ``p``, closing along the heading
    ``along`` (degrees from the tray x axis) on a width ``width``."""
    offset = (width + gripper.clearance + gripper.finger_width) / 2.0
    t = math.radians(along)
    dx, dy = offset * math.cos(t), offset * math.sin(t)
    fw = gripper.finger_width
    return (
        corners(p.x + dx, p.y + dy, fw, fw, along),
        corners(p.x - dx, p.y - dy, fw, fw, along),
    )


def _gap(a: np.ndarray, b: np.ndarray) -> float:
    """Distance between two convex quadrilaterals; minus the penetration when they overlap."""
    depth = penetration(a, b)
    if depth > 0:
        return -depth
    best = math.inf
    for pts, poly in ((a, b), (b, a)):
        for i in range(4):
            s, e = poly[i], poly[(i + 1) % 4]
            d = e - s
            u = np.clip((pts - s) @ d / float(d @ d), 0.0, 1.0)
            best = min(best, float(np.min(np.linalg.norm(pts - (s + u[:, None] * d), axis=1))))
    return best


def _clearances(
    pads: tuple[np.ndarray, np.ndarray], tray: tuple[float, float], before: Sequence[Placement]
) -> tuple[float, float, str]:
    """The pads' smallest distance to the tray's edge and to a placed part, and that part."""
    pts = np.vstack(pads)
    tw, th = tray
    edge = float(np.min(np.minimum.reduce([pts[:, 0], tw - pts[:, 0], pts[:, 1], th - pts[:, 1]])))
    near, nearest = math.inf, ""
    for q in before:
        box = corners(q.x, q.y, q.w, q.h, q.theta)
        gap = min(_gap(pad, box) for pad in pads)
        if gap < near:
            near, nearest = gap, q.part
    return edge, near, nearest


def _part_check(
    kit: int, p: Placement, before: Sequence[Placement], instance: Instance, gripper: Gripper
) -> GraspCheck:
    """The best grasp of ``p`` (the largest smallest clearance among the grasps the stroke
    holds) and its verdict."""
    lo, hi = gripper.grasp_range
    where = f"kit {kit}, part {p.part} (type {p.type})"
    axes = grasp_axes(instance.part_types[p.type], p)
    held = [(along, w) for along, w in axes if lo - TOL <= w <= hi + TOL]
    if not held:
        width = min(w for _, w in axes)
        problem = (
            f"{where}: grasp width {width:g} mm is outside the gripper's stroke "
            f"{gripper.stroke_min:g}-{gripper.stroke_max:g} mm less {gripper.clearance:g} mm "
            f"clearance ({lo:g}-{hi:g} mm)"
        )
        return GraspCheck(
            kit, p.part, p.type, width, math.nan, math.nan, math.nan, "", "stroke", problem
        )
    tray = (instance.tray.width, instance.tray.height)
    scored = []
    for along, w in held:
        edge, near, nearest = _clearances(finger_pads(p, along, w, gripper), tray, before)
        scored.append((min(edge, near), w, edge, near, nearest))
    _, width, edge, near, nearest = max(scored, key=lambda s: s[0])
    span = width + gripper.clearance + 2 * gripper.finger_width
    fingers = (
        f"the open fingers ({span:g} mm across: grasp width {width:g} + clearance "
        f"{gripper.clearance:g} + 2 x finger width {gripper.finger_width:g})"
    )
    fault, problem = "", ""
    if edge < -TOL:
        fault = "tray"
        problem = (
            f"{where}: {fingers} leave the {tray[0]:g} x {tray[1]:g} mm tray by {-edge:.2f} mm"
        )
    elif near < -TOL:
        fault = "part"
        problem = f"{where}: {fingers} overlap part {nearest}, placed before it, by {-near:.2f} mm"
    return GraspCheck(kit, p.part, p.type, width, span, edge, near, nearest, fault, problem)


def check_grasps(
    instance: Instance, plan: Plan, kits: Sequence[int] | None = None
) -> tuple[GraspCheck, ...]:
    """The gripper's feasibility pass over every part of ``plan`` (all kits, or the kit
    numbers ``kits``) with the instance's work-cell gripper (the URDF's fingers by default)."""
    from .cell import DEFAULT_WORK_CELL

    gripper = (instance.work_cell or DEFAULT_WORK_CELL).gripper
    chosen = range(1, len(plan.kits) + 1) if kits is None else kits
    out = []
    for k in chosen:
        layout = plan.kits[k - 1].layout
        out += [_part_check(k, p, layout[:i], instance, gripper) for i, p in enumerate(layout)]
    return tuple(out)


def verdicts(checks: Sequence[GraspCheck]) -> dict[str, tuple[int, float, float]]:
    """Per part type: (parts that fail, smallest tray clearance, smallest part clearance)."""
    out: dict[str, tuple[int, float, float]] = {}
    for c in checks:
        bad, tray, near = out.get(c.type, (0, math.inf, math.inf))
        out[c.type] = (
            bad + bool(c.problem),
            min(tray, c.tray_clearance),
            min(near, c.part_clearance),
        )
    return out


# --- finger room: what a packer keeps free for the fingers --------------------------------


def grasp_footprint(pt: PartType, gripper: Gripper) -> tuple[float, float]:
    """The rectangle (w, h, in the part's frame, centred on its footprint) that holds the part
    and its open fingers for the grasp across its smaller side (docs/execution.md#finger-room).

    Along the closing direction it spans the larger of the side and the open fingers' outer
    faces, ``grasp width + clearance + 2 x finger_width``; across it, the larger of the side
    and a pad. A part whose grasp the stroke does not hold keeps its footprint: no room helps.
    """
    declared = getattr(pt, "grasp_width", None)
    small = min(pt.width, pt.height)
    grasp = small if declared is None else float(declared)
    lo, hi = gripper.grasp_range
    if not lo - TOL <= grasp <= hi + TOL:
        return (pt.width, pt.height)
    span = grasp + gripper.clearance + 2.0 * gripper.finger_width
    if pt.height <= pt.width:  # closing along the part's y axis, across its height
        return (max(pt.width, gripper.finger_width), max(pt.height, span))
    return (max(pt.width, span), max(pt.height, gripper.finger_width))


def with_finger_room(instance: Instance) -> Instance:
    """A copy of ``instance`` whose part types are their :func:`grasp_footprint` with the
    work cell's gripper: a layout of the copy, given back its true sizes by
    :func:`true_sizes`, keeps the open fingers within the tray and off every other part."""
    from dataclasses import replace

    from ..errors import UsageError
    from .cell import DEFAULT_WORK_CELL

    gripper = (instance.work_cell or DEFAULT_WORK_CELL).gripper
    tw, th = instance.tray.width, instance.tray.height
    grown = {}
    for name, pt in instance.part_types.items():
        w, h = grasp_footprint(pt, gripper)
        upright = w <= tw + TOL and h <= th + TOL
        if not upright and not (pt.rotatable and h <= tw + TOL and w <= th + TOL):
            raise UsageError(
                f"{instance.source}: finger_room: part type {name!r} with its open fingers "
                f"({w:g} x {h:g} mm) does not fit the {tw:g} x {th:g} mm tray"
            )
        grown[name] = replace(pt, width=w, height=h)
    return replace(instance, part_types=grown)


def true_sizes(plan: Plan, instance: Instance) -> Plan:
    """``plan`` with every placement's footprint the part type's own (same centre and angle)."""
    from dataclasses import replace

    types = instance.part_types
    return replace(
        plan,
        kits=tuple(
            replace(
                k,
                layout=tuple(
                    replace(p, w=types[p.type].width, h=types[p.type].height) for p in k.layout
                ),
            )
            for k in plan.kits
        ),
    )
