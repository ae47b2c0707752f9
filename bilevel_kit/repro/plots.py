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

#: Figure 6's diverging colour map: ColorBrewer's red-blue, colour-blind safe (the paper's
#: red-green is not); blue is an improvement, red a loss.
FIG6_CMAP = "RdBu"
#: Figure 6's axes, spelled out (docs/simulation.md, "Processes").
MTTF_LABEL = "MTTF: the feeders' mean time to failure (s)"
MAT_LABEL = "MAT: mean time between part arrivals (s)"
#: Largest spread (in N) of the horizon study's instances around each N.
HORIZON_DODGE = 0.4
#: What the tags over the user study's bars mean.
KIND_NOTE = (
    "tags: fitted = a bar the calibration was fitted to, implied = fixed by the fitted bars;"
    " neither is a prediction"
)


def plot_user_study(
    table: Sequence[Mapping[str, Any]],
    ax: Axes | None = None,
    *,
    quick: bool = False,
    studies: int | None = None,
) -> Axes:
    """The analogue of Fig. 5 (top): per condition our median study mean with two 95 %
    prediction intervals (thick: the participants' variation alone; thin, capped: with the
    calibration's uncertainty) and, beside it (not on it), the paper's bar, hatched, with its
    read-off range. Fitted and implied means are labelled (they are not predictions).
    ``table``: the prediction table (:func:`.predictions.prediction_table`)."""
    import matplotlib.pyplot as plt

    if ax is None:
        _, ax = plt.subplots(figsize=(7.6, 4.8), layout="constrained")
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
            _user_study_pair(ax, r, x, width, colors[c])
    ax.set_xticks([0, 1], ["Total task time", "Human idle time"])
    ax.set_ylabel("time per table (s)")
    n = f"{studies} simulated studies" if studies else "simulated studies"
    ax.set_title(
        f"User study: our median study mean per condition over {n} of 18 participants"
        f"{' - QUICK run' if quick else ''}",
        fontsize=8.5,
    )
    ax.grid(axis="y", alpha=0.3)
    _user_study_legend(ax, colors, conds)
    return ax


def _user_study_legend(ax: Axes, colors: Mapping[str, str], conds: Sequence[str]) -> None:
    """Under the axes: each condition's bar and its paper bar (hatched, in its colour), the
    two kinds of error bar as drawn, and what the tags mean."""
    from matplotlib.lines import Line2D
    from matplotlib.patches import Patch

    handles: list[Any] = []
    for c in conds:
        handles.append(Patch(facecolor=colors[c], label=f"{LABELS[c]} (ours)"))
        handles.append(
            Patch(
                facecolor="white",
                edgecolor=colors[c],
                hatch="///",
                hatchcolor=colors[c],
                label=f"{LABELS[c]}, paper's Fig. 5 bar (± read-off)",
            )
        )
    handles += [
        Line2D([], [], color="black", lw=3.0, label="95 % PI, participants only (thick)"),
        Line2D(
            [],
            [],
            color="0.35",
            lw=0.9,
            marker="_",
            markersize=7,
            label="95 % PI, with calibration uncertainty (thin, capped)",
        ),
    ]
    ax.legend(
        handles=handles,
        fontsize=7,
        loc="upper center",
        bbox_to_anchor=(0.5, -0.08),
        ncols=3,
        title=KIND_NOTE,
        title_fontsize=7,
        frameon=False,
    )


