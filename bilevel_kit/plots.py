"""Figures: the robot/human Gantt chart, tray layouts, method comparisons and cross-entropy
convergence, all in the toolkit's one style (:mod:`bilevel_kit.style`, docs/figures.md).

Every ``plot_*`` function draws into ``ax`` when one is given (otherwise it makes a new figure)
and returns the Axes; :func:`plot_trays` makes many Axes and returns the Figure. Nothing here
calls ``plt.show``: write figures with :func:`save_figure`, which also closes them.

The artists carry ``gid`` tags so that tests and callers can find them again:

* Gantt chart: ``robot:kit:<k>``, ``robot:delivery:<k>``, ``robot:tray_wait:<k>``,
  ``robot:idle``, ``human:pickup:<k>``, ``human:task:<task id>``, ``human:idle`` (bar
  Rectangles), ``makespan`` (the vertical line).
* Tray: ``tray`` (the outline Rectangle), ``part:<part id>`` (one Polygon per placement).
* Comparison: ``makespan``/``human_idle`` (bars), ``status:<method>`` (texts), ``bound``.

Bars of zero duration (no delivery time, no pickup overhead ...) are not drawn. Labels that
would not fit inside their bar or part are left out; the colours and the legend still say
what each bar or part is.
"""

from __future__ import annotations

import math
import os
from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any, cast

import numpy as np

from . import atomic, style
from .geometry import corners
from .instance import Instance
from .plan import Kit, Plan, Timeline, evaluate
from .style import plural, styled

if TYPE_CHECKING:
    from matplotlib.artist import Artist
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure, SubFigure

#: Lane positions (y) and bar height of the Gantt chart.
ROBOT_Y = 1.0
HUMAN_Y = 0.0
BAR_HEIGHT = 0.6
#: Width bounds (inches) of a new Gantt chart; it grows with the number of tasks in between.
GANTT_WIDTH = (7.0, 10.0)
#: Most columns of a new :func:`plot_trays` grid, and the size (inches) of its cells.
TRAY_COLUMNS = 10
TRAY_CELL = (1.7, 3.4)


def _pyplot() -> Any:
    import matplotlib.pyplot as plt

    return plt


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


def tray_waits(
    instance: Instance, timeline: Timeline, tol: float = 1e-9
) -> list[tuple[int, float, float]]:
    """``(k, start, end)`` (k 1-based) of each wait of the robot for a returned tray: the gap
    between kit k-1's arrival and kit k's robot start, which the timeline rule
    (docs/timeline.md, "Trays in circulation") opens only for k > ``trays``."""
    limit = instance.tray_limit
    if limit is None:
        return []
    kits = timeline.kits
    return [
        (k + 1, kits[k - 1].arrive, kits[k].robot_start)
        for k in range(max(1, limit), len(kits))
        if kits[k].robot_start > kits[k - 1].arrive + tol
    ]


def _most(labels: Sequence[tuple[Any, ...]]) -> bool:
    """Whether at least half of the labels ``(..., text or "", colour)`` fit their bar."""
    return 2 * sum(1 for lab in labels if lab[-2]) >= len(labels)


def _figsize(ax: Axes) -> tuple[float, float]:
    """(width, height) in inches of the figure holding ``ax``."""
    fig = cast("Figure", ax.get_figure(root=True))
    width, height = fig.get_size_inches()
    return float(width), float(height)


def _axes_width_in(ax: Axes) -> float:
    """Width of ``ax`` in inches before layout (a slight under-estimate with constrained
    layout, which is the safe side for deciding whether a label fits)."""
    return max(ax.get_position().width * _figsize(ax)[0], 0.5)


def _bar(ax: Axes, y: float, start: float, end: float, gid: str, **kw: Any) -> Any:
    """One horizontal bar from ``start`` to ``end`` in the lane at ``y`` (None if empty)."""
    if end - start <= 0:
        return None
    (rect,) = ax.barh(y, end - start, left=start, height=BAR_HEIGHT, **kw).patches
    rect.set_gid(gid)
    return rect


