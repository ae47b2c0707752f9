"""Figures: the robot/human Gantt chart, tray layouts and cross-entropy convergence.

Every ``plot_*`` function draws into ``ax`` when one is given (otherwise it makes a new figure)
and returns the Axes; :func:`plot_trays` makes many Axes and returns the Figure. Nothing here
calls ``plt.show``: write figures with :func:`save_figure`, which also closes them.

The artists carry ``gid`` tags so that tests and callers can find them again:

* Gantt chart: ``robot:kit:<k>``, ``robot:delivery:<k>``, ``robot:idle``, ``human:pickup:<k>``,
  ``human:task:<task id>``, ``human:idle`` (bar Rectangles), ``makespan`` (the vertical line).
* Tray: ``tray`` (the outline Rectangle), ``part:<part id>`` (one Polygon per placement).

Bars of zero duration (no delivery time, no pickup overhead ...) are not drawn.
"""

from __future__ import annotations

import math
import os
from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from . import atomic
from .geometry import corners
from .instance import Instance
from .plan import Kit, Plan, Timeline, evaluate

if TYPE_CHECKING:
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure

#: Lane positions (y) and bar height of the Gantt chart.
ROBOT_Y = 1.0
HUMAN_Y = 0.0
BAR_HEIGHT = 0.6

_DELIVERY_COLOR = "#9e9e9e"
_PICKUP_COLOR = "#5d5d5d"
_IDLE_COLOR = "#e57373"
_MAKESPAN_COLOR = "#b71c1c"
_UNKNOWN_TYPE_COLOR = "#bdbdbd"


def _pyplot() -> Any:
    import matplotlib.pyplot as plt

    return plt


def _kit_color(k: int) -> Any:
    """Colour of kit ``k`` (0-based): its robot kitting bar and (lighter) its tasks."""
    from matplotlib import colormaps

    return colormaps["tab10"](k % 10)


def _lighten(color: Any, amount: float = 0.45) -> tuple[float, float, float, float]:
    from matplotlib.colors import to_rgba

    r, g, b, a = to_rgba(color)
    return (r + (1 - r) * amount, g + (1 - g) * amount, b + (1 - b) * amount, a)


def _idle_intervals(
    busy: Sequence[tuple[float, float]], end: float, tol: float = 1e-9
) -> list[tuple[float, float]]:
    """Gaps of [0, end] not covered by the (sorted, disjoint) busy intervals."""
    gaps: list[tuple[float, float]] = []
    clock = 0.0
    for s, e in busy:
        if s > clock + tol:
            gaps.append((clock, s))
        clock = max(clock, e)
    if end > clock + tol:
        gaps.append((clock, end))
    return gaps


def _bar(ax: Axes, y: float, start: float, end: float, gid: str, **style: Any) -> Any:
    """One horizontal bar from ``start`` to ``end`` in the lane at ``y`` (None if empty)."""
    if end - start <= 0:
        return None
    (rect,) = ax.barh(y, end - start, left=start, height=BAR_HEIGHT, **style).patches
    rect.set_gid(gid)
    return rect


