"""ROS 1 and ROS 2 bags of an execution, with standard message types (docs/execution.md).

Written and read with the pure-Python ``rosbags`` package, so no ROS installation is needed.
Topics (:data:`TOPICS`):

* ``/bilevel_kit/arm/joint_trajectory``: ``trajectory_msgs/JointTrajectory``, one message per
  kit, recorded when the kit's arm motion starts. Joint names ``right_j0`` .. ``right_j6``;
  every point has positions, velocities and accelerations and its ``time_from_start``.
  ``header.stamp`` is zero, ROS's "start when received", so a replayed bag drives a trajectory
  controller with the plan's timing.
* ``/move_group/display_planned_path``: ``moveit_msgs/DisplayTrajectory`` (:mod:`.moveit`),
  one per kit at the same time as its trajectory: model ``sawyer``, the kit's
  ``JointTrajectory`` and its first joint state as ``trajectory_start``, for RViz's MoveIt
  Trajectory display.
* ``/bilevel_kit/gripper/command``: ``sensor_msgs/JointState`` of the electric gripper's
  two finger joints, one message per command (close at a grasp, open at a release), stamped
  with the command's time. Positions are the URDF's finger limits: open
  (0.020833, -0.020833) m, closed (0, 0); a real gripper stops on the part.
* ``/joint_states``: ``sensor_msgs/JointState`` of ``right_j0`` .. ``right_j6`` (positions and
  velocities) every :data:`STATE_DT` seconds of each kit's arm motion and at its end, stamped
  with the sample's time; and ``/tf``: ``tf2_msgs/TFMessage`` with the arm's link transforms
  (:data:`.model.LINK_TREE`) at the same instants. With them RViz (RobotModel and TF displays,
  fixed frame ``base``) and PlotJuggler play a bag with no custom node.
* ``/bilevel_kit/events``: ``diagnostic_msgs/DiagnosticArray``, one message per instant of
  the timeline, one status per event there (name ``kit K``, message the event, key/values
  ``kit``, ``event``, ``plan_time``, ``detail``), stamped with the plan's time.

Plan time ``t`` is recorded as ROS time ``t +`` :data:`EPOCH` seconds: a ROS 1 bag's default
query starts at 1 ns, which would skip a message at exactly 0.
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Literal

import numpy as np

from . import moveit
from .model import JOINT_NAMES, LINK_TREE, tool_arm
from .trajectory import Event, Execution, KitTrajectory

#: Seconds of ROS time at plan time 0.
EPOCH = 1.0
TRAJECTORY_TOPIC = "/bilevel_kit/arm/joint_trajectory"
GRIPPER_TOPIC = "/bilevel_kit/gripper/command"
EVENTS_TOPIC = "/bilevel_kit/events"
TRAJECTORY_TYPE = "trajectory_msgs/msg/JointTrajectory"
GRIPPER_TYPE = "sensor_msgs/msg/JointState"
EVENTS_TYPE = "diagnostic_msgs/msg/DiagnosticArray"
JOINT_STATES_TOPIC = "/joint_states"
TF_TOPIC = "/tf"
TF_TYPE = "tf2_msgs/msg/TFMessage"
#: tf2_msgs/TFMessage's definition (not in rosbags' ROS 1 typestore) and its ROS 1 MD5.
TF_MSGDEF = "geometry_msgs/TransformStamped[] transforms"
TF_MD5 = "94810edda583a504dfda3829e70d7eec"
#: Period [s] of the sampled robot state on ``/joint_states`` and ``/tf`` (20 Hz).
STATE_DT = 0.05
#: Topic -> message type, in the order the connections are added.
TOPICS = {
    TRAJECTORY_TOPIC: TRAJECTORY_TYPE,
    moveit.DISPLAY_TOPIC: moveit.DISPLAY_TYPE,
    GRIPPER_TOPIC: GRIPPER_TYPE,
    JOINT_STATES_TOPIC: GRIPPER_TYPE,
    TF_TOPIC: TF_TYPE,
    EVENTS_TOPIC: EVENTS_TYPE,
}
FINGER_JOINTS = ("right_gripper_l_finger_joint", "right_gripper_r_finger_joint")
FINGERS_OPEN = (0.020833, -0.020833)
FINGERS_CLOSED = (0.0, 0.0)
FORMATS = ("ros1", "ros2")
#: rosbag2 metadata version written by the ``rosbags`` writer (it supports 8 and 9); the
#: bag is then rewritten as :data:`ROS2_METADATA_VERSION` (:func:`_as_humble`).
ROS2_VERSION: Literal[8, 9] = 8
#: Metadata version of the written ROS 2 bag: Humble's rosbag2 reads up to 5, Jazzy all.
ROS2_METADATA_VERSION = 5
#: sqlite3 schema version of Humble's rosbag2 storage.
ROS2_SQLITE_SCHEMA = 3


def to_ns(seconds: float) -> int:
    """Plan seconds as ROS time in integer nanoseconds."""
    return round((EPOCH + seconds) * 1e9)


def _stamp(types: dict[str, Any], ns: int) -> Any:
    return types["builtin_interfaces/msg/Time"](sec=ns // 10**9, nanosec=ns % 10**9)


def _header(types: dict[str, Any], ros1: bool, ns: int, frame: str = "") -> Any:
    extra = {"seq": 0} if ros1 else {}
    return types["std_msgs/msg/Header"](stamp=_stamp(types, ns), frame_id=frame, **extra)


def _trajectory(types: dict[str, Any], ros1: bool, kt: KitTrajectory) -> Any:
    point = types["trajectory_msgs/msg/JointTrajectoryPoint"]
    duration = types["builtin_interfaces/msg/Duration"]
    points = []
    for t, q, qd, qdd in zip(kt.times, kt.positions, kt.velocities, kt.accelerations, strict=True):
        ns = round(float(t) * 1e9)
        points.append(
            point(
                positions=np.asarray(q, dtype=np.float64),
                velocities=np.asarray(qd, dtype=np.float64),
                accelerations=np.asarray(qdd, dtype=np.float64),
                effort=np.zeros(0, dtype=np.float64),
                time_from_start=duration(sec=ns // 10**9, nanosec=ns % 10**9),
            )
        )
    return types[TRAJECTORY_TYPE](
        header=_header(types, ros1, 0, "base"), joint_names=list(JOINT_NAMES), points=points
    )


def _gripper(types: dict[str, Any], ros1: bool, ns: int, closed: bool) -> Any:
    return types[GRIPPER_TYPE](
        header=_header(types, ros1, ns),
        name=list(FINGER_JOINTS),
        position=np.array(FINGERS_CLOSED if closed else FINGERS_OPEN, dtype=np.float64),
        velocity=np.zeros(0, dtype=np.float64),
        effort=np.zeros(0, dtype=np.float64),
    )


def _events(types: dict[str, Any], ros1: bool, ns: int, events: Sequence[Event]) -> Any:
    kv = types["diagnostic_msgs/msg/KeyValue"]
    status = types["diagnostic_msgs/msg/DiagnosticStatus"]
    return types[EVENTS_TYPE](
        header=_header(types, ros1, ns),
        status=[
            status(
                level=0,
                name=f"kit {e.kit}",
                message=e.name,
                hardware_id="sawyer",
                values=[
                    kv(key="kit", value=str(e.kit)),
                    kv(key="event", value=e.name),
                    kv(key="plan_time", value=f"{e.time:.9f}"),
                    kv(key="detail", value=e.detail),
                ],
            )
            for e in events
        ],
    )


def typestore(fmt: str) -> Any:
    """rosbags' Noetic (``ros1``) or Humble (``ros2``) typestore, with ``tf2_msgs/TFMessage``
    and MoveIt's ``DisplayTrajectory``."""
    from rosbags.typesys import Stores, get_types_from_msg, get_typestore

    store = get_typestore(Stores.ROS1_NOETIC if fmt == "ros1" else Stores.ROS2_HUMBLE)
    if TF_TYPE not in store.types:
        store.register(get_types_from_msg(TF_MSGDEF, TF_TYPE))
    moveit.register(store)
    return store