@styled
def plot_gantt(
    instance: Instance,
    plan: Plan,
    timeline: Timeline | None = None,
    ax: Axes | None = None,
    *,
    method: str | None = None,
) -> Axes:
    """Gantt chart of the robot and the human (docs/timeline.md).

    Robot lane: one kitting bar per kit (``robot_start``..``robot_end``, in the kit's colour,
    labelled "kit k" or "k" when that fits), one hatched delivery bar (``robot_end``..``arrive``)
    and, with a tray limit, a light dotted bar for each wait for a returned tray
    (:func:`tray_waits`). Human lane: the kit pickup overhead, then each task
    (``task_start``..``task_end``, in a lighter shade of its kit's colour, labelled with its id
    when that fits). Up to ten kits have ten distinct colours; more kits take a continuous
    colormap explained by a colour bar (:func:`bilevel_kit.style.kit_colors`). Idle time of
    either lane is hatched red; a dashed line marks the makespan. The title names the instance
    (and ``method`` when given) and the timeline's metrics. ``timeline`` defaults to
    :func:`bilevel_kit.plan.evaluate` of the plan (pass one to draw e.g. a simulated run; the
    simulator's waits for parts are not part of a timeline and are not drawn).
    """
    from matplotlib.lines import Line2D
    from matplotlib.patches import Patch

    tl = timeline if timeline is not None else evaluate(instance, plan)
    n_kits = len(tl.kits)
    colors, colorbar = style.kit_colors(max(n_kits, len(plan.kits)))
    if ax is None:
        n_tasks = sum(len(k.tasks) for k in plan.kits)
        width = float(np.clip(5.0 + 0.25 * n_tasks, *GANTT_WIDTH))
        _, ax = _pyplot().subplots(figsize=(width, 3.4), layout="constrained")
    makespan = tl.makespan
    right = makespan * 1.02 if makespan > 0 else 1.0
    ax.set_xlim(0.0, right)
    inches_per_s = _axes_width_in(ax) / right
    label_size = style.SMALL_SIZE

    def fits(text: str, duration: float) -> bool:
        return style.text_width_in(text, label_size) + 0.03 <= duration * inches_per_s

    # thin edges when bars are narrow, so that 100 kits do not turn into black stripes
    mean_kit_in = inches_per_s * tl.robot_work / max(n_kits, 1)
    edge: dict[str, Any] = {"edgecolor": "black", "linewidth": 0.5 if mean_kit_in >= 0.15 else 0.15}
    oh = instance.kit_overhead_human
    robot_labels: list[tuple[float, str, Any]] = []  # (x, text or '', bar colour)
    task_labels: list[tuple[float, float, str, Any]] = []  # (x, y, text or '', bar colour)
    for k, (kit, kt) in enumerate(zip(plan.kits, tl.kits, strict=False)):
        color = colors[k]
        rect = _bar(
            ax, ROBOT_Y, kt.robot_start, kt.robot_end, f"robot:kit:{k + 1}", color=color, **edge
        )
        label = next(
            (s for s in (f"kit {k + 1}", f"{k + 1}") if fits(s, kt.robot_end - kt.robot_start)),
            None,
        )
        if rect is not None:
            robot_labels.append(((kt.robot_start + kt.robot_end) / 2, label or "", color))
        _bar(
            ax,
            ROBOT_Y,
            kt.robot_end,
            kt.arrive,
            f"robot:delivery:{k + 1}",
            color=style.DELIVERY_COLOR,
            hatch="//",
            **edge,
        )
        _bar(
            ax,
            HUMAN_Y,
            kt.human_start,
            min(kt.human_start + oh, kt.human_end),
            f"human:pickup:{k + 1}",
            color=style.PICKUP_COLOR,
            hatch="xx",
            **edge,
        )
        light = style.lighten(color)
        for j, t in enumerate(kit.tasks):
            if t not in tl.task_start:
                continue
            s, e = tl.task_start[t], tl.task_end[t]
            drawn = _bar(ax, HUMAN_Y, s, e, f"human:task:{t}", color=light, **edge)
            if drawn is not None:
                # stagger neighbouring labels so that short tasks stay readable
                dy = BAR_HEIGHT * (0.18 if j % 2 == 0 else -0.18)
                task_labels.append(((s + e) / 2, HUMAN_Y + dy, t if fits(t, e - s) else "", light))
    # a lane's labels are drawn only if most of them fit: a few scattered labels mislead
    lanes = [[(x, ROBOT_Y, t, c) for x, t, c in robot_labels], task_labels]
    for x, y, text, color in (lab for lane in lanes if _most(lane) for lab in lane):
        if text:
            ax.text(
                x,
                y,
                text,
                ha="center",
                va="center",
                fontsize=label_size,
                color=style.text_color(color),
                clip_on=True,
            )

    waits = tray_waits(instance, tl)
    wait_style: dict[str, Any] = {
        "facecolor": style.lighten(style.TRAY_WAIT_COLOR, 0.4),
        "hatch": "..",
        "edgecolor": style.TRAY_WAIT_COLOR,
        "linewidth": 0.5,
    }
    for k, s, e in waits:
        _bar(ax, ROBOT_Y, s, e, f"robot:tray_wait:{k}", **wait_style)
    idle_style: dict[str, Any] = {
        "facecolor": style.IDLE_COLOR,
        "alpha": 0.35,
        "hatch": "\\\\",
        "edgecolor": style.IDLE_COLOR,
        "linewidth": 0.0,
    }
    robot_busy = sorted(
        [(kt.robot_start, kt.arrive) for kt in tl.kits] + [(s, e) for _, s, e in waits]
    )
    for s, e in _idle_intervals(robot_busy, makespan):
        _bar(ax, ROBOT_Y, s, e, "robot:idle", **idle_style)
    human_busy = [(kt.human_start, kt.human_end) for kt in tl.kits]
    for s, e in _idle_intervals(human_busy, makespan):
        _bar(ax, HUMAN_Y, s, e, "human:idle", **idle_style)

    ax.axvline(makespan, color=style.MAKESPAN_COLOR, linestyle="--", linewidth=1.2, gid="makespan")

    ax.set_yticks([HUMAN_Y, ROBOT_Y], ["human", "robot"])
    ax.set_ylim(HUMAN_Y - 0.6, ROBOT_Y + 0.6)
    ax.set_xlabel("time (s)")
    ax.set_ylabel("resource")
    ax.grid(axis="x", alpha=0.3)
    ax.set_axisbelow(True)
    head = instance.name if method is None else f"{instance.name} / {method}"
    metrics = (
        f"makespan {makespan:.1f} s, human idle {tl.human_idle:.1f} s, "
        f"robot idle {tl.robot_idle:.1f} s, {plural(n_kits, 'kit')}"
    )
    one_line = f"{head}: {metrics}"
    wide = style.text_width_in(one_line, style.TITLE_SIZE) <= _axes_width_in(ax)
    ax.set_title(one_line if wide else f"{head}\n{metrics}")

    kit_label = "kitting (colour = kit, see bar)" if colorbar else "kitting (colour = kit)"
    handles: list[Artist] = [
        Patch(facecolor=colors[0] if colors else style.PALETTE[0], label=kit_label, **edge),
        Patch(facecolor=style.DELIVERY_COLOR, hatch="//", label="delivery", **edge),
    ]
    if waits:
        handles.append(Patch(label="waiting for tray", **wait_style))
    handles += [
        Patch(facecolor=style.PICKUP_COLOR, hatch="xx", label="kit pickup", **edge),
        Patch(
            facecolor=style.lighten(colors[0] if colors else style.PALETTE[0]), label="task", **edge
        ),
        Patch(label="idle", **idle_style),
        Line2D([], [], color=style.MAKESPAN_COLOR, linestyle="--", label="makespan"),
    ]
    ncols = len(handles) if _figsize(ax)[0] >= 9.5 else math.ceil(len(handles) / 2)
    ax.legend(
        handles=handles,
        loc="upper center",
        bbox_to_anchor=(0.5, -0.22),
        ncols=ncols,
        frameon=False,
    )
    if colorbar:
        _kit_colorbar(ax, len(colors))
    return ax


