"""Figures of the reproductions: the analogue of Fig. 5 (top), Figure 6's heatmaps and the
horizon study (matplotlib, imported lazily)."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import TYPE_CHECKING, Any

import numpy as np

from .. import style
from .common import LABELS, METRIC_LABELS, OPT, SINGLE, WHOLE

if TYPE_CHECKING:
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure


def plot_user_study(
    table: Sequence[Mapping[str, Any]],
    ax: Axes | None = None,
    *,
    quick: bool = False,
    studies: int | None = None,
) -> Axes:
    """The analogue of Fig. 5 (top): per condition our median study mean with its 95 %
    prediction interval (error bar) and, beside it (not on it), the paper's bar, hatched.
    ``table``: the prediction table (:func:`.user_study.prediction_table`)."""
    import matplotlib.pyplot as plt

    if ax is None:
        _, ax = plt.subplots(figsize=(7.0, 4.0))
    colors = {OPT: "#2e7d32", SINGLE: "#1565c0", WHOLE: "#c62828"}
    by = {r["quantity"]: r for r in table}
    conds = (OPT, SINGLE, WHOLE)
    width = 0.8 / len(conds)
    for g, m in enumerate(("total", "idle")):
        for i, c in enumerate(conds):
            r = by.get(f"mean {METRIC_LABELS[m]}, {LABELS[c]} (s)")
            if r is None:
                continue
            x = g + (i - (len(conds) - 1) / 2) * width
            med, lo, hi = float(r["median"]), float(r["pi_low"]), float(r["pi_high"])
            ax.bar(
                x - width * 0.22,
                med,
                width * 0.44,
                yerr=[[med - lo], [hi - med]],
                capsize=3,
                color=colors[c],
                label=f"{LABELS[c]} (ours)" if g == 0 else None,
                gid=f"bar:{m}:{c}",
            )
            ax.bar(
                x + width * 0.22,
                float(r["paper"]),
                width * 0.44,
                color="white",
                edgecolor=colors[c],
                hatch="///",
                label="paper (Fig. 5)" if g == 0 and i == 0 else None,
                gid=f"paper:{m}:{c}",
            )
            if r["role"] == "fitted":
                ax.annotate(
                    "fitted",
                    (x, hi),
                    xytext=(0, 3),
                    textcoords="offset points",
                    ha="center",
                    fontsize=7,
                )
    ax.set_xticks([0, 1], ["Total task time", "Human idle time"])
    ax.set_ylabel("time per table (s)")
    n = f"{studies} simulated studies" if studies else "simulated studies"
    ax.set_title(
        f"User study: our median study mean, error bars = 95 % prediction interval over {n} "
        f"of 18\n(hatched: the paper's value){' - QUICK run' if quick else ''}",
        fontsize=9,
    )
    ax.grid(axis="y", alpha=0.3)
    ax.legend(fontsize=8)
    return ax


def plot_fig6_panel(
    rows: Sequence[Mapping[str, Any]],
    metric: str,
    subject: str,
    baseline: str,
    ax: Axes | None = None,
    span: float | None = None,
    colorbar: bool = True,
) -> Axes:
    """One heatmap of Figure 6: percent improvement of ``subject`` over ``baseline`` in
    ``metric`` ("total" or "idle"), MAT on the y axis, MTTF on the x axis, annotated with the
    value and the significance stars; the no-delay reference cell in the title. ``span``: the
    colour scale's half-range (a figure passes one for all its panels)."""
    import matplotlib.pyplot as plt
    from matplotlib.colors import TwoSlopeNorm

    if ax is None:
        _, ax = plt.subplots(figsize=(4.6, 3.8))
    name = f"{subject}_over_{baseline}"
    grid = [r for r in rows if r["mat"] is not None]
    mats = sorted({r["mat"] for r in grid})
    mttfs = sorted({r["mttf"] for r in grid})
    z = np.full((len(mats), len(mttfs)), np.nan)
    marks = [["" for _ in mttfs] for _ in mats]
    for r in grid:
        i, j = mats.index(r["mat"]), mttfs.index(r["mttf"])
        v = r.get(f"pct_{metric}:{name}")
        z[i, j] = np.nan if v is None else v
        marks[i][j] = r.get(f"stars_{metric}:{name}", "")
    if span is None:
        span = _span(rows, [(metric, f"{subject}_over_{baseline}")])
    im = ax.imshow(
        z, origin="lower", cmap="RdYlGn", norm=TwoSlopeNorm(0.0, -span, span), aspect="auto"
    )
    for i in range(len(mats)):
        for j in range(len(mttfs)):
            if np.isfinite(z[i, j]):
                ax.text(
                    j,
                    i,
                    f"{z[i, j]:.1f}%\n{marks[i][j]}",
                    ha="center",
                    va="center",
                    fontsize=8,
                    color="white" if abs(z[i, j]) > 0.7 * span else "black",
                    gid=f"cell:{mats[i]:g}:{mttfs[j]:g}",
                )
    ax.set_xticks(range(len(mttfs)), [f"{v:g}" for v in mttfs])
    ax.set_yticks(range(len(mats)), [f"{v:g}" for v in mats])
    ax.set_xlabel("MTTF (s)")
    ax.set_ylabel("MAT (s)")
    title = (
        f"{METRIC_LABELS[metric]}: {LABELS.get(subject, subject)} over "
        f"{LABELS.get(baseline, baseline)}"
    )
    ref = next((r for r in rows if r["mat"] is None), None)
    if ref is not None and ref.get(f"pct_{metric}:{name}") is not None:
        title += (
            f"\nno delay: {ref[f'pct_{metric}:{name}']:.1f}% "
            f"{ref.get(f'stars_{metric}:{name}', '')}"
        )
    ax.set_title(title, fontsize=9)
    if colorbar:
        ax.figure.colorbar(im, ax=ax, label="improvement (%)")
    return ax


