"""``bilevel-kit execute``: per-kit Sawyer trajectories in ROS bags, read back and checked
against the joint limits, the motion model and the slot and bin poses (docs/execution.md)."""

from __future__ import annotations

import itertools
import json
import math
import re
from pathlib import Path

import numpy as np
import pytest

pin = pytest.importorskip("pinocchio")
pytest.importorskip("rosbags")

import bilevel_kit.sawyer as S  # noqa: E402, N812
from bilevel_kit import load, solve  # noqa: E402
from bilevel_kit import solution as solution_io  # noqa: E402
from bilevel_kit.cli import main  # noqa: E402
from bilevel_kit.plan import evaluate  # noqa: E402
from bilevel_kit.sawyer import bags  # noqa: E402
from bilevel_kit.sawyer.trajectory import plan_execution, verify  # noqa: E402

ROOT = Path(__file__).resolve().parents[2]
TABLE = ROOT / "instances" / "hrc_table.json"
REFERENCE = ROOT.parent / "shared" / "reference" / "sawyer"
ST = S.DEFAULT_WORK_CELL


def run(capsys, *argv):
    code = main([str(a) for a in argv])
    out, err = capsys.readouterr()
    return code, out, err


@pytest.fixture(scope="module")
def instance():
    return load(TABLE)


@pytest.fixture(scope="module")
def plan(instance):
    """Single Task's plan of the paper's table: 12 kits, 28 parts, solved in milliseconds."""
    res = solve(instance, "single-task")
    assert res.plan is not None
    return res


@pytest.fixture(scope="module")
def solution_file(plan, tmp_path_factory) -> Path:
    path = tmp_path_factory.mktemp("sol") / "single.json"
    solution_io.write(path, plan)
    return path


@pytest.fixture(scope="module")
def written(solution_file, tmp_path_factory):
    """One run of the command: (folder, stdout)."""
    out = tmp_path_factory.mktemp("exec")
    code = main(
        [
            "execute",
            str(TABLE),
            str(solution_file),
            "--bag",
            str(out / "bags"),
            "--html",
            str(out / "view.html"),
        ]
    )
    assert code == 0
    return out


def _tfs(point) -> float:
    return point.time_from_start.sec + point.time_from_start.nanosec * 1e-9


@pytest.mark.parametrize("fmt", ["ros1", "ros2"])
def test_bags_read_back_within_limits_and_on_the_plan_times(fmt, written, instance, plan):
    path = written / "bags" / bags.bag_name("hrc_table", fmt)
    topics = bags.read_bag(path)
    assert set(topics) == set(bags.TOPICS)
    timeline = evaluate(instance, plan.plan)
    kits = plan.plan.kits
    trajectories = topics[bags.TRAJECTORY_TOPIC]
    assert len(trajectories) == len(kits)  # one trajectory per kit
    for topic, msgs in topics.items():  # bag stamps strictly increase on every topic
        stamps = [ns for ns, _ in msgs]
        assert all(b > a for a, b in itertools.pairwise(stamps)), topic
    for k, (ns, msg) in enumerate(trajectories):
        times = timeline.kits[k]
        assert msg.header.stamp.sec == 0 and msg.header.stamp.nanosec == 0  # start on receipt
        assert ns == bags.to_ns(times.robot_start + instance.kit_overhead_robot)
        names, t, q, qd = bags.trajectory_arrays(msg)
        assert names == [f"right_j{i}" for i in range(7)]
        assert t[0] == 0.0 and np.all(np.diff(t) > 0)
        assert np.all(q >= S.Q_LOWER - 1e-9) and np.all(q <= S.Q_UPPER + 1e-9)
        assert np.all(np.abs(qd) <= S.V_MAX * (1 + 1e-9))
        fd = np.diff(q, axis=0) / np.diff(t)[:, None]
        assert np.all(np.abs(fd) <= S.V_MAX * (1 + 1e-6))
        # The duration is the motion model's time of this kit's layout, computed apart.
        assert t[-1] == pytest.approx(S.layout_time(ST, kits[k].layout), abs=1e-6)
        assert ns * 1e-9 - bags.EPOCH + t[-1] <= times.robot_end + 1e-6  # fits the plan


def _waypoint(traj_ns: int, msg, command_ns: int) -> np.ndarray:
    """The trajectory point at a gripper command's time (it is a sample, to the nanosecond)."""
    offset = (command_ns - traj_ns) * 1e-9
    for point in msg.points:
        if abs(_tfs(point) - offset) < 2e-9:
            return np.array(point.positions)
    raise AssertionError(f"no trajectory point at {offset} s")