def _kit_colorbar(ax: Axes, n: int) -> None:
    """The colour bar of :data:`bilevel_kit.style.KIT_CMAP` from kit 1 to kit ``n``."""
    from matplotlib.cm import ScalarMappable
    from matplotlib.colors import Normalize
    from matplotlib.ticker import MaxNLocator

    mappable = ScalarMappable(norm=Normalize(1, n), cmap=style.KIT_CMAP)
    bar = cast("Figure", ax.get_figure(root=True)).colorbar(
        mappable, ax=ax, pad=0.01, fraction=0.05, aspect=12
    )
    bar.set_label("kit (delivery order)")
    bar.ax.yaxis.set_major_locator(MaxNLocator(nbins=5, integer=True))


def type_swatches(instance: Instance) -> dict[str, style.Swatch]:
    """A fixed fill per part type: the sorted type ids mapped onto
    :func:`bilevel_kit.style.categorical`, so a type looks the same in every tray plot of the
    instance and no two types look alike."""
    ids = sorted(instance.part_types)
    return dict(zip(ids, style.categorical(len(ids)), strict=True))


def type_colors(instance: Instance) -> dict[str, Any]:
    """The colour of each part type's :func:`type_swatches` (types beyond the ten colours of
    the palette differ from earlier types by their hatch)."""
    return {t: s.color for t, s in type_swatches(instance).items()}


