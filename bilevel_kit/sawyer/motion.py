"""Robot motion times for pick-and-place: bin -> tray slot, from joint-space distances.

Every move is a straight line in joint space between two IK solutions, timed with a
**synchronised trapezoidal velocity profile**: all joints start and stop together and follow
the same normalised profile s(t) in [0, 1], so joint i moves at ``d_i * s'(t)``. The path speed
and acceleration limits are ``min_i v_i / |d_i|`` and ``min_i a_i / |d_i|``, i.e. the slowest
joint governs; the profile accelerates at the limit, cruises at the speed limit, and brakes
at the limit (a triangle when the move is too short to reach the cruise speed). This is the
time-optimal timing of that joint path under the box limits.

Limits: velocities are the Sawyer's (``model.V_MAX``); for accelerations we assume each joint
reaches its velocity limit in :data:`ACCEL_RAMP` = 0.5 s, i.e. ``a_i = 2 v_i`` (3.5 rad/s^2 for
``right_j0`` up to 9.1 rad/s^2 for ``right_j6``; Intera's own acceleration presets differ),
scaled by ``accel_scale``. ``speed_scale`` S slows every move down in time: velocity limits
times S, acceleration limits times S^2, so a move lasts 1/S times as long and keeps its shape.
On top, the tool tip's Cartesian speed is capped at ``tool_speed`` (default
:data:`TOOL_SPEED` = 0.6 m/s, Intera's default Cartesian speed limit): along a joint-space
line the tool moves at ``|J(q(s)) d| s'``, so the path speed is also limited by ``tool_speed``
over the largest ``|J d|`` at :data:`TOOL_SAMPLES` points of the line. The gripper's dwell
times are not scaled.

One pick-and-place cycle starts and ends above the part's bin (``approach_height`` above the
grasp point) and is, in order:

1. approach: descend to the grasp pose; 2. grasp (:data:`GRASP_TIME`); 3. retreat up;
4. transfer to the pose above the slot; 5. approach: descend to the release pose;
6. release (:data:`RELEASE_TIME`); 7. retreat up; 8. return to above the bin (optional).

The vertical approach / retreat moves are timed as joint-space lines too (over 100 mm the
Cartesian deviation is small). At the slot, the gripper yaw among the work cell's allowed yaws
is the one that needs the least ``right_j6`` travel from the pose above the bin; the allowed
yaws are measured from the part's x axis, which lies at the placement's angle ``theta`` from
the tray x axis (0 by default, the layout-free case). The IK at the slot is warm-started from
the bin pose, which keeps the arm on the same branch.
"""

from __future__ import annotations

import math
from collections.abc import Iterable
from dataclasses import dataclass, field, replace
from functools import lru_cache
from typing import Any

import numpy as np

from .cell import WorkCell
from .errors import UnreachableError
from .ik import IKSolution, solve_top_down
from .model import ELECTRIC_GRIPPER_TIP, LIMIT_PROFILES, V_MAX, Arm, tool_arm

#: Seconds for a joint to reach its velocity limit from rest (defines the assumed accels).
ACCEL_RAMP = 0.5
#: Assumed joint acceleration limits [rad/s^2].
A_MAX = V_MAX / ACCEL_RAMP
#: Default cap on the tool tip's Cartesian speed [m/s] (Intera's default Cartesian limit).
TOOL_SPEED = 0.6
#: Points of a joint-space line at which the tool speed is evaluated (ends included).
TOOL_SAMPLES = 33
#: Gripper close time at the bin [s] (assumed, Rethink electric gripper class).
GRASP_TIME = 0.5
#: Gripper open time at the slot [s] (assumed).
RELEASE_TIME = 0.3


