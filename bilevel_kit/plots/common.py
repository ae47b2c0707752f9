"""What every figure family shares: pyplot imported on first use (importing the package stays
cheap), the size of an Axes in inches (to decide whether a label fits) and
:func:`save_figure`."""

from __future__ import annotations

import os
from pathlib import Path
from typing import TYPE_CHECKING, Any, cast

from .. import atomic

if TYPE_CHECKING:
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure, SubFigure


def pyplot() -> Any:
    import matplotlib.pyplot as plt

    return plt


def figure_size(ax: Axes) -> tuple[float, float]:
    """(width, height) in inches of the figure holding ``ax``."""
    fig = cast("Figure", ax.get_figure(root=True))
    width, height = fig.get_size_inches()
    return float(width), float(height)


def axes_width_in(ax: Axes) -> float:
    """Width of ``ax`` in inches before layout (a slight under-estimate with constrained
    layout, which is the safe side for deciding whether a label fits)."""
    return max(ax.get_position().width * figure_size(ax)[0], 0.5)


def save_figure(figure: Figure | SubFigure, path: str | os.PathLike[str], dpi: int = 150) -> Path:
    """Write the figure that holds ``figure`` (``ax.figure`` may be a sub-figure) atomically
    (:func:`bilevel_kit.atomic.atomic_path`) with the usual permissions and close it. The
    format follows the suffix (PNG when there is none). Returns the path."""
    fig: Figure = figure.figure  # the root figure (a figure is its own root)
    plt = pyplot()
    out = Path(path)
    fmt = (out.suffix or ".png")[1:].lower()
    try:
        with atomic.atomic_path(out) as tmp:
            fig.savefig(tmp, format=fmt, dpi=dpi, bbox_inches="tight")
            if tmp.is_file():  # not a device written in place (/dev/null)
                umask = os.umask(0)
                os.umask(umask)
                os.chmod(tmp, 0o666 & ~umask)
    finally:
        plt.close(fig)
    return out
