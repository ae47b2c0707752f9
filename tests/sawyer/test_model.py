"""Sawyer model, forward kinematics, inverse kinematics and work cell geometry."""

from __future__ import annotations

import math
import time
from pathlib import Path

import numpy as np
import pytest

pin = pytest.importorskip("pinocchio")

import bilevel_kit.sawyer as S  # noqa: E402, N812
from bilevel_kit.errors import BilevelKitError  # noqa: E402
from bilevel_kit.sawyer.ik import clik_down, converged, out_of_reach, tool_yaw  # noqa: E402
from bilevel_kit.sawyer.model import Q_SHIPPING  # noqa: E402

REFERENCE = Path(__file__).resolve().parents[3] / "shared" / "reference" / "sawyer"
if not REFERENCE.exists():
    REFERENCE = Path("/work/shared/reference/sawyer")


def _reference_model(name: str):
    path = REFERENCE / "derived" / name
    if not path.exists():
        pytest.skip(f"upstream Sawyer description not available ({path})")
    return pin.buildModelFromUrdf(str(path))


def _upstream_q(model, q: np.ndarray) -> np.ndarray:
    """Our 7 arm angles in the upstream model's configuration (head and fingers at 0)."""
    full = pin.neutral(model)
    for name, value in zip(S.JOINT_NAMES, q, strict=True):
        full[model.joints[model.getJointId(name)].idx_q] = value
    return full


def _random_configs(n: int, seed: int = 7) -> np.ndarray:
    return np.random.default_rng(seed).uniform(S.Q_LOWER, S.Q_UPPER, size=(n, 7))


# --- model ------------------------------------------------------------------------------


def test_model_has_the_seven_arm_joints_with_limits() -> None:
    model = S.build_model()
    assert model.nq == model.nv == 7
    assert list(model.names)[1:] == list(S.JOINT_NAMES)
    np.testing.assert_allclose(model.lowerPositionLimit, S.Q_LOWER)
    np.testing.assert_allclose(model.upperPositionLimit, S.Q_UPPER)
    np.testing.assert_allclose(model.velocityLimit, S.V_MAX)
    np.testing.assert_allclose(S.V_MAX, [1.74, 1.328, 1.957, 1.957, 3.485, 3.485, 4.545])
    for frame in ("right_hand", "tool", "right_l6", "base"):
        assert model.existFrame(frame)


def test_limits_and_velocities_equal_upstream() -> None:
    up = _reference_model("sawyer.urdf")
    for i, name in enumerate(S.JOINT_NAMES):
        j = up.joints[up.getJointId(name)]
        assert up.lowerPositionLimit[j.idx_q] == pytest.approx(S.Q_LOWER[i])
        assert up.upperPositionLimit[j.idx_q] == pytest.approx(S.Q_UPPER[i])
        assert up.velocityLimit[j.idx_v] == pytest.approx(S.V_MAX[i])


def test_fk_equals_upstream_urdf_at_random_configurations() -> None:
    up = _reference_model("sawyer.urdf")
    data = up.createData()
    fid = up.getFrameId("right_hand", pin.BODY)
    configs = np.vstack([np.zeros(7), S.Q_NEUTRAL, Q_SHIPPING, _random_configs(12)])
    for q in configs:
        pin.framesForwardKinematics(up, data, _upstream_q(up, q))
        ours = S.fk_hand(q)
        ref = data.oMf[fid].homogeneous
        assert np.abs(ours[:3, 3] - ref[:3, 3]).max() < 1e-6
        assert np.abs(ours[:3, :3] - ref[:3, :3]).max() < 1e-6


def test_tool_tip_equals_upstream_electric_gripper_tip() -> None:
    up = _reference_model("sawyer_electric_gripper.urdf")
    data = up.createData()
    fid = up.getFrameId("right_gripper_tip")
    for q in _random_configs(6, seed=11):
        pin.framesForwardKinematics(up, data, _upstream_q(up, q))
        ours = S.fk_tool(q, S.ELECTRIC_GRIPPER_TIP)
        assert np.abs(ours[:3, 3] - data.oMf[fid].translation).max() < 1e-6