def _robot_state(
    types: dict[str, Any], ros1: bool, kt: KitTrajectory
) -> list[tuple[str, int, Any]]:
    """``/joint_states`` and ``/tf`` every :data:`STATE_DT` s of the kit's motion and at its
    end."""
    t = np.append(np.arange(0.0, kt.duration, STATE_DT), kt.duration)
    q, qd = kt.states_at(t)
    arm = tool_arm(0.0)
    tf, vec, quat = (
        types[n]
        for n in (
            "geometry_msgs/msg/TransformStamped",
            "geometry_msgs/msg/Vector3",
            "geometry_msgs/msg/Quaternion",
        )
    )
    transform = types["geometry_msgs/msg/Transform"]
    out = []
    for ti, qi, qdi in zip(t, q, qd, strict=True):
        ns = to_ns(kt.start + float(ti))
        state = types[GRIPPER_TYPE](
            header=_header(types, ros1, ns),
            name=list(JOINT_NAMES),
            position=np.asarray(qi, dtype=np.float64),
            velocity=np.asarray(qdi, dtype=np.float64),
            effort=np.zeros(0, dtype=np.float64),
        )
        links = [
            tf(
                header=_header(types, ros1, ns, parent),
                child_frame_id=child,
                transform=transform(
                    translation=vec(x=p[0], y=p[1], z=p[2]),
                    rotation=quat(x=r[0], y=r[1], z=r[2], w=r[3]),
                ),
            )
            for (parent, child), (p, r) in zip(LINK_TREE, arm.link_transforms(qi), strict=True)
        ]
        out.append((JOINT_STATES_TOPIC, ns, state))
        out.append((TF_TOPIC, ns, types[TF_TYPE](transforms=links)))
    return out


