"""Figures of an execution: one kit's joint positions and velocities against time, with the
joint limits drawn (docs/execution.md), in the toolkit's style (docs/figures.md).

Each ``plot_*`` function draws into ``ax`` when given (else a new figure) and returns the
Axes; :func:`plot_kit_trajectory` stacks both and returns the Figure. Grasps and releases
are shaded, so the eight steps of each part's cycle can be told apart.

Curves are drawn from the exact motion profile (:meth:`KitTrajectory.states_at`) on a grid of
:data:`DRAW_DT`, not from the trajectory's samples, so a coarse ``dt`` never shows. The
velocities are piecewise linear because the motion model's moves are trapezoidal (docs/
execution.md): straight ramps, and a peak where a short move never reaches its cruise speed.
Both panels are in % of each joint's limits, so the limits are two shared lines.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np

from ..style import PALETTE, styled
from .model import JOINT_NAMES, Q_LOWER, Q_UPPER
from .trajectory import DWELLS, KitTrajectory

#: Step (s) of the grid the curves are drawn on.
DRAW_DT = 0.01

if TYPE_CHECKING:
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure


def _axes(ax: Axes | None) -> Axes:
    if ax is not None:
        return ax
    import matplotlib.pyplot as plt

    _, new = plt.subplots(figsize=(8, 3.2))
    return new


def _grid(traj: KitTrajectory) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Times on a :data:`DRAW_DT` grid (and every sample time, so no corner is cut) and the
    exact positions and velocities there."""
    n = max(2, int(np.ceil(traj.duration / DRAW_DT)) + 1)
    t = np.union1d(np.linspace(0.0, traj.duration, n), traj.times)
    q, qd = traj.states_at(t)
    return t, q, qd


def _limits(ax: Axes, kind: str) -> None:
    for bound in (0.0, 100.0) if kind == "position" else (-100.0, 100.0):
        ax.axhline(bound, color="black", ls="--", lw=0.8, zorder=1, gid=f"limit:{kind}")


def _legend(ax: Axes) -> None:
    """The joints' legend right of the axes, never over the curves."""
    ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), borderaxespad=0.0, frameon=False)


def _dwells(ax: Axes, traj: KitTrajectory) -> None:
    for seg in traj.segments:
        if seg.name in DWELLS:
            ax.axvspan(seg.start, seg.end, color="0.85", lw=0, zorder=0, gid=f"{seg.name}")


@styled
def plot_joint_positions(traj: KitTrajectory, ax: Axes | None = None) -> Axes:
    """Joint angles as a share of each joint's range (0 % its lower limit, 100 % its upper:
    the limits of all seven joints are the two dashed lines, not fourteen lines on top of each
    other), the legend beside the axes."""
    ax = _axes(ax)
    _dwells(ax, traj)
    t, q, _ = _grid(traj)
    share = 100.0 * (q - Q_LOWER) / (Q_UPPER - Q_LOWER)
    for i, name in enumerate(JOINT_NAMES):
        ax.plot(t, share[:, i], color=PALETTE[i], label=name, gid=f"q:{name}", zorder=2)
    _limits(ax, "position")
    ax.set_xlim(0.0, traj.duration)
    ax.set_ylim(-8.0, 108.0)
    ax.set_xlabel("time from the kit's arm start (s)")
    ax.set_ylabel("joint angle (% of its range)")
    ax.set_title(
        f"kit {traj.kit}: joint positions ({len(traj.parts)} parts, {traj.duration:.2f} s); "
        "dashed: limits, grey: grasp and release"
    )
    _legend(ax)
    return ax


@styled
def plot_joint_velocities(traj: KitTrajectory, ax: Axes | None = None) -> Axes:
    """Joint velocities as a share of each joint's limit (the limits are the +-100 % lines),
    from the exact trapezoidal profiles: straight ramps, peaks where a move is too short to
    reach its cruise speed."""
    ax = _axes(ax)
    _dwells(ax, traj)
    t, _, qd = _grid(traj)
    share = 100.0 * qd / traj.params.v_max
    for i, name in enumerate(JOINT_NAMES):
        ax.plot(t, share[:, i], color=PALETTE[i], label=name, gid=f"v:{name}", zorder=2)
    _limits(ax, "velocity")
    ax.set_xlim(0.0, traj.duration)
    ax.set_ylim(-115.0, 115.0)
    ax.set_xlabel("time from the kit's arm start (s)")
    ax.set_ylabel("velocity (% of the limit)")
    ax.set_title(f"kit {traj.kit}: joint velocities, trapezoidal moves (dashed: velocity limits)")
    return ax


@styled
def plot_kit_trajectory(traj: KitTrajectory) -> Figure:
    """Positions above velocities, sharing the time axis."""
    import matplotlib.pyplot as plt

    fig, (top, bottom) = plt.subplots(2, 1, figsize=(9, 6), sharex=True, layout="constrained")
    plot_joint_positions(traj, top)
    plot_joint_velocities(traj, bottom)
    top.set_xlabel("")
    return fig


def limit_lines(ax: Axes) -> list[Any]:
    """The limit lines drawn on ``ax`` (tests find them by their ``gid``)."""
    return [line for line in ax.get_lines() if str(line.get_gid()).startswith("limit:")]


def velocity_share(traj: KitTrajectory) -> np.ndarray:
    """Per joint, the largest |velocity| as a share of its limit."""
    return np.abs(traj.velocities).max(axis=0) / traj.params.v_max