def test_fk_at_zero_and_neutral_matches_hard_coded_numbers() -> None:
    # Computed once with this model; they agree with the upstream table to 0.1 mm
    # (README: zero -> (1.0155, 0.1603, 0.3170), neutral -> (0.4496, 0.1603, 0.2158)).
    zero = S.fk_hand(np.zeros(7))
    np.testing.assert_allclose(zero[:3, 3], [1.0155, 0.1603, 0.31699982], atol=1e-6)
    np.testing.assert_allclose(
        zero[:3, :3],
        [
            [1.28e-06, -7.23e-06, 1.0],
            [-0.9848082, -0.17364562, 0.0],
            [0.17364562, -0.9848082, -7.35e-06],
        ],
        atol=1e-6,
    )
    neutral = S.fk_hand(S.Q_NEUTRAL)
    np.testing.assert_allclose(neutral[:3, 3], [0.44959778, 0.1603, 0.21575405], atol=1e-6)
    np.testing.assert_allclose(
        neutral[:3, :3],
        [
            [-2.298e-05, 0.99999969, 0.00078898],
            [1.0, 2.298e-05, 0.0],
            [-2e-08, 0.00078898, -0.99999969],
        ],
        atol=1e-6,
    )
    tip = S.fk_tool(S.Q_NEUTRAL, S.ELECTRIC_GRIPPER_TIP)
    np.testing.assert_allclose(tip[:3, 3], [0.44970478, 0.1603, 0.0801341], atol=1e-6)
    np.testing.assert_allclose(
        S.fk_tool(np.zeros(7), S.ELECTRIC_GRIPPER_TIP)[:3, 3],
        [1.15112, 0.1603, 0.31699882],
        atol=1e-6,
    )


def test_tool_offset_is_along_hand_z() -> None:
    for q in _random_configs(5):
        hand = S.fk_hand(q)
        tool = S.fk_tool(q, 0.1)
        np.testing.assert_allclose(tool[:3, 3], hand[:3, 3] + 0.1 * hand[:3, 2], atol=1e-12)
        np.testing.assert_allclose(tool[:3, :3], hand[:3, :3], atol=1e-12)


def test_manipulability_is_yoshikawa_measure() -> None:
    arm = S.Arm(0.0)
    q = S.Q_NEUTRAL
    J = arm.jacobian(q)
    assert J.shape == (6, 7)
    assert arm.manipulability(q) == pytest.approx(math.sqrt(np.linalg.det(J @ J.T)))
    assert arm.manipulability(np.zeros(7)) < 1e-3  # stretched arm: singular


def test_reach_bounds_are_conservative() -> None:
    """No configuration puts the tool beyond the quick pre-check's bounds."""
    arm = S.Arm(S.ELECTRIC_GRIPPER_TIP)
    for q in _random_configs(300, seed=3):
        assert not out_of_reach(arm.position(q), arm.tool_offset, tool_down=False)
        # Bring the tool z axis down from q: a top-down configuration near the same point.
        qd, pe, tilt = clik_down(arm, arm.position(q), q, max_iter=40)
        if converged(pe, tilt):
            assert not out_of_reach(arm.position(qd), arm.tool_offset, tool_down=True)


# --- inverse kinematics -----------------------------------------------------------------


def _inside_points() -> list[np.ndarray]:
    """Points well inside the workspace, table height and above, in front and to the side."""
    pts = []
    for x in (0.45, 0.6, 0.75):
        for y in (-0.3, 0.0, 0.3):
            for z in (-0.13, 0.05):
                pts.append(np.array([x, y, z]))
    pts += [np.array([0.2, 0.6, -0.1]), np.array([0.0, -0.6, 0.0])]
    return pts


