"""KitBench figures (docs/kitbench.md): the Dolan-More performance profile of methods against
the best-known plans (:func:`plot_profile`) and each method's certified gap against the
instance size (:func:`plot_gap_vs_size`)."""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from typing import TYPE_CHECKING, Any

import numpy as np

from .. import style
from ..style import styled
from .common import pyplot

if TYPE_CHECKING:
    from matplotlib.axes import Axes

#: The markers of the methods in the gap-versus-size plot (cycled).
MARKERS = ("o", "s", "^", "D", "v", "P", "X", "*")


@styled
def plot_profile(
    ratios: Mapping[str, Sequence[float]],
    ax: Axes | None = None,
    tau_max: float | None = None,
) -> Axes:
    """The performance profile: for each method, the share of instances whose makespan is
    within a factor tau of the best-known (``ratios``: makespan / best-known per instance,
    ``inf`` where the method has no plan). The x axis is tau - 1 in percent ("above
    best-known"), linear up to 1 % and logarithmic beyond, so the first percent and the tail
    both show; dotted lines mark 1 % and 5 %. It runs to ``tau_max`` (default: the largest
    finite ratio, at least 1.1). Each curve is a step function named ``profile:<method>``."""
    plt = pyplot()
    if ax is None:
        _, ax = plt.subplots(figsize=(6.5, 4), layout="constrained")
    finite = [r for rs in ratios.values() for r in rs if math.isfinite(r)]
    top = 100 * ((tau_max or max(1.1, 1.02 * max(finite, default=1.1))) - 1)
    swatches = style.categorical(len(ratios))
    for (method, rs), swatch, marker in zip(ratios.items(), swatches, _markers(), strict=False):
        n = len(rs)
        xs = 100 * (np.sort(np.asarray([r for r in rs if math.isfinite(r)], dtype=float)) - 1)
        share = np.arange(1, len(xs) + 1) / max(n, 1)
        x = np.concatenate([[0.0], np.maximum(xs, 0.0), [top]])
        y = np.concatenate([[0.0], share, [share[-1] if len(share) else 0.0]])
        ax.step(
            x,
            y,
            where="post",
            color=swatch.color,
            label=method,
            gid=f"profile:{method}",
            marker=marker,
            markevery=[len(x) - 1],
            markersize=4,
        )
    for pct in (1.0, 5.0):
        if pct < top:
            ax.axvline(pct, color="0.5", linestyle=":", lw=0.8, gid=f"tau:{pct:g} %")
    ax.set_xscale("symlog", linthresh=1.0, linscale=1.0)
    ax.set_xlim(0.0, top)
    ax.set_ylim(0.0, 1.02)
    ticks = [t for t in (0, 0.5, 1, 2, 5, 10, 20, 50, 100, 200, 500) if t <= top]
    ax.set_xticks(ticks, [f"{t:g}" for t in ticks])
    ax.minorticks_off()
    ax.set_xlabel("above best-known, τ - 1 (%; linear to 1 %, log beyond)")
    ax.set_ylabel("share of instances within τ")
    ax.set_title("performance profile")
    ax.legend(loc="lower right")
    return ax


def _markers() -> Any:
    while True:
        yield from MARKERS


@styled
def plot_gap_vs_size(
    rows: Sequence[Mapping[str, Any]],
    ax: Axes | None = None,
    methods: Sequence[str] | None = None,
    column: str = "certified_gap",
) -> Axes:
    """Each method's gap (``column``, a fraction, drawn in %) against the instance's task
    count (log scale), one marker per instance and method (``gap:<method>`` collections);
    rows without a value (no plan) are left out."""
    plt = pyplot()
    if ax is None:
        _, ax = plt.subplots(figsize=(6.5, 4), layout="constrained")
    methods = list(methods or dict.fromkeys(str(r["method"]) for r in rows))
    swatches = style.categorical(len(methods))
    for method, swatch, marker in zip(methods, swatches, _markers(), strict=False):
        mine = [r for r in rows if r["method"] == method and r.get(column) is not None]
        ax.scatter(
            [float(r["tasks"]) for r in mine],
            [100 * float(r[column]) for r in mine],
            color=swatch.color,
            marker=marker,
            s=16,
            alpha=0.8,
            label=method,
            gid=f"gap:{method}",
        )
    ax.set_xscale("log")
    ax.set_xlabel("tasks (log scale)")
    label = "certified gap" if column == "certified_gap" else column.replace("_", " ")
    ax.set_ylabel(f"{label} (%)")
    ax.set_title(f"{label} against size")
    ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), borderaxespad=0.0)
    return ax
