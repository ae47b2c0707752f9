"""The stations study's figures (docs/stations.md): throughput and human idle against the
stations per robot S, one figure per line, drawn from the study's rows (``stations.csv``) and
the capacity bound, so that a committed figure is redrawn from the committed CSV in seconds
(``python paper_repro/draw_stations.py``) instead of by the hour-long study.

Each policy keeps one colour and one marker in every figure (:data:`LABELS`' order). Its 95 %
interval is an error bar, not a shaded band: with four policies the bands overlapped and their
mixed colours matched no policy. The policies' points at one S are set slightly apart so none
hides another, and both panels of a row share their y scale, so the two supply settings read
against each other.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

from .. import style

if TYPE_CHECKING:
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure

#: The policies in their fixed order (colour, marker and offset follow it) and their names.
LABELS = {
    "single-task": "Single Task",
    "whole-assembly": "Whole Assembly",
    "cpsat-rolling": "cpsat-rolling",
    "optimized": "Optimized (greedy-ce)",
}
MARKERS = ("o", "s", "^", "D", "v", "P")
#: Horizontal distance (in S) between two policies' points at one S.
DODGE = 0.07
#: Columns of ``stations.csv`` read as numbers (the rest stay text).
_TEXT = ("line", "delay", "policy")


def rows_from_csv(records: Sequence[Mapping[str, str]]) -> list[dict[str, Any]]:
    """The study's rows as :func:`bilevel_kit.experiments.tables.read_csv` gives them back:
    ``stations`` and ``reps`` integers, every other column but the names a float."""
    out = []
    for r in records:
        row: dict[str, Any] = {}
        for key, text in r.items():
            if key in _TEXT:
                row[key] = text
            elif key in ("stations", "reps"):
                row[key] = int(text)
            else:
                row[key] = float(text)
        out.append(row)
    return out


def _policies(rows: Sequence[Mapping[str, Any]]) -> list[str]:
    known = [p for p in LABELS if any(r["policy"] == p for r in rows)]
    return known + [p for p in dict.fromkeys(r["policy"] for r in rows) if p not in known]


@style.styled
def plot_stations_panel(
    rows: Sequence[Mapping[str, Any]],
    *,
    line: str,
    delay: str,
    metric: str = "throughput",
    bound: Sequence[float] | None = None,
    threshold: float | None = None,
    ax: Axes | None = None,
) -> Axes:
    """One panel: ``metric`` (``throughput`` or ``idle``, the reproduction's) against S, one
    line per policy with its 95 % interval as error bars, ``bound`` (the capacity bound at each
    S of the rows, a ceiling on throughput and a floor on idle) dotted, and on the idle panel
    the ``threshold`` (a fraction) dashed."""
    import matplotlib.pyplot as plt

    if ax is None:
        _, ax = plt.subplots(figsize=(4.8, 3.2), layout="constrained")
    mine = [r for r in rows if r["line"] == line and r["delay"] == delay]
    every = _policies(rows)  # (the same order, colours and offsets in every panel)
    swatches = style.categorical(len(every))
    top = 100.0 if metric == "idle" else math.inf
    for i, policy in enumerate(every):
        rs = sorted((r for r in mine if r["policy"] == policy), key=lambda r: r["stations"])
        if not rs:
            continue
        shift = (i - (len(every) - 1) / 2) * DODGE
        x = [r["stations"] + shift for r in rs]
        y = [r[metric] for r in rs]
        # (a rate is never negative, a share never above 100 %: the t-interval is cut there)
        lo = [y_ - max(0.0, r[f"{metric}_low"]) for y_, r in zip(y, rs, strict=True)]
        hi = [min(top, r[f"{metric}_high"]) - y_ for y_, r in zip(y, rs, strict=True)]
        reps = sorted({int(r["reps"]) for r in rs})
        label = f"{LABELS.get(policy, policy)} ({'/'.join(map(str, reps))} replications)"
        ax.errorbar(
            x,
            y,
            yerr=[lo, hi],
            color=swatches[i].color,
            marker=MARKERS[i % len(MARKERS)],
            ms=4.5,
            mec="white",
            mew=0.6,
            lw=1.3,
            elinewidth=1.0,
            capsize=3,
            label=label,
            zorder=3 + i,
        )
    grid = sorted({int(r["stations"]) for r in mine})
    if bound is not None:
        ax.plot(grid, bound, color="black", ls=":", lw=1.2, label="capacity bound (any policy)")
    if metric == "idle":
        if threshold is not None:
            label = f"{100 * threshold:g} % idle"
            ax.axhline(100 * threshold, color="black", ls="--", lw=0.8, label=label)
        ax.set_ylabel("human idle per station (%)")
    else:
        ax.set_ylabel("throughput (units per hour)")
    ax.set_xlabel("stations per robot S")
    ax.set_xticks(grid)
    supply = "shared feeders, not scaled with S" if delay == "feeders" else "in stock"
    ax.set_title(f"{line} line, supply: {supply}")
    ax.grid(alpha=0.3)
    return ax


@style.styled
def plot_stations(
    rows: Sequence[Mapping[str, Any]],
    line: str,
    bounds: Mapping[str, Sequence[float]],
    *,
    threshold: float,
    quick: bool = False,
) -> Figure:
    """Throughput (top) and human idle (bottom) against S for one line, parts in stock and
    with shared feeders (columns, one y scale per row); ``bounds``: the capacity bound per
    metric at the rows' S."""
    import matplotlib.pyplot as plt

    present = list(dict.fromkeys(str(r["delay"]) for r in rows if r["line"] == line))
    delays: list[str] = [d for d in ("none", "feeders") if d in present]
    delays += [d for d in present if d not in delays]
    fig, axes = plt.subplots(
        2,
        len(delays),
        figsize=(4.6 * len(delays), 6.6),
        squeeze=False,
        sharey="row",
        layout="constrained",
    )
    for j, delay in enumerate(delays):
        for i, metric in enumerate(("throughput", "idle")):
            plot_stations_panel(
                rows,
                line=line,
                delay=delay,
                metric=metric,
                bound=bounds[metric],
                threshold=threshold,
                ax=axes[i][j],
            )
        axes[1][j].set_title("")
        if j:
            axes[0][j].set_ylabel("")
            axes[1][j].set_ylabel("")
    handles, labels = axes[1][0].get_legend_handles_labels()
    order = sorted(range(len(labels)), key=lambda k: "replications" not in labels[k])  # policies
    fig.legend(
        [handles[k] for k in order], [labels[k] for k in order], loc="outside lower center", ncols=3
    )
    note = "bars: 95 % t-interval over the replications"
    fig.suptitle(("QUICK run: fewer stations, units and replications; " if quick else "") + note)
    return fig


def draw_figures(
    rows: Sequence[Mapping[str, Any]],
    out: Path,
    bounds_of: Callable[[str, Sequence[int]], Mapping[str, Sequence[float]]],
    *,
    threshold: float,
    quick: bool = False,
    name: str = "stations_{line}.png",
) -> dict[str, Path]:
    """One figure per line of ``rows`` into ``out`` (file ``name``); ``bounds_of(line,
    grid)``: the capacity bound per metric at the S of ``grid``."""
    from ..plots import save_figure

    files = {}
    for line in dict.fromkeys(str(r["line"]) for r in rows):
        grid = sorted({int(r["stations"]) for r in rows if r["line"] == line})
        fig = plot_stations(rows, line, bounds_of(line, grid), threshold=threshold, quick=quick)
        files[f"figure_{line}"] = save_figure(fig, out / name.format(line=line))
    return files