def _user_study_pair(ax: Axes, r: Mapping[str, Any], x: float, width: float, color: str) -> None:
    """Our bar (two intervals) and the paper's hatched bar beside it for one condition."""
    med = float(r["median"])
    lo, hi = float(r["pi_low"]), float(r["pi_high"])
    clo = lo if r.get("cal_low") in (None, "") else float(r["cal_low"])
    chi = hi if r.get("cal_high") in (None, "") else float(r["cal_high"])
    xo, xp = x - width * 0.22, x + width * 0.22
    gid = str(r["quantity"])
    m = "idle" if "idle" in gid else "total"
    cond = next(c for c, name in LABELS.items() if name in gid)
    ax.bar(
        xo,
        med,
        width * 0.44,
        color=color,
        gid=f"bar:{m}:{cond}",
    )
    # side by side, so the thin interval never hides behind the thick one
    for low, high, line, cap, dx, bar_color, kind in (
        (clo, chi, 0.9, 3, 0.09, "0.35", "calibration"),
        (lo, hi, 3.0, 0, -0.07, "black", "participants"),
    ):
        ax.errorbar(
            xo + dx * width,
            med,
            yerr=[[max(med - low, 0.0)], [max(high - med, 0.0)]],
            fmt="none",
            ecolor=bar_color,
            elinewidth=line,
            capsize=cap,
            gid=f"pi:{kind}:{m}:{cond}",
        )
    h = float(r.get("readoff") or 0.0)
    paper = float(r["paper"])
    ax.bar(
        xp,
        paper,
        width * 0.44,
        color="white",
        edgecolor=color,
        hatch="///",
        hatchcolor=color,
        yerr=[[h], [h]],
        capsize=2,
        gid=f"paper:{m}:{cond}",
    )
    kind = str(r.get("kind") or r.get("role") or "")
    if kind in ("fitted", "implied"):
        ax.annotate(
            kind,
            (x, max(chi, paper + h)),
            xytext=(0, 3),
            textcoords="offset points",
            ha="center",
            fontsize=7,
        )


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
    paired = _paired_marks(grid, metric, name)
    for r, arrow in zip(grid, paired, strict=True):
        i, j = mats.index(r["mat"]), mttfs.index(r["mttf"])
        v = r.get(f"pct_{metric}:{name}")
        z[i, j] = np.nan if v is None else v
        marks[i][j] = f"{r.get(f'stars_{metric}:{name}', '')} {arrow}".strip()
    if span is None:
        span = _span(rows, [(metric, f"{subject}_over_{baseline}")])
    im = ax.imshow(
        z, origin="lower", cmap=FIG6_CMAP, norm=TwoSlopeNorm(0.0, -span, span), aspect="auto"
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
    ax.set_xlabel(MTTF_LABEL)
    ax.set_ylabel(MAT_LABEL)
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


def _paired_marks(grid: Sequence[Mapping[str, Any]], metric: str, name: str) -> list[str]:
    """▲/▼ where the paired t-test after Holm over the panel's cells finds the subject
    significantly better/worse (:mod:`.fig6_stats`), else nothing."""
    from .fig6_stats import BETTER, WORSE, direction, holm

    sig = holm([r.get(f"p_paired_{metric}:{name}") for r in grid])
    dirs = [direction(s, r.get(f"pct_{metric}:{name}")) for s, r in zip(sig, grid, strict=True)]
    return [{BETTER: "▲", WORSE: "▼"}.get(d, "") for d in dirs]


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
    fig.colorbar(
        axes[0][0].images[0],
        cax=cax,
        label="improvement (%; blue: better, red: worse), one scale for all panels",
    )
    r0 = next(iter(rows), {})
    fig.text(
        0.01,
        0.01,
        f"R = {r0.get('reps', '?')} replications per cell, {r0.get('units', '?')} tables per run."
        " * p < .05, ** p < .001: one-way ANOVA over the three policies, then Tukey HSD"
        " (per cell, no correction over cells).\n▲/▼: significantly better/worse by the paired"
        " t-test over the replications, after Holm over the panel's cells. MAT: mean time between"
        " part arrivals; MTTF: the feeders' mean time to failure."
        + ("  QUICK run: fewer cells and replications." if quick else ""),
        fontsize=8,
        gid="fig6:note",
    )
    return fig


def _legend_below(ax: Axes, handles: list[Any]) -> None:
    """The series' legend under ``ax`` (the lines share their colours with the panel below)."""
    ax.legend(
        handles=handles,
        fontsize=style.SMALL_SIZE,
        loc="upper center",
        bbox_to_anchor=(0.5, -0.2),
        ncols=3,
    )


def _log_if_wide(ax: Axes, values: Sequence[float]) -> None:
    """A log y axis when positive ``values`` span a decade or more."""
    pos = [v for v in values if v and v > 0]
    if pos and max(pos) / min(pos) >= 10.0:
        ax.set_yscale("log")


@style.styled
def plot_horizon_gap(
    rows: Sequence[Mapping[str, Any]],
    ax: Axes | None = None,
    mean: Mapping[int, float] | None = None,
) -> Axes:
    """Part A of the horizon study: the gap (%) of greedy-ce's makespan to the exact reference
    against the horizon N, one thin line per instance, dodged along N by up to
    :data:`HORIZON_DODGE` (hollow markers: the reference is CP-SAT's lower bound, not a proven
    optimum; the title says so) and ``mean`` (N -> mean gap) as a thick black line; the
    legend beside the axes.
    The plan times are a panel of their own (:func:`plot_horizon_time`): one y axis per
    panel, so no line reads against the wrong axis."""
    import matplotlib.pyplot as plt
    from matplotlib.lines import Line2D

    if ax is None:
        _, ax = plt.subplots(figsize=(6.4, 4.2), layout="constrained")
    names = list(dict.fromkeys(str(r["instance_file"]) for r in rows))
    handles = []
    for k, (name, sw) in enumerate(zip(names, style.categorical(len(names)), strict=True)):
        rs = sorted((r for r in rows if r["instance_file"] == name), key=lambda r: r["horizon"])
        # each instance a little apart along N (at most +-0.2), thin and light, so that eight
        # series on one spot stay apart and the mean reads above them
        dx = HORIZON_DODGE * (k - (len(names) - 1) / 2) / max(len(names) - 1, 1)
        pts = [(r["horizon"] + dx, r["gap_pct"]) for r in rs if r["gap_pct"] is not None]
        bound = any(r["reference"] == "bound" for r in rs)
        if pts:
            x, y = zip(*pts, strict=True)
            face = "white" if bound else sw.color
            ax.plot(
                x,
                y,
                marker="o",
                markersize=4,
                lw=0.9,
                alpha=0.75,
                color=sw.color,
                markerfacecolor=face,
                gid=f"gap:{name}",
            )
        label = f"{rs[0]['instance']}" + (" (vs bound)" if bound else "")
        handles.append(Line2D([], [], color=sw.color, marker="o", markersize=4, label=label))
    if mean:
        ax.plot(list(mean), list(mean.values()), color="black", lw=2.4, gid="gap:mean", zorder=5)
        handles.append(Line2D([], [], color="black", lw=2.4, label="mean over instances"))
    ax.set_xlabel("greedy horizon N (tasks per window)")
    ax.set_ylabel("gap to the exact reference (%)")
    ax.set_title(
        "greedy-ce: makespan gap against the horizon N\n"
        "exact reference: CP-SAT's proven optimum (filled), else its lower bound (hollow)",
        fontsize=style.FONT_SIZE,
    )
    ax.grid(alpha=0.3)
    ax.set_xticks(sorted({int(r["horizon"]) for r in rows}))
    ax.legend(
        handles=handles,
        fontsize=style.SMALL_SIZE,
        ncols=1,
        loc="upper left",
        bbox_to_anchor=(1.01, 1.0),
        borderaxespad=0.0,
    )
    return ax


@style.styled
def plot_horizon_time(rows: Sequence[Mapping[str, Any]], ax: Axes | None = None) -> Axes:
    """Part A's plan times (s) against N, one line per instance in the gap panel's colours."""
    import matplotlib.pyplot as plt

    if ax is None:
        _, ax = plt.subplots(figsize=(6.4, 3.2), layout="constrained")
    names = list(dict.fromkeys(str(r["instance_file"]) for r in rows))
    for name, sw in zip(names, style.categorical(len(names)), strict=True):
        rs = sorted((r for r in rows if r["instance_file"] == name), key=lambda r: r["horizon"])
        x = [r["horizon"] for r in rs]
        ax.plot(x, [r["plan_time_s"] for r in rs], marker=".", color=sw.color, gid=f"time:{name}")
    _log_if_wide(ax, [r["plan_time_s"] for r in rows])
    ax.set_xlabel("greedy horizon N (tasks per window)")
    ax.set_ylabel("plan time (s)")
    ax.set_title("greedy-ce: wall time of one plan")
    ax.grid(alpha=0.3, which="both")
    ax.set_xticks(sorted({int(r["horizon"]) for r in rows}))
    return ax


@style.styled
def plot_horizon_window(rows: Sequence[Mapping[str, Any]], ax: Axes | None = None) -> Axes:
    """Part B of the horizon study: cpsat-rolling's improvement in total time over Optimized
    in the same runs (%, positive: faster) against its window, one line per delay cell, with
    the 95 % interval of the paired gain as error bars."""
    import matplotlib.pyplot as plt
    from matplotlib.lines import Line2D

    if ax is None:
        _, ax = plt.subplots(figsize=(6.4, 4.2), layout="constrained")
    labels = list(dict.fromkeys(str(r["label"]) for r in rows))
    handles = []
    for k, (label, sw) in enumerate(zip(labels, style.categorical(len(labels)), strict=True)):
        roll = sorted(
            (r for r in rows if r["label"] == label and r["window"] is not None),
            key=lambda r: r["window"],
        )
        x = [r["window"] + 0.25 * (k - (len(labels) - 1) / 2) for r in roll]
        y = [r["total_pct_over_optimized"] for r in roll]
        lo = [r.get("total_pct_ci_low") for r in roll]
        hi = [r.get("total_pct_ci_high") for r in roll]
        ax.plot(x, y, marker="o", color=sw.color, gid=f"window:{label}")
        if all(v is not None for v in lo + hi):
            err = [
                [v - a for v, a in zip(y, lo, strict=True)],
                [b - v for v, b in zip(y, hi, strict=True)],
            ]
            ax.errorbar(x, y, yerr=err, fmt="none", ecolor=sw.color, capsize=3, lw=1.0)
        handles.append(Line2D([], [], color=sw.color, marker="o", label=label))
    ax.axhline(0.0, color="black", linewidth=0.8)
    ax.set_xlabel("cpsat-rolling window (tasks)")
    ax.set_ylabel("total time, gain over Optimized (%)")
    ax.set_title("cpsat-rolling against Optimized (N = 5), same runs; bars: 95 % CI")
    ax.grid(alpha=0.3)
    ax.set_xticks(sorted({int(r["window"]) for r in rows if r["window"] is not None}))
    ax.legend(handles=handles, fontsize=style.SMALL_SIZE)
    return ax


@style.styled
def plot_horizon_decision(rows: Sequence[Mapping[str, Any]], ax: Axes | None = None) -> Axes:
    """Part B's planning time per decision (s) against the window, one line per delay cell in
    the window panel's colours; Optimized's as a dashed level of the same colour."""
    import matplotlib.pyplot as plt
    from matplotlib.lines import Line2D

    if ax is None:
        _, ax = plt.subplots(figsize=(6.4, 3.2), layout="constrained")
    labels = list(dict.fromkeys(str(r["label"]) for r in rows))
    for label, sw in zip(labels, style.categorical(len(labels)), strict=True):
        rs = [r for r in rows if r["label"] == label]
        roll = sorted((r for r in rs if r["window"] is not None), key=lambda r: r["window"])
        ax.plot(
            [r["window"] for r in roll],
            [r["plan_s_per_decision"] for r in roll],
            marker=".",
            color=sw.color,
        )
        for r in rs:
            if r["window"] is None:
                ax.axhline(r["plan_s_per_decision"], color=sw.color, linestyle="--", lw=0.9)
    _log_if_wide(ax, [r["plan_s_per_decision"] for r in rows])
    ax.set_xlabel("cpsat-rolling window (tasks)")
    ax.set_ylabel("planning time per decision (s)")
    ax.set_title("planning time per decision")
    ax.grid(alpha=0.3, which="both")
    ax.set_xticks(sorted({int(r["window"]) for r in rows if r["window"] is not None}))
    dashed = Line2D([], [], color="black", linestyle="--", lw=0.9, label="Optimized (N = 5)")
    solid = Line2D([], [], color="black", marker=".", label="cpsat-rolling")
    ax.legend(handles=[solid, dashed], fontsize=style.SMALL_SIZE)
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
    above the plan times and, with Part B, the window's gain above its planning time; every
    panel has one y axis."""
    import matplotlib.pyplot as plt

    n = 1 + bool(window_rows)
    fig, axes = plt.subplots(
        2,
        n,
        figsize=(6.6 * n, 7.6),
        squeeze=False,
        layout="constrained",
        height_ratios=(1.5, 1.0),
        sharex="col",
    )
    plot_horizon_gap(rows, ax=axes[0][0], mean=mean)
    plot_horizon_time(rows, ax=axes[1][0])
    if window_rows:
        plot_horizon_window(window_rows, ax=axes[0][1])
        plot_horizon_decision(window_rows, ax=axes[1][1])
    for ax in axes[0]:
        ax.set_xlabel("")
    if quick:
        fig.suptitle("QUICK run: a reduced grid (fewer instances, N, windows, replications)")
    return fig
