"""What a joint trajectory controller makes of a trajectory's points (docs/execution.md).

ros2_control's ``joint_trajectory_controller`` interpolates between consecutive points that
carry positions, velocities and accelerations with a quintic polynomial per joint, matching
position, velocity and acceleration at both ends of the segment (its documentation, "Trajectory
Representation": "Quintic spline"). :func:`quintic` is that polynomial;
:func:`dwell_deviation` measures how far the tool moves while the gripper closes or opens,
when the controller runs the trajectory's points.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from .model import Arm

if TYPE_CHECKING:  # pragma: no cover - typing only
    from .trajectory import KitTrajectory

#: Evaluation points per dwell (both ends included).
DWELL_SAMPLES = 51


def quintic(
    times: np.ndarray,
    q: np.ndarray,
    qd: np.ndarray,
    qdd: np.ndarray,
    t: np.ndarray,
) -> np.ndarray:
    """Positions at times ``t`` (shape (n,)) of the quintic spline through the points
    ``(times, q, qd, qdd)`` (shapes (m,), (m, j) x 3): per segment, the polynomial matching
    position, velocity and acceleration at both ends. Shape (n, j)."""
    t = np.clip(np.asarray(t, dtype=float), times[0], times[-1])
    i = np.clip(np.searchsorted(times, t, side="right") - 1, 0, len(times) - 2)
    h = (times[i + 1] - times[i])[:, None]
    p0, v0, a0 = q[i], qd[i], qdd[i]
    p1, v1, a1 = q[i + 1], qd[i + 1], qdd[i + 1]
    dp = p1 - p0
    c3 = (20 * dp - (8 * v1 + 12 * v0) * h - (3 * a0 - a1) * h**2) / (2 * h**3)
    c4 = (-30 * dp + (14 * v1 + 16 * v0) * h + (3 * a0 - 2 * a1) * h**2) / (2 * h**4)
    c5 = (12 * dp - 6 * (v1 + v0) * h - (a0 - a1) * h**2) / (2 * h**5)
    s = (t - times[i])[:, None]
    return p0 + s * (v0 + s * (a0 / 2 + s * (c3 + s * (c4 + s * c5))))


@dataclass(frozen=True)
class DwellDeviation:
    """The largest tool displacement [m] during a dwell, and where."""

    deviation: float
    kit: int
    part: str
    step: str


def dwell_deviation(
    kits: tuple[KitTrajectory, ...] | list[KitTrajectory],
    tool_offset_m: float,
    *,
    times: list[np.ndarray] | None = None,
    points: list[tuple[np.ndarray, np.ndarray, np.ndarray]] | None = None,
) -> DwellDeviation:
    """Largest distance of the tool tip from its pose at the dwell's start, over every grasp
    and release of ``kits``, with the controller's quintic through the points. ``times`` and
    ``points`` (per kit: positions, velocities, accelerations) override the kits' own samples,
    e.g. with the points read back from a bag."""
    from .trajectory import DWELLS

    arm = Arm(tool_offset_m)
    worst = DwellDeviation(0.0, 0, "", "")
    for n, kt in enumerate(kits):
        t_pts = kt.times if times is None else times[n]
        q, qd, qdd = (
            (kt.positions, kt.velocities, kt.accelerations) if points is None else points[n]
        )
        for seg in kt.segments:
            if seg.name not in DWELLS:
                continue
            t = np.linspace(seg.start, seg.end, DWELL_SAMPLES)
            tool = np.array([arm.position(c) for c in quintic(t_pts, q, qd, qdd, t)])
            d = float(np.linalg.norm(tool - arm.position(seg.q0), axis=1).max())
            if d > worst.deviation:
                worst = DwellDeviation(d, kt.kit, seg.part, seg.name)
    return worst
