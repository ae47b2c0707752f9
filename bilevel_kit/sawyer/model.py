"""The project's own kinematic model of the Rethink Sawyer arm (7 revolute joints).

The numbers below are the published kinematic parameters of the arm (joint origins, axes,
position and velocity limits, the fixed ``right_hand`` frame) as given in Rethink Robotics'
``sawyer_base.urdf.xacro`` (Apache-2.0, non-gazebo branch). The model is built in code with
Pinocchio, without meshes or inertias, because the toolkit only needs kinematics. The head
joint is left out, so ``q`` has exactly the 7 arm joints ``right_j0 .. right_j6``.

Frames (all positions in metres, in the robot ``base`` frame, which equals
``right_arm_base_link``):

* ``right_hand``: the arm's flange frame; its z axis leaves the flange.
* ``tool``: the tool tip, ``tool_offset`` metres along the ``right_hand`` z axis. With the
  Rethink electric gripper (connector plate, standard narrow fingers) the tip is
  :data:`ELECTRIC_GRIPPER_TIP` = 0.13562 m out.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import lru_cache
from typing import TYPE_CHECKING, Any

import numpy as np

if TYPE_CHECKING:  # pragma: no cover - typing only
    import pinocchio as pin

#: Arm joint names, in configuration order.
JOINT_NAMES: tuple[str, ...] = tuple(f"right_j{i}" for i in range(7))

_HALF_PI = 1.57079632679  # the value the upstream description writes for pi/2

#: Per joint: (child link, origin xyz [m], origin rpy [rad], lower, upper [rad],
#: velocity limit [rad/s], effort limit [Nm]). Every axis is the child frame's z axis.
JOINT_TABLE: tuple[
    tuple[str, tuple[float, float, float], tuple[float, float, float], float, float, float, float],
    ...,
] = (
    ("right_l0", (0.0, 0.0, 0.08), (0.0, 0.0, 0.0), -3.0503, 3.0503, 1.74, 80.0),
    ("right_l1", (0.081, 0.05, 0.237), (-_HALF_PI, _HALF_PI, 0.0), -3.8095, 2.2736, 1.328, 80.0),
    ("right_l2", (0.0, -0.14, 0.1425), (_HALF_PI, 0.0, 0.0), -3.0426, 3.0426, 1.957, 40.0),
    ("right_l3", (0.0, -0.042, 0.26), (-_HALF_PI, 0.0, 0.0), -3.0439, 3.0439, 1.957, 40.0),
    ("right_l4", (0.0, -0.125, -0.1265), (_HALF_PI, 0.0, 0.0), -2.9761, 2.9761, 3.485, 9.0),
    ("right_l5", (0.0, 0.031, 0.275), (-_HALF_PI, 0.0, 0.0), -2.9761, 2.9761, 3.485, 9.0),
    ("right_l6", (0.0, -0.11, 0.1053), (-_HALF_PI, -0.17453, 3.1416), -4.7124, 4.7124, 4.545, 9.0),
)

#: Offset of ``right_hand`` from the ``right_l6`` origin along their common z axis [m].
HAND_FLANGE = 0.0245
#: Fixed ``right_l6 -> right_hand`` transform: xyz [m] and rpy [rad].
HAND_XYZ: tuple[float, float, float] = (0.0, 0.0, HAND_FLANGE)
HAND_RPY: tuple[float, float, float] = (0.0, 0.0, 1.570796)

#: Tip of the Rethink electric gripper along the ``right_hand`` z axis [m]: -0.005 (end of arm)
#: + 0.0151 (connector plate) + 0.04552 (gripper base) + 0.075 (standard narrow finger) + 0.005.
ELECTRIC_GRIPPER_TIP = 0.13562

Q_LOWER = np.array([row[3] for row in JOINT_TABLE])
Q_UPPER = np.array([row[4] for row in JOINT_TABLE])
#: Joint-limit profiles (lower, upper) [rad]: ``robot`` is the real arm's description;
#: ``gazebo`` is its simulator variant (``gazebo:=true`` in Rethink's ``sawyer_base.urdf.xacro``),
#: which limits ``right_j6`` to +-3.14 rad instead of +-4.7124 (docs/execution.md).
LIMIT_PROFILES: dict[str, tuple[np.ndarray, np.ndarray]] = {
    "robot": (Q_LOWER, Q_UPPER),
    "gazebo": (np.r_[Q_LOWER[:6], -3.14], np.r_[Q_UPPER[:6], 3.14]),
}
#: Joint velocity limits [rad/s].
V_MAX = np.array([row[5] for row in JOINT_TABLE])
EFFORT_MAX = np.array([row[6] for row in JOINT_TABLE])

#: Named poses of the arm (Rethink's ``named_poses.yaml``).
Q_NEUTRAL = np.array([0.0, -1.18, 0.0, 2.18, 0.0, 0.57, 3.3161])
Q_SHIPPING = np.array([0.0, -1.57, 0.0, 2.79, 0.0, -2.79, 3.3161])

#: Shoulder height: the ``right_j1`` origin lies on a circle of radius :data:`SHOULDER_RADIUS`
#: around the ``right_j0`` axis at this height [m].
SHOULDER_Z = 0.08 + 0.237
SHOULDER_RADIUS = math.hypot(0.081, 0.05)

#: Largest distance from the ``right_j1`` origin to the ``right_hand`` origin over all joint
#: angles [m], plus 5 mm of margin. Found by bounded multi-start optimisation over right_j2..5
#: (300 starts; best 1.0357 m); the link offsets alone bound it by 1.0945 m.
HAND_REACH = 1.0357 + 0.005
#: The same for the ``right_l6`` origin (best 1.0136 m), which is 0.0245 m above the hand
#: origin when the hand points straight down: the bound used for top-down grasps.
WRIST_REACH = 1.0136 + 0.005
#: The same for the ``right_l5`` origin (best 0.8699 m). When the hand points straight down,
#: that origin lies on a horizontal circle of radius :data:`L5_RADIUS` centred
#: :data:`L5_RISE` above the ``right_l6`` origin (from the ``right_j6`` joint origin).
L5_REACH = 0.8699 + 0.005
L5_RADIUS = 0.1053
L5_RISE = 0.11


def within_limits(q: np.ndarray, tol: float = 1e-9) -> bool:
    """True when every joint lies in its position range (within ``tol`` rad)."""
    q = np.asarray(q, dtype=float)
    return bool(((q >= Q_LOWER - tol) & (q <= Q_UPPER + tol)).all())


def _se3(xyz: tuple[float, float, float], rpy: tuple[float, float, float]) -> pin.SE3:
    import pinocchio as pin

    return pin.SE3(pin.rpy.rpyToMatrix(*rpy), np.array(xyz, dtype=float))


@lru_cache(maxsize=16)
def build_model(tool_offset: float = 0.0) -> pin.Model:
    """The 7-dof arm as a Pinocchio model with frames ``right_l0..6``, ``right_hand``, ``tool``.

    ``tool_offset`` [m] places the ``tool`` frame along the ``right_hand`` z axis. The model is
    cached per offset; treat it as read-only.
    """
    import pinocchio as pin

    model = pin.Model()
    model.name = "sawyer_arm"
    parent_joint = 0
    parent_frame = model.addFrame(
        pin.Frame("base", 0, 0, pin.SE3.Identity(), pin.FrameType.BODY), False
    )
    for name, row in zip(JOINT_NAMES, JOINT_TABLE, strict=True):
        link, xyz, rpy, lower, upper, vel, effort = row
        jid = model.addJoint(
            parent_joint,
            pin.JointModelRZ(),
            _se3(xyz, rpy),
            name,
            np.array([effort]),
            np.array([vel]),
            np.array([lower]),
            np.array([upper]),
        )
        model.appendBodyToJoint(jid, pin.Inertia.Zero(), pin.SE3.Identity())
        joint_frame = model.addFrame(
            pin.Frame(name, jid, parent_frame, pin.SE3.Identity(), pin.FrameType.JOINT), False
        )
        parent_frame = model.addBodyFrame(link, jid, pin.SE3.Identity(), joint_frame)
        parent_joint = jid
    hand = model.addFrame(
        pin.Frame(
            "right_hand",
            parent_joint,
            parent_frame,
            _se3(HAND_XYZ, HAND_RPY),
            pin.FrameType.OP_FRAME,
        ),
        False,
    )
    tool_placement = _se3(HAND_XYZ, HAND_RPY) * pin.SE3(
        np.eye(3), np.array([0.0, 0.0, tool_offset])
    )
    model.addFrame(
        pin.Frame("tool", parent_joint, hand, tool_placement, pin.FrameType.OP_FRAME), False
    )
    return model


@dataclass
class Arm:
    """A Sawyer model with its own Pinocchio data: one per thread, reused across calls.

    Every method takes ``q`` (7 joint angles, rad) and works in the ``base`` frame (metres).
    """

    tool_offset: float = 0.0

    def __post_init__(self) -> None:
        import pinocchio as pin

        self.model: Any = build_model(float(self.tool_offset))
        self.data: Any = self.model.createData()
        self.hand_id: int = self.model.getFrameId("right_hand")
        self.tool_id: int = self.model.getFrameId("tool")
        self._pin = pin

    def _frame(self, frame: str) -> int:
        if frame == "tool":
            return self.tool_id
        if frame == "right_hand":
            return self.hand_id
        return self.model.getFrameId(frame)

    def placement(self, q: np.ndarray, frame: str = "tool") -> pin.SE3:
        """Pose of ``frame`` (``"tool"``, ``"right_hand"`` or any link name) at ``q``."""
        pin = self._pin
        fid = self._frame(frame)
        pin.forwardKinematics(self.model, self.data, np.asarray(q, dtype=float))
        return pin.updateFramePlacement(self.model, self.data, fid).copy()

    def fk(self, q: np.ndarray, frame: str = "tool") -> np.ndarray:
        """Homogeneous 4 x 4 transform of ``frame`` at ``q``."""
        return self.placement(q, frame).homogeneous

    def position(self, q: np.ndarray, frame: str = "tool") -> np.ndarray:
        """Position (3,) of ``frame`` at ``q`` [m]."""
        return self.placement(q, frame).translation.copy()

    def jacobian(self, q: np.ndarray, frame: str = "tool") -> np.ndarray:
        """6 x 7 Jacobian of ``frame`` (linear rows first) in the base-aligned frame."""
        pin = self._pin
        q = np.asarray(q, dtype=float)
        pin.forwardKinematics(self.model, self.data, q)  # the frame's rotation must be current
        return pin.computeFrameJacobian(
            self.model, self.data, q, self._frame(frame), pin.LOCAL_WORLD_ALIGNED
        ).copy()

    def link_transforms(self, q: np.ndarray) -> list[tuple[np.ndarray, np.ndarray]]:
        """Per :data:`LINK_TREE` entry, the child's pose in its parent: translation [m] and
        quaternion (x, y, z, w), for ``/tf``."""
        pin = self._pin
        pin.forwardKinematics(self.model, self.data, np.asarray(q, dtype=float))
        poses = [pin.SE3.Identity()]
        poses += [self.data.liMi[j] for j in range(1, self.model.njoints)]
        poses.append(self.model.frames[self._frame("right_hand")].placement)
        return [(p.translation.copy(), pin.Quaternion(p.rotation).coeffs().copy()) for p in poses]

    def manipulability(self, q: np.ndarray, frame: str = "tool") -> float:
        """Yoshikawa's measure sqrt(det(J J^T)) of the 6 x 7 Jacobian: 0 at singularities."""
        J = self.jacobian(q, frame)
        return math.sqrt(max(float(np.linalg.det(J @ J.T)), 0.0))


#: Parent and child frames of the arm's links as Rethink's description names them, in the
#: order of :meth:`Arm.link_transforms`: ``right_arm_base_link`` is the model's ``base``.
LINK_TREE: tuple[tuple[str, str], ...] = (
    ("base", "right_arm_base_link"),
    *zip(
        ("right_arm_base_link", *(row[0] for row in JOINT_TABLE[:-1])),
        (row[0] for row in JOINT_TABLE),
        strict=True,
    ),
    (JOINT_TABLE[-1][0], "right_hand"),
)


@lru_cache(maxsize=16)
def tool_arm(tool_offset: float) -> Arm:
    """A shared :class:`Arm` with the tool tip ``tool_offset`` metres out (not thread-safe)."""
    return Arm(tool_offset)


def fk_hand(q: np.ndarray) -> np.ndarray:
    """4 x 4 pose of ``right_hand`` in the base frame at ``q`` (convenience, not thread-safe)."""
    return tool_arm(0.0).fk(q, "right_hand")


def fk_tool(q: np.ndarray, tool_offset: float = 0.0) -> np.ndarray:
    """4 x 4 pose of the tool tip ``tool_offset`` metres along the hand z axis at ``q``."""
    return tool_arm(float(tool_offset)).fk(q, "tool")
