"""``bilevel-kit execute``: a plan as Sawyer joint trajectories in ROS bags, and an animated
3-D view (docs/execution.md).

Everything that can fail on the input (the files, the plan against the instance, a bin or
slot out of reach) fails before anything is written; the outputs are then written under
temporary names next to their targets and renamed together, so a failed run leaves nothing
half-written.
"""

from __future__ import annotations

import argparse
import contextlib
import os
import shutil
import sys
import tempfile
from collections.abc import Iterator
from pathlib import Path
from typing import TYPE_CHECKING

from .common import EXIT_OK, add_derived_outputs, add_output, positive, positive_int, speed_scale

#: Default ``--tool-speed`` [m/s] (:data:`bilevel_kit.sawyer.motion.TOOL_SPEED`, kept here so
#: that building the parser does not import the Sawyer model).
TOOL_SPEED = 0.6

if TYPE_CHECKING:
    from ..instance import Instance
    from ..paths import Output
    from ..plan import Plan
    from ..sawyer.bags import BagInfo
    from ..sawyer.gripper import GraspCheck
    from ..sawyer.trajectory import Execution
    from ..sawyer.workcell import WorkCellFile
    from ..solution import LoadedSolution

HELP = "write a plan's Sawyer trajectories as ROS bags and an animated 3-D view"
DESCRIPTION = (
    "Turn a solution into what the Sawyer runs: per kit, one joint trajectory (the motion "
    "model's moves, limits and profiles, so it lasts the kit's modelled robot time), gripper "
    "commands and the timeline's events (wait for the tray, tray push, delivery) at the plan's "
    "times, as ROS 1 and/or ROS 2 bags with standard message types; and a standalone HTML page "
    "animating the arm, the trays and the parts. Prints per kit the trajectory's duration "
    "against the modelled time. Exit 2, writing nothing, when the solution does not fit the "
    "instance, a bin or slot is out of the arm's reach, or (--grasp-check strict) a part fails "
    "the gripper's feasibility pass, whose verdict is one line of the report. The work cell's "
    "geometry, its gripper and the parts' grasp widths may come from a work-cell file "
    "(--work-cell). See docs/execution.md."
)


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("instance", help="instance JSON file (format bilevel-kit/1)")
    p.add_argument("solution", help="solution JSON file of that instance")
    add_output(
        p,
        "--bag",
        folder=True,
        metavar="DIR",
        help="write the bags in this folder: NAME.bag (ROS 1) and NAME_ros2/ (ROS 2)",
    )
    p.add_argument(
        "--format",
        choices=("ros1", "ros2", "both"),
        default=None,
        help="which bags to write (default: both)",
    )
    add_output(
        p, "--html", metavar="FILE", writes="an HTML page", help="write the animated 3-D view here"
    )
    add_derived_outputs(p, _outputs)
    p.add_argument("--kit", type=positive_int, metavar="K", help="only kit K (default: all)")
    p.add_argument(
        "--speed-scale",
        type=speed_scale,
        default=1.0,
        metavar="S",
        help="run S times as fast (0 < S <= 1): times / S, velocities x S, accelerations x S^2 "
        "(default: 1); the gripper's dwells are not scaled",
    )
    p.add_argument(
        "--limits",
        choices=("robot", "gazebo"),
        default="robot",
        help="joint-limit profile: the real arm's (default) or the Gazebo simulator's, whose "
        "right_j6 stays within +-3.14 rad",
    )
    p.add_argument(
        "--grasp-check",
        choices=("auto", "strict", "warn", "off"),
        default="auto",
        help="the gripper's feasibility pass (docs/execution.md#the-gripper): warn reports in "
        "one line the parts no grasp holds or whose open fingers leave the tray or overlap a "
        "placed part; strict exits 2, writing nothing, on the first; off skips it; auto "
        "(default): strict when a work cell declares the gripper (--work-cell or recorded in "
        "the solution), warn when the URDF's fingers are only assumed",
    )
    p.add_argument(
        "--work-cell",
        metavar="FILE",
        help="work-cell JSON (docs/execution.md#the-work-cell): work_cell keys, the gripper and "
        "grasp_widths {part type: mm} that override the instance's, e.g. "
        "examples/hrc_table_cell.json (default: the cell the solution file records, if any)",
    )
    p.add_argument(
        "--tool-speed",
        type=positive,
        default=TOOL_SPEED,
        metavar="V",
        help=f"cap on the tool tip's speed in m/s (default: {TOOL_SPEED}, Intera's default "
        "Cartesian limit; the motion model uses the same cap)",
    )


