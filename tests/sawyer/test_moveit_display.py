"""``moveit_msgs/DisplayTrajectory`` in the execution bags: Noetic's exact definitions (the
published MD5s), one message per kit on MoveIt's topic, read back by ``rosbags``' readers
with the same points as the kit's ``JointTrajectory`` (docs/execution.md, "The bags")."""

from __future__ import annotations

import tomllib
from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("rosbags")

from bilevel_kit import load, solve
from bilevel_kit.sawyer import bags, moveit
from bilevel_kit.sawyer.trajectory import plan_execution

ROOT = Path(__file__).resolve().parents[2]
TABLE = ROOT / "instances" / "hrc_table.json"

#: ROS 1 MD5s of the Noetic types as roscpp's message traits publish them.
PUBLISHED_MD5 = {
    "moveit_msgs/msg/DisplayTrajectory": "41936b74e168ba754279ae683ce3f121",
    "moveit_msgs/msg/RobotTrajectory": "dfa9556423d709a3729bcef664bddf67",
    "moveit_msgs/msg/AttachedCollisionObject": "30199ef516f64c8bc1edb1084ce4584e",
    "moveit_msgs/msg/CollisionObject": "dbba710596087da521c07564160dfccb",
    "object_recognition_msgs/msg/ObjectType": "ac757ec5be1998b0167e7efcda79e3cf",
}


@pytest.fixture(scope="module")
def execution():
    """Kits 1 and 2 of Single Task's plan of the paper's table."""
    instance = load(TABLE)
    res = solve(instance, "single-task")
    assert res.plan is not None
    return plan_execution(instance, res.plan, kits=[1, 2])


@pytest.fixture(scope="module")
def written(execution, tmp_path_factory):
    out = tmp_path_factory.mktemp("moveit")
    return {
        fmt: bags.write_bag(execution, out / bags.bag_name("t", fmt), fmt) for fmt in bags.FORMATS
    }


def test_the_ros1_definitions_have_the_published_md5s():
    store = bags.typestore("ros1")
    for name, md5 in PUBLISHED_MD5.items():
        assert store.generate_msgdef(name, ros_version=1)[1] == md5, name
    assert PUBLISHED_MD5[moveit.DISPLAY_TYPE] == moveit.DISPLAY_MD5


def test_the_ros1_bag_carries_the_definition_and_its_md5(written):
    from rosbags.rosbag1 import Reader

    with Reader(written["ros1"].path) as reader:
        (conn,) = [c for c in reader.connections if c.topic == moveit.DISPLAY_TOPIC]
    assert conn.msgtype == moveit.DISPLAY_TYPE
    assert conn.digest == moveit.DISPLAY_MD5
    msgdef = conn.msgdef.data
    assert "MSG: moveit_msgs/CollisionObject" in msgdef and "subframe_names" in msgdef
    assert msgdef.startswith("string model_id\n")


@pytest.mark.parametrize("fmt", bags.FORMATS)
def test_one_display_trajectory_per_kit_with_the_kits_points(fmt, written, execution):
    """Read back (ROS 1: with the bag's own definitions) on MoveIt's topic: model ``sawyer``,
    the kit's trajectory point for point, and its first joint state as the start state."""
    info = written[fmt]
    assert info.counts[moveit.DISPLAY_TOPIC] == len(execution.kits) == 2
    topics = bags.read_bag(info.path)
    displays, trajectories = topics[moveit.DISPLAY_TOPIC], topics[bags.TRAJECTORY_TOPIC]
    assert [ns for ns, _ in displays] == [ns for ns, _ in trajectories]
    for (ns, display), (_, traj), kt in zip(displays, trajectories, execution.kits, strict=True):
        assert ns == bags.to_ns(kt.start)
        assert display.model_id == "sawyer"
        (robot_trajectory,) = display.trajectory
        jt = robot_trajectory.joint_trajectory
        assert list(jt.joint_names) == list(traj.joint_names) == [f"right_j{i}" for i in range(7)]
        assert jt.header.frame_id == "base"
        assert len(jt.points) == len(kt.times) > 10
        names, t, q, qd = bags.trajectory_arrays(jt)
        np.testing.assert_allclose(t, kt.times, atol=1e-9)
        np.testing.assert_array_equal(q, kt.positions)
        np.testing.assert_array_equal(qd, kt.velocities)
        np.testing.assert_array_equal(q, bags.trajectory_arrays(traj)[2])
        assert robot_trajectory.multi_dof_joint_trajectory.points == []
        start = display.trajectory_start
        assert list(start.joint_state.name) == names
        np.testing.assert_array_equal(start.joint_state.position, kt.positions[0])
        assert start.attached_collision_objects == [] and not start.is_diff


def test_packaging_ships_the_definitions_and_their_licence():
    """Every data file under ``sawyer/msg`` matches the package-data globs of pyproject."""
    config = tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))
    patterns = config["tool"]["setuptools"]["package-data"]["bilevel_kit"]
    package = ROOT / "bilevel_kit"
    files = {p for p in moveit.MSG_DIR.rglob("*") if p.is_file()}
    shipped = {p for pattern in patterns for p in package.glob(pattern)}
    assert moveit.MSG_DIR / "LICENSE" in files
    assert sum(p.suffix == ".msg" for p in files) == 6
    assert files <= shipped, sorted(str(p) for p in files - shipped)
