"""The Gantt chart of the robot and the human (docs/timeline.md, docs/figures.md); with several
assembly stations one human lane per station under the shared robot's
(docs/timeline.md#several-stations).

:func:`plot_gantt` draws in steps: the kits' bars (kitting, delivery, pickup, tasks), their
labels (inside their bars or on leaders, :mod:`.lanes`), the tray waits and idle time, then the
axes' dress, the legend, beyond eight kits the colour bar and, when the task bars are too
narrow to name, the list of tasks by kit. The order of the steps is the order the artists are
added, hence the drawing order.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import replace
from typing import TYPE_CHECKING, Any, cast

import numpy as np

from .. import style
from ..instance import Instance
from ..plan import KitTimes, Plan, Timeline, evaluate, kit_station
from ..style import plural, styled
from . import lanes
from .common import axes_width_in, figure_size, pyplot

if TYPE_CHECKING:
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure

#: Lane positions (y) and bar height of the Gantt chart.
ROBOT_Y = 1.0
HUMAN_Y = 0.0
BAR_HEIGHT = 0.6
#: Width bounds (inches) of a new Gantt chart; it grows with the number of tasks in between.
GANTT_WIDTH = (7.0, 10.0)


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
    limit = 1 if instance.stations else instance.tray_limit  # stations: only trays delay
    if limit is None:
        return []
    kits = timeline.kits
    return [
        (k + 1, kits[k - 1].arrive, kits[k].robot_start)
        for k in range(max(1, limit), len(kits))
        if kits[k].robot_start > kits[k - 1].arrive + tol
    ]


def _bar(ax: Axes, y: float, start: float, end: float, gid: str, **kw: Any) -> Any:
    """One horizontal bar from ``start`` to ``end`` in the lane at ``y`` (None if empty)."""
    if end - start <= 0:
        return None
    (rect,) = ax.barh(y, end - start, left=start, height=BAR_HEIGHT, **kw).patches
    rect.set_gid(gid)
    return rect


def _wait_style() -> dict[str, Any]:
    """The bars of the robot's waits for a returned tray (light, dotted)."""
    return {
        "facecolor": style.lighten(style.TRAY_WAIT_COLOR, 0.4),
        "hatch": "..",
        "edgecolor": style.TRAY_WAIT_COLOR,
        "linewidth": 0.5,
    }


def _idle_style() -> dict[str, Any]:
    """The bars of idle time of either lane (light red, hatched red)."""
    return {
        "facecolor": style.IDLE_FILL,
        "hatch": "\\\\",
        "edgecolor": style.IDLE_COLOR,
        "linewidth": 0.0,
    }