def _formats(args: argparse.Namespace) -> tuple[str, ...]:
    from ..errors import UsageError

    if args.format is not None and args.bag is None:
        raise UsageError("--format needs --bag DIR")
    if args.bag is None:
        return ()
    return ("ros1", "ros2") if args.format in (None, "both") else (args.format,)


def _stem(args: argparse.Namespace) -> str:
    """The bags' name: the instance's name, as a file name, and the kit of ``--kit``."""
    from ..instance import load
    from ..paths import safe_name

    return safe_name(load(args.instance).name) + ("" if args.kit is None else f"_kit{args.kit}")


def _bag_targets(args: argparse.Namespace, stem: str) -> dict[str, Path]:
    """Each bag's path, refusing to replace a folder that is not a ROS 2 bag (a ROS 1 bag
    replaces only a ROS 1 bag: :func:`_outputs`)."""
    from ..errors import UsageError
    from ..sawyer.bags import bag_name

    out = {}
    for fmt in _formats(args):
        target = Path(args.bag) / bag_name(stem, fmt)
        is_bag = target.is_dir() and (target / "metadata.yaml").is_file()
        if fmt == "ros2" and target.exists() and not is_bag:
            raise UsageError(f"--bag {args.bag}: {target} exists and is not a ROS 2 bag")
        out[fmt] = target
    return out


def _outputs(args: argparse.Namespace) -> list[Output]:
    """The bags ``--bag DIR`` will hold, declared with the output options so that ``--html``
    can be neither one of them nor inside one (docs/cli.md#output-paths)."""
    from ..paths import Output

    if not _formats(args):
        return []
    return [
        Output(
            f"--bag {args.bag} (its ROS {fmt[-1]} bag {target})",
            target,
            "file" if fmt == "ros1" else "folder",
            writes="a ROS 1 bag",
            replaced=fmt == "ros2",
        )
        for fmt, target in _bag_targets(args, _stem(args)).items()
    ]


class _Staging:
    """Outputs written as ``.NAME.*/NAME`` next to their targets, then renamed together."""

    def __init__(self) -> None:
        self.moves: list[tuple[Path, Path]] = []
        self.created: list[Path] = []

    def path(self, target: Path) -> Path:
        missing = [p for p in (target.parent, *target.parent.parents) if not p.exists()]
        target.parent.mkdir(parents=True, exist_ok=True)
        if missing:
            self.created.append(missing[-1])
        tmp = Path(tempfile.mkdtemp(prefix=f".{target.name}.", dir=target.parent))
        self.moves.append((tmp / target.name, target))
        return tmp / target.name

    def commit(self) -> None:
        for src, dst in self.moves:
            if dst.is_dir() and not dst.is_symlink():  # a ROS 2 bag being replaced
                old = Path(tempfile.mkdtemp(prefix=f".{dst.name}.old.", dir=dst.parent))
                os.replace(dst, old / dst.name)
                os.replace(src, dst)
                shutil.rmtree(old)
            else:
                os.replace(src, dst)
            src.parent.rmdir()
        self.moves = []

    def abort(self) -> None:
        for src, _ in self.moves:
            shutil.rmtree(src.parent, ignore_errors=True)
        for folder in self.created:
            shutil.rmtree(folder, ignore_errors=True)


@contextlib.contextmanager
def _staging() -> Iterator[_Staging]:
    staging = _Staging()
    try:
        yield staging
        staging.commit()
    except BaseException:
        staging.abort()
        raise


def _load(args: argparse.Namespace) -> tuple[Execution, tuple[GraspCheck, ...], str | None]:
    """The execution of the solution (or of its kit ``--kit``), after checking it fits, the
    gripper's feasibility pass, and the work cell's source (None without one)."""
    from .. import solution
    from ..errors import UsageError
    from ..instance import load
    from ..sawyer.motion import MotionParams
    from ..sawyer.trajectory import plan_execution

    instance = load(args.instance)
    sol = solution.read(args.solution)
    cell = _work_cell(args, sol)
    if cell is not None:
        from ..sawyer.workcell import apply_work_cell

        instance = apply_work_cell(instance, cell)
    violations = sol.check(instance)
    if violations:
        raise UsageError(
            f"{args.solution} is not a valid plan of {args.instance}: {violations[0]} "
            f"({len(violations)} violation(s); bilevel-kit check lists them)"
        )
    n = len(sol.plan.kits)
    if args.kit is not None and args.kit > n:
        raise UsageError(f"--kit {args.kit}: the solution has {n} kit{'s' * (n != 1)}")
    kits = None if args.kit is None else [args.kit]
    params = MotionParams(
        speed_scale=args.speed_scale, tool_speed=args.tool_speed, limits=args.limits
    )
    checks = _check_grasps(args, instance, sol.plan, kits, declared=cell is not None)
    ex = plan_execution(instance, sol.plan, kits=kits, params=params)
    return ex, checks, None if cell is None else cell.source