def plot_gantt(
    instance: Instance, plan: Plan, timeline: Timeline | None = None, ax: Axes | None = None
) -> Axes:
    """Gantt chart of the robot and the human (docs/timeline.md).

    Robot lane: one kitting bar per kit (``robot_start``..``robot_end``, labelled "kit k", in
    the kit's colour) and one hatched delivery bar (``robot_end``..``arrive``). Human lane: the
    kit pickup overhead, then each task (``task_start``..``task_end``, labelled with its id, in a
    lighter shade of its kit's colour). Idle time of either lane is hatched red; a vertical line
    marks the makespan. ``timeline`` defaults to :func:`bilevel_kit.plan.evaluate` of the plan
    (pass one to draw e.g. a simulated run).
    """
    from matplotlib.lines import Line2D
    from matplotlib.patches import Patch

    tl = timeline if timeline is not None else evaluate(instance, plan)
    if ax is None:
        n_tasks = sum(len(k.tasks) for k in plan.kits)
        width = float(np.clip(4.0 + 0.55 * n_tasks, 8.0, 20.0))
        _, ax = _pyplot().subplots(figsize=(width, 3.6), layout="constrained")
    makespan = tl.makespan
    label_size = 7
    oh = instance.kit_overhead_human

    for k, (kit, kt) in enumerate(zip(plan.kits, tl.kits, strict=False)):
        color = _kit_color(k)
        rect = _bar(
            ax,
            ROBOT_Y,
            kt.robot_start,
            kt.robot_end,
            f"robot:kit:{k + 1}",
            color=color,
            edgecolor="black",
            linewidth=0.6,
        )
        if rect is not None:
            ax.text(
                (kt.robot_start + kt.robot_end) / 2,
                ROBOT_Y,
                f"kit {k + 1}",
                ha="center",
                va="center",
                fontsize=label_size + 1,
                clip_on=True,
            )
        _bar(
            ax,
            ROBOT_Y,
            kt.robot_end,
            kt.arrive,
            f"robot:delivery:{k + 1}",
            color=_DELIVERY_COLOR,
            edgecolor="black",
            linewidth=0.6,
            hatch="//",
        )
        _bar(
            ax,
            HUMAN_Y,
            kt.human_start,
            min(kt.human_start + oh, kt.human_end),
            f"human:pickup:{k + 1}",
            color=_PICKUP_COLOR,
            edgecolor="black",
            linewidth=0.6,
            hatch="xx",
        )
        light = _lighten(color)
        for j, t in enumerate(kit.tasks):
            if t not in tl.task_start:
                continue
            s, e = tl.task_start[t], tl.task_end[t]
            if (
                _bar(
                    ax,
                    HUMAN_Y,
                    s,
                    e,
                    f"human:task:{t}",
                    color=light,
                    edgecolor="black",
                    linewidth=0.6,
                )
                is not None
            ):
                # stagger neighbouring labels so that short tasks stay readable
                dy = BAR_HEIGHT * (0.18 if j % 2 == 0 else -0.18)
                ax.text(
                    (s + e) / 2,
                    HUMAN_Y + dy,
                    t,
                    ha="center",
                    va="center",
                    fontsize=label_size,
                    clip_on=True,
                )

    idle_style = {
        "color": _IDLE_COLOR,
        "alpha": 0.35,
        "hatch": "\\\\",
        "edgecolor": _IDLE_COLOR,
        "linewidth": 0.0,
    }
    robot_busy = [(kt.robot_start, kt.arrive) for kt in tl.kits]
    for s, e in _idle_intervals(robot_busy, makespan):
        _bar(ax, ROBOT_Y, s, e, "robot:idle", **idle_style)
    human_busy = [(kt.human_start, kt.human_end) for kt in tl.kits]
    for s, e in _idle_intervals(human_busy, makespan):
        _bar(ax, HUMAN_Y, s, e, "human:idle", **idle_style)

    ax.axvline(makespan, color=_MAKESPAN_COLOR, linestyle="--", linewidth=1.2, gid="makespan")

    ax.set_yticks([HUMAN_Y, ROBOT_Y], ["human", "robot"])
    ax.set_ylim(HUMAN_Y - 0.6, ROBOT_Y + 0.6)
    right = makespan * 1.02 if makespan > 0 else 1.0
    ax.set_xlim(0.0, right)
    ax.set_xlabel("time (s)")
    ax.grid(axis="x", alpha=0.3)
    ax.set_axisbelow(True)
    ax.set_title(
        f"{instance.name}: makespan {makespan:.1f} s, human idle {tl.human_idle:.1f} s, "
        f"robot idle {tl.robot_idle:.1f} s ({len(tl.kits)} kits)"
    )
    handles = [
        Patch(facecolor=_kit_color(0), edgecolor="black", label="kitting (colour = kit)"),
        Patch(facecolor=_DELIVERY_COLOR, edgecolor="black", hatch="//", label="delivery"),
        Patch(facecolor=_PICKUP_COLOR, edgecolor="black", hatch="xx", label="kit pickup"),
        Patch(facecolor=_lighten(_kit_color(0)), edgecolor="black", label="task"),
        Patch(facecolor=_IDLE_COLOR, alpha=0.35, hatch="\\\\", edgecolor=_IDLE_COLOR, label="idle"),
        Line2D([], [], color=_MAKESPAN_COLOR, linestyle="--", label="makespan"),
    ]
    ax.legend(
        handles=handles,
        loc="upper center",
        bbox_to_anchor=(0.5, -0.2),
        ncols=6,
        fontsize=8,
        frameon=False,
    )
    return ax