def _type_patch(swatch: style.Swatch | None, label: str) -> Any:
    from matplotlib.patches import Patch

    face = swatch.color if swatch is not None else style.UNKNOWN_COLOR
    return Patch(
        facecolor=face,
        hatch=swatch.hatch if swatch is not None else "",
        edgecolor="black",
        linewidth=0.5,
        label=label,
    )


def _label_angle(theta: float, w: float, h: float) -> float:
    """Text rotation along the placement's long side, kept upright (-90, 90]."""
    a = theta if w >= h else theta + 90.0
    a = (a + 90.0) % 180.0 - 90.0
    return 90.0 if a == -90.0 else a


def _part_label(part: str, long_in: float, short_in: float, size: float) -> str | None:
    """The part id if it fits inside the part (``long_in`` x ``short_in`` inches), else its
    trailing copy number ("foot-3" -> "3"; the fill already gives the type), else None."""
    if size / 72 * 1.2 > short_in:
        return None
    short = part.rstrip("0123456789")
    candidates = [part] + ([part[len(short) :]] if short and short != part else [])
    return next((c for c in candidates if style.text_width_in(c, size) + 0.02 <= long_in), None)


def kit_fitness(instance: Instance, kit: Kit) -> float | None:
    """Kit fitness (mm, bigger is better; paper Eq. 11 with the sign of docs/errata.md) of the
    kit's layout, None without one."""
    if not kit.layout:
        return None
    from .fitness import layout_fitness

    return layout_fitness(kit.layout, instance.weights["W6"])


def _fitness_text(instance: Instance, kit: Kit) -> str:
    f = kit_fitness(instance, kit)
    return "no layout" if f is None else f"fitness {round(f):,} mm"  # an int: never "-0"