def _work_cell(args: argparse.Namespace, sol: LoadedSolution) -> WorkCellFile | None:
    """``--work-cell``'s cell, else the one the solution file records (docs/formats.md): a
    plan runs in the cell it was solved in unless told otherwise, and a different cell given
    on the command line is a warning (its timing and grasps are not the plan's)."""
    from ..sawyer.workcell import cell_digest, load_work_cell, recorded_cell

    record = sol.work_cell
    if args.work_cell is not None:
        cell = load_work_cell(args.work_cell)
        if record is not None and cell_digest(cell) != record["sha256"]:
            print(
                f"warning: --work-cell {args.work_cell} is not the work cell {args.solution} "
                f"was solved in ({record['path']}, recorded in the file); executing in "
                f"{args.work_cell}",
                file=sys.stderr,
            )
        return cell
    if record is None:
        return None
    print(f"work cell: {record['path']}, as recorded in {args.solution}")
    return recorded_cell(record, str(args.solution))


def _check_grasps(
    args: argparse.Namespace,
    instance: Instance,
    plan: Plan,
    kits: list[int] | None,
    *,
    declared: bool,
) -> tuple[GraspCheck, ...]:
    """The gripper's feasibility pass (none with ``--grasp-check off``); with ``strict``,
    exit 2 on the first part that fails it. ``auto`` is ``strict`` when a work cell declares
    the gripper (a plan its declared gripper cannot place is an error) and ``warn`` when the
    URDF's fingers are only assumed (docs/execution.md#the-gripper)."""
    from ..errors import UsageError
    from ..sawyer.gripper import check_grasps

    if args.grasp_check == "off":
        return ()
    checks = check_grasps(instance, plan, kits)
    bad = [c for c in checks if c.problem]
    strict = args.grasp_check == "strict" or (args.grasp_check == "auto" and declared)
    if bad and strict:
        raise UsageError(
            f"{args.solution}: {bad[0].problem} ({len(bad)} of {len(checks)} part(s) fail "
            "the gripper check; nothing written)"
        )
    return checks


def _mm(value: float) -> str:
    """A clearance to two decimals, a touching finger as 0.00 (never -0.00)."""
    return f"{round(value, 2) + 0.0:.2f}"


def _grip_line(checks: tuple[GraspCheck, ...], work_cell: str | None) -> str:
    """One line: how many parts fail the gripper's pass and why, or the fingers' smallest
    clearances when none does."""
    bad = [c for c in checks if c.problem]
    if not bad:
        tray = min(checks, key=lambda c: c.tray_clearance)
        near = min(checks, key=lambda c: c.part_clearance)
        line = (
            f"gripper: all {len(checks)} part(s) pass; smallest finger clearance to the tray "
            f"{_mm(tray.tray_clearance)} mm (kit {tray.kit}, {tray.part})"
        )
        if near.nearest:
            gap = _mm(near.part_clearance)
            line += f", to a placed part {gap} mm (kit {near.kit}, {near.part})"
        return line
    why = {"stroke": "beyond the stroke", "tray": "with fingers off the tray"}
    counts = ", ".join(
        f"{sum(c.fault == f for c in bad)} {why.get(f, 'with fingers on a placed part')}"
        for f in ("stroke", "tray", "part")
        if any(c.fault == f for c in bad)
    )
    hint = "--grasp-check strict makes this exit 2"
    if work_cell is None and any(c.fault == "stroke" for c in bad):
        hint = "declare the gripper and grasp widths with --work-cell; " + hint
    return (
        f"gripper: {len(bad)} of {len(checks)} part(s) fail the check ({counts}); first: "
        f"{bad[0].problem}; {hint} (docs/execution.md#the-gripper)"
    )