@styled
def plot_gantt(
    instance: Instance,
    plan: Plan,
    timeline: Timeline | None = None,
    ax: Axes | None = None,
    *,
    method: str | None = None,
) -> Axes:
    """Gantt chart of the robot and the human (docs/timeline.md, docs/figures.md).

    Robot lane: one kitting bar per kit (``robot_start``..``robot_end``, in the kit's colour),
    one hatched delivery bar (``robot_end``..``arrive``) and, with a tray limit, a light dotted
    bar for each wait for a returned tray (:func:`tray_waits`). Human lane: the kit pickup
    overhead, then each task (``task_start``..``task_end``, in a lighter shade of its kit's
    colour). Up to eight kits have eight distinct colours; more kits take a continuous
    colormap explained by a colour bar (:func:`bilevel_kit.style.kit_colors`); no kit colour
    resembles a mark. Idle time of either lane is hatched red; a dashed line marks the
    makespan. The title names the instance (and ``method`` when given) and the metrics.

    Every kit and task is named: inside its bar where the label fits, else on a leader beside
    the lane (:mod:`.lanes`); when the leaders do not fit either, a list of the tasks by kit
    under the chart names them (on a new figure, which grows to hold it). Kit labels take one
    format per chart, "kit k" when all fit, else "k". ``timeline`` defaults to
    :func:`bilevel_kit.plan.evaluate` of the plan (pass one to draw e.g. a simulated run; the
    simulator's waits for parts are not part of a timeline and are not drawn).
    """
    tl = timeline if timeline is not None else evaluate(instance, plan)
    n_kits = len(tl.kits)
    colors, colorbar = style.kit_colors(max(n_kits, len(plan.kits)))
    where = list(tl.kit_stations) or [kit_station(instance, kit.tasks) for kit in plan.kits]
    ids = instance.station_ids  # ("",): one human lane, as without stations
    created = ax is None
    if ax is None:
        ax = _new_gantt_axes(plan, len(ids))
    makespan = tl.makespan
    right = makespan * 1.02 if makespan > 0 else 1.0
    ax.set_xlim(0.0, right)
    inches_per_s = axes_width_in(ax) / right
    # thin edges when bars are narrow, so that 100 kits do not turn into black stripes
    mean_kit_in = inches_per_s * tl.robot_work / max(n_kits, 1)
    edge: dict[str, Any] = {"edgecolor": "black", "linewidth": 0.5 if mean_kit_in >= 0.15 else 0.15}
    kit_bars, task_bars = _lane_bars(plan, tl, colors, where, ids)
    robot, human, listed = _place_labels(kit_bars, task_bars, inches_per_s, right, colorbar)
    ys = _lane_ys(ids, human)
    _draw_kits(ax, instance, plan, tl, (colors, where, ys), edge)
    lanes.draw(ax, robot, ROBOT_Y, +1, BAR_HEIGHT / 2, stagger=False)
    for s, placement in zip(ids, human, strict=True):
        lanes.draw(ax, placement, ys[s], -1, BAR_HEIGHT / 2, stagger=True)
    waits = tray_waits(instance, tl)
    _draw_waits_and_idle(ax, tl, waits, where, ys)
    ax.axvline(makespan, color=style.MAKESPAN_COLOR, linestyle="--", linewidth=1.2, gid="makespan")
    _dress_gantt(ax, instance, tl, method, (lanes.room(human[-1]), lanes.room(robot)), (where, ys))
    _gantt_legend(ax, colors, colorbar, edge, bool(waits))
    if colorbar:
        _kit_colorbar(ax, len(colors))
    if listed:
        _task_list(ax, plan, colors, resize=created)
    return ax


def _new_gantt_axes(plan: Plan, n_humans: int = 1) -> Axes:
    """A new chart 3.4 inches high (0.9 more per human lane beyond one), wider with more tasks
    (within :data:`GANTT_WIDTH`)."""
    n_tasks = sum(len(k.tasks) for k in plan.kits)
    width = float(np.clip(5.0 + 0.25 * n_tasks, *GANTT_WIDTH))
    height = 3.4 + 0.9 * (n_humans - 1)
    _, ax = pyplot().subplots(figsize=(width, height), layout="constrained")
    return cast("Axes", ax)


def _lane_bars(
    plan: Plan, tl: Timeline, colors: Sequence[Any], where: Sequence[str], ids: Sequence[str]
) -> tuple[list[lanes.Bar], list[list[lanes.Bar]]]:
    """The bars to label: the robot lane's (kits, texts "k") and each human lane's (tasks, in
    the order of ``ids``); bars of zero length are not drawn, so not labelled."""
    kit_bars: list[lanes.Bar] = []
    task_bars: dict[str, list[lanes.Bar]] = {s: [] for s in ids}
    for k, (kit, kt) in enumerate(zip(plan.kits, tl.kits, strict=False)):
        if kt.robot_end > kt.robot_start:
            kit_bars.append(
                lanes.Bar(kt.robot_start, kt.robot_end, f"{k + 1}", colors[k], f"label:kit:{k + 1}")
            )
        light = style.lighten(colors[k])
        for t in kit.tasks:
            if t in tl.task_start and tl.task_end[t] > tl.task_start[t]:
                bar = lanes.Bar(tl.task_start[t], tl.task_end[t], t, light, f"label:task:{t}")
                task_bars[where[k]].append(bar)
    return kit_bars, [task_bars[s] for s in ids]