@styled
def plot_tray(
    instance: Instance,
    kit: Kit,
    ax: Axes | None = None,
    title: str | None = None,
    *,
    legend: bool = True,
) -> Axes:
    """The kit's tray layout: the tray outline and each placement as a rotated rectangle
    (:func:`bilevel_kit.geometry.corners`) filled by part type (:func:`type_swatches`) and
    labelled with its part id where the label fits inside the part, or else its copy number
    (small parts stay unlabelled; labels never leave the axes). The default title gives the
    number of parts, the kit fitness (:func:`kit_fitness`) and the tasks. ``legend=False``
    leaves out the legend of part types."""
    from matplotlib.patches import Polygon, Rectangle

    W, H = instance.tray.width, instance.tray.height
    if ax is None:
        fig_w = 5.5
        _, ax = _pyplot().subplots(figsize=(fig_w + 1.5, fig_w * H / W + 0.9), layout="constrained")
    swatches = type_swatches(instance)
    ax.add_patch(
        Rectangle(
            (0.0, 0.0),
            W,
            H,
            fill=True,
            facecolor="#f5f5f0",
            edgecolor="black",
            linewidth=1.2,
            gid="tray",
            zorder=1,
        )
    )
    xs, ys = [0.0, W], [0.0, H]
    for p in kit.layout:
        c = corners(p.x, p.y, p.w, p.h, p.theta)
        xs += [float(c[:, 0].min()), float(c[:, 0].max())]
        ys += [float(c[:, 1].min()), float(c[:, 1].max())]
    margin = 0.03 * max(W, H)
    ax.set_xlim(min(xs) - margin, max(xs) + margin)
    ax.set_ylim(min(ys) - margin, max(ys) + margin)
    ax.set_aspect("equal")
    # inches per mm, from the width or the height, whichever limits the equal-aspect box
    x0, x1 = ax.get_xlim()
    y0, y1 = ax.get_ylim()
    pos = ax.get_position()
    scale = min(
        _axes_width_in(ax) / (x1 - x0),
        pos.height * _figsize(ax)[1] / (y1 - y0),
    )
    size = style.SMALL_SIZE if scale * min(W, H) >= 1.5 else style.SMALL_SIZE - 1
    for p in kit.layout:
        sw = swatches.get(p.type)
        ax.add_patch(
            Polygon(
                corners(p.x, p.y, p.w, p.h, p.theta),
                closed=True,
                facecolor=sw.color if sw is not None else style.UNKNOWN_COLOR,
                hatch=sw.hatch if sw is not None else "",
                edgecolor="black",
                linewidth=0.6,
                alpha=0.85,
                gid=f"part:{p.part}",
                zorder=2,
            )
        )
        label = _part_label(p.part, max(p.w, p.h) * scale, min(p.w, p.h) * scale, size)
        if label is not None:
            ax.text(
                p.x,
                p.y,
                label,
                ha="center",
                va="center",
                fontsize=size,
                rotation=_label_angle(p.theta, p.w, p.h),
                rotation_mode="anchor",
                zorder=3,
                clip_on=True,
            )
    ax.set_xlabel("x (mm)")
    ax.set_ylabel("y (mm)")
    if title is None:
        tasks = ", ".join(kit.tasks)
        if len(tasks) > 40:
            tasks = tasks[:37] + "..."
        title = (
            f"{plural(len(kit.layout), 'part')}, {_fitness_text(instance, kit)}\ntasks {tasks}"
            if kit.tasks
            else "empty kit"
        )
    ax.set_title(title, fontsize=style.FONT_SIZE)
    if not kit.layout:
        ax.text(W / 2, H / 2, "no layout", ha="center", va="center", color="gray")
    if legend:
        used = sorted({p.type for p in kit.layout})
        if used:
            ax.legend(
                handles=[_type_patch(swatches.get(t), t) for t in used],
                title="part type",
                loc="upper left",
                bbox_to_anchor=(1.02, 1.0),
                borderaxespad=0.0,
            )
    return ax


def _tray_extent(instance: Instance, plan: Plan) -> tuple[float, float, float, float]:
    """(x0, x1, y0, y1) in mm: the tray and every placement of the plan, with a 3 % margin."""
    W, H = instance.tray.width, instance.tray.height
    xs, ys = [0.0, W], [0.0, H]
    for kit in plan.kits:
        for p in kit.layout:
            c = corners(p.x, p.y, p.w, p.h, p.theta)
            xs += [float(c[:, 0].min()), float(c[:, 0].max())]
            ys += [float(c[:, 1].min()), float(c[:, 1].max())]
    m = 0.03 * max(W, H)
    return min(xs) - m, max(xs) + m, min(ys) - m, max(ys) + m


