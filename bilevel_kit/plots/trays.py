"""Tray layouts: one kit's tray (:func:`plot_tray`) or every kit's on one page
(:func:`plot_trays`), with a fixed fill per part type across all trays of an instance."""

from __future__ import annotations

import math
import re
from collections.abc import Iterable, Sequence
from typing import TYPE_CHECKING, Any, cast

import numpy as np

from .. import style
from ..geometry import corners
from ..instance import Instance
from ..plan import Kit, Placement, Plan
from ..style import plural, styled
from .common import axes_width_in, figure_size, pyplot

if TYPE_CHECKING:
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure

#: Most columns of a new :func:`plot_trays` grid, and the size (inches) of its cells (a
#: single tray, e.g. Whole Assembly's, gets :data:`SINGLE_CELL`: its title lists every task).
TRAY_COLUMNS = 10
TRAY_CELL = (1.7, 3.4)
SINGLE_CELL = 5.5
#: Lines of task names in a tray's title before "+N more".
TASK_LINES = 2
#: What the kit fitness means, for the captions (docs/figures.md#tray-layouts, docs/errata.md).
FITNESS_MEANING = (
    "kit fitness = sum of the distances between parts of different types - sum of those "
    "between parts of one type (mm; paper Eq. 11, minus W6 x overlap, 0 in a valid layout): "
    "bigger is better, negative for a kit of one part type"
)


def type_swatches(instance: Instance) -> dict[str, style.Swatch]:
    """A fixed fill per part type: the sorted type ids mapped onto
    :func:`bilevel_kit.style.categorical`, so a type looks the same in every tray plot of the
    instance and no two types look alike."""
    ids = sorted(instance.part_types)
    return dict(zip(ids, style.categorical(len(ids)), strict=True))


def type_keys(instance: Instance) -> dict[str, str]:
    """A short key per part type, for parts too small to carry the type's name: the initials
    of the words of its id ("screw_short" -> "SS", "foot" -> "F"), numbered when types share
    them ("C1", "C2"). The legend of part types gives each type's key."""
    ids = sorted(instance.part_types)
    initials = {
        t: "".join(w[0] for w in re.split(r"[_\-\s.]+", t) if w).upper() or "?" for t in ids
    }
    out: dict[str, str] = {}
    for t in ids:
        same = [u for u in ids if initials[u] == initials[t]]
        out[t] = initials[t] if len(same) == 1 else f"{initials[t]}{same.index(t) + 1}"
    return out


def type_label(type_id: str, key: str) -> str:
    """A part type's legend entry: its id and its key."""
    return f"{type_id} ({key})"


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


def _type_legend(instance: Instance, used: list[str]) -> dict[str, Any]:
    """The legend's handles (one swatch per part type in ``used``) and title."""
    swatches, keys = type_swatches(instance), type_keys(instance)
    handles = [_type_patch(swatches.get(t), type_label(t, keys[t])) for t in used]
    return {"handles": handles, "title": "part type"}


def _label_angle(theta: float, w: float, h: float) -> float:
    """Text rotation along the placement's long side, kept upright (-90, 90]."""
    a = theta if w >= h else theta + 90.0
    a = (a + 90.0) % 180.0 - 90.0
    return 90.0 if a == -90.0 else a


def _fits(text: str, long_in: float, short_in: float, size: float) -> bool:
    """Whether ``text`` fits inside a part of ``long_in`` x ``short_in`` inches, along its
    long side."""
    return size / 72 * 1.2 <= short_in and style.text_width_in(text, size) + 0.02 <= long_in


def _part_label(type_id: str, key: str, long_in: float, short_in: float, size: float) -> str | None:
    """What names a part inside it: its type where that fits, else the type's key
    (:func:`type_keys`), else None (the part is named on a leader outside it)."""
    return next((c for c in (type_id, key) if _fits(c, long_in, short_in, size)), None)


def kit_fitness(instance: Instance, kit: Kit) -> float | None:
    """Kit fitness (mm, bigger is better; paper Eq. 11 with the sign of docs/errata.md) of the
    kit's layout, None without one."""
    if not kit.layout:
        return None
    from ..fitness import layout_fitness

    return layout_fitness(kit.layout, instance.weights["W6"])


def _fitness_text(instance: Instance, kit: Kit) -> str:
    """ "fitness 2,218 mm", with a true minus sign ("−6 mm": same-type parts only)."""
    f = kit_fitness(instance, kit)
    if f is None:
        return "no layout"
    return f"fitness {round(f):,} mm".replace("-", "−")  # an int: never "-0"