@pytest.mark.parametrize("yaw", [0.0, 90.0, -135.0])
def test_ik_round_trip_top_down(yaw: float) -> None:
    arm = S.Arm(S.ELECTRIC_GRIPPER_TIP)
    for p in _inside_points():
        sol = S.solve_top_down(arm, p, (yaw,))
        assert sol is not None, p
        assert S.within_limits(sol.q)
        T = arm.fk(sol.q)
        assert np.linalg.norm(T[:3, 3] - p) <= S.POS_TOL
        target = S.top_down_rotation(math.radians(yaw))
        angle = np.linalg.norm(pin.log3(T[:3, :3].T @ target))
        assert angle <= S.ROT_TOL
        assert sol.yaw_deg == yaw
        assert np.all(sol.q >= S.Q_LOWER) and np.all(sol.q <= S.Q_UPPER)


def test_ik_top_down_picks_an_allowed_yaw_and_wrapper_returns_configuration() -> None:
    p = np.array([0.6, 0.1, -0.1])
    q = S.ik_top_down(p, (0.0, 90.0, 180.0, -90.0), tool_offset=0.1)
    assert q is not None and q.shape == (7,)
    arm = S.Arm(0.1)
    assert np.linalg.norm(arm.position(q) - p) <= S.POS_TOL
    yaw = tool_yaw(arm, q)
    assert min(abs((yaw - a + 180) % 360 - 180) for a in (0, 90, 180, -90)) < 1.0


def test_ik_is_deterministic() -> None:
    p = np.array([0.7, -0.2, -0.1])
    a = S.ik_top_down(p, 30.0, 0.13562)
    b = S.ik_top_down(p, 30.0, 0.13562)
    assert a is not None and b is not None
    np.testing.assert_array_equal(a, b)


def test_ik_full_pose_round_trip() -> None:
    arm = S.Arm(0.05)
    ok = 0
    configs = _random_configs(20, seed=5)
    for q in configs:
        T = arm.fk(q)
        sol = S.solve_pose(arm, T)
        if sol is None:
            continue
        ok += 1
        T2 = arm.fk(sol)
        assert np.linalg.norm(T2[:3, 3] - T[:3, 3]) <= S.POS_TOL
        assert np.linalg.norm(pin.log3(T2[:3, :3].T @ T[:3, :3])) <= S.ROT_TOL
    assert ok >= 18


def test_ik_success_on_witnessed_top_down_targets() -> None:
    """Targets reachable by construction (a top-down configuration exists): >= 95 %."""
    arm = S.Arm(S.ELECTRIC_GRIPPER_TIP)
    rng = np.random.default_rng(21)
    targets = []
    while len(targets) < 40:
        q = rng.uniform(S.Q_LOWER, S.Q_UPPER)
        qd, pe, tilt = clik_down(arm, arm.position(q), q)
        if converged(pe, tilt):
            targets.append(arm.position(qd))
    ok = sum(S.solve_top_down(arm, p, (0.0,)) is not None for p in targets)
    assert ok >= 38


@pytest.mark.parametrize(
    "direction", [(1, 0, 0), (0, 1, 0), (-1, 0, 0), (0.6, -0.8, 0), (0, 0, 1), (0.7, 0, -0.7)]
)
def test_points_beyond_reach_are_unreachable_quickly(direction: tuple[float, ...]) -> None:
    arm = S.Arm(S.ELECTRIC_GRIPPER_TIP)
    d = np.array(direction, dtype=float)
    p = np.array([0.0, 0.0, 0.317]) + 1.5 * d / np.linalg.norm(d)
    start = time.perf_counter()
    assert S.solve_top_down(arm, p, (0.0, 90.0)) is None
    assert S.ik_top_down(p, 0.0, S.ELECTRIC_GRIPPER_TIP) is None
    assert S.solve_pose(arm, _pose_at(p)) is None
    assert time.perf_counter() - start < 0.05


def _pose_at(p: np.ndarray) -> np.ndarray:
    T = np.eye(4)
    T[:3, :3] = S.top_down_rotation(0.0)
    T[:3, 3] = p
    return T


def test_with_yaw_turns_only_the_last_joint() -> None:
    arm = S.Arm(0.1)
    sol = S.solve_top_down(arm, np.array([0.6, 0.0, 0.0]), (0.0,))
    assert sol is not None
    q2 = S.with_yaw(sol.q, 0.0, 90.0)
    assert q2 is not None
    np.testing.assert_allclose(q2[:6], sol.q[:6])
    assert tool_yaw(arm, q2) == pytest.approx(90.0, abs=0.2)
    np.testing.assert_allclose(arm.position(q2), arm.position(sol.q), atol=1e-9)


