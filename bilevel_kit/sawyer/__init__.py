"""Sawyer reachability of tray slots and robot motion times (Pinocchio).

Modules: :mod:`.model` (the 7-dof arm built in code, FK), :mod:`.cell` (the work cell: tray
and bin poses, mm), :mod:`.ik` (top-down grasp IK), :mod:`.reach` (reachability maps and
checks, plotting), :mod:`.motion` (pick-and-place times). Pinocchio is imported only when a
model is built, so importing this package is cheap. Executing a plan (docs/execution.md) lives
in submodules this package does not import: :mod:`.trajectory` (per-kit joint trajectories and
the timeline's events), :mod:`.bags` (ROS 1 and ROS 2 bags), :mod:`.scene` (the animated 3-D
view) and :mod:`.figures` (joint trajectory plots).

Units: the public API takes tray points in mm (tray frame) and work-cell poses in mm (robot
base frame); the model and IK work in metres and radians.

``Station``, ``DEFAULT_STATION``, ``StationError`` and ``station_schema`` are the former names of
:class:`WorkCell`, :data:`DEFAULT_WORK_CELL`, :class:`WorkCellError` and
:func:`work_cell_schema`, kept importable from this package (CHANGELOG.md); new code uses the
new names (a work cell is not an assembly station, docs/stations.md).
"""

from .cell import DEFAULT_WORK_CELL, WorkCell, work_cell_schema
from .errors import UnreachableError, WorkCellError
from .ik import (
    POS_TOL,
    ROT_TOL,
    IKSolution,
    clik,
    clik_down,
    ik_top_down,
    out_of_reach,
    solve_pose,
    solve_top_down,
    top_down_rotation,
    with_yaw,
)
from .model import (
    ELECTRIC_GRIPPER_TIP,
    JOINT_NAMES,
    LIMIT_PROFILES,
    Q_LOWER,
    Q_NEUTRAL,
    Q_UPPER,
    V_MAX,
    Arm,
    build_model,
    fk_hand,
    fk_tool,
    within_limits,
)
from .motion import (
    A_MAX,
    DEFAULT_PARAMS,
    MotionParams,
    PickPlace,
    layout_time,
    move_profile,
    move_time,
    pick_place,
    pick_place_time,
    trapezoid_time,
    tray_average_time,
)
from .reach import (
    ReachMap,
    build_reach_map,
    check_points,
    ensure_placeable,
    ensure_points_reachable,
    plot_reach_map,
)

#: Former names (see the module docstring).
Station = WorkCell
DEFAULT_STATION = DEFAULT_WORK_CELL
StationError = WorkCellError
station_schema = work_cell_schema

__all__ = [
    "A_MAX",
    "DEFAULT_PARAMS",
    "DEFAULT_STATION",
    "DEFAULT_WORK_CELL",
    "ELECTRIC_GRIPPER_TIP",
    "JOINT_NAMES",
    "LIMIT_PROFILES",
    "POS_TOL",
    "Q_LOWER",
    "Q_NEUTRAL",
    "Q_UPPER",
    "ROT_TOL",
    "V_MAX",
    "Arm",
    "IKSolution",
    "MotionParams",
    "PickPlace",
    "ReachMap",
    "Station",
    "StationError",
    "UnreachableError",
    "WorkCell",
    "WorkCellError",
    "build_model",
    "build_reach_map",
    "check_points",
    "clik",
    "clik_down",
    "ensure_placeable",
    "ensure_points_reachable",
    "fk_hand",
    "fk_tool",
    "ik_top_down",
    "layout_time",
    "move_profile",
    "move_time",
    "out_of_reach",
    "pick_place",
    "pick_place_time",
    "plot_reach_map",
    "solve_pose",
    "solve_top_down",
    "station_schema",
    "top_down_rotation",
    "trapezoid_time",
    "tray_average_time",
    "with_yaw",
    "within_limits",
    "work_cell_schema",
]