@styled
def plot_trays(instance: Instance, plan: Plan, ncols: int | None = None) -> Figure:
    """One :func:`plot_tray` subplot per kit (in delivery order), titled with the kit's number,
    tasks and fitness, and one legend of the part types used by the plan; returns the Figure
    (unused grid cells are hidden). All trays share one scale; tick labels and axis labels
    ("x (mm)", "y (mm)") sit on the left column and on the lowest tray of each column.
    ``ncols`` defaults to about the square root of the number of kits (at least 3, at most
    :data:`TRAY_COLUMNS`); cells shrink from 3.4 to 1.7 inches as columns are added, so 100
    kits stay one readable page. The margins are fixed in inches (no layout engine), which
    keeps a 100-tray figure quick to draw."""
    from matplotlib.ticker import NullLocator

    n = len(plan.kits)
    if ncols is None:
        ncols = min(TRAY_COLUMNS, max(3, math.ceil(math.sqrt(n))))
    ncols = max(1, min(ncols, n))
    nrows = max(1, math.ceil(n / ncols))
    W, H = instance.tray.width, instance.tray.height
    x0, x1, y0, y1 = _tray_extent(instance, plan)
    cell = float(np.clip(12.0 / ncols, *TRAY_CELL))
    small = cell < 2.5
    title_size = style.SMALL_SIZE if small else style.FONT_SIZE
    swatches = type_swatches(instance)
    used = sorted({p.type for kit in plan.kits for p in kit.layout})
    # margins and gaps (inches): two title lines above each tray, ticks and labels outside
    box_h = cell * (y1 - y0) / (x1 - x0)
    left, bottom, top = 0.75, 0.55, 0.5
    right = 0.3 + (
        max(style.text_width_in(t, style.LEGEND_SIZE) for t in used) + 0.5 if used else 0
    )
    wgap, hgap = 0.15, 2.6 * title_size / 72 + 0.2
    fig_w = left + ncols * cell + (ncols - 1) * wgap + right
    fig_h = bottom + nrows * box_h + (nrows - 1) * hgap + hgap + top
    fig = _pyplot().figure(figsize=(fig_w, fig_h))
    grid = fig.add_gridspec(
        nrows,
        ncols,
        left=left / fig_w,
        right=1 - right / fig_w,
        bottom=bottom / fig_h,
        top=1 - (top + hgap) / fig_h,
        wspace=wgap / cell,
        hspace=hgap / box_h,
    )
    flat = [fig.add_subplot(grid[r, c]) for r in range(nrows) for c in range(ncols)]
    width = 22 if small else 32
    for k, kit in enumerate(plan.kits):
        tasks = ", ".join(kit.tasks)
        if len(tasks) > width:
            tasks = tasks[: width - 3] + "..."
        ax = flat[k]
        plot_tray(
            instance,
            kit,
            ax=ax,
            title=f"kit {k + 1}: {tasks}\n{_fitness_text(instance, kit)}",
            legend=False,
        )
        ax.title.set_fontsize(title_size)
        ax.set_xlim(x0, x1)
        ax.set_ylim(y0, y1)
        if small:
            ax.tick_params(labelsize=style.SMALL_SIZE - 1, length=2, pad=1)
            ax.locator_params(nbins=3)
        if k + ncols < n:  # a tray below shows the x axis (no ticks: quicker to draw)
            ax.set_xlabel("")
            ax.xaxis.set_major_locator(NullLocator())
        if k % ncols:
            ax.set_ylabel("")
            ax.yaxis.set_major_locator(NullLocator())
    for ax in flat[n:]:
        ax.set_visible(False)
    if n == 0:
        flat[0].set_visible(True)
        flat[0].set_axis_off()
        flat[0].text(0.5, 0.5, "no kits", ha="center", va="center")
    if used:
        fig.legend(
            handles=[_type_patch(swatches.get(t), t) for t in used],
            title="part type",
            loc="upper right",
            bbox_to_anchor=(1.0, 1 - (top + hgap) / fig_h),
            frameon=False,
        )
    fig.suptitle(
        f"{instance.name}: tray layouts of {plural(n, 'kit')} ({W:g} x {H:g} mm; "
        "kit fitness, bigger is better)",
        y=1 - 0.12 / fig_h,
        va="top",
    )
    return fig


@styled
def plot_convergence(
    trace: Sequence[float],
    ax: Axes | None = None,
    label: str | None = None,
    *,
    converged: bool | None = None,
    title: str = "cross-entropy convergence",
) -> Axes:
    """Best kit fitness (mm, bigger is better; docs/errata.md) per cross-entropy iteration
    (iterations numbered from 1). Call it again on the same Axes to overlay several runs;
    non-finite scores leave gaps. ``converged=False`` (the run's ``converged`` flag,
    :class:`bilevel_kit.heuristics.cross_entropy.Arrangement`) marks the last point: the run met the
    iteration cap while still improving by more than its stopping tolerance."""
    from matplotlib.ticker import MaxNLocator

    if ax is None:
        _, ax = _pyplot().subplots(figsize=(6.0, 3.8), layout="constrained")
    y = np.asarray(list(trace), dtype=float)
    y[~np.isfinite(y)] = np.nan
    x = np.arange(1, len(y) + 1)
    (line,) = ax.plot(x, y, marker="o" if len(y) <= 40 else None, markersize=3, label=label)
    if converged is False and len(y) and np.isfinite(y[-1]):
        ax.plot(
            [x[-1]],
            [y[-1]],
            marker=">",
            markersize=9,
            color=line.get_color(),
            markeredgecolor="black",
            linestyle="none",
            gid="cap",
        )
        ax.annotate(
            "iteration cap,\nstill improving",
            (x[-1], y[-1]),
            xytext=(-4, -14),
            textcoords="offset points",
            ha="right",
            va="top",
            fontsize=style.SMALL_SIZE,
            gid="cap",
        )
    ax.set_xlabel("iteration")
    ax.set_ylabel("kit fitness (mm), best score so far")
    ax.set_title(title)
    ax.xaxis.set_major_locator(MaxNLocator(integer=True))
    ax.grid(alpha=0.3)
    if label is not None:
        ax.legend()
    return ax