# --- work cell --------------------------------------------------------------------------


def test_default_work_cell_and_tray_frame() -> None:
    st = S.DEFAULT_WORK_CELL
    assert st.tray_yaw == -90.0
    np.testing.assert_allclose(st.tray_to_base(0, 0), [0.45, 0.30, -0.15])
    # tray x runs to the robot's right (-y), tray y away from the robot (+x)
    np.testing.assert_allclose(st.tray_to_base(600, 0), [0.45, -0.30, -0.15], atol=1e-12)
    np.testing.assert_allclose(st.tray_to_base(300, 200, 20), [0.65, 0.0, -0.13], atol=1e-12)
    grid = st.tray_to_base(np.array([[0.0, 600.0]]), np.array([[0.0], [400.0]]))
    assert grid.shape == (2, 2, 3)
    assert st.tool_offset == pytest.approx(135.62)
    assert st.bin_xyz("anything") == st.default_bin


def test_work_cell_dict_round_trip_and_schema() -> None:
    jsonschema = pytest.importorskip("jsonschema")
    st = S.WorkCell(
        tray_x=400,
        tray_y=250,
        tray_z=-120,
        tray_yaw=-80,
        bins={"bolt": (300, 500, -100), "nut": [200.0, 550.0, -90.0]},
        grasp_yaws=(0, 90),
        approach_height=80,
        tool_offset=0,
    )
    doc = st.to_dict()
    jsonschema.validate(doc, S.work_cell_schema())
    jsonschema.validate({}, S.work_cell_schema())
    back = S.WorkCell.from_dict(doc)
    assert back == st
    assert hash(back) == hash(st)
    assert back.bin_xyz("nut") == (200.0, 550.0, -90.0)
    assert S.WorkCell.from_dict({}) == S.DEFAULT_WORK_CELL
    assert S.WorkCell.from_dict(None) == S.DEFAULT_WORK_CELL
    assert S.WorkCell.from_dict({"tray_pose": {"x": 500}}).tray_x == 500.0
    with pytest.raises(jsonschema.ValidationError):
        jsonschema.validate({"tray_pose": {"x": "far"}}, S.work_cell_schema())


@pytest.mark.parametrize(
    "doc",
    [
        {"tray_pose": {"x": "far"}},
        {"tray_pose": {"w": 1}},
        {"colour": "red"},
        {"grasp_yaws": []},
        {"grasp_yaws": "0"},
        {"bins": {"a": [1, 2]}},
        {"default_bin": [0, 0, float("nan")]},
        {"tool_offset": -5},
        {"approach_height": True},
        [1, 2],
    ],
)
def test_work_cell_from_dict_rejects_bad_input(doc: object) -> None:
    with pytest.raises(S.WorkCellError) as info:
        S.WorkCell.from_dict(doc)  # type: ignore[arg-type]
    assert isinstance(info.value, ValueError)
    assert isinstance(info.value, BilevelKitError)


def test_jacobian_matches_finite_differences() -> None:
    arm = S.Arm(0.1)
    q = _random_configs(1, seed=9)[0]
    arm.position(np.zeros(7))  # leave stale data behind on purpose
    J = arm.jacobian(q)
    eps = 1e-7
    for i in range(7):
        dq = np.zeros(7)
        dq[i] = eps
        num = (arm.position(q + dq) - arm.position(q - dq)) / (2 * eps)
        np.testing.assert_allclose(J[:3, i], num, atol=1e-6)


def test_importing_the_package_does_not_load_pinocchio_or_matplotlib() -> None:
    import subprocess
    import sys

    code = (
        "import sys, bilevel_kit.sawyer; "
        "assert 'pinocchio' not in sys.modules and 'matplotlib' not in sys.modules"
    )
    root = str(Path(__file__).resolve().parents[2])
    env = {"PYTHONPATH": root, "PATH": "/usr/bin:/bin"}
    subprocess.run([sys.executable, "-c", code], check=True, env=env, cwd=root)