@dataclass(frozen=True)
class MotionParams:
    """Timing assumptions; the defaults are documented in the module docstring."""

    #: Time scaling in (0, 1]: velocity limits times S, acceleration limits times S^2.
    speed_scale: float = 1.0
    #: Fraction of :data:`A_MAX` used (before ``speed_scale``).
    accel_scale: float = 1.0
    grasp_time: float = GRASP_TIME
    release_time: float = RELEASE_TIME
    #: Whether a cycle includes the move back above the bin.
    return_to_bin: bool = True
    #: Cap on the tool tip's Cartesian speed [m/s]; None: no cap.
    tool_speed: float | None = TOOL_SPEED
    #: Tool tip distance beyond the flange [m] at which ``tool_speed`` applies (the
    #: work cell's ``tool_offset``: :meth:`for_work_cell`).
    tool_offset: float = ELECTRIC_GRIPPER_TIP
    #: Joint-limit profile the IK keeps to (:data:`.model.LIMIT_PROFILES`).
    limits: str = "robot"

    def __post_init__(self) -> None:
        if not (0 < self.speed_scale <= 1 and self.accel_scale > 0):
            raise ValueError("speed_scale must be in (0, 1] and accel_scale positive")
        if self.tool_speed is not None and not (0 < self.tool_speed < math.inf):
            raise ValueError("tool_speed must be a finite number > 0 (or None)")
        if self.limits not in LIMIT_PROFILES:
            raise ValueError(f"limits must be one of {', '.join(LIMIT_PROFILES)}")
        if self.grasp_time < 0 or self.release_time < 0:
            raise ValueError("grasp_time and release_time must be >= 0")

    @property
    def v_max(self) -> np.ndarray:
        return V_MAX * self.speed_scale

    @property
    def a_max(self) -> np.ndarray:
        return A_MAX * self.accel_scale * self.speed_scale**2

    @property
    def q_limits(self) -> tuple[np.ndarray, np.ndarray]:
        """Lower and upper joint limits of the profile [rad]."""
        return LIMIT_PROFILES[self.limits]

    @property
    def q6_bounds(self) -> tuple[float, float]:
        low, high = self.q_limits
        return float(low[6]), float(high[6])

    def for_work_cell(self, work_cell: WorkCell) -> MotionParams:
        """These parameters with the work cell's tool tip."""
        if self.tool_offset == work_cell.tool_offset_m:
            return self
        return replace(self, tool_offset=work_cell.tool_offset_m)


DEFAULT_PARAMS = MotionParams()


def trapezoid_time(distance: float, v_max: float, a_max: float) -> float:
    """Minimum time to move ``distance`` from rest to rest under speed ``v_max`` and
    acceleration ``a_max`` (trapezoid, or triangle for short moves)."""
    d = abs(float(distance))
    if d == 0.0:
        return 0.0
    if d * a_max <= v_max * v_max:  # never reaches the cruise speed
        return 2.0 * math.sqrt(d / a_max)
    return d / v_max + v_max / a_max


def _path_limits(
    q0: np.ndarray, q1: np.ndarray, params: MotionParams
) -> tuple[np.ndarray, float, float]:
    d = np.asarray(q1, dtype=float) - np.asarray(q0, dtype=float)
    ad = np.abs(d)
    moving = ad > 1e-12
    if not moving.any():
        return d, math.inf, math.inf
    v = float(np.min(params.v_max[moving] / ad[moving]))
    a = float(np.min(params.a_max[moving] / ad[moving]))
    if params.tool_speed is not None:
        gain = _tool_gain(np.asarray(q0, dtype=float).tobytes(), d.tobytes(), params.tool_offset)
        if gain > 0.0:
            v = min(v, params.tool_speed / gain)
    return d, v, a


@lru_cache(maxsize=4096)
def _tool_gain(q0: bytes, d: bytes, tool_offset: float) -> float:
    """Largest tool tip speed [m/s] per unit path speed along the line ``q0 + s d``,
    ``max |J(q(s)) d|`` over :data:`TOOL_SAMPLES` values of s in [0, 1]."""
    arm = tool_arm(tool_offset)
    start, step = np.frombuffer(q0), np.frombuffer(d)
    return max(
        float(np.linalg.norm(arm.jacobian(start + s * step)[:3] @ step))
        for s in np.linspace(0.0, 1.0, TOOL_SAMPLES)
    )