def save_figure(figure: Figure | SubFigure, path: str | os.PathLike[str], dpi: int = 150) -> Path:
    """Write the figure that holds ``figure`` (``ax.figure`` may be a sub-figure) atomically
    (:func:`bilevel_kit.atomic.atomic_path`) with the usual permissions and close it. The
    format follows the suffix (PNG when there is none). Returns the path."""
    fig: Figure = figure.figure  # the root figure (a figure is its own root)
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


def _nice_ticks(lo: float, hi: float, nbins: int) -> list[float]:
    from matplotlib.ticker import MaxNLocator

    return [float(t) for t in MaxNLocator(nbins=nbins).tick_values(lo, hi) if lo <= t <= hi]


def _break_axis(ax: Axes, a: float, b: float, top: float) -> str:
    """Break the y axis of ``ax`` between ``a`` and ``b``: [0, a] takes the lower 30 % of the
    height, (a, b) a thin band marked by a white gap and ``//`` on both spines, [b, top] the
    rest, so differences between values above ``b`` show while values below ``a`` stay
    readable. Values keep their data coordinates (bars are drawn from 0 as usual). Returns the
    sentence that states the break (for the legend)."""
    from matplotlib.ticker import FixedLocator

    fa, gap = 0.3, 0.04
    slope = (1.0 - fa - gap) / (top - b)

    def forward(y: np.ndarray) -> np.ndarray:
        y = np.asarray(y, dtype=float)
        return np.where(
            y <= a,
            y * fa / a,
            np.where(y < b, fa + (y - a) * gap / (b - a), fa + gap + (y - b) * slope),
        )

    def inverse(u: np.ndarray) -> np.ndarray:
        u = np.asarray(u, dtype=float)
        return np.where(
            u <= fa,
            u * a / fa,
            np.where(u < fa + gap, a + (u - fa) * (b - a) / gap, b + (u - fa - gap) / slope),
        )

    ax.set_yscale("function", functions=(forward, inverse))
    ax.set_ylim(0.0, top)
    ax.yaxis.set_major_locator(FixedLocator(_nice_ticks(0.0, a, 3) + _nice_ticks(b, top, 5)))
    ax.axhspan(a, b, facecolor="white", edgecolor="none", zorder=2.5, gid="axis_break")
    marks = ax.get_yaxis_transform()
    mid = inverse(np.array(fa + gap / 2))
    for x in (0.0, 1.0):
        ax.text(
            x,
            float(mid),
            "//",
            transform=marks,
            ha="center",
            va="center",
            fontsize=style.FONT_SIZE,
            fontweight="bold",
            clip_on=False,
            zorder=5,
        )
    return f"y axis broken: {a:.0f}-{b:.0f} s left out"


