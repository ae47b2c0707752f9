"""Methods compared: makespan and human idle per method (:func:`plot_comparison`, with a broken
y axis when the makespans differ by little) and the gap of each method to the best lower bound
(:func:`plot_gaps`)."""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING, Any

import numpy as np

from .. import style
from ..style import styled
from .common import pyplot

if TYPE_CHECKING:
    from matplotlib.artist import Artist
    from matplotlib.axes import Axes


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

    plt = pyplot()
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