def _commands(topics):
    """Per kit, the gripper commands (ns, closed) inside its trajectory's time span."""
    trajectories = topics[bags.TRAJECTORY_TOPIC]
    out = []
    for i, (ns, msg) in enumerate(trajectories):
        end = ns + round(_tfs(msg.points[-1]) * 1e9)
        cmds = [
            (c_ns, bool(np.all(np.asarray(c.position) == 0.0)))
            for c_ns, c in topics[bags.GRIPPER_TOPIC]
            if ns <= c_ns <= end
        ]
        out.append((ns, msg, cmds))
        assert i == 0 or ns > trajectories[i - 1][0]
    return out


@pytest.mark.parametrize("fmt", ["ros1", "ros2"])
def test_grasp_and_place_waypoints_hit_the_bin_and_the_slot(fmt, written, plan):
    topics = bags.read_bag(written / "bags" / bags.bag_name("hrc_table", fmt))
    arm = S.Arm(ST.tool_offset_m)
    worst = 0.0
    for kit, (ns, msg, cmds) in zip(plan.plan.kits, _commands(topics), strict=True):
        assert [closed for _, closed in cmds] == [True, False] * len(kit.layout)
        for p, (close, release) in zip(
            kit.layout, zip(cmds[::2], cmds[1::2], strict=True), strict=True
        ):
            grasp = arm.placement(_waypoint(ns, msg, close[0]))
            assert np.linalg.norm(grasp.translation - ST.bin_point(p.type)) <= 1e-3
            place = arm.placement(_waypoint(ns, msg, release[0]))
            target = ST.tray_to_base(p.x, p.y, ST.place_height)
            worst = max(worst, float(np.linalg.norm(place.translation - target)))
            R = place.rotation
            assert math.acos(min(1.0, -R[2, 2])) <= 1e-2  # tool z straight down
            yaw = math.degrees(math.atan2(R[1, 0], R[0, 0])) - ST.tray_yaw - p.theta
            assert min(abs((yaw - g + 180) % 360 - 180) for g in ST.grasp_yaws) <= 0.6
    assert worst <= 1e-3


def test_place_waypoints_match_the_upstream_urdf(written, plan):
    """The same waypoints through Rethink's own description (electric gripper tip)."""
    path = REFERENCE / "derived" / "sawyer_electric_gripper.urdf"
    if not path.exists():
        pytest.skip(f"upstream Sawyer description not available ({path})")
    model = pin.buildModelFromUrdf(str(path))
    data = model.createData()
    tip = model.getFrameId("right_gripper_tip")
    topics = bags.read_bag(written / "bags" / bags.bag_name("hrc_table", "ros2"))
    for kit, (ns, msg, cmds) in zip(plan.plan.kits, _commands(topics), strict=True):
        for p, (release_ns, _) in zip(kit.layout, cmds[1::2], strict=True):
            q = pin.neutral(model)
            for name, value in zip(S.JOINT_NAMES, _waypoint(ns, msg, release_ns), strict=True):
                q[model.joints[model.getJointId(name)].idx_q] = value
            pin.framesForwardKinematics(model, data, q)
            target = ST.tray_to_base(p.x, p.y, ST.place_height)
            assert np.linalg.norm(data.oMf[tip].translation - target) <= 1e-3


def test_events_carry_the_plan_times(written, instance, plan):
    topics = bags.read_bag(written / "bags" / bags.bag_name("hrc_table", "ros1"))
    events = bags.event_names(topics[bags.EVENTS_TOPIC])
    timeline = evaluate(instance, plan.plan)
    for k, times in enumerate(timeline.kits, start=1):
        mine = {name: t for t, kit, name in events if kit == k}
        assert mine["tray_ready"] == pytest.approx(times.robot_start, abs=1e-9)
        assert mine["tray_push"] == pytest.approx(times.robot_end, abs=1e-9)
        assert mine["tray_delivered"] == pytest.approx(times.arrive, abs=1e-9)
        if k > 1 and times.robot_start > timeline.kits[k - 2].arrive + 1e-9:
            assert mine["wait_for_tray"] == pytest.approx(timeline.kits[k - 2].arrive, abs=1e-9)
        else:
            assert "wait_for_tray" not in mine
    assert any(name == "wait_for_tray" for _, _, name in events)  # one tray in circulation


