"""Reachability of tray points: maps over the whole tray and exact checks of given points.

A tray point (x, y) in mm is *reachable* when a top-down grasp IK (:mod:`.ik`) converges for
the tool tip at the release pose, ``work_cell.place_height`` above the tray surface, with one of
the work cell's allowed gripper yaws, and (by default) the approach pose ``approach_height``
above it is reachable too. Because the tool lies on the last joint's axis and that joint
spans 540 deg, the answer does not depend on which yaws are allowed (see :mod:`.ik`).

Maps are built in a serpentine sweep (row 0 left to right, row 1 right to left, ...), each
cell warm-started from the previous cell's solution, so most cells converge in a few
iterations; only cells whose warm start fails fall back to the neutral seeds and
:data:`MAP_SEEDS` random seeds (fewer than the exact check's, which keeps maps of partly
reachable trays fast: cells beyond the reach fail every seed).
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from .cell import WorkCell
from .errors import UnreachableError
from .ik import N_SEEDS, IKSolution, solve_top_down
from .model import Arm

if TYPE_CHECKING:  # pragma: no cover - typing only
    from matplotlib.axes import Axes

#: Random IK seeds per map cell whose warm start failed (exact checks use ``ik.N_SEEDS``).
MAP_SEEDS = 2


@dataclass(frozen=True, eq=False)
class ReachMap:
    """Reachability of the cells of a ``width`` x ``height`` mm tray.

    Arrays are indexed ``[row, column]`` = ``[y index, x index]``; cell centres are ``xs``
    (columns) and ``ys`` (rows) in mm in the tray frame. Cells tile the tray exactly, so the
    cell size is at most the requested resolution. Unreachable cells have manipulability 0,
    NaN configurations and NaN yaw.
    """

    work_cell: WorkCell
    width: float
    height: float
    xs: np.ndarray
    ys: np.ndarray
    reachable: np.ndarray
    #: Yoshikawa's measure sqrt(det(J J^T)) of the 6 x 7 tool Jacobian (base-aligned; linear
    #: rows in m, angular rows in rad), 0 where unreachable.
    manipulability: np.ndarray
    #: IK solutions, shape (ny, nx, 7).
    configs: np.ndarray
    #: Gripper yaw used per cell, degrees from the tray x axis.
    yaws: np.ndarray
    #: Wall-clock seconds spent building the map.
    build_time: float = 0.0

    @property
    def shape(self) -> tuple[int, int]:
        return self.reachable.shape  # type: ignore[return-value]

    @property
    def cell_size(self) -> tuple[float, float]:
        """(cell width, cell height) in mm."""
        return self.width / len(self.xs), self.height / len(self.ys)

    @property
    def fraction(self) -> float:
        """Share of reachable cells."""
        return float(self.reachable.mean())

    @property
    def is_empty(self) -> bool:
        return not bool(self.reachable.any())

    def cell_index(self, x_mm: float, y_mm: float) -> tuple[int, int] | None:
        """(row, column) of the cell containing the point; None outside the tray. Points on
        the tray's far edges belong to the last cells."""
        if not (0.0 <= x_mm <= self.width and 0.0 <= y_mm <= self.height):
            return None
        cw, ch = self.cell_size
        col = min(int(x_mm // cw), len(self.xs) - 1)
        row = min(int(y_mm // ch), len(self.ys) - 1)
        return row, col

    def reachable_at(self, x_mm: float, y_mm: float) -> bool:
        """Whether the cell containing (x, y) mm is reachable; False outside the tray."""
        idx = self.cell_index(x_mm, y_mm)
        return idx is not None and bool(self.reachable[idx])

    def lookup(self, points: Iterable[Sequence[float]]) -> np.ndarray:
        """:meth:`reachable_at` of every (x, y) point, as a bool array."""
        return np.array([self.reachable_at(float(p[0]), float(p[1])) for p in points], dtype=bool)


def _grid(width: float, height: float, resolution: float) -> tuple[np.ndarray, np.ndarray]:
    if not (width > 0 and height > 0):
        raise ValueError(f"tray size must be positive, got {width} x {height} mm")
    if not resolution > 0:
        raise ValueError(f"resolution must be positive, got {resolution} mm")
    nx = max(1, math.ceil(width / resolution - 1e-9))
    ny = max(1, math.ceil(height / resolution - 1e-9))
    return (np.arange(nx) + 0.5) * (width / nx), (np.arange(ny) + 0.5) * (height / ny)


def _approach(
    arm: Arm, sol: IKSolution, point: np.ndarray, rise_m: float, q_hint: np.ndarray | None = None
) -> np.ndarray | None:
    """IK of the pose ``rise_m`` above a solved grasp: warm-started from ``q_hint`` (the
    previous map cell's approach pose), then from the grasp solution, then from the seeds.
    Returns the configuration or None."""
    target = point + np.array([0.0, 0.0, rise_m])
    yaw = (sol.yaw_deg,)
    for q0 in (q_hint, sol.q):
        if q0 is not None:
            up = solve_top_down(arm, target, yaw, q_init=q0, n_seeds=0, max_iter=30)
            if up is not None:
                return up.q
    up = solve_top_down(arm, target, yaw)
    return None if up is None else up.q


def build_reach_map(
    work_cell: WorkCell,
    width: float,
    height: float,
    resolution: float = 10.0,
    *,
    approach: bool = True,
    n_seeds: int = MAP_SEEDS,
    seed: int = 0,
) -> ReachMap:
    """Reachability map of a ``width`` x ``height`` mm tray at ``resolution`` mm per cell.

    A 600 x 400 mm tray at 10 mm gives 60 x 40 cells. With ``approach`` (the default, as in
    :func:`check_points`) a cell also needs the approach pose above it; ``approach=False``
    checks the release pose only (about 0.7x the time). Deterministic for given arguments.
    """
    import time

    start = time.perf_counter()
    xs, ys = _grid(float(width), float(height), float(resolution))
    nx, ny = len(xs), len(ys)
    arm = Arm(work_cell.tool_offset_m)
    base_yaws = work_cell.slot_yaws()
    rise = work_cell.approach_height / 1000.0
    reachable = np.zeros((ny, nx), dtype=bool)
    manip = np.zeros((ny, nx))
    configs = np.full((ny, nx, 7), np.nan)
    yaws = np.full((ny, nx), np.nan)
    points = work_cell.tray_to_base(xs[None, :], ys[:, None], work_cell.place_height)
    q_prev: np.ndarray | None = None
    q_prev_up: np.ndarray | None = None
    for row in range(ny):
        cols = range(nx) if row % 2 == 0 else range(nx - 1, -1, -1)
        for col in cols:
            p = points[row, col]
            sol = solve_top_down(arm, p, base_yaws, q_init=q_prev, n_seeds=n_seeds, seed=seed)
            if sol is None:
                continue
            if approach:
                q_up = _approach(arm, sol, p, rise, q_prev_up)
                if q_up is None:
                    continue
                q_prev_up = q_up
            reachable[row, col] = True
            configs[row, col] = sol.q
            yaws[row, col] = work_cell.grasp_yaws[base_yaws.index(sol.yaw_deg)]
            manip[row, col] = arm.manipulability(sol.q)
            q_prev = sol.q
    return ReachMap(
        work_cell,
        float(width),
        float(height),
        xs,
        ys,
        reachable,
        manip,
        configs,
        yaws,
        time.perf_counter() - start,
    )


def check_points(
    work_cell: WorkCell,
    points: Iterable[Sequence[float]],
    *,
    approach: bool = True,
    n_seeds: int = N_SEEDS,
    seed: int = 0,
) -> np.ndarray:
    """Exact reachability of tray points (x, y) in mm, one bool per point.

    Each point is solved on its own from the fixed seed list (no warm start), so the answer
    for a point does not depend on the other points or their order: this is the test for the
    checker and the packers. ``approach=True`` also requires the approach pose above it.
    """
    arm = Arm(work_cell.tool_offset_m)
    yaws = work_cell.slot_yaws()
    rise = work_cell.approach_height / 1000.0
    out = []
    for pt in points:
        p = work_cell.tray_to_base(float(pt[0]), float(pt[1]), work_cell.place_height)
        sol = solve_top_down(arm, p, yaws, n_seeds=n_seeds, seed=seed)
        out.append(sol is not None and (not approach or _approach(arm, sol, p, rise) is not None))
    return np.array(out, dtype=bool)


def ensure_placeable(reach_map: ReachMap, what: str = "a kit") -> ReachMap:
    """Return the map, or raise :class:`UnreachableError` when no cell is reachable, i.e.
    when ``what`` cannot be placed anywhere on the tray."""
    if reach_map.is_empty:
        s = reach_map.work_cell
        raise UnreachableError(
            f"cannot place {what}: no point of the {reach_map.width:g} x {reach_map.height:g} "
            f"mm tray is reachable by the Sawyer (tray corner at ({s.tray_x:g}, {s.tray_y:g}, "
            f"{s.tray_z:g}) mm, yaw {s.tray_yaw:g} deg, in the robot base frame); move the "
            "tray closer to the robot"
        )
    return reach_map


def ensure_points_reachable(
    work_cell: WorkCell, points: Sequence[Sequence[float]], labels: Sequence[str] | None = None
) -> None:
    """Raise :class:`UnreachableError` listing the points (x, y mm) the robot cannot reach."""
    ok = check_points(work_cell, points)
    if ok.all():
        return
    names = labels if labels is not None else [f"({p[0]:g}, {p[1]:g})" for p in points]
    bad = [str(n) for n, good in zip(names, ok, strict=True) if not good]
    raise UnreachableError(f"unreachable tray point(s): {', '.join(bad)}")


def plot_reach_map(
    reach_map: ReachMap,
    layout: Iterable[Any] | None = None,
    ax: Axes | None = None,
    title: str | None = None,
) -> Axes:
    """Draw the map (manipulability of reachable cells, grey where unreachable) in tray mm.

    ``layout`` is a sequence of objects with ``x``, ``y`` (centre, mm), ``theta`` (deg), ``w``,
    ``h`` (mm), e.g. :class:`bilevel_kit.plan.Placement`; they are drawn as rotated
    rectangles, red when their centre lies on an unreachable cell. Works with the Agg backend.
    """
    import matplotlib.pyplot as plt
    from matplotlib.colors import ListedColormap
    from matplotlib.patches import Polygon

    if ax is None:
        _, ax = plt.subplots(figsize=(7, 7 * reach_map.height / max(reach_map.width, 1e-9) + 0.8))
    extent = (0.0, reach_map.width, 0.0, reach_map.height)
    ax.imshow(
        np.where(reach_map.reachable, 0.0, 1.0),
        origin="lower",
        extent=extent,
        cmap=ListedColormap(["white", "0.6"]),
        vmin=0,
        vmax=1,
        interpolation="nearest",
    )
    data = np.ma.masked_where(~reach_map.reachable, reach_map.manipulability)
    image = ax.imshow(data, origin="lower", extent=extent, cmap="viridis", interpolation="nearest")
    if not reach_map.is_empty:
        ax.figure.colorbar(image, ax=ax, label="manipulability sqrt(det(J J^T))", shrink=0.8)
    for item in layout or ():
        t = math.radians(float(item.theta))
        c, s = math.cos(t), math.sin(t)
        hw, hh = float(item.w) / 2.0, float(item.h) / 2.0
        corners = [
            (float(item.x) + c * u - s * v, float(item.y) + s * u + c * v)
            for u, v in ((-hw, -hh), (hw, -hh), (hw, hh), (-hw, hh))
        ]
        ok = reach_map.reachable_at(float(item.x), float(item.y))
        ax.add_patch(
            Polygon(corners, closed=True, fill=False, lw=1.5, edgecolor="white" if ok else "red")
        )
        ax.plot([item.x], [item.y], marker="+", color="white" if ok else "red")
    ax.set_xlim(0, reach_map.width)
    ax.set_ylim(0, reach_map.height)
    ax.set_aspect("equal")
    ax.set_xlabel("tray x (mm)")
    ax.set_ylabel("tray y (mm)")
    ny, nx = reach_map.shape
    ax.set_title(title or f"Sawyer reachability: {reach_map.fraction:.0%} of {nx} x {ny} cells")
    return ax