def _report(ex: Execution, cap: float) -> None:
    from ..sawyer.trajectory import verify

    n_parts = sum(len(layout) for layout in ex.layouts.values())
    print(f"{ex.instance}: {len(ex.layouts)} of {ex.n_plan_kits} kits, {n_parts} parts")
    print("kit  parts  robot start  arm start  trajectory  modelled  difference  plan robot  slack")
    print("                   (s)        (s)        (s)       (s)        (s)        (s)     (s)")
    overhead = {kt.kit: kt.start - kt.plan.robot_start for kt in ex.kits}
    for kt in ex.kits:
        plan_robot = kt.plan.robot_end - kt.plan.robot_start - overhead[kt.kit]
        print(
            f"{kt.kit:>3}  {len(kt.parts):>5}  {kt.plan.robot_start:>11.3f}  {kt.start:>9.3f}  "
            f"{kt.duration:>10.3f}  {kt.modelled:>8.3f}  {kt.duration - kt.modelled:>10.1e}  "
            f"{plan_robot:>10.3f}  {kt.plan.robot_end - kt.end:>6.3f}"
        )
        if kt.extra > 0:
            print(f"     kit {kt.kit}: {kt.extra:.3f} s of bin changes (not in the motion model)")
        if kt.overrun > 0:
            print(
                f"     warning: kit {kt.kit}'s arm ends {kt.overrun:.3f} s after the plan's "
                'push; "robot_times": "motion" in the instance makes the plan use the arm\'s '
                "times (docs/execution.md#what-the-robot-does-and-when)"
            )
    v = verify(ex)
    print(
        f"largest |trajectory - modelled - bin changes|: {v.duration_error:.1e} s; closest to a "
        f"joint position limit: {v.position_margin:.3f} rad ({v.margin_joint}); peak speed "
        f"{100 * v.speed_share:.1f}% of the velocity limit ({100 * v.fd_speed_share:.1f}% by "
        f"finite differences); FK error at place waypoints {1000 * v.place_error:.4f} mm, at "
        f"grasp waypoints {1000 * v.grasp_error:.4f} mm; peak tool speed "
        f"{v.tool_speed:.3f} m/s (cap {cap:g} m/s)"
    )


def _describe(info: BagInfo) -> str:
    from ..sawyer.bags import (
        EVENTS_TOPIC,
        GRIPPER_TOPIC,
        JOINT_STATES_TOPIC,
        TF_TOPIC,
        TRAJECTORY_TOPIC,
    )
    from ..sawyer.moveit import DISPLAY_TOPIC
    from ..style import plural

    c = info.counts
    return (
        f"wrote {info.path} ({info.format.upper()} bag, {info.size / 1e3:.0f} kB, "
        f"{info.n_messages} messages: {c[TRAJECTORY_TOPIC]} "
        f"{'trajectory' if c[TRAJECTORY_TOPIC] == 1 else 'trajectories'}, "
        f"{c[DISPLAY_TOPIC]} on {DISPLAY_TOPIC}, "
        f"{plural(c[GRIPPER_TOPIC], 'gripper command')}, "
        f"{c[JOINT_STATES_TOPIC]} on {JOINT_STATES_TOPIC}, {c[TF_TOPIC]} on {TF_TOPIC}, "
        f"{plural(c[EVENTS_TOPIC], 'event stamp')})"
    )


@contextlib.contextmanager
def _writing(target: Path | str) -> Iterator[None]:
    """An OS error while writing ``target`` as a one-line usage error (exit 2)."""
    from ..errors import UsageError

    try:
        yield
    except OSError as exc:
        raise UsageError(f"cannot write {target}: {exc.strerror or exc}; nothing written") from None


def _write(
    ex: Execution, targets: dict[str, Path], html: str | None, page: str | None
) -> list[BagInfo]:
    """Write every output through one staging: all of them, or none."""
    from ..sawyer.bags import BagInfo, write_bag

    infos = []
    with _writing("the outputs"), _staging() as staging:
        for fmt, target in targets.items():
            with _writing(target):
                info = write_bag(ex, staging.path(target), fmt)
            infos.append(BagInfo(fmt, target, info.size, info.counts))
        if html is not None and page is not None:
            with _writing(html), open(staging.path(Path(html)), "w", encoding="utf-8") as fh:
                fh.write(page)
    return infos


def run(args: argparse.Namespace) -> int:
    ex, checks, cell = _load(args)
    targets = _bag_targets(args, _stem(args))  # as checked up front (:func:`_outputs`)
    page = None
    if args.html:
        from ..sawyer.scene import html_page

        page = html_page(ex)
    infos = _write(ex, targets, args.html, page)
    _report(ex, args.tool_speed)
    if checks:
        print(_grip_line(checks, cell))
    for info in infos:
        print(_describe(info))
    if page is not None:
        print(f"wrote {args.html} (animated 3-D view, {len(page.encode()) / 1e6:.2f} MB)")
    return EXIT_OK