def _span(rows: Sequence[Mapping[str, Any]], panels: Sequence[tuple[str, str]]) -> float:
    """Half-range of a colour scale that holds every value of ``panels`` (at least 1 %)."""
    vals = [
        abs(float(v))
        for r in rows
        if r["mat"] is not None
        for m, name in panels
        if (v := r.get(f"pct_{m}:{name}")) is not None
    ]
    return max([1.0, *vals])


def plot_fig6(
    rows: Sequence[Mapping[str, Any]],
    subject: str = OPT,
    baselines: Sequence[str] = (SINGLE, WHOLE),
    *,
    quick: bool = False,
) -> Figure:
    """Figure 6: a grid of heatmaps, one row per metric, one column per baseline, on one
    shared colour scale (colours comparable across panels), with the test, R and whether the
    run was quick written on the figure."""
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(2, len(baselines), figsize=(5.0 * len(baselines), 8.6), squeeze=False)
    panels = [(m, f"{subject}_over_{b}") for m in ("total", "idle") for b in baselines]
    span = _span(rows, panels)
    for i, m in enumerate(("total", "idle")):
        for j, b in enumerate(baselines):
            plot_fig6_panel(rows, m, subject, b, ax=axes[i][j], span=span, colorbar=False)
    fig.tight_layout(rect=(0, 0.06, 0.9, 1))
    cax = fig.add_axes((0.91, 0.12, 0.018, 0.8))
    fig.colorbar(axes[0][0].images[0], cax=cax, label="improvement (%), one scale for all panels")
    r0 = next(iter(rows), {})
    fig.text(
        0.01,
        0.01,
        f"R = {r0.get('reps', '?')} replications per cell, {r0.get('units', '?')} tables per run."
        " * p < .05, ** p < .001: one-way ANOVA over the three policies, then Tukey HSD"
        " (per cell, no correction over cells)."
        + ("  QUICK run: fewer cells and replications." if quick else ""),
        fontsize=8,
        gid="fig6:note",
    )
    return fig


def _time_axis(ax: Axes, label: str, values: Sequence[float]) -> Axes:
    """A second y axis for wall times: log scale when they span a decade or more."""
    twin = ax.twinx()
    pos = [v for v in values if v and v > 0]
    if pos and max(pos) / min(pos) >= 10.0:
        twin.set_yscale("log")
        twin.set_ylim(min(pos) / 2.0, max(pos) * 2.0)
    twin.set_ylabel(label)
    return twin


def _style_legend(ax: Axes, handles: list[Any], what: str, time_what: str) -> None:
    """The series' colours plus what a solid and a dotted line mean."""
    from matplotlib.lines import Line2D

    handles = [
        *handles,
        Line2D([], [], color="black", linestyle="-", marker="o", label=what),
        Line2D([], [], color="black", linestyle=":", label=time_what),
    ]
    ax.legend(
        handles=handles,
        fontsize=style.SMALL_SIZE,
        loc="upper center",
        bbox_to_anchor=(0.5, -0.14),
        ncols=3,
    )