def type_colors(instance: Instance) -> dict[str, Any]:
    """A fixed colour per part type: the sorted type ids mapped onto a qualitative colormap,
    so a type has the same colour in every tray plot of the instance."""
    from matplotlib import colormaps

    ids = sorted(instance.part_types)
    cmap = colormaps["tab10" if len(ids) <= 10 else "tab20"]
    return {t: cmap(i % cmap.N) for i, t in enumerate(ids)}


def _label_angle(theta: float, w: float, h: float) -> float:
    """Text rotation along the placement's long side, kept upright (-90, 90]."""
    a = theta if w >= h else theta + 90.0
    a = (a + 90.0) % 180.0 - 90.0
    return 90.0 if a == -90.0 else a


def plot_tray(
    instance: Instance,
    kit: Kit,
    ax: Axes | None = None,
    title: str | None = None,
    *,
    legend: bool = True,
) -> Axes:
    """The kit's tray layout: the tray outline and each placement as a rotated rectangle
    (:func:`bilevel_kit.geometry.corners`) coloured by part type (:func:`type_colors`) and
    labelled with its part id. ``legend=False`` leaves out the legend of part types."""
    from matplotlib.patches import Patch, Polygon, Rectangle

    W, H = instance.tray.width, instance.tray.height
    if ax is None:
        fig_w = 5.5
        _, ax = _pyplot().subplots(figsize=(fig_w + 1.5, fig_w * H / W + 0.8), layout="constrained")
    colors = type_colors(instance)
    ax.add_patch(
        Rectangle(
            (0.0, 0.0),
            W,
            H,
            fill=True,
            facecolor="#f5f5f0",
            edgecolor="black",
            linewidth=1.5,
            gid="tray",
            zorder=1,
        )
    )
    xs, ys = [0.0, W], [0.0, H]
    for p in kit.layout:
        c = corners(p.x, p.y, p.w, p.h, p.theta)
        xs += [float(c[:, 0].min()), float(c[:, 0].max())]
        ys += [float(c[:, 1].min()), float(c[:, 1].max())]
        ax.add_patch(
            Polygon(
                c,
                closed=True,
                facecolor=colors.get(p.type, _UNKNOWN_TYPE_COLOR),
                edgecolor="black",
                linewidth=0.7,
                alpha=0.85,
                gid=f"part:{p.part}",
                zorder=2,
            )
        )
        ax.text(
            p.x,
            p.y,
            p.part,
            ha="center",
            va="center",
            fontsize=6,
            rotation=_label_angle(p.theta, p.w, p.h),
            rotation_mode="anchor",
            zorder=3,
        )
    margin = 0.03 * max(W, H)
    ax.set_xlim(min(xs) - margin, max(xs) + margin)
    ax.set_ylim(min(ys) - margin, max(ys) + margin)
    ax.set_aspect("equal")
    ax.set_xlabel("x (mm)")
    ax.set_ylabel("y (mm)")
    if title is None:
        tasks = ", ".join(kit.tasks)
        if len(tasks) > 40:
            tasks = tasks[:37] + "..."
        title = f"{len(kit.layout)} parts; tasks {tasks}" if kit.tasks else "empty kit"
    ax.set_title(title, fontsize=9)
    if not kit.layout:
        ax.text(W / 2, H / 2, "no layout", ha="center", va="center", color="gray")
    if legend:
        used = sorted({p.type for p in kit.layout})
        if used:
            handles = [
                Patch(facecolor=colors.get(t, _UNKNOWN_TYPE_COLOR), edgecolor="black", label=t)
                for t in used
            ]
            ax.legend(
                handles=handles,
                title="part type",
                fontsize=7,
                title_fontsize=7,
                loc="upper left",
                bbox_to_anchor=(1.02, 1.0),
                borderaxespad=0.0,
            )
    return ax


