"""Inverse kinematics of the Sawyer arm for top-down grasps (closed-loop IK, CLIK).

Top-down grasps (:func:`solve_top_down`) constrain 5 of the tool's 6 degrees of freedom: the
tool tip position and its z axis pointing straight down. The yaw about that axis is left
free while solving, because the tool tip lies on the ``right_j6`` axis and that joint spans
540 deg: any top-down solution turns into one for any yaw by moving ``right_j6`` alone
(:func:`with_yaw`). So reachability does not depend on the yaw, and after convergence the
allowed yaw needing the least ``right_j6`` travel is chosen.

Solver (both the 5-D top-down form and the 6-D :func:`clik` for full poses): damped least
squares, ``dq = J^T (J J^T + lambda^2 I)^-1 e``, the step capped at :data:`MAX_STEP` rad, and
``q`` projected onto the joint limits (clamped) after every step, so every returned
configuration satisfies them. A run stops when converged, after ``max_iter`` iterations, or
when 15 iterations brought less than 5 % progress (a limit or the end of the reach).

Success tolerances (checked on the returned configuration): tool position within
:data:`POS_TOL` = 1 mm of the target and orientation within :data:`ROT_TOL` = 1e-2 rad
(angle of the residual rotation). Runs iterate to 10x tighter than that, so a solution
returned is normally accurate to about 0.1 mm and 1e-3 rad.

Seeds, in order (deterministic): the caller's warm start ``q_init`` if any; the neutral pose;
the neutral pose turned about ``right_j0`` towards the target; then ``n_seeds`` uniform random
configurations drawn from ``numpy.random.default_rng(seed)`` (inside 90 % of each joint's
range). The first seed that converges wins.

Before any iteration, a target farther from the shoulder than the stretched arm is rejected
at once (:func:`out_of_reach`), which makes points beyond the reach cost microseconds.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Iterator, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from .model import (
    HAND_FLANGE,
    HAND_REACH,
    L5_RADIUS,
    L5_REACH,
    L5_RISE,
    Q_LOWER,
    Q_NEUTRAL,
    Q_UPPER,
    SHOULDER_RADIUS,
    SHOULDER_Z,
    WRIST_REACH,
    Arm,
)

#: Success tolerance on the tool position [m].
POS_TOL = 1e-3
#: Success tolerance on the tool orientation (angle of the residual rotation) [rad].
ROT_TOL = 1e-2
#: Damping of the least-squares step (lambda, in the units of the twist error).
DAMPING = 1e-3
#: Largest joint step per iteration [rad] (norm of dq), which keeps far seeds stable.
MAX_STEP = 0.5
#: Default iteration budget of one CLIK run.
MAX_ITER = 150
#: Default number of random seeds after the warm start and the neutral seeds.
N_SEEDS = 6

_NEUTRAL_AZIMUTH = math.atan2(0.1603, 0.4496)  # of right_hand at the neutral pose
_EYE6 = np.eye(6)
_EYE5 = np.eye(5)


@dataclass(frozen=True)
class IKSolution:
    """A converged IK solution: configuration, tool yaw (deg, base frame), position error
    [m] and tilt of the tool z axis from vertical [rad]."""

    q: np.ndarray
    yaw_deg: float
    pos_err: float
    tilt: float


def top_down_rotation(yaw_rad: float) -> np.ndarray:
    """Rotation whose z axis points down (-z of the base) and whose x axis has heading
    ``yaw_rad`` in the base xy plane: ``Rz(yaw) Rx(pi)``."""
    c, s = math.cos(yaw_rad), math.sin(yaw_rad)
    return np.array([[c, s, 0.0], [s, -c, 0.0], [0.0, 0.0, -1.0]])


def out_of_reach(point: np.ndarray, tool_offset: float, tool_down: bool = True) -> bool:
    """Quick necessary test: True when no configuration can put the tool at ``point`` [m].

    Compares distances from the circle that the ``right_j1`` origin sweeps around the
    ``right_j0`` axis with the arm's largest stretch (:mod:`.model`). With a top-down tool, the
    ``right_l6`` origin sits exactly ``tool_offset + 0.0245`` m above the tool point
    (:data:`WRIST_REACH` applies) and the ``right_l5`` origin on a known horizontal circle
    above it (:data:`L5_REACH` applies); otherwise the hand is within ``tool_offset`` of the
    point and :data:`HAND_REACH` applies.
    """
    p = np.asarray(point, dtype=float)
    rho = math.hypot(p[0], p[1])
    if not tool_down:
        reach = HAND_REACH + abs(tool_offset)
        return math.hypot(rho - SHOULDER_RADIUS, p[2] - SHOULDER_Z) > reach
    z6 = p[2] + tool_offset + HAND_FLANGE
    if math.hypot(rho - SHOULDER_RADIUS, z6 - SHOULDER_Z) > WRIST_REACH:
        return True
    gap = max(0.0, rho - SHOULDER_RADIUS - L5_RADIUS)
    return math.hypot(gap, z6 + L5_RISE - SHOULDER_Z) > L5_REACH


def clik(
    arm: Arm,
    target: Any,
    q0: np.ndarray,
    max_iter: int = MAX_ITER,
    damping: float = DAMPING,
) -> tuple[np.ndarray, float, float]:
    """One 6-D damped-least-squares CLIK run from ``q0`` to the tool pose ``target`` (pin.SE3).

    The error is the SE(3) log ``log(T(q)^-1 T*)`` with the tool-frame Jacobian. Returns
    ``(q, position error [m], rotation error [rad])`` of the last iterate, within limits.
    """
    pin = arm._pin
    model, data, fid = arm.model, arm.data, arm.tool_id
    q = np.minimum(np.maximum(np.asarray(q0, dtype=float), Q_LOWER), Q_UPPER)
    eye = _EYE6 * (damping * damping)
    p_target = target.translation
    history: list[float] = []
    pos_err = rot_err = math.inf
    for it in range(max_iter + 1):
        pin.forwardKinematics(model, data, q)
        current = pin.updateFramePlacement(model, data, fid)
        err = pin.log6(current.actInv(target)).vector
        pos_err = float(np.linalg.norm(current.translation - p_target))
        rot_err = float(np.linalg.norm(err[3:]))
        if _stop(it, max_iter, pos_err, rot_err, history):
            break
        J = pin.computeFrameJacobian(model, data, q, fid, pin.LOCAL)
        q = _step(q, J, err, eye)
    return q, pos_err, rot_err


def clik_down(
    arm: Arm,
    point: np.ndarray,
    q0: np.ndarray,
    max_iter: int = MAX_ITER,
    damping: float = DAMPING,
) -> tuple[np.ndarray, float, float]:
    """One 5-D CLIK run: tool tip to ``point`` [m], tool z axis to -z of the base, yaw free.

    Rows: the 3 linear rows of the base-aligned Jacobian, and the angular rows projected on
    the tool's x and y axes (rotation about the tool z axis is unconstrained). Returns
    ``(q, position error [m], tilt of the tool z axis from vertical [rad])``.
    """
    pin = arm._pin
    model, data, fid = arm.model, arm.data, arm.tool_id
    q = np.minimum(np.maximum(np.asarray(q0, dtype=float), Q_LOWER), Q_UPPER)
    eye = _EYE5 * (damping * damping)
    p_target = np.asarray(point, dtype=float)
    history: list[float] = []
    err = np.empty(5)
    A = np.empty((5, 7))
    pos_err = tilt = math.inf
    for it in range(max_iter + 1):
        pin.forwardKinematics(model, data, q)
        current = pin.updateFramePlacement(model, data, fid)
        R = current.rotation
        err[:3] = p_target - current.translation
        # w = z x (0, 0, -1): rotation axis * sin(tilt) that brings the tool z axis down.
        wx, wy = -R[1, 2], R[0, 2]
        pos_err = float(math.sqrt(err[0] ** 2 + err[1] ** 2 + err[2] ** 2))
        tilt = math.atan2(math.hypot(wx, wy), -R[2, 2])
        if _stop(it, max_iter, pos_err, tilt, history):
            break
        J = pin.computeFrameJacobian(model, data, q, fid, pin.LOCAL_WORLD_ALIGNED)
        A[:3] = J[:3]
        A[3] = R[:, 0] @ J[3:]
        A[4] = R[:, 1] @ J[3:]
        err[3] = R[0, 0] * wx + R[1, 0] * wy
        err[4] = R[0, 1] * wx + R[1, 1] * wy
        q = _step(q, A, err, eye)
    return q, pos_err, tilt


def _stop(it: int, max_iter: int, pos_err: float, rot_err: float, history: list[float]) -> bool:
    """Converged (10x tighter than the success tolerances), out of budget, or stalled."""
    if (pos_err < 0.1 * POS_TOL and rot_err < 0.1 * ROT_TOL) or it == max_iter:
        return True
    total = pos_err + 0.1 * rot_err
    history.append(total)
    return it >= 15 and total > 0.95 * history[it - 15] and total > 1e-3


def _step(q: np.ndarray, J: np.ndarray, err: np.ndarray, eye: np.ndarray) -> np.ndarray:
    """Damped least-squares step, capped at MAX_STEP and clamped to the joint limits."""
    dq = J.T @ np.linalg.solve(J @ J.T + eye, err)
    n = float(np.linalg.norm(dq))
    if n > MAX_STEP:
        dq *= MAX_STEP / n
    q = q + dq
    return np.minimum(np.maximum(q, Q_LOWER, out=q), Q_UPPER, out=q)


def converged(pos_err: float, rot_err: float) -> bool:
    """The documented success test: 1 mm and 1e-2 rad."""
    return pos_err <= POS_TOL and rot_err <= ROT_TOL


def seeds(
    point: np.ndarray | None = None,
    q_init: np.ndarray | None = None,
    n_seeds: int = N_SEEDS,
    seed: int = 0,
) -> Iterator[np.ndarray]:
    """The deterministic seed sequence described in the module docstring (lazy, so the
    random seeds cost nothing when an early seed converges)."""
    if q_init is not None:
        yield np.asarray(q_init, dtype=float)
    yield Q_NEUTRAL.copy()
    if point is not None:
        turned = Q_NEUTRAL.copy()
        turned[0] = math.atan2(point[1], point[0]) - _NEUTRAL_AZIMUTH
        yield np.clip(turned, Q_LOWER, Q_UPPER)
    if n_seeds > 0:
        rng = np.random.default_rng(seed)
        mid, half = (Q_LOWER + Q_UPPER) / 2, 0.45 * (Q_UPPER - Q_LOWER)
        yield from rng.uniform(mid - half, mid + half, size=(n_seeds, 7))


def solve_pose(
    arm: Arm,
    target: Any,
    q_init: np.ndarray | None = None,
    n_seeds: int = N_SEEDS,
    seed: int = 0,
    max_iter: int = MAX_ITER,
) -> np.ndarray | None:
    """IK of a full tool pose (``pin.SE3`` or 4 x 4 array) over the seed list; None if no
    seed converges."""
    import pinocchio as pin

    if not isinstance(target, pin.SE3):
        target = pin.SE3(np.asarray(target, dtype=float))
    if out_of_reach(target.translation, arm.tool_offset, tool_down=False):
        return None
    for q0 in seeds(target.translation, q_init, n_seeds, seed):
        q, pe, re = clik(arm, target, q0, max_iter)
        if converged(pe, re):
            return q
    return None


def tool_yaw(arm: Arm, q: np.ndarray) -> float:
    """Heading (deg, base frame) of the tool x axis at ``q``."""
    R = arm.placement(q).rotation
    return math.degrees(math.atan2(R[1, 0], R[0, 0]))


def solve_top_down(
    arm: Arm,
    point: Sequence[float] | np.ndarray,
    yaws_deg: Iterable[float] = (0.0,),
    q_init: np.ndarray | None = None,
    n_seeds: int = N_SEEDS,
    seed: int = 0,
    max_iter: int = MAX_ITER,
    q6_ref: float | None = None,
    q6_bounds: tuple[float, float] | None = None,
) -> IKSolution | None:
    """Top-down grasp IK: tool tip at ``point`` [m, base frame], tool z down, tool x heading
    one of ``yaws_deg`` (degrees, base frame). None when unreachable.

    Solves the 5-D problem (:func:`clik_down`) from the seeds, then picks the allowed yaw whose
    ``right_j6`` value lies closest to ``q6_ref`` (default: the converged ``right_j6``); ties go
    to the earlier yaw in ``yaws_deg``. ``q6_bounds``: tighter ``right_j6`` limits (a joint-limit
    profile, :data:`.model.LIMIT_PROFILES`); the tool's position does not depend on that joint.
    """
    p = np.asarray(point, dtype=float)
    yaws = [float(y) for y in yaws_deg]
    if not yaws:
        raise ValueError("at least one gripper yaw angle is needed")
    if out_of_reach(p, arm.tool_offset, tool_down=True):
        return None
    for q0 in seeds(p, q_init, n_seeds, seed):
        q, pe, tilt = clik_down(arm, p, q0, max_iter)
        if not converged(pe, tilt):
            continue
        now = tool_yaw(arm, q)
        ref = q[6] if q6_ref is None else q6_ref
        best: tuple[float, np.ndarray, float] | None = None
        for yaw in yaws:
            qy = with_yaw(q, now, yaw, ref, q6_bounds)
            if qy is not None and (best is None or abs(qy[6] - ref) < best[0] - 1e-9):
                best = (abs(qy[6] - ref), qy, yaw)
        if best is None:  # pragma: no cover - right_j6 spans more than a full turn
            continue
        return IKSolution(best[1], best[2], pe, tilt)
    return None


def with_yaw(
    q: np.ndarray,
    yaw_from_deg: float,
    yaw_to_deg: float,
    q6_ref: float | None = None,
    q6_bounds: tuple[float, float] | None = None,
) -> np.ndarray | None:
    """Turn a top-down solution from one tool yaw to another by moving ``right_j6`` only.

    Raising ``right_j6`` by d turns a downward tool by -d about the base z axis. Among the
    2*pi-equivalent values within the joint limits, the one closest to ``q6_ref`` (default:
    the current ``right_j6``) is taken; None if none fits (cannot happen for the Sawyer's
    own limits). ``q6_bounds`` replaces those limits.
    """
    low, high = (Q_LOWER[6], Q_UPPER[6]) if q6_bounds is None else q6_bounds
    q = np.array(q, dtype=float)
    ref = q[6] if q6_ref is None else q6_ref
    base = q[6] - math.radians(yaw_to_deg - yaw_from_deg)
    k = round((ref - base) / (2 * math.pi))
    options = [base + 2 * math.pi * m for m in (k - 1, k, k + 1)]
    options = [v for v in options if low <= v <= high]
    if not options:
        return None
    q[6] = min(options, key=lambda v: abs(v - ref))
    return q


def ik_top_down(
    point: Sequence[float] | np.ndarray,
    yaw_deg: float | Iterable[float] = 0.0,
    tool_offset: float = 0.0,
    q_init: np.ndarray | None = None,
    n_seeds: int = N_SEEDS,
    seed: int = 0,
) -> np.ndarray | None:
    """Convenience form of :func:`solve_top_down`: the configuration, or None if unreachable.

    With several yaws, the one nearest to the solver's ``right_j6`` is used.
    ``tool_offset`` is in metres along the hand z axis, ``point`` in metres in the base frame.
    """
    yaws = (float(yaw_deg),) if isinstance(yaw_deg, int | float) else tuple(yaw_deg)
    sol = solve_top_down(Arm(tool_offset), point, yaws, q_init, n_seeds, seed)
    return None if sol is None else sol.q
