"""Pick-and-place motion times under the Sawyer's velocity limits."""

from __future__ import annotations

import itertools
from dataclasses import dataclass

import numpy as np
import pytest

pytest.importorskip("pinocchio")

import bilevel_kit.sawyer as S  # noqa: N812

ST = S.DEFAULT_WORK_CELL


def test_trapezoid_time_triangle_and_trapezoid() -> None:
    assert S.trapezoid_time(0.0, 1.0, 2.0) == 0.0
    # triangle: d = 0.25 < v^2 / a = 0.5 -> 2 sqrt(d / a)
    assert S.trapezoid_time(0.25, 1.0, 2.0) == pytest.approx(2 * np.sqrt(0.125))
    # trapezoid: d / v + v / a
    assert S.trapezoid_time(2.0, 1.0, 2.0) == pytest.approx(2.5)
    # continuous at the switch d = v^2 / a
    assert S.trapezoid_time(0.5 - 1e-12, 1.0, 2.0) == pytest.approx(
        S.trapezoid_time(0.5 + 1e-12, 1.0, 2.0)
    )
    assert S.trapezoid_time(-2.0, 1.0, 2.0) == pytest.approx(2.5)


def test_accel_limits_are_documented_ramp() -> None:
    np.testing.assert_allclose(S.A_MAX, S.V_MAX / 0.5)


def test_move_time_slowest_joint_governs_and_limits_hold() -> None:
    rng = np.random.default_rng(2)
    for _ in range(5):
        q0, q1 = rng.uniform(S.Q_LOWER, S.Q_UPPER, size=(2, 7))
        for params in (S.DEFAULT_PARAMS, S.MotionParams(speed_scale=0.3, accel_scale=0.5)):
            T = S.move_time(q0, q1, params)
            d = np.abs(q1 - q0)
            single = [S.trapezoid_time(d[i], params.v_max[i], params.a_max[i]) for i in range(7)]
            assert max(single) - 1e-12 <= T
            t = np.linspace(0.0, T, 2001)
            q, qd, qdd = S.move_profile(q0, q1, t, params)
            assert np.all(np.abs(qd) <= params.v_max * (1 + 1e-9) + 1e-12)
            assert np.all(np.abs(qdd) <= params.a_max * (1 + 1e-9) + 1e-12)
            np.testing.assert_allclose(q[0], q0, atol=1e-12)
            np.testing.assert_allclose(q[-1], q1, atol=1e-9)
            np.testing.assert_allclose(qd[[0, -1]], 0.0, atol=1e-9)
            np.testing.assert_array_equal(qdd[[0, -1]], 0.0)  # at rest: no acceleration
            # some joint actually hits a limit: the timing is tight
            assert (np.abs(qd) >= params.v_max * (1 - 1e-6)).any() or (
                np.abs(qdd) >= params.a_max * (1 - 1e-6)
            ).any()
    assert S.move_time(q0, q0) == 0.0
    assert S.move_time(q0, q1) == pytest.approx(S.move_time(q1, q0))


def test_pick_place_time_is_positive_and_made_of_the_documented_steps() -> None:
    plan = S.pick_place(ST, "bolt", (300.0, 200.0))
    assert list(plan.steps) == [
        "approach_bin",
        "grasp",
        "retreat_bin",
        "transfer",
        "approach_slot",
        "release",
        "retreat_slot",
        "return",
    ]
    assert plan.steps["grasp"] == S.DEFAULT_PARAMS.grasp_time
    assert all(v > 0 for v in plan.steps.values())
    t = S.pick_place_time(ST, "bolt", (300.0, 200.0))
    assert t == pytest.approx(plan.total)
    assert 2.0 < t < 30.0
    arm = S.Arm(ST.tool_offset_m)
    place = ST.tray_to_base(300.0, 200.0, ST.place_height)
    assert np.linalg.norm(arm.position(plan.q_slot) - place) <= S.POS_TOL
    assert plan.slot_yaw in ST.grasp_yaws
    no_return = S.pick_place_time(ST, "bolt", (300.0, 200.0), S.MotionParams(return_to_bin=False))
    assert no_return == pytest.approx(t - plan.steps["return"])


def test_farther_slots_are_not_faster() -> None:
    # The default bin is to the robot's left (+y), next to the tray's x = 0 edge; slots along
    # the tray x axis move away from it.
    times = [S.pick_place_time(ST, "bolt", (x, 200.0)) for x in (0.0, 150.0, 300.0, 450.0, 600.0)]
    assert all(b >= a - 0.05 for a, b in itertools.pairwise(times))
    assert times[-1] > times[0] + 0.5
    near = S.pick_place_time(ST, "bolt", (20.0, 20.0))
    far = S.pick_place_time(ST, "bolt", (580.0, 380.0))
    assert far > near


def test_slower_robot_takes_longer_and_bins_per_part_type() -> None:
    slow = S.MotionParams(speed_scale=0.5)
    assert S.pick_place_time(ST, "a", (300, 200), slow) > S.pick_place_time(ST, "a", (300, 200))
    st = S.WorkCell(bins={"near": (450.0, 200.0, -100.0), "far": (200.0, 700.0, -100.0)})
    assert S.pick_place_time(st, "near", (100, 100)) < S.pick_place_time(st, "far", (100, 100))