@styled
def plot_comparison(records: Sequence[dict[str, Any]], ax: Axes | None = None) -> Axes:
    """Grouped bars of makespan and human idle per method (records of ``compare``), both
    labelled with their value, each method's status (optimal / feasible / unknown, when the
    records have one) under its name, and the best lower bound on makespan as a dashed line.

    When the makespans differ by little compared with their size (spread under 25 % of the
    largest, all of them well above the largest human idle) the y axis is broken
    (:func:`_break_axis`, stated in the legend) so that the differences show."""
    from matplotlib.lines import Line2D

    plt = _pyplot()
    if ax is None:
        _, ax = plt.subplots(figsize=(max(5.5, 1.4 * len(records) + 3), 4), layout="constrained")
    names = [str(r["method"]) for r in records]
    makespan = np.array([float(r["makespan"]) for r in records])
    idle = np.array([float(r["human_idle"]) for r in records])
    pos = np.arange(len(records))
    ms_color = style.PALETTE[0]
    bars = ax.bar(pos - 0.2, makespan, 0.4, label="makespan", color=ms_color, gid="makespan")
    idle_bars = ax.bar(
        pos + 0.2, idle, 0.4, label="human idle", color=style.IDLE_COLOR, gid="human_idle"
    )
    for group, values in ((bars, makespan), (idle_bars, idle)):
        for rect, value in zip(group, values, strict=True):
            ax.annotate(
                f"{value:.1f}",
                (rect.get_x() + rect.get_width() / 2, value),
                xytext=(0, 1),
                textcoords="offset points",
                ha="center",
                va="bottom",
                fontsize=style.SMALL_SIZE,
            )
    bound = records[0].get("best_bound")
    if bound is not None:
        ax.axhline(
            float(bound),
            color=style.MAKESPAN_COLOR,
            linestyle="--",
            lw=1,
            label=f"best lower bound {float(bound):.1f} s",
            gid="bound",
        )
    labels = [
        f"{name}\n({r['status']})" if r.get("status") is not None else name
        for name, r in zip(names, records, strict=True)
    ]
    ax.set_xticks(pos, labels)
    ax.set_xlabel(
        "method (status)" if any(r.get("status") is not None for r in records) else "method"
    )
    ax.set_ylabel("time (s)")
    ax.set_title(f"{records[0].get('instance', '')}: methods compared")
    handles: list[Artist] = list(ax.get_legend_handles_labels()[0])
    if len(records):
        levels = list(makespan) + ([float(bound)] if bound is not None else [])
        low, high = min(levels), max(levels)
        a = max(float(idle.max()) * 1.3, 0.05 * low)
        b = low - 0.6 * (high - low) - 0.03 * low
        if high > 0 and (high - low) < 0.25 * high and b > 1.5 * a:
            note = _break_axis(ax, a, b, high + 0.3 * (high - b))
            handles.append(
                Line2D([], [], linestyle="none", marker="$//$", color="black", label=note)
            )
    ax.legend(handles=handles, loc="upper left", bbox_to_anchor=(1.01, 1.0), borderaxespad=0.0)
    return ax


@styled
def plot_gaps(
    records: Sequence[dict[str, Any]],
    ax: Axes | None = None,
    methods: Sequence[str] | None = None,
) -> Axes:
    """Gap (%) of each method's makespan to the instance's best lower bound, grouped by
    instance (records of ``compare`` with a ``gap`` field). Bars are labelled with their value;
    a method without a plan on an instance (e.g. a kit that does not fit) is marked "n/a".
    Methods take :func:`bilevel_kit.style.categorical` fills."""
    from matplotlib.patches import Patch

    plt = _pyplot()
    instances = list(dict.fromkeys(str(r["instance"]) for r in records))
    methods = list(methods or dict.fromkeys(str(r["method"]) for r in records))
    if ax is None:
        _, ax = plt.subplots(
            figsize=(max(6.0, 0.45 * len(instances) * len(methods) + 2), 4), layout="constrained"
        )
    width = 0.8 / max(1, len(methods))
    swatches = style.categorical(len(methods))
    gap = {(str(r["instance"]), str(r["method"])): r.get("gap") for r in records}
    for m, method in enumerate(methods):
        pos = np.arange(len(instances)) + (m - (len(methods) - 1) / 2) * width
        for x, inst in zip(pos, instances, strict=True):
            v = gap.get((inst, method))
            if v is None:
                ax.annotate(
                    "n/a", (x, 0), ha="center", va="bottom", fontsize=style.SMALL_SIZE, rotation=90
                )
                continue
            ax.bar(
                x,
                100 * v,
                width,
                color=swatches[m].color,
                hatch=swatches[m].hatch,
                edgecolor="black",
                linewidth=0.4,
                gid=f"gap:{method}:{inst}",
            )
            ax.annotate(
                f"{100 * v:.1f}", (x, 100 * v), ha="center", va="bottom", fontsize=style.SMALL_SIZE
            )
    ax.set_xticks(np.arange(len(instances)), instances, rotation=20, ha="right")
    ax.set_xlabel("instance")
    ax.set_ylabel("gap to best lower bound (%)")
    ax.set_title("heuristic vs exact: makespan gap")
    ax.legend(
        handles=[
            Patch(facecolor=s.color, hatch=s.hatch, edgecolor="black", linewidth=0.4, label=name)
            for s, name in zip(swatches, methods, strict=True)
        ],
    )
    return ax