def _lane_ys(ids: Sequence[str], human: Sequence[lanes.Placement]) -> dict[str, float]:
    """Each station's human lane: the first at :data:`HUMAN_Y`, the next ones below, each
    beyond the leader rows of the lane above it (:func:`.lanes.room`)."""
    ys: dict[str, float] = {}
    y = HUMAN_Y
    for s, placement in zip(ids, human, strict=True):
        ys[s] = y
        y -= 1.0 + lanes.room(placement)
    return ys


def _draw_kits(
    ax: Axes,
    instance: Instance,
    plan: Plan,
    tl: Timeline,
    lanes_of: tuple[Sequence[Any], Sequence[str], dict[str, float]],
    edge: dict[str, Any],
) -> None:
    """Every kit's bars in the robot's lane and its station's human lane (``lanes_of``: the
    kit colours, each kit's station and each station's lane y)."""
    colors, where, ys = lanes_of
    for k, (kit, kt) in enumerate(zip(plan.kits, tl.kits, strict=False)):
        color = colors[k]
        gid = f"robot:kit:{k + 1}"
        _bar(ax, ROBOT_Y, kt.robot_start, kt.robot_end, gid, color=color, **edge)
        y, o_h = ys[where[k]], instance.station_params[where[k]].kit_overhead_human
        _draw_delivery_and_pickup(ax, k, kt, (y, o_h), edge)
        light = style.lighten(color)
        for t in kit.tasks:
            if t in tl.task_start:
                s, e = tl.task_start[t], tl.task_end[t]
                _bar(ax, y, s, e, f"human:task:{t}", color=light, **edge)


def _place_labels(
    kit_bars: list[lanes.Bar],
    task_bars: list[list[lanes.Bar]],
    inches_per_s: float,
    width_s: float,
    colorbar: bool,
) -> tuple[lanes.Placement, list[lanes.Placement], bool]:
    """Where the kit and task labels go, and whether the tasks must also be listed by kit.

    Kit labels read "kit k" when every one fits its bar that way, else "k" (one format per
    chart). A lane whose leaders do not fit keeps its inside labels only if at least half of
    its labels fit (a few scattered labels would suggest the others are missing); the list of
    tasks by kit then names every task, and every kit when no colour bar does. ``task_bars``:
    one list per human lane."""
    long = [replace(b, text=f"kit {b.text}") for b in kit_bars]
    if all(lanes.fits_inside(b, inches_per_s) for b in long):
        kit_bars = long
    robot = lanes.place(kit_bars, inches_per_s, width_s)
    human = [lanes.place(bars, inches_per_s, width_s) for bars in task_bars]
    listed = None in human or (robot is None and not colorbar)

    def inside_only(bars: list[lanes.Bar]) -> lanes.Placement:
        fit = [b for b in bars if lanes.fits_inside(b, inches_per_s)]
        return lanes.Placement(fit if 2 * len(fit) >= len(bars) else [], [])

    return (
        robot if robot is not None else inside_only(kit_bars),
        [h if h is not None else inside_only(b) for h, b in zip(human, task_bars, strict=True)],
        listed,
    )


def _draw_delivery_and_pickup(
    ax: Axes, k: int, kt: KitTimes, lane: tuple[float, float], edge: dict[str, Any]
) -> None:
    """Kit ``k``'s (0-based) hatched delivery bar and the human's pickup of it (``lane``: the
    human lane's y and the station's pickup overhead)."""
    y, overhead = lane
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
        y,
        kt.human_start,
        min(kt.human_start + overhead, kt.human_end),
        f"human:pickup:{k + 1}",
        color=style.PICKUP_COLOR,
        hatch="xx",
        **edge,
    )


