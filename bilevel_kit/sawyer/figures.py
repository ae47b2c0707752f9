"""Figures of an execution: one kit's joint positions and velocities against time, with the
joint limits drawn (docs/execution.md), in the toolkit's style (docs/figures.md).

Each ``plot_*`` function draws into ``ax`` when given (else a new figure) and returns the
Axes; :func:`plot_kit_trajectory` stacks both and returns the Figure. Grasps and releases
are shaded, so the eight steps of each part's cycle can be told apart.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np

from ..style import PALETTE, styled
from .model import JOINT_NAMES, Q_LOWER, Q_UPPER
from .trajectory import DWELLS, KitTrajectory

if TYPE_CHECKING:
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure


def _axes(ax: Axes | None) -> Axes:
    if ax is not None:
        return ax
    import matplotlib.pyplot as plt

    _, new = plt.subplots(figsize=(8, 3.2))
    return new


def _dwells(ax: Axes, traj: KitTrajectory) -> None:
    for seg in traj.segments:
        if seg.name in DWELLS:
            ax.axvspan(seg.start, seg.end, color="0.85", lw=0, zorder=0, gid=f"{seg.name}")


@styled
def plot_joint_positions(traj: KitTrajectory, ax: Axes | None = None) -> Axes:
    """Joint angles (rad) against time, each joint's position limits dashed in its colour."""
    ax = _axes(ax)
    _dwells(ax, traj)
    for i, name in enumerate(JOINT_NAMES):
        color = PALETTE[i]
        ax.plot(traj.times, traj.positions[:, i], color=color, label=name, gid=f"q:{name}")
        for bound in (Q_LOWER[i], Q_UPPER[i]):
            ax.axhline(bound, color=color, ls="--", lw=0.7, alpha=0.7, gid=f"limit:{name}")
    ax.set_xlim(0.0, traj.duration)
    ax.set_ylim(float(Q_LOWER.min()) - 0.3, float(Q_UPPER.max()) + 0.3)
    ax.set_xlabel("time from the kit's arm start (s)")
    ax.set_ylabel("joint angle (rad)")
    ax.set_title(
        f"kit {traj.kit}: joint positions ({len(traj.parts)} parts, {traj.duration:.2f} s); "
        "dashed: limits, grey: grasp and release"
    )
    ax.legend(loc="lower center", ncol=7, fontsize="small", frameon=True, framealpha=0.9)
    return ax


@styled
def plot_joint_velocities(traj: KitTrajectory, ax: Axes | None = None) -> Axes:
    """Joint velocities as a share of each joint's limit (the limits are the +-100 % lines):
    the joint that governs each move touches them."""
    ax = _axes(ax)
    _dwells(ax, traj)
    share = 100.0 * traj.velocities / traj.params.v_max
    for i, name in enumerate(JOINT_NAMES):
        ax.plot(traj.times, share[:, i], color=PALETTE[i], label=name, gid=f"v:{name}")
    for bound in (-100.0, 100.0):
        ax.axhline(bound, color="black", ls="--", lw=0.8, gid="limit:velocity")
    ax.set_xlim(0.0, traj.duration)
    ax.set_ylim(-115.0, 115.0)
    ax.set_xlabel("time from the kit's arm start (s)")
    ax.set_ylabel("velocity (% of the limit)")
    ax.set_title(f"kit {traj.kit}: joint velocities (dashed: velocity limits)")
    return ax


@styled
def plot_kit_trajectory(traj: KitTrajectory) -> Figure:
    """Positions above velocities, sharing the time axis."""
    import matplotlib.pyplot as plt

    fig, (top, bottom) = plt.subplots(2, 1, figsize=(8, 6), sharex=True)
    plot_joint_positions(traj, top)
    plot_joint_velocities(traj, bottom)
    top.set_xlabel("")
    fig.tight_layout()
    return fig


def limit_lines(ax: Axes) -> list[Any]:
    """The limit lines drawn on ``ax`` (tests find them by their ``gid``)."""
    return [line for line in ax.get_lines() if str(line.get_gid()).startswith("limit:")]


def velocity_share(traj: KitTrajectory) -> np.ndarray:
    """Per joint, the largest |velocity| as a share of its limit."""
    return np.abs(traj.velocities).max(axis=0) / traj.params.v_max
