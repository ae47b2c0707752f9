"""Methods compared: on one instance, each method's makespan against the best lower bound and
its human idle (:func:`plot_comparison`); over instances, the gap of each method to the best
lower bound (:func:`plot_gaps`). :func:`plot_comparison` labels each method with the lead
figure of ``compare``'s table, "above best bound", (makespan - best bound) / best bound
(docs/timeline.md#terms, docs/figures.md); :func:`plot_gaps` shows the table's ``gap``
field, (makespan - best bound) / makespan."""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING, Any

import numpy as np

from .. import style
from ..methods import above_bound
from ..style import styled
from .common import pyplot

if TYPE_CHECKING:
    from matplotlib.artist import Artist
    from matplotlib.axes import Axes


#: How the chart defines the figure it shows: ``compare``'s "above best bound (%)" column.
ABOVE_TEXT = "+x %: above bound = (makespan - best lower bound) / best lower bound"
#: Makespan of a method, or None when it found no plan.
_Value = float | None


def record_above(record: dict[str, Any]) -> float | None:
    """The record's distance above the best lower bound as ``compare``'s table shows it,
    (makespan - best bound) / best bound, computed from ``best_bound`` when the record has no
    ``above_best`` field; None without a plan or a bound."""
    if record.get("above_best") is not None:
        return float(record["above_best"])
    ms, bound = record.get("makespan"), record.get("best_bound")
    return None if ms is None or bound is None else above_bound(float(ms), float(bound))


def above_label(makespan: float, above: float | None) -> str:
    """A method's label on the chart: its makespan and how far above the best bound it is, in
    % (the title says so, :data:`ABOVE_TEXT`; a longer label overlaps its neighbour's)."""
    if above is None:
        return f"{makespan:.1f} s"
    return f"{makespan:.1f} s\n+{100 * above:.1f} %"


@styled
def plot_comparison(
    records: Sequence[dict[str, Any]], ax: Axes | None = None, idle_ax: Axes | None = None
) -> Axes:
    """Methods compared on one instance (records of ``compare``): each method's makespan as a dot on
    a stem that rises from the best lower bound (a dashed line), so the stem *is* the method's
    distance to the bound, labelled with the makespan and the table's lead figure, "above best
    bound", (makespan - best bound) / best bound; the y axis spans the makespans, not 0..max, and a
    method without a plan says "no plan". Beside it (a new figure, or ``idle_ax``), the human idle
    per method as bars from 0. Each method's status (optimal / feasible / unknown) is under its
    name. Returns the makespan Axes."""
    if ax is None:
        n = len(records)
        _, (ax, idle_ax) = pyplot().subplots(
            1,
            2,
            figsize=(min(12.0, max(6.5, 1.25 * n + 3.5)), 4),
            width_ratios=(3, 2),
            layout="constrained",
        )
    assert ax is not None
    names = [str(r["method"]) for r in records]
    makespans: list[_Value] = [
        float(r["makespan"]) if r.get("makespan") is not None else None for r in records
    ]
    bounds = [float(r["best_bound"]) for r in records if r.get("best_bound") is not None]
    bound = max(bounds) if bounds else None
    _makespan_panel(ax, records, makespans, bound)
    labels = [
        f"{name}\n({r['status']})" if r.get("status") is not None else name
        for name, r in zip(names, records, strict=True)
    ]
    ax.set_xticks(np.arange(len(records)), labels)
    ax.set_xlabel(
        "method (status)" if any(r.get("status") is not None for r in records) else "method"
    )
    name = records[0].get("instance", "") if records else ""
    ax.set_title(f"{name}: makespan per method\n{ABOVE_TEXT}")
    if idle_ax is not None:
        _idle_panel(idle_ax, names, records)
    return ax