def messages(execution: Execution, fmt: str) -> list[tuple[str, int, Any]]:
    """``(topic, ROS time ns, message)`` of every message of the bag, in time order."""
    ros1 = fmt == "ros1"
    types = typestore(fmt).types
    out: list[tuple[str, int, Any]] = []
    for kt in execution.kits:
        ns = to_ns(kt.start)
        trajectory = _trajectory(types, ros1, kt)
        out.append((TRAJECTORY_TOPIC, ns, trajectory))
        display = moveit.display_trajectory(
            types, _header(types, ros1, ns, "base"), trajectory, kt.positions[0], kt.velocities[0]
        )
        out.append((moveit.DISPLAY_TOPIC, ns, display))
        out += _robot_state(types, ros1, kt)
    for t, _kit, _part, closed in execution.gripper_commands():
        ns = to_ns(t)
        out.append((GRIPPER_TOPIC, ns, _gripper(types, ros1, ns, closed)))
    groups: dict[int, list[Event]] = {}
    for e in execution.events:
        groups.setdefault(to_ns(e.time), []).append(e)
    for ns, group in groups.items():
        out.append((EVENTS_TOPIC, ns, _events(types, ros1, ns, group)))
    order = list(TOPICS)
    out.sort(key=lambda m: (m[1], order.index(m[0])))
    return out


@dataclass(frozen=True)
class BagInfo:
    """A written bag: its path (a file for ROS 1, a folder for ROS 2), size and counts."""

    format: str
    path: Path
    size: int
    counts: dict[str, int] = field(default_factory=dict)

    @property
    def n_messages(self) -> int:
        return sum(self.counts.values())


def _size(path: Path) -> int:
    if path.is_dir():
        return sum(p.stat().st_size for p in path.rglob("*") if p.is_file())
    return path.stat().st_size