def plot_trays(instance: Instance, plan: Plan, ncols: int = 3) -> Figure:
    """One :func:`plot_tray` subplot per kit (in delivery order) and one legend of the part
    types used by the plan; returns the Figure (unused grid cells are hidden)."""
    from matplotlib.patches import Patch

    n = len(plan.kits)
    ncols = max(1, min(ncols, n))
    nrows = max(1, math.ceil(n / ncols))
    W, H = instance.tray.width, instance.tray.height
    cell = 3.6
    fig, axes = _pyplot().subplots(
        nrows,
        ncols,
        squeeze=False,
        layout="constrained",
        figsize=(cell * ncols + 1.4, (cell * H / W + 0.7) * nrows),
    )
    flat = list(axes.ravel())
    for k, kit in enumerate(plan.kits):
        tasks = ", ".join(kit.tasks)
        if len(tasks) > 32:
            tasks = tasks[:29] + "..."
        plot_tray(instance, kit, ax=flat[k], title=f"kit {k + 1}: {tasks}", legend=False)
    for ax in flat[n:]:
        ax.set_visible(False)
    if n == 0:
        flat[0].set_visible(True)
        flat[0].set_axis_off()
        flat[0].text(0.5, 0.5, "no kits", ha="center", va="center")
    colors = type_colors(instance)
    used = sorted({p.type for kit in plan.kits for p in kit.layout})
    if used:
        fig.legend(
            handles=[
                Patch(facecolor=colors.get(t, _UNKNOWN_TYPE_COLOR), edgecolor="black", label=t)
                for t in used
            ],
            title="part type",
            loc="outside right upper",
            fontsize=8,
        )
    fig.suptitle(f"{instance.name}: tray layouts ({W:g} x {H:g} mm)")
    return fig


def plot_convergence(
    trace: Sequence[float], ax: Axes | None = None, label: str | None = None
) -> Axes:
    """Best cross-entropy score per iteration (iterations numbered from 1). Call it again on
    the same Axes to overlay several runs; non-finite scores leave gaps."""
    from matplotlib.ticker import MaxNLocator

    if ax is None:
        _, ax = _pyplot().subplots(figsize=(6.0, 3.8), layout="constrained")
    y = np.asarray(list(trace), dtype=float)
    y[~np.isfinite(y)] = np.nan
    x = np.arange(1, len(y) + 1)
    ax.plot(x, y, marker="o" if len(y) <= 40 else None, markersize=3, linewidth=1.4, label=label)
    ax.set_xlabel("iteration")
    ax.set_ylabel("best CE score")
    ax.set_title("cross-entropy convergence")
    ax.xaxis.set_major_locator(MaxNLocator(integer=True))
    ax.grid(alpha=0.3)
    if label is not None:
        ax.legend(fontsize=8)
    return ax


