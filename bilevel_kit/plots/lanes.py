"""Labels of the bars of a Gantt lane (docs/figures.md): inside a bar where the text fits, else
outside the lane on a *leader*, a thin line from the bar to its label, in up to
:data:`MAX_TIERS` rows, so that every bar is named; :func:`place` says when that is impossible
(the chart then lists the tasks by kit instead)."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

from .. import style

if TYPE_CHECKING:
    from matplotlib.axes import Axes

#: Rows of leader labels beside a lane, and their spacing (data units of the lane axis).
MAX_TIERS = 3
TIER_STEP = 0.17
#: Length of the shortest leader line (data units): the label of row 0 starts there.
LINE_START = 0.06
#: Horizontal room (inches) kept free around a label, inside its bar and between leaders.
PAD_IN = 0.03


@dataclass(frozen=True)
class Bar:
    """A labelled bar: its span (s), text, fill (for the text colour) and ``gid`` of the text."""

    start: float
    end: float
    text: str
    color: Any
    gid: str

    @property
    def mid(self) -> float:
        return (self.start + self.end) / 2


@dataclass(frozen=True)
class Leader:
    """A label outside the lane: its bar, its row (0 is next to the lane) and the x (s) of
    its text (moved inwards when the bar is at an edge of the chart)."""

    bar: Bar
    tier: int
    text_x: float


@dataclass
class Placement:
    """Which bars are labelled inside and which on leaders."""

    inside: list[Bar]
    leaders: list[Leader]

    @property
    def tiers(self) -> int:
        return 1 + max((ld.tier for ld in self.leaders), default=-1)


def fits_inside(bar: Bar, inches_per_s: float) -> bool:
    """Whether the bar's text fits inside it at :data:`bilevel_kit.style.SMALL_SIZE`."""
    width = style.text_width_in(bar.text, style.SMALL_SIZE) + PAD_IN
    return width <= (bar.end - bar.start) * inches_per_s


def place(
    bars: Sequence[Bar],
    inches_per_s: float,
    width_s: float,
    max_tiers: int = MAX_TIERS,
    *,
    outside: bool = False,
) -> Placement | None:
    """Every bar's label inside it where it fits, the others on leaders in the lowest row where
    the label overlaps no other label of that row, no leader line of a row nearer the lane
    crosses it, and its own line crosses no label nearer the lane. ``width_s`` is the width
    of the chart (s). ``outside``: every label on a leader (one place for a lane's labels).
    None when a label finds no row within ``max_tiers``."""
    inside = [] if outside else [b for b in bars if fits_inside(b, inches_per_s)]
    rest = sorted((b for b in bars if b not in inside), key=lambda b: b.mid)
    pad = PAD_IN / inches_per_s
    placed: list[tuple[int, float, float, float]] = []  # tier, left, right, line x (s)
    leaders: list[Leader] = []
    for bar in rest:
        half = (style.text_width_in(bar.text, style.SMALL_SIZE) / 2 + PAD_IN) / inches_per_s
        x = min(max(bar.mid, half), max(width_s - half, half))
        left, right = x - half, x + half
        for tier in range(max_tiers):
            if all(_compatible(tier, left, right, bar.mid, other, pad) for other in placed):
                placed.append((tier, left, right, bar.mid))
                leaders.append(Leader(bar, tier, x))
                break
        else:
            return None
    return Placement(inside, leaders)


def _compatible(
    tier: int,
    left: float,
    right: float,
    line: float,
    other: tuple[int, float, float, float],
    pad: float,
) -> bool:
    """Whether a label (``tier``, ``left``..``right``, its line at ``line``) and a placed one
    can coexist: apart in one row; a line never through a label nearer the lane."""
    o_tier, o_left, o_right, o_line = other
    if o_tier == tier:
        return right + pad <= o_left or o_right + pad <= left
    if o_tier < tier:  # our line passes the other's row
        return not o_left - pad <= line <= o_right + pad
    return not left - pad <= o_line <= right + pad


def draw(
    ax: Axes,
    placement: Placement,
    lane_y: float,
    side: int,
    half_height: float,
    stagger: bool,
) -> None:
    """Draw the labels of a lane at ``lane_y``: inside ones centred (``stagger``: alternately
    above and below the centre line, so that neighbours stay apart), leaders on ``side`` (+1
    above the lane, -1 below): a line from the bar's edge to the label beyond it."""
    for j, bar in enumerate(placement.inside):
        dy = (0.3 * half_height * (1 if j % 2 == 0 else -1)) if stagger else 0.0
        _text(ax, bar.mid, lane_y + dy, bar, style.text_color(bar.color), "center")
    edge = lane_y + side * half_height
    for ld in placement.leaders:
        end = edge + side * (LINE_START + TIER_STEP * ld.tier)
        ax.plot(
            [ld.bar.mid, ld.text_x],
            [edge, end],
            color="0.25",
            linewidth=0.6,
            solid_capstyle="butt",
            gid=f"leader:{ld.bar.gid}",
        )
        _text(ax, ld.text_x, end, ld.bar, "black", "bottom" if side > 0 else "top")


def _text(ax: Axes, x: float, y: float, bar: Bar, color: str, va: str) -> None:
    ax.text(
        x,
        y,
        bar.text,
        ha="center",
        va=va,
        fontsize=style.SMALL_SIZE,
        color=color,
        clip_on=False,
        gid=bar.gid,
    )


def room(placement: Placement | None) -> float:
    """Room (data units) the leader rows of a lane take beyond the lane's edge."""
    tiers = placement.tiers if placement is not None else 0
    return TIER_STEP * tiers + 0.02 if tiers else 0.0