def test_the_report_shows_durations_against_the_model(capsys, solution_file, tmp_path):
    code, out, err = run(capsys, "execute", TABLE, solution_file, "--bag", tmp_path / "b")
    assert code == 0 and err == ""
    rows = [line.split() for line in out.splitlines() if line[:3].strip().isdigit()]
    assert len(rows) == 12
    for row in rows:
        assert float(row[4]) == pytest.approx(float(row[5]), abs=1e-3)  # trajectory = model
        assert abs(float(row[6])) < 1e-9
    assert "hrc_table.bag (ROS1 bag" in out and "hrc_table_ros2 (ROS2 bag" in out
    assert sorted(p.name for p in (tmp_path / "b").iterdir()) == [
        "hrc_table.bag",
        "hrc_table_ros2",
    ]


def test_one_kit_and_one_format(capsys, solution_file, tmp_path, instance, plan):
    code, _out, _ = run(
        capsys, "execute", TABLE, solution_file, "--bag", tmp_path, "--kit", 3, "--format", "ros1"
    )
    assert code == 0
    assert [p.name for p in tmp_path.iterdir()] == ["hrc_table_kit3.bag"]
    topics = bags.read_bag(tmp_path / "hrc_table_kit3.bag")
    assert len(topics[bags.TRAJECTORY_TOPIC]) == 1
    assert {kit for _, kit, _ in bags.event_names(topics[bags.EVENTS_TOPIC])} == {3}
    # run again: the bag is replaced, not refused
    code, _, _ = run(
        capsys, "execute", TABLE, solution_file, "--bag", tmp_path, "--kit", 3, "--format", "ros1"
    )
    assert code == 0 and [p.name for p in tmp_path.iterdir()] == ["hrc_table_kit3.bag"]


def _far_instance(tmp_path: Path, work_cell: dict) -> tuple[Path, Path]:
    doc = json.loads(TABLE.read_text())
    doc["work_cell"] = work_cell
    inst_path = tmp_path / "far.json"
    inst_path.write_text(json.dumps(doc))
    sol_path = tmp_path / "far_solution.json"
    solution_io.write(sol_path, solve(load(inst_path), "single-task"))
    return inst_path, sol_path


@pytest.mark.parametrize(
    ("work_cell", "message"),
    [
        ({"tray_pose": {"x": 1400.0}}, r"kit 1, part foot-1 \(type foot\): .*tray slot"),
        ({"bins": {"leg": [0.0, 1600.0, 0.0]}}, r"kit 1, part leg-1 \(type leg\): .*bin of part"),
    ],
)
def test_out_of_reach_is_exit_2_naming_kit_and_part(capsys, tmp_path, work_cell, message):
    inst_path, sol_path = _far_instance(tmp_path, work_cell)
    out = tmp_path / "out"
    code, text, err = run(
        capsys, "execute", inst_path, sol_path, "--bag", out, "--html", out / "v.html"
    )
    assert code == 2 and text == ""
    assert len(err.strip().splitlines()) == 1 and "Traceback" not in err
    assert re.search(message, err), err
    assert not out.exists()


def test_bad_input_is_one_line_and_writes_nothing(capsys, tmp_path, solution_file, root):
    other = tmp_path / "tiny_solution.json"
    solution_io.write(other, solve(load(root / "instances" / "tiny.json"), "single-task"))
    a_file = tmp_path / "a_file"
    a_file.write_text("x")
    out = tmp_path / "out"
    cases = [
        (tmp_path / "missing.json", solution_file, "--bag", out),
        (TABLE, tmp_path / "missing.json", "--bag", out),
        (TABLE, other, "--bag", out),
        (TABLE, solution_file, "--bag", out, "--kit", 13),
        (TABLE, solution_file, "--bag", out, "--kit", 0),
        (TABLE, solution_file, "--format", "ros1"),
        (TABLE, solution_file, "--bag", a_file),
        (TABLE, solution_file, "--html", a_file / "v.html"),
    ]
    for argv in cases:
        code, _text, err = run(capsys, "execute", *argv)
        assert code == 2, argv
        assert len(err.strip().splitlines()) == 1 and "Traceback" not in err, err
        assert not out.exists()