def off_quarter_turn(plan: Plan, tol_deg: float = 0.05) -> int:
    """How many parts of the plan lie at an angle that is not a multiple of 90 degrees: the
    cross-entropy method samples continuous angles (paper Algorithm 1; docs/figures.md,
    "Quarter turns"), and the figure draws them as solved, never rounded."""
    return sum(
        1
        for kit in plan.kits
        for p in kit.layout
        if min(p.theta % 90.0, 90.0 - p.theta % 90.0) > tol_deg
    )


def _task_lines(tasks: Sequence[str], width_in: float, size: float) -> str:
    """The task ids on up to :data:`TASK_LINES` lines of ``width_in`` inches, the last ending
    in "+N more" when they do not all fit (never a task cut in the middle)."""

    def fits(words: list[str]) -> bool:
        return style.text_width_in(", ".join(words) + ",", size) <= width_in

    lines: list[list[str]] = [[]]
    for i, t in enumerate(tasks):
        if fits([*lines[-1], t]):
            lines[-1].append(t)
        elif len(lines) < TASK_LINES and lines[-1]:
            lines.append([t])
        else:
            placed = i
            while lines[-1] and not fits([*lines[-1], f"+{len(tasks) - placed} more"]):
                lines[-1].pop()
                placed -= 1
            lines[-1].append(f"+{len(tasks) - placed} more")
            break
    return ",\n".join(", ".join(words) for words in lines if words)