def test_unreachable_slot_or_bin_raises() -> None:
    far_tray = S.WorkCell(tray_x=1400.0)
    with pytest.raises(S.UnreachableError, match="tray slot"):
        S.pick_place_time(far_tray, "a", (100.0, 100.0))
    far_bin = S.WorkCell(bins={"x": (0.0, 1600.0, 0.0)})
    with pytest.raises(S.UnreachableError, match="bin of part type 'x'"):
        S.pick_place_time(far_bin, "x", (100.0, 100.0))


@dataclass
class _Placement:
    type: str
    x: float
    y: float


def test_layout_time_sums_the_cycles() -> None:
    layout = [_Placement("a", 100, 100), _Placement("b", 400, 300)]
    expected = S.pick_place_time(ST, "a", (100, 100)) + S.pick_place_time(ST, "b", (400, 300))
    assert S.layout_time(ST, layout) == pytest.approx(expected)
    assert S.layout_time(ST, []) == 0.0


def test_motion_params_validation() -> None:
    with pytest.raises(ValueError):
        S.MotionParams(speed_scale=0)
    with pytest.raises(ValueError):
        S.MotionParams(grasp_time=-1)


def test_tray_average_time_lies_between_extremes() -> None:
    avg = S.tray_average_time(ST, "a", 600.0, 400.0, resolution=200.0)
    corners = [S.pick_place_time(ST, "a", xy) for xy in ((0, 0), (600, 400), (600, 0))]
    assert min(corners) - 1.0 < avg < max(corners) + 1.0
    with pytest.raises(S.UnreachableError):
        S.tray_average_time(S.WorkCell(tray_x=1400.0), "a", 600.0, 400.0, resolution=200.0)


def test_speed_scale_scales_time_velocities_and_accelerations() -> None:
    """Without the tool cap, S = 0.4 is the same move 1 / S times slower."""
    rng = np.random.default_rng(5)
    q0, q1 = rng.uniform(S.Q_LOWER, S.Q_UPPER, size=(2, 7)) * 0.5
    fast = S.MotionParams(tool_speed=None)
    slow = S.MotionParams(speed_scale=0.4, tool_speed=None)
    T = S.move_time(q0, q1, fast)
    assert S.move_time(q0, q1, slow) == pytest.approx(T / 0.4, rel=1e-12)
    t = np.linspace(0.0, T, 101)[1:-1]
    q, qd, qdd = S.move_profile(q0, q1, t, fast)
    q_s, qd_s, qdd_s = S.move_profile(q0, q1, t / 0.4, slow)
    np.testing.assert_allclose(q_s, q, atol=1e-12)
    np.testing.assert_allclose(qd_s, 0.4 * qd, atol=1e-12)
    np.testing.assert_allclose(qdd_s, 0.16 * qdd, atol=1e-9)
    with pytest.raises(ValueError):
        S.MotionParams(speed_scale=1.5)
    with pytest.raises(ValueError):
        S.MotionParams(tool_speed=0.0)


@pytest.mark.parametrize("cap", [0.6, 0.25])
def test_the_tool_speed_cap_holds_along_a_pick_and_place(cap) -> None:
    params = S.MotionParams(tool_speed=cap)
    cycle = S.pick_place(ST, "bolt", (550.0, 350.0), params)
    free = S.pick_place(ST, "bolt", (550.0, 350.0), S.MotionParams(tool_speed=None))
    assert cycle.steps["transfer"] > free.steps["transfer"]  # the cap governs the transfer
    arm = S.Arm(ST.tool_offset_m)
    T = cycle.steps["transfer"]
    t = np.linspace(0.0, T, 401)
    q, qd, _ = S.move_profile(cycle.q_bin_above, cycle.q_slot_above, t, params)
    speed = [np.linalg.norm(arm.jacobian(c)[:3] @ v) for c, v in zip(q, qd, strict=True)]
    # the cap holds at TOOL_SAMPLES points of the line; in between, within 1 %
    assert max(speed) <= cap * 1.01
    assert max(speed) >= cap * 0.95  # and it is reached: the timing is tight


def test_place_height_per_part_type() -> None:
    st = S.WorkCell.from_dict({"place_heights": {"foot": 35.0}})
    assert st.place_height_of("foot") == 35.0 and st.place_height_of("leg") == st.place_height
    assert S.WorkCell.from_dict(st.to_dict()) == st
    arm = S.Arm(st.tool_offset_m)
    for part_type, height in (("foot", 35.0), ("leg", 20.0)):
        q = S.pick_place(st, part_type, (150.0, 100.0)).q_slot
        z = arm.position(q)[2]
        assert z == pytest.approx((st.tray_z + height) / 1000.0, abs=1e-3)
    with pytest.raises(S.WorkCellError, match="place_heights"):
        S.WorkCell.from_dict({"place_heights": {"foot": "high"}})