def test_a_failed_write_leaves_nothing(capsys, tmp_path, solution_file, monkeypatch):
    real = bags.write_bag

    def flaky(ex, path, fmt):
        if fmt == "ros2":
            raise OSError(28, "No space left on device")
        return real(ex, path, fmt)

    monkeypatch.setattr(bags, "write_bag", flaky)
    old = tmp_path / "bags"
    old.mkdir()
    (old / "hrc_table_kit1.bag").write_text("the previous bag")
    code, _, err = run(
        capsys,
        "execute",
        TABLE,
        solution_file,
        "--kit",
        1,
        "--bag",
        old,
        "--html",
        tmp_path / "v.html",
    )
    assert code == 2 and "No space left on device" in err
    assert [p.name for p in old.iterdir()] == ["hrc_table_kit1.bag"]  # no temporary left
    assert (old / "hrc_table_kit1.bag").read_text() == "the previous bag"
    assert not (tmp_path / "v.html").exists()


def test_bin_changes_are_timed_apart_from_the_model(instance, plan):
    doc = instance.to_dict()
    doc["work_cell"] = {"bins": {"leg": [350.0, 450.0, -100.0], "foot": [250.0, 600.0, -80.0]}}
    from bilevel_kit.instance import from_dict

    other = from_dict(doc)
    ex = plan_execution(other, plan.plan)
    work_cell = other.work_cell
    assert any(kt.extra > 0 for kt in ex.kits)
    for kt, kit in zip(ex.kits, plan.plan.kits, strict=True):
        assert kt.modelled == pytest.approx(S.layout_time(work_cell, kit.layout), abs=1e-9)
        assert kt.duration == pytest.approx(kt.modelled + kt.extra, abs=1e-9)
        assert ("to_bin" in [s.name for s in kt.segments]) == (kt.extra > 0)
    v = verify(ex)
    assert v.place_error <= 1e-3 and v.grasp_error <= 1e-3
    assert v.speed_share <= 1 + 1e-9 and v.fd_speed_share <= 1 + 1e-9
    assert v.position_margin > 0 and v.duration_error < 1e-9


def test_exact_positions_agree_with_the_samples(instance, plan):
    ex = plan_execution(instance, plan.plan, kits=[2], dt=0.01)
    kt = ex.kits[0]
    np.testing.assert_allclose(kt.positions_at(kt.times), kt.positions, atol=1e-9)
    coarse = plan_execution(instance, plan.plan, kits=[2], dt=0.2).kits[0]
    assert coarse.duration == pytest.approx(kt.duration, abs=1e-12)
    assert len(coarse.times) < len(kt.times)


def test_joint_trajectory_figure(instance, plan):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from bilevel_kit.sawyer.figures import (
        limit_lines,
        plot_joint_positions,
        plot_joint_velocities,
        plot_kit_trajectory,
    )

    kt = plan_execution(instance, plan.plan, kits=[1]).kits[0]
    _fig, ax = plt.subplots()
    assert plot_joint_positions(kt, ax=ax) is ax
    # positions in % of each joint's range: the 14 limits are two shared lines, 0 and 100 %
    assert [tuple(line.get_ydata()) for line in limit_lines(ax)] == [(0.0, 0.0), (100.0, 100.0)]
    assert ax.get_xlabel() and ax.get_ylabel() == "joint angle (% of its range)"
    shares = [line.get_ydata() for line in ax.get_lines() if "q:" in str(line.get_gid())]
    assert len(shares) == 7 and all(y.min() >= 0.0 and y.max() <= 100.0 for y in shares)
    ax.figure.canvas.draw()  # the legend is beside the axes, not over the curves and limits
    assert ax.get_legend().get_window_extent().x0 >= ax.get_window_extent().x1
    ax2 = plot_joint_velocities(kt)
    assert len(limit_lines(ax2)) == 2
    v_lines = [line for line in ax2.get_lines() if "v:" in str(line.get_gid())]
    top = max(line.get_ydata().max() for line in v_lines)
    assert top <= 100.0 + 1e-6
    # drawn from the exact profile on a 0.01 s grid, whatever the samples' dt: a run with
    # dt = 0.2 draws the same velocities
    t = v_lines[0].get_xdata()
    assert np.diff(t).max() <= 0.01 + 1e-9 and len(t) > len(kt.times)
    coarse = plan_execution(instance, plan.plan, kits=[1], dt=0.2).kits[0]
    again = [ln for ln in plot_joint_velocities(coarse).get_lines() if "v:" in str(ln.get_gid())]
    y_fine = np.interp(np.linspace(0, kt.duration, 997), t, v_lines[0].get_ydata())
    y_coarse = np.interp(
        np.linspace(0, kt.duration, 997), again[0].get_xdata(), again[0].get_ydata()
    )
    np.testing.assert_allclose(y_coarse, y_fine, atol=1e-6)
    figure = plot_kit_trajectory(kt)
    assert len(figure.axes) == 2
    plt.close("all")