def move_time(q0: np.ndarray, q1: np.ndarray, params: MotionParams = DEFAULT_PARAMS) -> float:
    """Duration [s] of the synchronised joint-space move ``q0 -> q1`` (rest to rest)."""
    _, v, a = _path_limits(q0, q1, params)
    return 0.0 if math.isinf(v) else trapezoid_time(1.0, v, a)


def move_profile(
    q0: np.ndarray, q1: np.ndarray, t: float | np.ndarray, params: MotionParams = DEFAULT_PARAMS
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Positions, velocities and accelerations at time(s) ``t`` of :func:`move_time`'s move.

    Shapes (..., 7). Lets tests and animations check the limits. At rest (``t <= 0`` or
    ``t >= T``) the acceleration is 0: the profile's acceleration steps there, and a point
    with zero velocity and non-zero acceleration makes a controller's quintic overshoot the
    stop (docs/execution.md, "What a controller makes of the points").
    """
    d, v, a = _path_limits(q0, q1, params)
    t = np.asarray(t, dtype=float)[..., None]
    q0 = np.asarray(q0, dtype=float)
    if math.isinf(v):
        zero = np.zeros((*t.shape[:-1], 7))
        return np.broadcast_to(q0, zero.shape).copy(), zero, zero.copy()
    total = trapezoid_time(1.0, v, a)
    ta = min(v / a, total / 2.0)  # acceleration phase
    vp = a * ta  # peak path speed
    tc = np.clip(t, 0.0, total)
    s = np.where(
        tc < ta,
        0.5 * a * tc**2,
        np.where(
            tc <= total - ta, 0.5 * a * ta**2 + vp * (tc - ta), 1.0 - 0.5 * a * (total - tc) ** 2
        ),
    )
    sd = np.where(tc < ta, a * tc, np.where(tc <= total - ta, vp, a * (total - tc)))
    sdd = np.where(tc < ta, a, np.where(tc <= total - ta, 0.0, -a))
    sdd = np.where((t <= 0.0) | (t >= total), 0.0, sdd)
    return q0 + s * d, sd * d, sdd * d


@dataclass(frozen=True)
class PickPlace:
    """One pick-and-place cycle: the key configurations and the time of each step [s]."""

    q_bin_above: np.ndarray
    q_bin: np.ndarray
    q_slot_above: np.ndarray
    q_slot: np.ndarray
    #: Gripper yaw at the slot, degrees from the tray x axis: the part's angle ``theta`` plus
    #: one of ``work_cell.grasp_yaws``.
    slot_yaw: float
    steps: dict[str, float] = field(default_factory=dict)

    @property
    def total(self) -> float:
        return float(sum(self.steps.values()))


def _solve(
    arm: Arm,
    point: np.ndarray,
    yaws: tuple[float, ...],
    q_start: np.ndarray | None,
    what: str,
    q6_bounds: tuple[float, float],
) -> IKSolution:
    """Top-down IK warm-started from ``q_start`` (so it stays on that branch, with the yaw
    needing the least ``right_j6`` travel), falling back to the seeds; raises when
    unreachable."""
    q6 = None if q_start is None else float(q_start[6])
    sol = solve_top_down(arm, point, yaws, q_init=q_start, q6_ref=q6, q6_bounds=q6_bounds)
    if sol is None:
        raise UnreachableError(f"{what} is out of the Sawyer's reach")
    return sol


@lru_cache(maxsize=256)
def _bin_configs(
    work_cell: WorkCell, part_type: str, q6_bounds: tuple[float, float]
) -> tuple[np.ndarray, np.ndarray]:
    """IK above and at the bin of ``part_type`` (cached per work cell, part type and limits)."""
    arm = Arm(work_cell.tool_offset_m)
    grasp = work_cell.bin_point(part_type)
    above = grasp + np.array([0.0, 0.0, work_cell.approach_height / 1000.0])
    where = f"the bin of part type {part_type!r} at {work_cell.bin_xyz(part_type)} mm"
    sol = _solve(arm, above, work_cell.grasp_yaws, None, f"the pose above {where}", q6_bounds)
    q_grasp = _solve(arm, grasp, (sol.yaw_deg,), sol.q, f"the grasp pose in {where}", q6_bounds).q
    return sol.q, q_grasp


def pick_place(
    work_cell: WorkCell,
    part_type: str,
    slot_xy_mm: tuple[float, float] | np.ndarray,
    params: MotionParams = DEFAULT_PARAMS,
    theta: float = 0.0,
) -> PickPlace:
    """Plan one cycle (see the module docstring) for a part laid at angle ``theta`` (deg, from
    the tray x axis); raises :class:`UnreachableError` when the bin or the slot (release or
    approach pose) cannot be reached."""
    arm = Arm(work_cell.tool_offset_m)
    params = params.for_work_cell(work_cell)
    bounds = params.q6_bounds
    q_ba, q_bg = (q.copy() for q in _bin_configs(work_cell, part_type, bounds))
    x, y = float(slot_xy_mm[0]), float(slot_xy_mm[1])
    place = work_cell.tray_to_base(x, y, work_cell.place_height_of(part_type))
    above = place + np.array([0.0, 0.0, work_cell.approach_height / 1000.0])
    where = f"tray slot ({x:g}, {y:g}) mm"
    yaws = tuple(a + float(theta) for a in work_cell.slot_yaws())
    sol = _solve(arm, above, yaws, q_ba, f"the approach pose above {where}", bounds)
    q_sa, yaw = sol.q, sol.yaw_deg
    q_sp = _solve(arm, place, (yaw,), q_sa, where, bounds).q
    down_bin = move_time(q_ba, q_bg, params)
    down_slot = move_time(q_sa, q_sp, params)
    steps = {
        "approach_bin": down_bin,
        "grasp": params.grasp_time,
        "retreat_bin": down_bin,
        "transfer": move_time(q_ba, q_sa, params),
        "approach_slot": down_slot,
        "release": params.release_time,
        "retreat_slot": down_slot,
    }
    if params.return_to_bin:
        steps["return"] = move_time(q_sa, q_ba, params)
    slot_yaw = float(theta) + work_cell.grasp_yaws[yaws.index(yaw)]
    return PickPlace(q_ba, q_bg, q_sa, q_sp, slot_yaw, steps)


def pick_place_time(
    work_cell: WorkCell,
    part_type: str,
    slot_xy_mm: tuple[float, float] | np.ndarray,
    params: MotionParams = DEFAULT_PARAMS,
    theta: float = 0.0,
) -> float:
    """Seconds for one pick at the bin of ``part_type`` and place at tray point (x, y) mm,
    the part at angle ``theta`` (deg)."""
    return pick_place(work_cell, part_type, slot_xy_mm, params, theta).total


def layout_time(
    work_cell: WorkCell, layout: Iterable[Any], params: MotionParams = DEFAULT_PARAMS
) -> float:
    """Robot seconds to kit a layout: the sum of :func:`pick_place_time` over its placements
    (objects with ``type``, ``x``, ``y`` and optionally ``theta``, e.g.
    :class:`bilevel_kit.plan.Placement`)."""
    return float(
        sum(
            pick_place_time(
                work_cell, str(p.type), (float(p.x), float(p.y)), params, getattr(p, "theta", 0.0)
            )
            for p in layout
        )
    )


def tray_average_time(
    work_cell: WorkCell,
    part_type: str,
    width: float,
    height: float,
    resolution: float = 50.0,
    params: MotionParams = DEFAULT_PARAMS,
) -> float:
    """Mean :func:`pick_place_time` over the reachable cell centres of a ``width`` x
    ``height`` mm tray at ``resolution`` mm: a layout-free robot time per part, for when the
    placement is not known yet. Raises :class:`UnreachableError` when no cell is reachable."""
    from .reach import build_reach_map, ensure_placeable

    reach_map = ensure_placeable(
        build_reach_map(work_cell, width, height, resolution), f"a part of type {part_type!r}"
    )
    times = [
        pick_place_time(
            work_cell, part_type, (float(reach_map.xs[c]), float(reach_map.ys[r])), params
        )
        for r, c in np.argwhere(reach_map.reachable)
    ]
    return float(np.mean(times))
