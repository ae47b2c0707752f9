"""A plan executed by the Sawyer: one joint trajectory per kit, and the timeline's events.

For every kit in plan order and every part in layout order, the arm runs the motion model's
pick-and-place cycle (:func:`.motion.pick_place`, with the part's angle): approach and grasp
at the bin, retreat, transfer, approach and release at the slot, retreat, return above the
bin. Each move is the motion model's synchronised trapezoidal joint-space move under the same
velocity and (assumed) acceleration limits (:func:`.motion.move_profile`), so a kit's
trajectory lasts exactly its modelled robot time (docs/execution.md). The only moves the
model does not time are bin changes (the next part comes from another bin, or a cycle ends
without the return move): they are added as ``to_bin`` moves and reported apart.

Times: a kit's trajectory starts at the plan's ``robot_start_k`` plus the per-kit robot
overhead (the tray is squared first) and its samples are seconds from that start. Events
(wait for the tray, tray ready, arm start and end, tray push, tray delivered) carry the plan's
times (:func:`bilevel_kit.plan.evaluate`).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from .cell import DEFAULT_WORK_CELL, WorkCell
from .errors import UnreachableError
from .model import JOINT_NAMES, Arm
from .motion import DEFAULT_PARAMS, MotionParams, _path_limits, move_profile, move_time, pick_place

if TYPE_CHECKING:  # pragma: no cover - typing only
    from ..instance import Instance
    from ..plan import KitTimes, Placement, Plan, Timeline

#: Largest gap between trajectory samples [s]; phase boundaries of every move are samples too.
SAMPLE_DT = 0.05
#: Samples closer than this are merged [s] (ROS durations have 1 ns resolution).
MERGE_TOL = 1e-6
#: Steps of the motion model in cycle order; ``grasp`` and ``release`` hold the arm still.
DWELLS = ("grasp", "release")


@dataclass(frozen=True)
class Segment:
    """One step of a kit's trajectory: a move from ``q0`` to ``q1`` or a dwell (``q0 == q1``),
    from ``start`` to ``end`` seconds after the trajectory's start."""

    name: str
    part: str
    start: float
    end: float
    q0: np.ndarray
    q1: np.ndarray


@dataclass(frozen=True)
class PartMotion:
    """One placement as the arm executes it, with the motion model's time for its cycle."""

    part: str
    type: str
    x: float
    y: float
    theta: float
    #: Gripper yaw at the slot, degrees from the tray x axis (``theta`` + an allowed yaw).
    slot_yaw: float
    #: The motion model's seconds for this cycle (:func:`.motion.pick_place_time`).
    modelled: float
    #: Seconds after the trajectory's start at which the gripper closes / opens.
    grasp_at: float
    release_at: float


@dataclass(frozen=True, eq=False)
class KitTrajectory:
    """The arm's motion for one kit: samples, the steps they come from, and the plan's times."""

    kit: int
    #: Plan time [s] of the first sample: ``robot_start`` + the per-kit robot overhead.
    start: float
    times: np.ndarray
    positions: np.ndarray
    velocities: np.ndarray
    accelerations: np.ndarray
    segments: tuple[Segment, ...]
    parts: tuple[PartMotion, ...]
    #: Seconds of ``to_bin`` moves, which the motion model does not count.
    extra: float
    #: The plan's times of this kit.
    plan: KitTimes
    params: MotionParams

    @property
    def duration(self) -> float:
        return float(self.times[-1])

    @property
    def modelled(self) -> float:
        """The kit's robot time by the motion model: the sum of its cycles."""
        return float(sum(p.modelled for p in self.parts))

    @property
    def end(self) -> float:
        """Plan time at which the arm stops."""
        return self.start + self.duration

    @property
    def overrun(self) -> float:
        """Seconds by which the arm ends after the plan's ``robot_end`` (0 when it fits)."""
        return max(0.0, self.end - self.plan.robot_end)

    def positions_at(self, t: np.ndarray | float) -> np.ndarray:
        """Exact joint positions at times ``t`` (seconds from the start), shape (..., 7)."""
        return self.states_at(t)[0]

    def states_at(self, t: np.ndarray | float) -> tuple[np.ndarray, np.ndarray]:
        """Exact joint positions and velocities at times ``t`` (seconds from the start),
        shapes (..., 7)."""
        shape = np.shape(t)
        flat = np.clip(np.asarray(t, dtype=float).ravel(), 0.0, self.duration)
        starts = np.array([s.start for s in self.segments])
        idx = np.clip(np.searchsorted(starts, flat, side="right") - 1, 0, len(starts) - 1)
        q, qd = np.empty((len(flat), 7)), np.empty((len(flat), 7))
        for i in np.unique(idx):
            seg, mask = self.segments[i], idx == i
            q[mask], qd[mask], _ = move_profile(seg.q0, seg.q1, flat[mask] - seg.start, self.params)
        return q.reshape(*shape, 7), qd.reshape(*shape, 7)


