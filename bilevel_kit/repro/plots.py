"""Figures of the reproductions: the analogue of Fig. 5 (top) and Figure 6's heatmaps
(matplotlib, imported lazily)."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import TYPE_CHECKING, Any

import numpy as np

from .common import LABELS, METRIC_LABELS, OPT, PAPER_MEANS, SINGLE, WHOLE

if TYPE_CHECKING:
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure


def plot_user_study(summary: Mapping[str, Any], ax: Axes | None = None, paper: bool = True) -> Axes:
    """The analogue of Fig. 5 (top): mean total task time and human idle time per condition,
    error bars = 1 SD over participants; the paper's bars as black diamonds."""
    import matplotlib.pyplot as plt

    if ax is None:
        _, ax = plt.subplots(figsize=(6.0, 3.8))
    per = summary["conditions"]
    conds = [c for c in (OPT, SINGLE, WHOLE) if c in per]
    colors = {OPT: "#2e7d32", SINGLE: "#1565c0", WHOLE: "#c62828"}
    width = 0.8 / len(conds)
    for g, m in enumerate(("total", "idle")):
        for i, c in enumerate(conds):
            x = g + (i - (len(conds) - 1) / 2) * width
            ax.bar(
                x,
                per[c][f"{m}_mean"],
                width * 0.92,
                yerr=per[c][f"{m}_sd"],
                capsize=3,
                color=colors.get(c, "0.5"),
                label=LABELS.get(c, c) if g == 0 else None,
                gid=f"bar:{m}:{c}",
            )
            if paper and c in PAPER_MEANS[m]:
                ax.plot(
                    x,
                    PAPER_MEANS[m][c],
                    "D",
                    color="black",
                    ms=5,
                    zorder=5,
                    label="paper (Fig. 5)" if g == 0 and i == 0 else None,
                    gid=f"paper:{m}:{c}",
                )
    ax.set_xticks([0, 1], ["Total task time", "Human idle time"])
    ax.set_ylabel("time (s)")
    ax.set_title("Simulated user study (error bars: 1 SD)")
    ax.grid(axis="y", alpha=0.3)
    ax.legend(fontsize=8)
    return ax


def plot_fig6_panel(
    rows: Sequence[Mapping[str, Any]],
    metric: str,
    subject: str,
    baseline: str,
    ax: Axes | None = None,
) -> Axes:
    """One heatmap of Figure 6: percent improvement of ``subject`` over ``baseline`` in
    ``metric`` ("total" or "idle"), MAT on the y axis, MTTF on the x axis, annotated with the
    value and the significance stars; the no-delay reference cell in the title."""
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
    finite = z[np.isfinite(z)]
    span = max(1.0, float(np.abs(finite).max())) if finite.size else 1.0
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
    ax.figure.colorbar(im, ax=ax, label="improvement (%)")
    return ax


def plot_fig6(
    rows: Sequence[Mapping[str, Any]],
    subject: str = OPT,
    baselines: Sequence[str] = (SINGLE, WHOLE),
) -> Figure:
    """Figure 6: a grid of heatmaps, one row per metric, one column per baseline."""
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(2, len(baselines), figsize=(5.0 * len(baselines), 8.0), squeeze=False)
    for i, m in enumerate(("total", "idle")):
        for j, b in enumerate(baselines):
            plot_fig6_panel(rows, m, subject, b, ax=axes[i][j])
    fig.tight_layout()
    return fig