def write_bag(execution: Execution, path: str | Path, fmt: str) -> BagInfo:
    """Write the ``fmt`` (``"ros1"`` or ``"ros2"``) bag of ``execution`` at ``path``, which
    must not exist (a ``.bag`` file for ROS 1, a folder for ROS 2)."""
    if fmt not in FORMATS:
        raise ValueError(f"unknown bag format {fmt!r}; expected one of {', '.join(FORMATS)}")
    path = Path(path)
    msgs = messages(execution, fmt)
    counts = dict.fromkeys(TOPICS, 0)
    if fmt == "ros1":
        from rosbags.rosbag1 import Writer as Writer1

        store = typestore(fmt)
        with Writer1(path) as w1:
            conns = {t: w1.add_connection(t, m, typestore=store) for t, m in TOPICS.items()}
            for topic, ns, msg in msgs:
                w1.write(conns[topic], ns, store.serialize_ros1(msg, TOPICS[topic]))
                counts[topic] += 1
    else:
        from rosbags.rosbag2 import Writer as Writer2

        store = typestore(fmt)
        with Writer2(path, version=ROS2_VERSION) as w2:
            conns = {t: w2.add_connection(t, m, typestore=store) for t, m in TOPICS.items()}
            for topic, ns, msg in msgs:
                w2.write(conns[topic], ns, store.serialize_cdr(msg, TOPICS[topic]))
                counts[topic] += 1
        _as_humble(path)
    return BagInfo(fmt, path, _size(path), counts)


#: Keys rosbag2 added to its metadata after version 5 (``custom_data``, ``ros_distro`` and the
#: topics' ``type_description_hash``).
_AFTER_V5 = ("custom_data", "ros_distro")


def _as_humble(path: Path) -> None:
    """Rewrite a ROS 2 bag written as metadata version 8 as Humble writes it: metadata
    version 5 without the later keys, and sqlite3 schema 3 (no ``metadata`` table)."""
    import io
    import sqlite3

    from ruamel.yaml import YAML

    yaml = YAML(typ="safe")
    yaml.default_flow_style = False
    meta_path = path / "metadata.yaml"
    doc = yaml.load(meta_path.read_text(encoding="utf-8"))
    info = doc["rosbag2_bagfile_information"]
    for key in _AFTER_V5:
        info.pop(key, None)
    for topic in info["topics_with_message_count"]:
        topic["topic_metadata"].pop("type_description_hash", None)
    info["version"] = ROS2_METADATA_VERSION
    text = io.StringIO()
    yaml.dump(doc, text)
    meta_path.write_text(text.getvalue(), encoding="utf-8")
    for name in info["relative_file_paths"]:
        db = sqlite3.connect(path / name)
        try:
            with db:
                db.execute("DROP TABLE IF EXISTS metadata")
                db.execute("UPDATE schema SET schema_version = ?", (ROS2_SQLITE_SCHEMA,))
        finally:
            db.close()


def bag_name(stem: str, fmt: str) -> str:
    """File (ROS 1) or folder (ROS 2) name of a bag under ``--bag DIR``."""
    return f"{stem}.bag" if fmt == "ros1" else f"{stem}_ros2"


def read_bag(path: str | Path) -> dict[str, list[tuple[int, Any]]]:
    """Every message of a bag written here (either format), per topic: ``(ROS time ns,
    deserialised message)`` in the bag's order."""
    from rosbags.highlevel import AnyReader

    out: dict[str, list[tuple[int, Any]]] = {}
    # A ROS 2 bag of metadata version 5 carries no message definitions: Humble's are used.
    with AnyReader([Path(path)], default_typestore=typestore("ros2")) as reader:
        for conn, ns, raw in reader.messages():
            out.setdefault(conn.topic, []).append((ns, reader.deserialize(raw, conn.msgtype)))
    return out


def trajectory_arrays(msg: Any) -> tuple[list[str], np.ndarray, np.ndarray, np.ndarray]:
    """``(joint names, time_from_start [s], positions, velocities)`` of a read-back
    ``JointTrajectory``."""
    t = np.array([p.time_from_start.sec + p.time_from_start.nanosec * 1e-9 for p in msg.points])
    q = np.array([p.positions for p in msg.points], dtype=float)
    qd = np.array([p.velocities for p in msg.points], dtype=float)
    return list(msg.joint_names), t, q, qd


def event_names(msgs: Iterable[tuple[int, Any]]) -> list[tuple[float, int, str]]:
    """``(plan time, kit, event)`` of read-back event messages, from the stamps."""
    out = []
    for ns, msg in msgs:
        for status in msg.status:
            values = {kv.key: kv.value for kv in status.values}
            out.append((ns * 1e-9 - EPOCH, int(values["kit"]), values["event"]))
    return out