@dataclass(frozen=True)
class Event:
    """A moment of the plan's timeline: ``name`` is one of :data:`EVENT_NAMES`."""

    time: float
    kit: int
    name: str
    detail: str = ""


#: Event names, in the order they happen within a kit.
EVENT_NAMES = (
    "wait_for_tray",
    "tray_ready",
    "arm_start",
    "arm_done",
    "tray_push",
    "tray_delivered",
)


@dataclass(frozen=True, eq=False)
class Execution:
    """Everything a plan's execution writes: trajectories, events and the scene geometry."""

    instance: str
    work_cell: WorkCell
    tray: tuple[float, float]
    kits: tuple[KitTrajectory, ...]
    events: tuple[Event, ...]
    timeline: Timeline
    #: Number of kits of the whole plan (``kits`` may hold one of them).
    n_plan_kits: int
    #: Per kit of the plan: ``o_H`` of its station (docs/timeline.md#several-stations).
    kit_overhead_human: tuple[float, ...]
    #: Part type ids in the instance's order (for colours).
    part_types: tuple[str, ...]
    #: Per kit number: its placements (id, type, x, y, theta, w, h), for drawing.
    layouts: dict[int, tuple[Placement, ...]]

    def gripper_commands(self) -> list[tuple[float, int, str, bool]]:
        """``(plan time, kit, part, closed)`` of every gripper command, in time order."""
        out = []
        for kt in self.kits:
            for p in kt.parts:
                out.append((kt.start + p.grasp_at, kt.kit, p.part, True))
                out.append((kt.start + p.release_at, kt.kit, p.part, False))
        return sorted(out)