def _makespan_panel(
    ax: Axes, records: Sequence[dict[str, Any]], makespans: list[_Value], bound: float | None
) -> None:
    """Dots on stems from the best lower bound (or the best makespan without one), labelled
    with :func:`above_label`; the axis spans the values with room for the labels."""

    values = [v for v in makespans if v is not None]
    base = bound if bound is not None else (min(values) if values else 0.0)
    levels = [*values, base]
    low, high = min(levels), max(levels)
    span = high - low if high > low else max(abs(high) * 0.05, 1.0)
    ax.set_ylim(max(0.0, low - 0.45 * span), high + 0.35 * span)  # the legend goes below
    color = style.PALETTE[0]
    for x, (r, v) in enumerate(zip(records, makespans, strict=True)):
        if v is None:
            _note_above(ax, "no plan", (x, base), 4, color="0.35", gid=f"noplan:{r['method']}")
            continue
        ax.plot([x, x], [base, v], color=color, linewidth=2.5, solid_capstyle="butt")
        ax.plot([x], [v], marker="o", color=color, markersize=7, gid=f"makespan:{r['method']}")
        _note_above(ax, above_label(v, record_above(r)), (x, v), 6)
    ax.set_xlim(-0.6, len(records) - 0.4)
    ax.set_ylabel("makespan (s)")
    ax.grid(axis="y", alpha=0.3)
    ax.set_axisbelow(True)
    _makespan_legend(ax, records, makespans, bound)


def _note_above(ax: Axes, text: str, xy: tuple[float, float], dy: float, **extra: Any) -> None:
    """Small centred text ``dy`` points above the point ``xy``."""
    ax.annotate(
        text,
        xy,
        xytext=(0, dy),
        textcoords="offset points",
        ha="center",
        va="bottom",
        fontsize=style.SMALL_SIZE,
        **extra,
    )


def _makespan_legend(
    ax: Axes, records: Sequence[dict[str, Any]], makespans: list[_Value], bound: float | None
) -> None:
    """The bound line and the legend, in the room left under the lowest value; the bound is
    "optimum = best lower bound" when a method proved a makespan equal to it optimal."""
    from matplotlib.lines import Line2D

    color = style.PALETTE[0]
    handles: list[Artist] = [
        Line2D([], [], color=color, marker="o", linewidth=2.5, label="makespan")
    ]
    if bound is not None:
        optimal = any(
            r.get("status") == "optimal" and v is not None and abs(v - bound) <= 1e-6 * bound
            for r, v in zip(records, makespans, strict=True)
        )
        name = "optimum = best lower bound" if optimal else "best lower bound"
        ax.axhline(bound, color=style.MAKESPAN_COLOR, linestyle="--", lw=1, gid="bound")
        handles.append(
            Line2D(
                [], [], color=style.MAKESPAN_COLOR, linestyle="--", label=f"{name} {bound:.1f} s"
            )
        )
    ax.legend(
        handles=handles,
        loc="lower center",
        ncols=2 if len(records) >= 4 else 1,
        fontsize=style.SMALL_SIZE,
        handlelength=1.6,
        framealpha=0.9,
    )


def _idle_panel(ax: Axes, names: list[str], records: Sequence[dict[str, Any]]) -> None:
    """Human idle per method, bars from 0 labelled with their value."""
    pos = np.arange(len(records))
    for x, r in zip(pos, records, strict=True):
        idle = r.get("human_idle")
        if idle is None or r.get("makespan") is None:
            ax.annotate(
                "no plan", (x, 0), ha="center", va="bottom", fontsize=style.SMALL_SIZE, color="0.35"
            )
            continue
        ax.bar(x, float(idle), 0.6, color=style.IDLE_COLOR, gid="human_idle")
        ax.annotate(
            f"{float(idle):.1f}",
            (x, float(idle)),
            xytext=(0, 1),
            textcoords="offset points",
            ha="center",
            va="bottom",
            fontsize=style.SMALL_SIZE,
        )
    ax.set_xticks(pos, names, rotation=30, ha="right")
    ax.set_xlim(-0.6, len(records) - 0.4)
    ax.set_xlabel("method")
    ax.set_ylabel("human idle (s)")
    ax.set_title("human idle")
    ax.set_ylim(0.0, ax.get_ylim()[1] * 1.12)
    ax.grid(axis="y", alpha=0.3)
    ax.set_axisbelow(True)


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

    plt = pyplot()
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