def _points(msg) -> tuple[np.ndarray, tuple[np.ndarray, np.ndarray, np.ndarray]]:
    """``time_from_start`` and (positions, velocities, accelerations) of a read-back message."""
    t = np.array([_tfs(p) for p in msg.points])
    arrays = tuple(
        np.array([getattr(p, name) for p in msg.points], dtype=float)
        for name in ("positions", "velocities", "accelerations")
    )
    return t, (arrays[0], arrays[1], arrays[2])


@pytest.mark.parametrize("fmt", ["ros1", "ros2"])
def test_a_controllers_quintic_holds_the_tool_still_while_the_gripper_works(
    fmt, written, instance, plan
):
    """ros2_control's trajectory controller fits a quintic (position, velocity, acceleration
    at both ends) between points: through the bag's points, the tool moves at most 0.5 mm
    during every grasp and release, and every stop has zero acceleration."""
    from bilevel_kit.sawyer.controller import dwell_deviation, quintic

    topics = bags.read_bag(written / "bags" / bags.bag_name("hrc_table", fmt))
    times, points = [], []
    for _, msg in topics[bags.TRAJECTORY_TOPIC]:
        t, (q, qd, qdd) = _points(msg)
        still = np.all(qd == 0.0, axis=1)
        assert still.sum() > 0 and np.all(qdd[still] == 0.0)
        np.testing.assert_allclose(quintic(t, q, qd, qdd, t), q, atol=1e-9)  # through the points
        times.append(t)
        points.append((q, qd, qdd))
    ex = plan_execution(instance, plan.plan)
    worst = dwell_deviation(ex.kits, ST.tool_offset_m, times=times, points=points)
    assert worst.deviation <= 0.5e-3, worst
    # The same measure sees stops that carry the braking deceleration (as before the fix).
    kt = ex.kits[0]
    braking = np.diff(kt.velocities, axis=0) / np.diff(kt.times)[:, None]
    still = np.all(kt.velocities[1:] == 0.0, axis=1)
    qdd = kt.accelerations.copy()
    qdd[1:][still] = braking[still]
    bad = dwell_deviation([kt], ST.tool_offset_m, points=[(kt.positions, kt.velocities, qdd)])
    assert bad.deviation > 0.5e-3


def test_speed_scale_and_tool_speed_options(capsys, tmp_path, solution_file, plan):
    """``--speed-scale`` slows the arm (the motion model with the same parameters times it),
    ``--tool-speed`` caps the tool tip's speed; a late arm's warning names the fix."""
    argv = ("execute", TABLE, solution_file, "--kit", 1, "--format", "ros2", "--bag", tmp_path)
    code, out, err = run(capsys, *argv, "--speed-scale", 0.5, "--tool-speed", 0.3)
    assert code == 0 and err == ""
    assert '"robot_times": "motion"' in out  # the slowed arm ends after the plan's push
    topics = bags.read_bag(tmp_path / "hrc_table_kit1_ros2")
    ((_, msg),) = topics[bags.TRAJECTORY_TOPIC]
    t, (q, qd, _) = _points(msg)
    params = S.MotionParams(speed_scale=0.5, tool_speed=0.3)
    assert t[-1] == pytest.approx(S.layout_time(ST, plan.plan.kits[0].layout, params), abs=1e-6)
    assert np.all(np.abs(qd) <= 0.5 * S.V_MAX * (1 + 1e-9))
    arm = S.Arm(ST.tool_offset_m)
    speeds = [np.linalg.norm(arm.jacobian(c)[:3] @ v) for c, v in zip(q, qd, strict=True)]
    assert 0.25 <= max(speeds) <= 0.3 * 1.01
    for bad in (("--speed-scale", 0), ("--speed-scale", 1.5), ("--tool-speed", -1)):
        code, _, err = run(capsys, *argv, *bad)
        assert code == 2 and len(err.strip().splitlines()) == 1, err