def sample_move(
    q0: np.ndarray, q1: np.ndarray, params: MotionParams = DEFAULT_PARAMS, dt: float = SAMPLE_DT
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Samples ``(t, q, qd, qdd)`` of the motion model's move ``q0 -> q1`` on (0, T]: a grid
    of step at most ``dt`` plus the ends of the acceleration and braking phases."""
    total = move_time(q0, q1, params)
    if total == 0.0:
        empty = np.zeros((0, 7))
        return np.zeros(0), empty, empty.copy(), empty.copy()
    _, v, a = _path_limits(q0, q1, params)
    ta = min(v / a, total / 2.0)
    n = max(1, math.ceil(total / dt - 1e-9))
    grid = np.concatenate([np.linspace(0.0, total, n + 1)[1:], [ta, total - ta]])
    t = _merge(np.sort(grid[grid > MERGE_TOL]), total)
    q, qd, qdd = move_profile(q0, q1, t, params)
    q[-1] = q1  # the end of the move is exact, not rounded through the profile
    return t, q, qd, qdd


def _merge(t: np.ndarray, last: float) -> np.ndarray:
    """Sorted samples without near-duplicates; the last one is exactly ``last``."""
    keep = [t[0]]
    for v in t[1:]:
        if v - keep[-1] > MERGE_TOL:
            keep.append(v)
    keep[-1] = last
    return np.array(keep)


def _cycle_segments(
    part: str, cycle_q: Sequence[np.ndarray], steps: dict[str, float]
) -> list[tuple[str, str, np.ndarray, np.ndarray, float]]:
    """The motion model's steps of one cycle as ``(name, part, q0, q1, seconds)``."""
    q_ba, q_bg, q_sa, q_sp = cycle_q
    ends = {
        "approach_bin": (q_ba, q_bg),
        "grasp": (q_bg, q_bg),
        "retreat_bin": (q_bg, q_ba),
        "transfer": (q_ba, q_sa),
        "approach_slot": (q_sa, q_sp),
        "release": (q_sp, q_sp),
        "retreat_slot": (q_sp, q_sa),
        "return": (q_sa, q_ba),
    }
    return [(name, part, *ends[name], seconds) for name, seconds in steps.items()]


def _plan_parts(
    work_cell: WorkCell,
    layout: Sequence[Placement],
    kit: int,
    params: MotionParams,
    q_prev: np.ndarray | None,
) -> tuple[list[tuple[str, str, np.ndarray, np.ndarray, float]], list[PartMotion], float]:
    """Every step of a kit (bin changes included), its parts, and the bin-change seconds."""
    steps: list[tuple[str, str, np.ndarray, np.ndarray, float]] = []
    parts: list[PartMotion] = []
    extra = 0.0
    clock = 0.0
    for p in layout:
        try:
            cycle = pick_place(work_cell, p.type, (p.x, p.y), params, p.theta)
        except UnreachableError as exc:
            raise UnreachableError(f"kit {kit}, part {p.part} (type {p.type}): {exc}") from None
        if q_prev is not None and np.abs(q_prev - cycle.q_bin_above).max() > 1e-12:
            seconds = move_time(q_prev, cycle.q_bin_above, params)
            steps.append(("to_bin", p.part, q_prev, cycle.q_bin_above, seconds))
            extra += seconds
            clock += seconds
        configs = (cycle.q_bin_above, cycle.q_bin, cycle.q_slot_above, cycle.q_slot)
        here = _cycle_segments(p.part, configs, cycle.steps)
        marks = np.cumsum([0.0] + [s[4] for s in here])
        names = [s[0] for s in here]
        parts.append(
            PartMotion(
                p.part,
                p.type,
                p.x,
                p.y,
                p.theta,
                cycle.slot_yaw,
                cycle.total,
                clock + float(marks[names.index("grasp")]),
                clock + float(marks[names.index("release")]),
            )
        )
        steps += here
        clock += float(marks[-1])
        q_prev = here[-1][3]
    return steps, parts, extra


def _sample(
    steps: Sequence[tuple[str, str, np.ndarray, np.ndarray, float]],
    params: MotionParams,
    dt: float,
) -> tuple[list[Segment], np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Segments and samples ``(t, q, qd, qdd)`` of consecutive steps, starting at t = 0."""
    ts, qs = [np.zeros(1)], [steps[0][2][None, :]]
    qds, qdds = [np.zeros((1, 7))], [np.zeros((1, 7))]
    segments = []
    clock = 0.0
    for name, part, q0, q1, seconds in steps:
        if name in DWELLS:
            t = np.array([seconds]) if seconds > MERGE_TOL else np.zeros(0)
            q, qd = np.repeat(q0[None, :], len(t), axis=0), np.zeros((len(t), 7))
            qdd = qd.copy()
        else:
            t, q, qd, qdd = sample_move(q0, q1, params, dt)
            if len(t) and abs(t[-1] - seconds) > 1e-9:  # pragma: no cover - same formula
                raise AssertionError(f"{name}: sampled {t[-1]} s, modelled {seconds} s")
        segments.append(Segment(name, part, clock, clock + seconds, q0, q1))
        ts.append(clock + t)
        qs.append(q)
        qds.append(qd)
        qdds.append(qdd)
        clock += seconds
    t_all = np.concatenate(ts)
    keep = np.concatenate([[True], np.diff(t_all) > MERGE_TOL])
    return (
        segments,
        t_all[keep],
        np.concatenate(qs)[keep],
        np.concatenate(qds)[keep],
        np.concatenate(qdds)[keep],
    )


def kit_trajectory(
    work_cell: WorkCell,
    layout: Sequence[Placement],
    kit: int,
    times: KitTimes,
    overhead: float,
    *,
    params: MotionParams = DEFAULT_PARAMS,
    dt: float = SAMPLE_DT,
    q_start: np.ndarray | None = None,
) -> KitTrajectory | None:
    """The trajectory of one kit (None for a kit without parts). ``q_start``: where the arm
    is (the previous kit's end); None: above the first part's bin."""
    if not layout:
        return None
    params = params.for_work_cell(work_cell)
    steps, parts, extra = _plan_parts(work_cell, layout, kit, params, q_start)
    segments, t, q, qd, qdd = _sample(steps, params, dt)
    return KitTrajectory(
        kit,
        times.robot_start + overhead,
        t,
        q,
        qd,
        qdd,
        tuple(segments),
        tuple(parts),
        extra,
        times,
        params,
    )


def timeline_events(
    timeline: Timeline, kits: Sequence[int], trajectories: dict[int, KitTrajectory]
) -> tuple[Event, ...]:
    """The events of ``kits`` (numbers from 1) at the plan's times, in time order."""
    out = []
    for k in kits:
        times = timeline.kits[k - 1]
        if k > 1:
            before = timeline.kits[k - 2].arrive
            if times.robot_start - before > 1e-9:
                out.append(Event(before, k, "wait_for_tray", f"until {times.robot_start:.3f} s"))
        out.append(Event(times.robot_start, k, "tray_ready"))
        traj = trajectories.get(k)
        if traj is not None:
            out.append(Event(traj.start, k, "arm_start", f"{len(traj.parts)} parts"))
            out.append(Event(traj.end, k, "arm_done", f"{traj.duration:.3f} s"))
        out.append(Event(times.robot_end, k, "tray_push"))
        out.append(Event(times.arrive, k, "tray_delivered"))
    order = {name: i for i, name in enumerate(EVENT_NAMES)}
    return tuple(sorted(out, key=lambda e: (e.time, e.kit, order[e.name])))


def plan_execution(
    instance: Instance,
    plan: Plan,
    *,
    kits: Sequence[int] | None = None,
    params: MotionParams = DEFAULT_PARAMS,
    dt: float = SAMPLE_DT,
) -> Execution:
    """The execution of ``plan`` (all kits, or the kit numbers ``kits``) in the instance's
    work cell. Raises :class:`UnreachableError` naming the kit and part of a bin or slot out of
    reach. The plan is not checked here: see :func:`bilevel_kit.validate.check`."""
    from ..plan import evaluate, kit_station

    timeline = evaluate(instance, plan)
    work_cell = instance.work_cell or DEFAULT_WORK_CELL
    chosen = list(range(1, len(plan.kits) + 1)) if kits is None else list(kits)
    trajectories: dict[int, KitTrajectory] = {}
    q_prev: np.ndarray | None = None
    for k in chosen:
        traj = kit_trajectory(
            work_cell,
            plan.kits[k - 1].layout,
            k,
            timeline.kits[k - 1],
            instance.kit_overhead_robot,
            params=params,
            dt=dt,
            q_start=q_prev,
        )
        if traj is not None:
            trajectories[k] = traj
            q_prev = traj.positions[-1]
    return Execution(
        instance.name,
        work_cell,
        (instance.tray.width, instance.tray.height),
        tuple(trajectories[k] for k in chosen if k in trajectories),
        timeline_events(timeline, chosen, trajectories),
        timeline,
        len(plan.kits),
        tuple(
            instance.params_of(kit_station(instance, k.tasks)).kit_overhead_human for k in plan.kits
        ),
        tuple(instance.part_types),
        {k: plan.kits[k - 1].layout for k in chosen},
    )


@dataclass(frozen=True)
class Verification:
    """How the trajectories sit against the limits and the targets (all maxima over kits)."""

    #: Smallest distance of any sample to a joint position limit [rad], and that joint.
    position_margin: float
    margin_joint: str
    #: Largest share of a velocity limit: the samples' velocities, and finite differences.
    speed_share: float
    fd_speed_share: float
    #: Largest tool position error at a place / grasp waypoint [m].
    place_error: float
    grasp_error: float
    #: Largest |duration - modelled time - bin changes| [s].
    duration_error: float
    #: Largest tool tip speed at the samples [m/s] (``|J(q) qd|``).
    tool_speed: float


def verify(execution: Execution) -> Verification:
    """Measure the execution against the joint limits and the slot and bin positions."""
    work_cell = execution.work_cell
    arm = Arm(work_cell.tool_offset_m)
    margin, joint, share, fd_share = math.inf, JOINT_NAMES[0], 0.0, 0.0
    place_err = grasp_err = dur_err = tool = 0.0
    for kt in execution.kits:
        v_max = kt.params.v_max
        low, high = kt.params.q_limits
        gaps = np.minimum(kt.positions - low, high - kt.positions)
        i = int(np.argmin(gaps.min(axis=0)))
        if gaps[:, i].min() < margin:
            margin, joint = float(gaps[:, i].min()), JOINT_NAMES[i]
        share = max(share, float((np.abs(kt.velocities) / v_max).max()))
        fd = np.diff(kt.positions, axis=0) / np.diff(kt.times)[:, None]
        fd_share = max(fd_share, float((np.abs(fd) / v_max).max()))
        dur_err = max(dur_err, abs(kt.duration - kt.modelled - kt.extra))
        jac = (arm.jacobian(q)[:3] for q in kt.positions)
        speeds = [float(np.linalg.norm(j @ qd)) for j, qd in zip(jac, kt.velocities, strict=True)]
        tool = max(tool, *speeds)
        for p in kt.parts:
            q_place = kt.positions_at(p.release_at)
            target = work_cell.tray_to_base(p.x, p.y, work_cell.place_height_of(p.type))
            place_err = max(place_err, float(np.linalg.norm(arm.position(q_place) - target)))
            q_grasp = kt.positions_at(p.grasp_at)
            bin_point = work_cell.bin_point(p.type)
            grasp_err = max(grasp_err, float(np.linalg.norm(arm.position(q_grasp) - bin_point)))
    return Verification(margin, joint, share, fd_share, place_err, grasp_err, dur_err, tool)