def save_figure(fig: Figure, path: str | os.PathLike[str], dpi: int = 150) -> Path:
    """Write ``fig`` atomically (:func:`bilevel_kit.atomic.atomic_path`) with the usual
    permissions and close it. The format follows the suffix (PNG when there is none). Returns
    the path."""
    plt = _pyplot()
    out = Path(path)
    fmt = (out.suffix or ".png")[1:].lower()
    try:
        with atomic.atomic_path(out) as tmp:
            fig.savefig(tmp, format=fmt, dpi=dpi, bbox_inches="tight")
            umask = os.umask(0)
            os.umask(umask)
            os.chmod(tmp, 0o666 & ~umask)
    finally:
        plt.close(fig)
    return out


def plot_comparison(records: Sequence[dict[str, Any]], ax: Axes | None = None) -> Axes:
    """Grouped bars of makespan and human idle per method (records of ``compare``), with the
    best lower bound on makespan as a dashed line."""
    plt = _pyplot()
    if ax is None:
        _, ax = plt.subplots(figsize=(max(5.0, 1.3 * len(records) + 2), 4), layout="constrained")
    names = [str(r["method"]) for r in records]
    makespan = np.array([float(r["makespan"]) for r in records])
    idle = np.array([float(r["human_idle"]) for r in records])
    pos = np.arange(len(records))
    bars = ax.bar(pos - 0.2, makespan, 0.4, label="makespan", color="#1f77b4", gid="makespan")
    ax.bar(pos + 0.2, idle, 0.4, label="human idle", color=_IDLE_COLOR, gid="human_idle")
    for rect, value in zip(bars, makespan, strict=True):
        ax.annotate(
            f"{value:.0f}",
            (rect.get_x() + rect.get_width() / 2, value),
            ha="center",
            va="bottom",
            fontsize=8,
        )
    bound = records[0].get("best_bound")
    if bound is not None:
        ax.axhline(
            float(bound),
            color=_MAKESPAN_COLOR,
            linestyle="--",
            lw=1,
            label=f"lower bound {float(bound):.0f} s",
            gid="bound",
        )
    ax.set_xticks(pos, names)
    ax.set_ylabel("time (s)")
    ax.set_title(f"{records[0].get('instance', '')}: methods compared")
    ax.legend(loc="upper left", fontsize=8)
    return ax


def plot_gaps(
    records: Sequence[dict[str, Any]],
    ax: Axes | None = None,
    methods: Sequence[str] | None = None,
) -> Axes:
    """Gap (%) of each method's makespan to the instance's best lower bound, grouped by
    instance (records of ``compare`` with a ``gap`` field). Bars are labelled with their value;
    a method without a plan on an instance (e.g. a kit that does not fit) is marked "n/a"."""
    plt = _pyplot()
    instances = list(dict.fromkeys(str(r["instance"]) for r in records))
    methods = list(methods or dict.fromkeys(str(r["method"]) for r in records))
    if ax is None:
        _, ax = plt.subplots(
            figsize=(max(6.0, 0.45 * len(instances) * len(methods) + 2), 4), layout="constrained"
        )
    width = 0.8 / max(1, len(methods))
    gap = {(str(r["instance"]), str(r["method"])): r.get("gap") for r in records}
    for m, method in enumerate(methods):
        pos = np.arange(len(instances)) + (m - (len(methods) - 1) / 2) * width
        for x, inst in zip(pos, instances, strict=True):
            v = gap.get((inst, method))
            if v is None:
                ax.annotate("n/a", (x, 0), ha="center", va="bottom", fontsize=7, rotation=90)
                continue
            ax.bar(x, 100 * v, width, color=_kit_color(m), gid=f"gap:{method}:{inst}")
            ax.annotate(f"{100 * v:.1f}", (x, 100 * v), ha="center", va="bottom", fontsize=7)
    from matplotlib.patches import Patch

    ax.set_xticks(np.arange(len(instances)), instances, rotation=20, ha="right")
    ax.set_ylabel("gap to best lower bound (%)")
    ax.set_title("heuristic vs exact: makespan gap")
    ax.legend(
        handles=[Patch(color=_kit_color(m), label=name) for m, name in enumerate(methods)],
        fontsize=8,
    )
    return ax