@pytest.mark.slow
def test_the_documented_table_run(instance):
    """docs/execution.md's table and numbers for greedy-ce's plan of the paper's table."""
    text = (ROOT / "docs" / "execution.md").read_text(encoding="utf-8")
    section = text[text.index("### The paper's table with greedy-ce's plan") :]
    rows = [
        [float(c) for c in line.strip("|").split("|")]
        for line in section.splitlines()
        if re.match(r"\| \d", line)
    ]
    ex = plan_execution(instance, solve(instance, "greedy-ce").plan)
    assert len(rows) == len(ex.kits) == 8
    for row, kt in zip(rows, ex.kits, strict=True):
        plan_robot = kt.plan.robot_end - kt.plan.robot_start - (kt.start - kt.plan.robot_start)
        mine = [kt.kit, len(kt.parts), kt.plan.robot_start, kt.start, kt.duration, kt.modelled]
        mine += [plan_robot, kt.plan.robot_end - kt.end]
        # kit, parts and plan times exactly; the arm's times depend on greedy-ce's layouts,
        # which another CPU's float32 search can move by millimetres (docs/scaling.md#portability)
        assert row[:4] == [round(v, 3) for v in mine[:4]]
        assert row[4:] == pytest.approx(mine[4:], abs=0.1)
    late = max(kt.overrun for kt in ex.kits)
    (doc_late,) = re.findall(r"arms end ([0-9.]+) s after", section)
    assert float(doc_late) == pytest.approx(late, abs=0.1)
    v = verify(ex)
    assert f"peaks at the cap, {v.tool_speed:.3f} m/s" in section and v.speed_share < 1.0
    assert v.place_error <= 1e-6 and v.grasp_error <= 1e-6


def test_gazebo_limits_keep_j6_within_the_simulators_range(capsys, tmp_path, solution_file):
    """``--limits gazebo``: every point within the simulator description's limits (right_j6
    within +-3.14 rad), which the real arm's profile exceeds on this plan."""
    low, high = S.LIMIT_PROFILES["gazebo"]
    assert high[6] == 3.14 and low[6] == -3.14
    np.testing.assert_array_equal(high[:6], S.Q_UPPER[:6])
    argv = ("execute", TABLE, solution_file, "--format", "ros1")
    code, _, _ = run(capsys, *argv, "--bag", tmp_path / "g", "--limits", "gazebo")
    assert code == 0
    code, _, _ = run(capsys, *argv, "--bag", tmp_path / "r")
    assert code == 0
    q6 = {}
    for name in ("g", "r"):
        topics = bags.read_bag(tmp_path / name / "hrc_table.bag")
        arrays = [bags.trajectory_arrays(m)[2] for _, m in topics[bags.TRAJECTORY_TOPIC]]
        q = np.concatenate(arrays)
        q6[name] = np.abs(q[:, 6]).max()
        assert np.all(q >= low - 1e-9) or name == "r"
        assert np.all(q <= high + 1e-9) or name == "r"
    assert q6["g"] <= 3.14 < q6["r"]
    # the same numbers as Rethink's simulator description, when it is at hand
    xacro = REFERENCE / "sawyer_robot" / "sawyer_description" / "urdf" / "sawyer_base.urdf.xacro"
    if xacro.exists():
        text = xacro.read_text()
        block = text[text.index('<joint name="right_j6"') :]
        block = block[block.index('<xacro:if value="$(arg gazebo)">') :]
        limit = re.search(r'lower="([-\d.]+)" upper="([-\d.]+)"', block)
        assert limit is not None
        assert (float(limit[1]), float(limit[2])) == (low[6], high[6])


def _chain(msg, child: str) -> np.ndarray:
    """``child``'s 4 x 4 pose in ``base`` from a read-back ``TFMessage``."""
    parents = {t.child_frame_id: t for t in msg.transforms}
    pose = np.eye(4)
    while child != "base":
        t = parents[child]
        r, p = t.transform.rotation, t.transform.translation
        step = np.eye(4)
        step[:3, :3] = pin.Quaternion(r.w, r.x, r.y, r.z).toRotationMatrix()
        step[:3, 3] = (p.x, p.y, p.z)
        pose = step @ pose
        child = t.header.frame_id
    return pose