def _draw_waits_and_idle(
    ax: Axes,
    tl: Timeline,
    waits: Sequence[tuple[int, float, float]],
    where: Sequence[str],
    ys: dict[str, float],
) -> None:
    """The robot's waits for a returned tray, then the idle time of each lane: the robot's up
    to the makespan (a wait is not idle time), each human's up to its station's completion
    (the makespan with one station; ``Timeline.station_metrics``)."""
    wait_style = _wait_style()
    for k, s, e in waits:
        _bar(ax, ROBOT_Y, s, e, f"robot:tray_wait:{k}", **wait_style)
    idle_style = _idle_style()
    robot_busy = sorted(
        [(kt.robot_start, kt.arrive) for kt in tl.kits] + [(s, e) for _, s, e in waits]
    )
    for s, e in _idle_intervals(robot_busy, tl.makespan):
        _bar(ax, ROBOT_Y, s, e, "robot:idle", **idle_style)
    for station, y in ys.items():
        mine = (k < len(where) and where[k] == station for k in range(len(tl.kits)))
        busy = [(kt.human_start, kt.human_end) for kt, m in zip(tl.kits, mine, strict=True) if m]
        if len(ys) == 1:  # every kit, as without stations
            busy = [(kt.human_start, kt.human_end) for kt in tl.kits]
        end = tl.makespan if len(ys) == 1 else max((e for _, e in busy), default=0.0)
        for s, e in _idle_intervals(busy, end):
            _bar(ax, y, s, e, "human:idle", **idle_style)


def _dress_gantt(
    ax: Axes,
    instance: Instance,
    tl: Timeline,
    method: str | None,
    room: tuple[float, float],
    lanes_of: tuple[Sequence[str], dict[str, float]],
) -> None:
    """Lanes, axis labels, grid and the title: the instance (and method) and the metrics (with
    several stations each one's completion), on one line when it fits the axes, else on two
    (three). ``room``: the leader rows' room below the lowest human lane and above the robot
    lane (:func:`.lanes.room`); ``where``: each kit's station; ``ys``: each station's lane."""
    where, ys = lanes_of
    several = len(ys) > 1
    names = [f"human {s}" if several else "human" for s in ys]
    ax.set_yticks([*ys.values(), ROBOT_Y], [*names, "robot"])
    margin = 0.6 - BAR_HEIGHT / 2  # between a lane and the edge of the chart
    below, above = (max(r - margin, 0.0) for r in room)
    ax.set_ylim(min(ys.values()) - 0.6 - below, ROBOT_Y + 0.6 + above)
    ax.set_xlabel("time (s)")
    ax.set_ylabel("resource")
    ax.grid(axis="x", alpha=0.3)
    ax.set_axisbelow(True)
    head = instance.name if method is None else f"{instance.name} / {method}"
    metrics = (
        f"makespan {tl.makespan:.1f} s, human idle {tl.human_idle:.1f} s, "
        f"robot idle {tl.robot_idle:.1f} s, {plural(len(tl.kits), 'kit')}"
    )
    lines = [head, metrics]
    if several:
        ends = {w: kt.human_end for kt, w in zip(tl.kits, where, strict=False)}  # in order
        done = (f"{s} {ends[s]:.1f} s" for s in ys if s in ends)
        lines.append(f"completion {', '.join(done)}")
    one_line = f"{head}: {'; '.join(lines[1:])}"
    wide = style.text_width_in(one_line, style.TITLE_SIZE) <= axes_width_in(ax)
    ax.set_title(one_line if wide else "\n".join(lines))


class KitSwatch:
    """A legend handle drawn as side-by-side stripes of a few kits' colours: "colour = kit"
    shown with the chart's own kit colours, never one kit's colour standing for all."""

    def __init__(self, colors: Sequence[Any], edge: dict[str, Any], label: str) -> None:
        self.colors = list(colors)
        self.edge = edge
        self.label = label

    def get_label(self) -> str:
        return self.label


def _swatch_handler() -> Any:
    """The legend handler of :class:`KitSwatch` (matplotlib imported on first use)."""
    from matplotlib.legend_handler import HandlerBase
    from matplotlib.patches import Rectangle

    class Handler(HandlerBase):
        def create_artists(  # type: ignore[override]
            self,
            legend: Any,
            orig_handle: KitSwatch,
            xdescent: float,
            ydescent: float,
            width: float,
            height: float,
            fontsize: float,
            trans: Any,
        ) -> list[Any]:
            n = len(orig_handle.colors)
            w = width / n
            return [
                Rectangle(
                    (-xdescent + i * w, -ydescent),
                    w,
                    height,
                    facecolor=c,
                    transform=trans,
                    gid=f"swatch:{orig_handle.label}",
                    **orig_handle.edge,
                )
                for i, c in enumerate(orig_handle.colors)
            ]

    return Handler()


