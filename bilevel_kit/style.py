"""One figure style for the toolkit: fonts, sizes, colours (docs/figures.md).

Every plot function runs under :func:`styled`, so fonts and line widths are the same in every
figure whatever the caller's rcParams. Colours come from two sources:

* :func:`categorical` for a few named things (methods, part types): the ten ``tab10`` colours,
  then the same colours again *with a hatch* (never the same swatch twice without a visible
  difference), and for more than :data:`MAX_SWATCHES` things a continuous colormap sampled at
  distinct points;
* :data:`KIT_PALETTE` for the kits of a plan: kit k takes colour (k - 1) mod 8 whatever the
  number of kits, and each further round of eight a hatch
  (:func:`bilevel_kit.plots.gantt.kit_colors`, docs/figures.md#colours). It holds no red, pink
  or grey: those are the marks every Gantt chart shows (idle time, the makespan, deliveries,
  pickups, tray waits), and a kit must never be mistaken for one (:func:`color_distance` at
  least :data:`MIN_CONTRAST`).

Every axis of every figure carries a label with its unit ("time (s)", "x (mm)").
matplotlib is imported inside the functions, so importing this module stays cheap.
"""

from __future__ import annotations

import functools
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, ParamSpec, TypeVar, cast

#: Font sizes (points): body text and axis labels, titles, tick labels, labels inside bars.
FONT_SIZE = 9.0
TITLE_SIZE = 10.0
TICK_SIZE = 8.0
SMALL_SIZE = 7.0
LEGEND_SIZE = 8.0

#: matplotlib settings every figure of the toolkit is drawn with.
RC: dict[str, Any] = {
    "font.family": "sans-serif",
    "font.size": FONT_SIZE,
    "axes.titlesize": TITLE_SIZE,
    "axes.labelsize": FONT_SIZE,
    "xtick.labelsize": TICK_SIZE,
    "ytick.labelsize": TICK_SIZE,
    "legend.fontsize": LEGEND_SIZE,
    "legend.title_fontsize": LEGEND_SIZE,
    "figure.titlesize": TITLE_SIZE + 1,
    "axes.linewidth": 0.8,
    "hatch.linewidth": 0.6,
    "lines.linewidth": 1.4,
    "savefig.dpi": 150,
}

#: Categorical colours (matplotlib's ``tab10``, colour-blind friendlier than most).
PALETTE = (
    "#1f77b4",
    "#ff7f0e",
    "#2ca02c",
    "#d62728",
    "#9467bd",
    "#8c564b",
    "#e377c2",
    "#7f7f7f",
    "#bcbd22",
    "#17becf",
)
#: Colours of the kits of a Gantt chart: ``tab10`` without its red, pink and grey (the marks'
#: colours below), and two darker colours of matplotlib's ``Set1`` and ``tab20b``. Every two
#: of them, their lighter task shades (:func:`lighten`) and every mark are at least
#: :data:`MIN_CONTRAST` apart (tests/core/test_plots.py).
KIT_PALETTE = (
    "#1f77b4",
    "#ff7f0e",
    "#2ca02c",
    "#9467bd",
    "#17becf",
    "#bcbd22",
    "#a65628",
    "#637939",
)
#: Least CIE76 colour difference (:func:`color_distance`) between two kit colours, or a kit
#: colour and a mark; 20 is "clearly different at a glance" (2.3 is just noticeable).
MIN_CONTRAST = 20.0
#: Hatches that tell apart the second, third ... round of :data:`PALETTE`.
HATCHES = ("", "//", "..", "xx", "\\\\", "oo")
#: How many things :func:`categorical` tells apart by colour and hatch.
MAX_SWATCHES = len(PALETTE) * len(HATCHES)

#: Fixed colours of the things every Gantt chart shows. Idle time is drawn opaque in
#: :data:`IDLE_FILL` (a light :data:`IDLE_COLOR`) hatched in :data:`IDLE_COLOR`.
DELIVERY_COLOR = "#9e9e9e"
PICKUP_COLOR = "#5d5d5d"
IDLE_COLOR = "#e57373"
IDLE_FILL = "#f7d5d5"
TRAY_WAIT_COLOR = "#90a4ae"
MAKESPAN_COLOR = "#b71c1c"
UNKNOWN_COLOR = "#bdbdbd"

RGBA = tuple[float, float, float, float]