@pytest.mark.parametrize("fmt", ["ros1", "ros2"])
def test_joint_states_and_tf_replay_the_trajectories(fmt, written, instance, plan):
    """``/joint_states`` and ``/tf`` sample each kit's motion every STATE_DT s; their link
    chain puts ``right_hand`` where forward kinematics does; the ROS 2 bag is Humble's
    format (metadata version 5, sqlite3 schema 3) and the ROS 1 bag carries TFMessage's MD5."""
    path = written / "bags" / bags.bag_name("hrc_table", fmt)
    topics = bags.read_bag(path)
    ex = plan_execution(instance, plan.plan)
    expected = sum(math.ceil(kt.duration / bags.STATE_DT - 1e-9) + 1 for kt in ex.kits)
    states, tfs = topics[bags.JOINT_STATES_TOPIC], topics[bags.TF_TOPIC]
    assert len(states) == len(tfs) == expected
    arm = S.Arm(0.0)
    for (ns, state), (tf_ns, tf) in list(zip(states, tfs, strict=True))[::97]:
        assert ns == tf_ns and list(state.name) == list(S.JOINT_NAMES)
        hand = arm.fk(np.array(state.position), "right_hand")
        np.testing.assert_allclose(_chain(tf, "right_hand"), hand, atol=1e-9)
    if fmt == "ros2":
        import sqlite3

        meta = (path / "metadata.yaml").read_text()
        assert "version: 5" in meta and "type_description_hash" not in meta
        db = sqlite3.connect(next(path.glob("*.db3")))
        assert db.execute("SELECT schema_version FROM schema").fetchall() == [(3,)]
        db.close()
    else:
        from rosbags.rosbag1 import Reader

        with Reader(path) as reader:
            md5 = {c.topic: c.digest for c in reader.connections}
        assert md5[bags.TF_TOPIC] == bags.TF_MD5


def test_the_3d_view_stands_the_bin_on_the_table(instance, plan):
    """The bin rests on the robot's table (its top at the tray's height), inside its edges;
    the floor lies under the pedestal, and meshcat's own grid is hidden."""
    from bilevel_kit.sawyer.scene import FLOOR_Z, scene_commands

    ex = plan_execution(instance, plan.plan, kits=[1])
    commands, _ = scene_commands(ex)
    boxes, poses = {}, {}
    for c in commands:
        path = str(c.get("path", ""))
        if c["type"] == "set_object" and path.startswith("/bk/station/"):
            geometry = c["object"]["geometries"][0]
            if geometry.get("type") == "BoxGeometry":
                boxes[path] = np.array([geometry[k] for k in ("width", "height", "depth")])
        elif c["type"] == "set_transform" and path in boxes:
            poses[path] = np.array(c["matrix"]).reshape(4, 4).T[:3, 3]
    hidden = [c for c in commands if c["type"] == "set_property" and c["path"] == "/Grid"]
    assert [(c["property"], c["value"]) for c in hidden] == [("visible", False)]
    floor, slab = poses["/bk/station/floor"], boxes["/bk/station/floor"]
    assert floor[2] + slab[2] / 2 == pytest.approx(FLOOR_Z, abs=1e-9)
    table, box = poses["/bk/station/table"], boxes["/bk/station/table"]
    top = table[2] + box[2] / 2
    for path in (p for p in boxes if "/bin" in p):
        centre, size = poses[path], boxes[path]
        assert centre[2] - size[2] / 2 == pytest.approx(top, abs=0.02)  # on the table
        assert np.all(np.abs(centre[:2] - table[:2]) + size[:2] / 2 <= box[:2] / 2 + 1e-9)
        grasp = ST.bin_point("foot")
        assert centre[2] + size[2] / 2 > grasp[2]  # the grasp point is inside the bin


def test_the_documented_constants():
    """The constants docs/execution.md states, as the code has them."""
    from bilevel_kit.cli.execute import TOOL_SPEED
    from bilevel_kit.sawyer.motion import TOOL_SAMPLES

    text = " ".join((ROOT / "docs" / "execution.md").read_text(encoding="utf-8").split())
    assert TOOL_SPEED == S.MotionParams().tool_speed == 0.6
    assert f"(default {TOOL_SPEED:g}," in text and f"at {TOOL_SAMPLES} points" in text
    assert f"every {bags.STATE_DT:g} s of each kit's arm motion" in text
    assert f"metadata version {bags.ROS2_METADATA_VERSION} and sqlite3 schema" in text
    assert f"sqlite3 schema {bags.ROS2_SQLITE_SCHEMA} " in text
    assert f"limited to +-{S.LIMIT_PROFILES['gazebo'][1][6]:g} rad" in text