def _extent(
    instance: Instance, placements: Iterable[Placement]
) -> tuple[float, float, float, float]:
    """(x0, x1, y0, y1) in mm: the tray and every placement, with a margin of 3 % of the
    tray's longer side (a part may stick out; the checker says so, the figure shows it)."""
    W, H = instance.tray.width, instance.tray.height
    xs, ys = [0.0, W], [0.0, H]
    for p in placements:
        c = corners(p.x, p.y, p.w, p.h, p.theta)
        xs += [float(c[:, 0].min()), float(c[:, 0].max())]
        ys += [float(c[:, 1].min()), float(c[:, 1].max())]
    m = 0.03 * max(W, H)
    return min(xs) - m, max(xs) + m, min(ys) - m, max(ys) + m


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
    named by its type: the type's id where it fits inside the part, else the type's short key
    (:func:`type_keys`), else the key on a leader beside the part (one leader for neighbouring
    parts of a type, "SS x2"). The legend gives each type's fill and key. The default title
    gives the number of parts, the kit fitness (:func:`kit_fitness`) and the tasks.
    ``legend=False`` leaves out the legend of part types."""
    W, H = instance.tray.width, instance.tray.height
    if ax is None:
        fig_w = 5.5
        _, ax = pyplot().subplots(figsize=(fig_w + 1.5, fig_w * H / W + 0.9), layout="constrained")
        ax = cast("Axes", ax)
    swatches = type_swatches(instance)
    _draw_tray_outline(ax, W, H)
    x0, x1, y0, y1 = _extent(instance, kit.layout)
    ax.set_xlim(x0, x1)
    ax.set_ylim(y0, y1)
    ax.set_aspect("equal")
    _draw_placements(ax, instance, kit, swatches)
    ax.set_xlabel("x (mm)")
    ax.set_ylabel("y (mm)")
    ax.set_title(_tray_title(instance, kit) if title is None else title, fontsize=style.FONT_SIZE)
    if not kit.layout:
        ax.text(W / 2, H / 2, "no layout", ha="center", va="center", color="gray")
    if legend:
        used = sorted({p.type for p in kit.layout})
        if used:
            ax.legend(
                **_type_legend(instance, used),
                loc="upper left",
                bbox_to_anchor=(1.02, 1.0),
                borderaxespad=0.0,
            )
    return ax


def _draw_tray_outline(ax: Axes, width: float, height: float) -> None:
    from matplotlib.patches import Rectangle

    ax.add_patch(
        Rectangle(
            (0.0, 0.0),
            width,
            height,
            fill=True,
            facecolor="#f5f5f0",
            edgecolor="0.45",
            linewidth=0.6,
            gid="tray",
            zorder=1,
        )
    )


def _inches_per_mm(ax: Axes) -> float:
    """The scale of an equal-aspect Axes: from its width or its height, whichever limits the
    box (before layout, like :func:`~bilevel_kit.plots.common.axes_width_in`)."""
    x0, x1 = ax.get_xlim()
    y0, y1 = ax.get_ylim()
    pos = ax.get_position()
    return min(axes_width_in(ax) / (x1 - x0), pos.height * figure_size(ax)[1] / (y1 - y0))


def _draw_placements(
    ax: Axes, instance: Instance, kit: Kit, swatches: dict[str, style.Swatch]
) -> None:
    """Each placement as a polygon filled by its type and named by its type: inside the part
    where the type (or its key) fits, else on a leader (:func:`_draw_leaders`). A size
    smaller on a tray drawn under 1.5 inches."""
    from matplotlib.patches import Polygon

    scale = _inches_per_mm(ax)
    W, H = instance.tray.width, instance.tray.height
    size = style.SMALL_SIZE if scale * min(W, H) >= 1.5 else style.SMALL_SIZE - 1
    keys = type_keys(instance)
    small: list[Placement] = []
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
        key = keys.get(p.type, p.type)
        label = _part_label(p.type, key, max(p.w, p.h) * scale, min(p.w, p.h) * scale, size)
        if label is None:
            small.append(p)
            continue
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
            gid=f"label:part:{p.part}",
        )
    _draw_leaders(ax, instance, _clusters(small, 0.08 * max(W, H)), keys, size)


def _clusters(parts: Sequence[Placement], reach: float) -> list[list[Placement]]:
    """Parts of one type grouped when their centres are within ``reach`` mm of another part
    of the group (single linkage), so that two screws side by side share one leader."""
    groups: list[list[Placement]] = []
    for p in parts:
        near = [
            g
            for g in groups
            if g[0].type == p.type and any(math.hypot(p.x - q.x, p.y - q.y) <= reach for q in g)
        ]
        merged = [p] + [q for g in near for q in g]
        groups = [g for g in groups if g not in near] + [merged]
    return [sorted(g, key=lambda q: q.part) for g in groups]


#: A label box in points on the page of a tray: (left, bottom, right, top).
_Box = tuple[float, float, float, float]


def _draw_leaders(
    ax: Axes,
    instance: Instance,
    groups: list[list[Placement]],
    keys: dict[str, str],
    size: float,
) -> None:
    """The key of each group of small parts ("SS", or "SS x2" for two), boxed, beside the
    group on a line to its centre: towards the tray's centre where that box is free, else
    turned or moved further out (:func:`_leader_offset`), so that no two boxes overlap."""
    pts_per_mm = 72.0 * _inches_per_mm(ax)
    placed: list[_Box] = []
    for g in groups:
        x = sum(q.x for q in g) / len(g)
        y = sum(q.y for q in g) / len(g)
        text = keys.get(g[0].type, g[0].type) + (f" x{len(g)}" if len(g) > 1 else "")
        box = (72.0 * style.text_width_in(text, size) + 4.0, 1.4 * size + 3.0)
        offset = _leader_offset(ax, instance, (x, y), box, size, pts_per_mm, placed)
        ax.annotate(
            text,
            (x, y),
            xytext=offset,
            textcoords="offset points",
            ha="center",
            va="center",
            fontsize=size,
            zorder=4,
            annotation_clip=True,
            bbox={"boxstyle": "round,pad=0.15", "fc": "white", "ec": "0.4", "lw": 0.4},
            arrowprops={"arrowstyle": "-", "lw": 0.6, "color": "0.2", "shrinkA": 0, "shrinkB": 0},
            gid="label:parts:" + ",".join(q.part for q in g),
        )


def _leader_offset(
    ax: Axes,
    instance: Instance,
    anchor: tuple[float, float],
    box: tuple[float, float],
    size: float,
    pts_per_mm: float,
    placed: list[_Box],
) -> tuple[float, float]:
    """Offset (points) of a leader label of ``box`` (width, height in points) from ``anchor``
    (mm): the first of the directions towards the tray's centre, then turned by 30, 60 and
    90 degrees either way, at 2.6, then 4 and 5.5 font sizes, whose box overlaps no box in
    ``placed`` and stays inside the axes; the first candidate when none does. The chosen box
    is added to ``placed``."""
    x0, x1 = ax.get_xlim()
    y0, y1 = ax.get_ylim()
    ax_, ay = (anchor[0] - x0) * pts_per_mm, (anchor[1] - y0) * pts_per_mm
    limits = (0.0, 0.0, (x1 - x0) * pts_per_mm, (y1 - y0) * pts_per_mm)
    dx, dy = instance.tray.width / 2 - anchor[0], instance.tray.height / 2 - anchor[1]
    base = math.atan2(dy, dx) if (dx, dy) != (0.0, 0.0) else math.pi / 4
    w, h = box
    candidates = [
        (r * size * math.cos(base + t), r * size * math.sin(base + t))
        for r in (2.6, 4.0, 5.5)
        for t in (0.0, *(sign * math.radians(a) for a in (30, 60, 90) for sign in (1, -1)))
    ]
    for ox, oy in candidates:
        cand = (ax_ + ox - w / 2, ay + oy - h / 2, ax_ + ox + w / 2, ay + oy + h / 2)
        inside = (
            cand[0] >= limits[0]
            and cand[1] >= limits[1]
            and cand[2] <= limits[2]
            and cand[3] <= limits[3]
        )
        if inside and not any(_overlap(cand, other) for other in placed):
            placed.append(cand)
            return ox, oy
    ox, oy = candidates[0]
    placed.append((ax_ + ox - w / 2, ay + oy - h / 2, ax_ + ox + w / 2, ay + oy + h / 2))
    return ox, oy


def _overlap(a: _Box, b: _Box) -> bool:
    return a[0] < b[2] and b[0] < a[2] and a[1] < b[3] and b[1] < a[3]


def _tray_title(instance: Instance, kit: Kit) -> str:
    """The default title: number of parts and kit fitness, then the tasks (two lines at
    most, "+N more")."""
    if not kit.tasks:
        return "empty kit"
    tasks = _task_lines(kit.tasks, 4.5, style.FONT_SIZE)
    return f"{plural(len(kit.layout), 'part')}, {_fitness_text(instance, kit)}\ntasks {tasks}"


@styled
def plot_trays(
    instance: Instance, plan: Plan, ncols: int | None = None, *, method: str | None = None
) -> Figure:
    """One :func:`plot_tray` subplot per kit (in delivery order), titled with the kit's number,
    tasks and fitness, and one legend of the part types used by the plan; returns the Figure
    (unused grid cells are hidden). All trays share one scale; tick labels and axis labels
    ("x (mm)", "y (mm)") sit on the left column and on the lowest tray of each column.
    ``ncols`` defaults to about the square root of the number of kits (at least 3, at most
    :data:`TRAY_COLUMNS`); cells shrink from 3.4 to 1.7 inches as columns are added, so 100
    kits stay one readable page. The margins are fixed in inches (no layout engine), which
    keeps a 100-tray figure quick to draw. The title names the instance (and ``method`` when
    given)."""
    n = len(plan.kits)
    if ncols is None:
        ncols = min(TRAY_COLUMNS, max(3, math.ceil(math.sqrt(n))))
    ncols = max(1, min(ncols, n))
    extent = _extent(instance, (p for kit in plan.kits for p in kit.layout))
    cell = SINGLE_CELL if ncols == 1 else float(np.clip(12.0 / ncols, *TRAY_CELL))
    used = sorted({p.type for kit in plan.kits for p in kit.layout})
    keys = type_keys(instance)
    grid = _TrayGrid(n, ncols, cell, extent, [type_label(t, keys[t]) for t in used])
    caption = _caption(instance, plan, method, grid.width - 0.3)
    grid.caption_lines(caption.count("\n") + 1)
    fig, flat = grid.figure()
    for k, kit in enumerate(plan.kits):
        _draw_tray_cell(instance, kit, k, flat[k], grid)
    for ax in flat[n:]:
        ax.set_visible(False)
    if n == 0:
        flat[0].set_visible(True)
        flat[0].set_axis_off()
        flat[0].text(0.5, 0.5, "no kits", ha="center", va="center")
    if used:
        fig.legend(
            **_type_legend(instance, used),
            loc="upper right",
            bbox_to_anchor=(1.0, 1 - (grid.top + grid.hgap) / grid.height),
            frameon=False,
        )
    fig.suptitle(
        caption,
        y=1 - 0.12 / grid.height,
        va="top",
        fontsize=style.FONT_SIZE,
    )
    return fig


def _caption(instance: Instance, plan: Plan, method: str | None, width_in: float) -> str:
    """The page's title, wrapped to ``width_in``: the instance (and method), what the kit
    fitness means (:data:`FITNESS_MEANING`) and, when parts lie off a quarter turn, that the
    angles are drawn as solved (continuous angles of the cross-entropy method)."""
    import textwrap

    W, H = instance.tray.width, instance.tray.height
    head = instance.name if method is None else f"{instance.name} / {method}"
    text = f"{head}: tray layouts of {plural(len(plan.kits), 'kit')} ({W:g} x {H:g} mm). "
    text += FITNESS_MEANING + "."
    off = off_quarter_turn(plan)
    if off:
        text += (
            f" {plural(off, 'part')} at angles off a quarter turn, drawn as solved "
            "(continuous angles; greedy-ce -p snap=true turns them)."
        )
    chars = max(40, int(width_in / style.text_width_in("x", style.FONT_SIZE)))
    return textwrap.fill(text, chars)


class _TrayGrid:
    """The page of :func:`plot_trays`: ``nrows`` x ``ncols`` cells ``cell`` inches wide, and
    margins and gaps fixed in inches (three title lines above each tray, ticks and labels
    outside, the legend of part types on the right, ``top`` for the page's caption)."""

    left, bottom, top, wgap = 0.75, 0.55, 0.5, 0.15

    def caption_lines(self, lines: int) -> None:
        """Make room above the trays for a caption of ``lines`` lines."""
        self.height += 0.2 + lines * 1.3 * style.FONT_SIZE / 72 - self.top
        self.top = 0.2 + lines * 1.3 * style.FONT_SIZE / 72

    def __init__(
        self,
        n: int,
        ncols: int,
        cell: float,
        extent: tuple[float, float, float, float],
        legend: list[str],
    ) -> None:
        self.n, self.ncols = n, ncols
        self.nrows = max(1, math.ceil(n / ncols))
        self.cell, self.extent = cell, extent
        self.small = cell < 2.5
        self.title_size = style.SMALL_SIZE if self.small else style.FONT_SIZE
        x0, x1, y0, y1 = extent
        self.box_h = cell * (y1 - y0) / (x1 - x0)
        self.right = 0.3 + (
            max(style.text_width_in(t, style.LEGEND_SIZE) for t in legend) + 0.5 if legend else 0
        )
        self.hgap = (TASK_LINES + 1.3) * 1.2 * self.title_size / 72 + 0.2
        self.width = self.left + ncols * cell + (ncols - 1) * self.wgap + self.right
        self.height = (
            self.bottom
            + self.nrows * self.box_h
            + (self.nrows - 1) * self.hgap
            + self.hgap
            + self.top
        )

    def figure(self) -> tuple[Figure, list[Axes]]:
        """The figure and its Axes, row by row."""
        fig = pyplot().figure(figsize=(self.width, self.height))
        spec = fig.add_gridspec(
            self.nrows,
            self.ncols,
            left=self.left / self.width,
            right=1 - self.right / self.width,
            bottom=self.bottom / self.height,
            top=1 - (self.top + self.hgap) / self.height,
            wspace=self.wgap / self.cell,
            hspace=self.hgap / self.box_h,
        )
        flat = [fig.add_subplot(spec[r, c]) for r in range(self.nrows) for c in range(self.ncols)]
        return fig, flat


def _draw_tray_cell(instance: Instance, kit: Kit, k: int, ax: Axes, grid: _TrayGrid) -> None:
    """Kit ``k``'s (0-based) tray in its cell, at the page's shared scale; ticks only on the
    left column and on the lowest tray of each column."""
    from matplotlib.ticker import NullLocator

    head = f"kit {k + 1}: " + (kit.tasks[0] if kit.tasks else "no tasks")
    tasks = _task_lines([head, *kit.tasks[1:]], grid.cell, grid.title_size)
    plot_tray(
        instance,
        kit,
        ax=ax,
        title=f"{tasks}\n{_fitness_text(instance, kit)}",
        legend=False,
    )
    ax.title.set_fontsize(grid.title_size)
    x0, x1, y0, y1 = grid.extent
    ax.set_xlim(x0, x1)
    ax.set_ylim(y0, y1)
    if grid.small:
        ax.tick_params(labelsize=style.SMALL_SIZE - 1, length=2, pad=1)
        ax.locator_params(nbins=3)
    if k + grid.ncols < grid.n:  # a tray below shows the x axis (no ticks: quicker to draw)
        ax.set_xlabel("")
        ax.xaxis.set_major_locator(NullLocator())
    if k % grid.ncols:
        ax.set_ylabel("")
        ax.yaxis.set_major_locator(NullLocator())