def _swatch_colors(colors: Sequence[Any], colorbar: bool) -> list[Any]:
    """Up to four kit colours for the legend's kit swatches: the first kits of the palette,
    or the colormap at its ends and thirds."""
    if colorbar:
        n = len(colors)
        return [colors[round(i * (n - 1) / 3)] for i in range(4)]
    return list(colors[:4]) or [style.KIT_PALETTE[0]]


def _gantt_legend(
    ax: Axes, colors: Sequence[Any], colorbar: bool, edge: dict[str, Any], waits: bool
) -> None:
    """The legend under the chart: one row on a wide figure, else two. Kitting and task
    swatches show the chart's kit colours side by side (tasks in their lighter shades)."""
    from matplotlib.lines import Line2D
    from matplotlib.patches import Patch

    sample = _swatch_colors(colors, colorbar)
    kit_label = "kitting (colour = kit, see bar)" if colorbar else "kitting (colour = kit)"
    handles: list[Any] = [
        KitSwatch(sample, edge, kit_label),
        Patch(facecolor=style.DELIVERY_COLOR, hatch="//", label="delivery", **edge),
    ]
    if waits:
        handles.append(Patch(label="waiting for tray", **_wait_style()))
    handles += [
        Patch(facecolor=style.PICKUP_COLOR, hatch="xx", label="kit pickup", **edge),
        KitSwatch([style.lighten(c) for c in sample], edge, "task (its kit's colour, lighter)"),
        Patch(label="idle", **_idle_style()),
        Line2D([], [], color=style.MAKESPAN_COLOR, linestyle="--", label="makespan"),
    ]
    ncols = len(handles) if figure_size(ax)[0] >= 9.5 else math.ceil(len(handles) / 2)
    ax.legend(
        handles=handles,
        labels=[h.get_label() for h in handles],
        handler_map={KitSwatch: _swatch_handler()},
        loc="upper center",
        bbox_to_anchor=(0.5, -0.22),
        ncols=ncols,
        frameon=False,
    )


def _task_list(ax: Axes, plan: Plan, colors: Sequence[Any], *, resize: bool) -> None:
    """The tasks of each kit as a legend under the chart ("k: task, task"), in the kits'
    colours, for charts whose task bars are too narrow to name. ``resize``: grow the figure
    by the list's height (a figure made by :func:`plot_gantt`)."""
    import textwrap

    from matplotlib.patches import Patch

    fig = cast("Figure", ax.get_figure(root=True))
    width, height = figure_size(ax)
    size = style.SMALL_SIZE
    char_in = style.text_width_in("x", size)
    wrap = max(12, int((width - 1.0) / char_in))
    labels = [
        textwrap.fill(f"{k}: {', '.join(kit.tasks)}", wrap) for k, kit in enumerate(plan.kits, 1)
    ]
    lines = [lab.split("\n") for lab in labels]
    entry_in = max(style.text_width_in(x, size) for ls in lines for x in ls) + 0.45
    ncols = max(1, min(len(labels), int((width - 0.3) // entry_in)))
    rows = math.ceil(len(labels) / ncols)
    tall = max(len(ls) for ls in lines)
    handles = [Patch(facecolor=c, edgecolor="black", linewidth=0.4) for c in colors[: len(labels)]]
    outside = type(fig.get_layout_engine()).__name__ == "ConstrainedLayoutEngine"
    fig.legend(
        handles,
        labels,
        loc="outside lower center" if outside else "lower center",
        ncols=ncols,
        title="tasks by kit",
        fontsize=size,
        handlelength=1.0,
        columnspacing=1.0,
        frameon=False,
    )
    if resize:
        fig.set_size_inches(width, height + rows * tall * 1.4 * size / 72 + 0.35)


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
