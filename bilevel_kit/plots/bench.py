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


#: The left edge (%) of the profile's log axis: instances within it of the reference are drawn
#: there (the reference itself is 0 %, which a log axis cannot show).
PROFILE_FLOOR = 0.01
#: The label of the profile's x axis; its y axis reads "share of instances at most x % above".
PROFILE_X = "x: makespan above best-known (%, log scale; ≤ 0.01 at the left edge)"


@styled
def plot_profile(
    ratios: Mapping[str, Sequence[float]],
    ax: Axes | None = None,
    tau_max: float | None = None,
    *,
    legend: bool = True,
) -> Axes:
    """The performance profile: for each method, the share of instances whose makespan is at
    most x % above the best-known (``ratios``: makespan / best-known per instance, ``inf``
    where the method has no plan; x = 100 (ratio - 1)). The x axis is logarithmic throughout,
    from :data:`PROFILE_FLOOR` % (instances within it, the best-known's own among them, are
    drawn at that edge, labelled "≤0.01") to ``tau_max`` (default: the largest finite ratio,
    at least 1.1); dotted lines mark 1 % and 5 %. Each curve is a step function named
    ``profile:<method>``. The legend sits outside the axes, right (``legend=False``: none, for
    a figure that draws one legend for several profiles)."""
    plt = pyplot()
    if ax is None:
        _, ax = plt.subplots(figsize=(7.5, 4), layout="constrained")
    finite = [r for rs in ratios.values() for r in rs if math.isfinite(r)]
    top = 100 * ((tau_max or max(1.1, 1.02 * max(finite, default=1.1))) - 1)
    swatches = style.categorical(len(ratios))
    for (method, rs), swatch, marker in zip(ratios.items(), swatches, _markers(), strict=False):
        n = len(rs)
        xs = 100 * (np.sort(np.asarray([r for r in rs if math.isfinite(r)], dtype=float)) - 1)
        share = np.arange(1, len(xs) + 1) / max(n, 1)
        x = np.concatenate([[PROFILE_FLOOR], np.maximum(xs, PROFILE_FLOOR), [top]])
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
    ax.set_xscale("log")
    ax.set_xlim(PROFILE_FLOOR, top)
    ax.set_ylim(0.0, 1.02)
    ticks = [t for t in (0.01, 0.1, 1, 5, 10, 100, 1000) if t <= top]
    ax.set_xticks(ticks, ["≤0.01" if t == PROFILE_FLOOR else f"{t:g}" for t in ticks])
    ax.minorticks_off()
    ax.set_xlabel(PROFILE_X)
    ax.set_ylabel("share of instances at most x % above")
    ax.set_title("performance profile")
    if legend:
        ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), borderaxespad=0.0)
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
    count (log scale), one hollow marker per instance and method (``gap:<method>``
    collections), so that markers on one spot stay countable; rows without a value (no plan)
    are left out. The y axis is linear to 1 % and logarithmic beyond (most gaps are near 0
    and a few are large), and each legend entry counts the method's gaps of 0 ("cpsat, 41 at
    0 %"), which all lie on one line."""
    from matplotlib.ticker import NullLocator

    plt = pyplot()
    if ax is None:
        _, ax = plt.subplots(figsize=(6.5, 4), layout="constrained")
    methods = list(methods or dict.fromkeys(str(r["method"]) for r in rows))
    swatches = style.categorical(len(methods))
    for method, swatch, marker in zip(methods, swatches, _markers(), strict=False):
        mine = [r for r in rows if r["method"] == method and r.get(column) is not None]
        gaps = [100 * float(r[column]) for r in mine]
        zeros = sum(g <= 1e-9 for g in gaps)
        ax.scatter(
            [float(r["tasks"]) for r in mine],
            gaps,
            facecolors="none",
            edgecolors=[swatch.color],
            linewidths=0.9,
            marker=marker,
            s=22,
            label=f"{method}, {zeros} at 0 %" if zeros else method,
            gid=f"gap:{method}",
        )
    ax.set_yscale("symlog", linthresh=1.0, linscale=0.6)
    ax.set_ylim(bottom=-0.05)
    ax.axhline(1.0, color="0.6", linestyle=":", lw=0.8)
    high = max(1.0, ax.get_ylim()[1])
    yticks = [t for t in (0, 0.5, 1, 2, 5, 10, 20, 50, 100, 200, 500, 1000) if t <= high]
    ax.set_yticks(yticks, [f"{t:g}" for t in yticks])
    ax.yaxis.set_minor_locator(NullLocator())
    ax.set_xscale("log")
    ax.set_xlabel("tasks (log scale)")
    label = "certified gap" if column == "certified_gap" else column.replace("_", " ")
    ax.set_ylabel(f"{label} (%; linear to 1 %, log beyond)")
    ax.set_title(f"{label} against size")
    ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), borderaxespad=0.0)
    return ax