@style.styled
def plot_horizon_gap(
    rows: Sequence[Mapping[str, Any]],
    ax: Axes | None = None,
    mean: Mapping[int, float] | None = None,
) -> Axes:
    """Part A of the horizon study: the gap (%) of greedy-ce's makespan to the exact reference
    against the horizon N, one line per instance (hollow markers: the reference is CP-SAT's
    lower bound, not a proven optimum), ``mean`` (N -> mean gap) as a thick black line, and
    the plan's wall time (dotted) on a second axis."""
    import matplotlib.pyplot as plt
    from matplotlib.lines import Line2D

    if ax is None:
        _, ax = plt.subplots(figsize=(6.4, 4.2), layout="constrained")
    names = list(dict.fromkeys(str(r["instance_file"]) for r in rows))
    swatches = style.categorical(len(names))
    twin = _time_axis(ax, "plan time (s), dotted", [r["plan_time_s"] for r in rows])
    handles = []
    for name, sw in zip(names, swatches, strict=True):
        rs = sorted((r for r in rows if r["instance_file"] == name), key=lambda r: r["horizon"])
        pts = [(r["horizon"], r["gap_pct"]) for r in rs if r["gap_pct"] is not None]
        bound = any(r["reference"] == "bound" for r in rs)
        label = f"{rs[0]['instance']}" + (" (vs bound)" if bound else "")
        if pts:
            x, y = zip(*pts, strict=True)
            ax.plot(
                x,
                y,
                marker="o",
                color=sw.color,
                markerfacecolor="white" if bound else sw.color,
                gid=f"gap:{name}",
            )
        twin.plot(
            [r["horizon"] for r in rs],
            [r["plan_time_s"] for r in rs],
            linestyle=":",
            color=sw.color,
            linewidth=1.0,
            gid=f"time:{name}",
        )
        handles.append(Line2D([], [], color=sw.color, marker="o", label=label))
    if mean:
        ax.plot(list(mean), list(mean.values()), color="black", lw=2.4, gid="gap:mean")
        handles.append(Line2D([], [], color="black", lw=2.4, label="mean over instances"))
    ax.set_xlabel("greedy horizon N (tasks per window)")
    ax.set_ylabel("gap to exact reference (%)")
    ax.set_title("greedy-ce: makespan gap against the horizon N")
    ax.grid(alpha=0.3)
    ax.set_xticks(sorted({int(r["horizon"]) for r in rows}))
    _style_legend(ax, handles, "gap (solid)", "plan time (dotted)")
    return ax


@style.styled
def plot_horizon_window(rows: Sequence[Mapping[str, Any]], ax: Axes | None = None) -> Axes:
    """Part B of the horizon study: cpsat-rolling's improvement in total time over Optimized
    in the same runs (%, positive: faster) against its window, one line per delay cell, and
    the planning time per decision (dotted; Optimized's as a dash-dot level) on a second
    axis."""
    import matplotlib.pyplot as plt
    from matplotlib.lines import Line2D

    if ax is None:
        _, ax = plt.subplots(figsize=(6.4, 4.2), layout="constrained")
    labels = list(dict.fromkeys(str(r["label"]) for r in rows))
    swatches = style.categorical(len(labels))
    twin = _time_axis(
        ax, "planning time per decision (s), dotted", [r["plan_s_per_decision"] for r in rows]
    )
    handles = []
    for label, sw in zip(labels, swatches, strict=True):
        rs = [r for r in rows if r["label"] == label]
        roll = sorted((r for r in rs if r["window"] is not None), key=lambda r: r["window"])
        ax.plot(
            [r["window"] for r in roll],
            [r["total_pct_over_optimized"] for r in roll],
            marker="o",
            color=sw.color,
            gid=f"window:{label}",
        )
        twin.plot(
            [r["window"] for r in roll],
            [r["plan_s_per_decision"] for r in roll],
            linestyle=":",
            color=sw.color,
            linewidth=1.0,
        )
        for r in rs:
            if r["window"] is None:
                twin.axhline(r["plan_s_per_decision"], color=sw.color, linestyle="-.", lw=0.8)
        handles.append(Line2D([], [], color=sw.color, marker="o", label=label))
    ax.axhline(0.0, color="black", linewidth=0.8)
    ax.set_xlabel("cpsat-rolling window (tasks)")
    ax.set_ylabel("total time, improvement over Optimized (%)")
    ax.set_title("cpsat-rolling against Optimized (N = 5) in the same runs")
    ax.grid(alpha=0.3)
    ax.set_xticks(sorted({int(r["window"]) for r in rows if r["window"] is not None}))
    handles.append(
        Line2D([], [], color="black", linestyle="-.", lw=0.8, label="Optimized, s per decision")
    )
    _style_legend(ax, handles, "improvement (solid)", "s per decision (dotted)")
    return ax


@style.styled
def plot_horizon(
    rows: Sequence[Mapping[str, Any]],
    window_rows: Sequence[Mapping[str, Any]] = (),
    *,
    quick: bool = False,
    mean: Mapping[int, float] | None = None,
) -> Figure:
    """The horizon study's figure: the gap against N (``mean``: the mean over the instances)
    and, with Part B, the window panel."""
    import matplotlib.pyplot as plt

    n = 1 + bool(window_rows)
    fig, axes = plt.subplots(1, n, figsize=(6.6 * n, 4.6), squeeze=False, layout="constrained")
    plot_horizon_gap(rows, ax=axes[0][0], mean=mean)
    if window_rows:
        plot_horizon_window(window_rows, ax=axes[0][1])
    if quick:
        fig.suptitle("QUICK run: a reduced grid (fewer instances, N, windows, replications)")
    return fig
