"""MoveIt's ``moveit_msgs/DisplayTrajectory`` in the bags, so RViz's MoveIt Trajectory display
plays a kit's motion (docs/execution.md, "The bags").

``rosbags`` ships no MoveIt definitions, and a ROS 1 bag's connection carries the full
definition and its MD5, which RViz checks against its own. The definitions are data files
under ``msg/`` (moveit_msgs and object_recognition_msgs, BSD-licensed, see
``msg/LICENSE``): the ROS 1 Noetic texts, whose MD5s (:data:`DISPLAY_MD5`) equal the published
ones. The same field lists are registered in the ROS 2 (Humble) typestore, whose own
``std_msgs``, ``sensor_msgs``, ``trajectory_msgs`` and ``shape_msgs`` they then use.
"""

from __future__ import annotations

from functools import cache
from pathlib import Path
from typing import Any

import numpy as np

from .model import JOINT_NAMES

#: Folder of the ``.msg`` data files, one sub-folder per package.
MSG_DIR = Path(__file__).parent / "msg"
#: MoveIt's default topic for planned paths (the ``move_group`` node's private topic).
DISPLAY_TOPIC = "/move_group/display_planned_path"
DISPLAY_TYPE = "moveit_msgs/msg/DisplayTrajectory"
#: ROS 1 MD5 of Noetic's ``moveit_msgs/DisplayTrajectory`` (as roscpp's message traits report
#: it); Kinetic's was ``c3c039261ab9e8a11457dac56b6316c8`` (CollisionObject had no ``pose``
#: and no subframes then).
DISPLAY_MD5 = "41936b74e168ba754279ae683ce3f121"
#: ``model_id``: the robot's name in Rethink's description (RViz warns on a mismatch).
MODEL_ID = "sawyer"


@cache
def _definitions() -> tuple[tuple[str, str], ...]:
    """``(type name, .msg text)`` of every data file, e.g. ``moveit_msgs/msg/RobotState``."""
    return tuple(
        (f"{path.parent.name}/msg/{path.stem}", path.read_text(encoding="utf-8"))
        for path in sorted(MSG_DIR.glob("*/*.msg"))
    )


def register(store: Any) -> None:
    """Add the MoveIt types to a ``rosbags`` typestore (once)."""
    from rosbags.typesys import get_types_from_msg

    if DISPLAY_TYPE in store.types:
        return
    types: dict[str, Any] = {}
    for name, text in _definitions():
        types.update(get_types_from_msg(text, name))
    store.register(types)


def display_trajectory(
    types: dict[str, Any], header: Any, trajectory: Any, q0: np.ndarray, qd0: np.ndarray
) -> Any:
    """One kit's ``DisplayTrajectory``: the kit's ``JointTrajectory`` message as the only
    ``RobotTrajectory``, and its first joint state (``header``'s stamp) as the start state."""
    empty = np.zeros(0, dtype=np.float64)
    multi_dof = types["trajectory_msgs/msg/MultiDOFJointTrajectory"](
        header=header, joint_names=[], points=[]
    )
    robot_trajectory = types["moveit_msgs/msg/RobotTrajectory"](
        joint_trajectory=trajectory, multi_dof_joint_trajectory=multi_dof
    )
    joint_state = types["sensor_msgs/msg/JointState"](
        header=header,
        name=list(JOINT_NAMES),
        position=np.asarray(q0, dtype=np.float64),
        velocity=np.asarray(qd0, dtype=np.float64),
        effort=empty,
    )
    multi_dof_state = types["sensor_msgs/msg/MultiDOFJointState"](
        header=header, joint_names=[], transforms=[], twist=[], wrench=[]
    )
    start = types["moveit_msgs/msg/RobotState"](
        joint_state=joint_state,
        multi_dof_joint_state=multi_dof_state,
        attached_collision_objects=[],
        is_diff=False,
    )
    return types[DISPLAY_TYPE](
        model_id=MODEL_ID, trajectory=[robot_trajectory], trajectory_start=start
    )
