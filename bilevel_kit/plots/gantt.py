"""The Gantt chart of the robot and the human (docs/timeline.md, docs/figures.md).

:func:`plot_gantt` draws in steps: the kits' bars (kitting, delivery, pickup, tasks), their
labels, the tray waits and idle time, then the axes' dress, the legend and, beyond ten kits, the
colour bar. The order of the steps is the order the artists are added, hence the drawing order.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from typing import TYPE_CHECKING, Any, cast

import numpy as np

from .. import style
from ..instance import Instance
from ..plan import Kit, KitTimes, Plan, Timeline, evaluate
from ..style import plural, styled
from .common import axes_width_in, figure_size, pyplot

if TYPE_CHECKING:
    from matplotlib.artist import Artist
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure

#: Lane positions (y) and bar height of the Gantt chart.
ROBOT_Y = 1.0
HUMAN_Y = 0.0
BAR_HEIGHT = 0.6
#: Width bounds (inches) of a new Gantt chart; it grows with the number of tasks in between.
GANTT_WIDTH = (7.0, 10.0)

#: A label of a bar: (x, y, text or "" when it does not fit, the bar's colour).
_Label = tuple[float, float, str, Any]


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
    """The bars of idle time of either lane (hatched red)."""
    return {
        "facecolor": style.IDLE_COLOR,
        "alpha": 0.35,
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
    tl = timeline if timeline is not None else evaluate(instance, plan)
    n_kits = len(tl.kits)
    colors, colorbar = style.kit_colors(max(n_kits, len(plan.kits)))
    if ax is None:
        ax = _new_gantt_axes(plan)
    makespan = tl.makespan
    right = makespan * 1.02 if makespan > 0 else 1.0
    ax.set_xlim(0.0, right)
    inches_per_s = axes_width_in(ax) / right
    # thin edges when bars are narrow, so that 100 kits do not turn into black stripes
    mean_kit_in = inches_per_s * tl.robot_work / max(n_kits, 1)
    edge: dict[str, Any] = {"edgecolor": "black", "linewidth": 0.5 if mean_kit_in >= 0.15 else 0.15}
    fits = _label_fits(inches_per_s)
    labels = _draw_kits(ax, instance, plan, tl, colors, edge, fits)
    _draw_labels(ax, labels)
    waits = tray_waits(instance, tl)
    _draw_waits_and_idle(ax, tl, waits)
    ax.axvline(makespan, color=style.MAKESPAN_COLOR, linestyle="--", linewidth=1.2, gid="makespan")
    _dress_gantt(ax, instance, tl, method)
    _gantt_legend(ax, colors, colorbar, edge, bool(waits))
    if colorbar:
        _kit_colorbar(ax, len(colors))
    return ax


def _new_gantt_axes(plan: Plan) -> Axes:
    """A new chart 3.4 inches high, wider with more tasks (within :data:`GANTT_WIDTH`)."""
    n_tasks = sum(len(k.tasks) for k in plan.kits)
    width = float(np.clip(5.0 + 0.25 * n_tasks, *GANTT_WIDTH))
    _, ax = pyplot().subplots(figsize=(width, 3.4), layout="constrained")
    return cast("Axes", ax)


def _label_fits(inches_per_s: float) -> Callable[[str, float], bool]:
    """Whether a label fits inside a bar of the given duration (s), with a small margin."""

    def fits(text: str, duration: float) -> bool:
        return style.text_width_in(text, style.SMALL_SIZE) + 0.03 <= duration * inches_per_s

    return fits


def _draw_kits(
    ax: Axes,
    instance: Instance,
    plan: Plan,
    tl: Timeline,
    colors: Sequence[Any],
    edge: dict[str, Any],
    fits: Callable[[str, float], bool],
) -> tuple[list[_Label], list[_Label]]:
    """Every kit's bars in both lanes; returns the labels of the robot's and the human's lane
    (drawn afterwards, only when most of a lane's labels fit)."""
    robot_labels: list[_Label] = []
    task_labels: list[_Label] = []
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
            robot_labels.append(((kt.robot_start + kt.robot_end) / 2, ROBOT_Y, label or "", color))
        _draw_delivery_and_pickup(ax, k, kt, instance.kit_overhead_human, edge)
        task_labels += _draw_tasks(ax, kit, tl, style.lighten(color), edge, fits)
    return robot_labels, task_labels


def _draw_delivery_and_pickup(
    ax: Axes, k: int, kt: KitTimes, overhead: float, edge: dict[str, Any]
) -> None:
    """Kit ``k``'s (0-based) hatched delivery bar and the human's pickup of it."""
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
        min(kt.human_start + overhead, kt.human_end),
        f"human:pickup:{k + 1}",
        color=style.PICKUP_COLOR,
        hatch="xx",
        **edge,
    )