P = ParamSpec("P")
R = TypeVar("R")


@dataclass(frozen=True)
class Swatch:
    """A fill: colour and hatch (``""`` for none)."""

    color: RGBA
    hatch: str = ""


def styled(fn: Callable[P, R]) -> Callable[P, R]:
    """Run ``fn`` with :data:`RC` in force (fonts are fixed when text is created)."""

    @functools.wraps(fn)
    def wrapper(*args: P.args, **kwargs: P.kwargs) -> R:
        import matplotlib

        with matplotlib.rc_context(cast(Any, RC)):  # keys are checked by matplotlib
            return fn(*args, **kwargs)

    return wrapper


def rgba(color: object) -> RGBA:
    from matplotlib.colors import to_rgba

    r, g, b, a = to_rgba(color)  # type: ignore[arg-type]
    return (r, g, b, a)


def categorical(n: int) -> list[Swatch]:
    """``n`` swatches no two of which look the same: :data:`PALETTE`, then the palette again
    with each of :data:`HATCHES`; beyond :data:`MAX_SWATCHES`, ``n`` distinct colours of the
    continuous ``turbo`` colormap (no hatch)."""
    if n <= MAX_SWATCHES:
        return [
            Swatch(rgba(PALETTE[i % len(PALETTE)]), HATCHES[i // len(PALETTE)]) for i in range(n)
        ]
    from matplotlib import colormaps

    cmap = colormaps["turbo"]
    return [Swatch(rgba(cmap(i / (n - 1)))) for i in range(n)]


def mark_colors() -> dict[str, RGBA]:
    """The colours of the marks of a Gantt chart that no kit colour may resemble: the idle
    fill and hatch, the makespan line, deliveries, pickups and tray waits as drawn."""
    return {
        "idle": rgba(IDLE_FILL),
        "idle hatch": rgba(IDLE_COLOR),
        "makespan": rgba(MAKESPAN_COLOR),
        "delivery": rgba(DELIVERY_COLOR),
        "pickup": rgba(PICKUP_COLOR),
        "tray wait": lighten(TRAY_WAIT_COLOR, 0.4),
    }


def _lab(color: object) -> tuple[float, float, float]:
    """CIE L*a*b* (D65) of an sRGB colour (alpha ignored)."""
    r, g, b, _ = rgba(color)

    def linear(c: float) -> float:
        return c / 12.92 if c <= 0.04045 else ((c + 0.055) / 1.055) ** 2.4

    lr, lg, lb = linear(r), linear(g), linear(b)
    xyz = (
        (0.4124 * lr + 0.3576 * lg + 0.1805 * lb) / 0.95047,
        0.2126 * lr + 0.7152 * lg + 0.0722 * lb,
        (0.0193 * lr + 0.1192 * lg + 0.9505 * lb) / 1.08883,
    )
    fx, fy, fz = (v ** (1 / 3) if v > 216 / 24389 else (24389 / 27 * v + 16) / 116 for v in xyz)
    return 116 * fy - 16, 500 * (fx - fy), 200 * (fy - fz)


def color_distance(a: object, b: object) -> float:
    """CIE76 colour difference (Euclidean distance in L*a*b*) of two colours: about 2.3 is
    just noticeable, 20 and more tells things apart at a glance."""
    la, lb = _lab(a), _lab(b)
    return float(sum((u - v) ** 2 for u, v in zip(la, lb, strict=True)) ** 0.5)


def lighten(color: object, amount: float = 0.45) -> RGBA:
    """``color`` mixed with white (``amount`` 0: unchanged, 1: white)."""
    r, g, b, a = rgba(color)
    return (r + (1 - r) * amount, g + (1 - g) * amount, b + (1 - b) * amount, a)


def text_color(background: object) -> str:
    """Black or white, whichever reads better on ``background`` (relative luminance)."""
    r, g, b, _ = rgba(background)
    return "black" if 0.2126 * r + 0.7152 * g + 0.0722 * b > 0.45 else "white"


def plural(n: int, word: str) -> str:
    """``1 kit``, ``12 kits``."""
    return f"{n} {word}" if n == 1 else f"{n} {word}s"


def text_width_in(text: str, size: float) -> float:
    """Rough width (inches) of ``text`` at ``size`` points: 0.6 em per character."""
    return 0.6 * size * len(text) / 72.0
