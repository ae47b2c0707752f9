"""Cross-entropy convergence: the best kit fitness per iteration, one line per run."""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING

import numpy as np

from .. import style
from ..style import styled
from .common import pyplot

if TYPE_CHECKING:
    from matplotlib.axes import Axes


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
        _, ax = pyplot().subplots(figsize=(6.0, 3.8), layout="constrained")
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