def _draw_tasks(
    ax: Axes,
    kit: Kit,
    tl: Timeline,
    light: Any,
    edge: dict[str, Any],
    fits: Callable[[str, float], bool],
) -> list[_Label]:
    """The human's bar of each task of the kit (tasks the timeline does not hold are skipped);
    returns their labels."""
    labels: list[_Label] = []
    for j, t in enumerate(kit.tasks):
        if t not in tl.task_start:
            continue
        s, e = tl.task_start[t], tl.task_end[t]
        drawn = _bar(ax, HUMAN_Y, s, e, f"human:task:{t}", color=light, **edge)
        if drawn is not None:
            # stagger neighbouring labels so that short tasks stay readable
            dy = BAR_HEIGHT * (0.18 if j % 2 == 0 else -0.18)
            labels.append(((s + e) / 2, HUMAN_Y + dy, t if fits(t, e - s) else "", light))
    return labels


def _draw_labels(ax: Axes, lanes: Sequence[Sequence[_Label]]) -> None:
    """A lane's labels are drawn only if most of them fit: a few scattered labels mislead."""
    for x, y, text, color in (lab for lane in lanes if _most(lane) for lab in lane):
        if text:
            ax.text(
                x,
                y,
                text,
                ha="center",
                va="center",
                fontsize=style.SMALL_SIZE,
                color=style.text_color(color),
                clip_on=True,
            )


def _draw_waits_and_idle(ax: Axes, tl: Timeline, waits: Sequence[tuple[int, float, float]]) -> None:
    """The robot's waits for a returned tray, then the idle time of each lane up to the
    makespan (a wait is not idle time)."""
    wait_style = _wait_style()
    for k, s, e in waits:
        _bar(ax, ROBOT_Y, s, e, f"robot:tray_wait:{k}", **wait_style)
    idle_style = _idle_style()
    robot_busy = sorted(
        [(kt.robot_start, kt.arrive) for kt in tl.kits] + [(s, e) for _, s, e in waits]
    )
    for s, e in _idle_intervals(robot_busy, tl.makespan):
        _bar(ax, ROBOT_Y, s, e, "robot:idle", **idle_style)
    human_busy = [(kt.human_start, kt.human_end) for kt in tl.kits]
    for s, e in _idle_intervals(human_busy, tl.makespan):
        _bar(ax, HUMAN_Y, s, e, "human:idle", **idle_style)


def _dress_gantt(ax: Axes, instance: Instance, tl: Timeline, method: str | None) -> None:
    """Lanes, axis labels, grid and the title: the instance (and method) and the metrics, on
    one line when it fits the axes, else on two."""
    ax.set_yticks([HUMAN_Y, ROBOT_Y], ["human", "robot"])
    ax.set_ylim(HUMAN_Y - 0.6, ROBOT_Y + 0.6)
    ax.set_xlabel("time (s)")
    ax.set_ylabel("resource")
    ax.grid(axis="x", alpha=0.3)
    ax.set_axisbelow(True)
    head = instance.name if method is None else f"{instance.name} / {method}"
    metrics = (
        f"makespan {tl.makespan:.1f} s, human idle {tl.human_idle:.1f} s, "
        f"robot idle {tl.robot_idle:.1f} s, {plural(len(tl.kits), 'kit')}"
    )
    one_line = f"{head}: {metrics}"
    wide = style.text_width_in(one_line, style.TITLE_SIZE) <= axes_width_in(ax)
    ax.set_title(one_line if wide else f"{head}\n{metrics}")


def _gantt_legend(
    ax: Axes, colors: Sequence[Any], colorbar: bool, edge: dict[str, Any], waits: bool
) -> None:
    """The legend under the chart: one row on a wide figure, else two."""
    from matplotlib.lines import Line2D
    from matplotlib.patches import Patch

    first = colors[0] if colors else style.PALETTE[0]
    kit_label = "kitting (colour = kit, see bar)" if colorbar else "kitting (colour = kit)"
    handles: list[Artist] = [
        Patch(facecolor=first, label=kit_label, **edge),
        Patch(facecolor=style.DELIVERY_COLOR, hatch="//", label="delivery", **edge),
    ]
    if waits:
        handles.append(Patch(label="waiting for tray", **_wait_style()))
    handles += [
        Patch(facecolor=style.PICKUP_COLOR, hatch="xx", label="kit pickup", **edge),
        Patch(facecolor=style.lighten(first), label="task", **edge),
        Patch(label="idle", **_idle_style()),
        Line2D([], [], color=style.MAKESPAN_COLOR, linestyle="--", label="makespan"),
    ]
    ncols = len(handles) if figure_size(ax)[0] >= 9.5 else math.ceil(len(handles) / 2)
    ax.legend(
        handles=handles,
        loc="upper center",
        bbox_to_anchor=(0.5, -0.22),
        ncols=ncols,
        frameon=False,
    )


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
