"""The one way a verdict word of the reproduction is produced: from an interval, or from a
test's decision and its estimate's sign (docs/reproduction.md, "Verdicts").

Every verdict the rendered pages print (the adaptive study's gaps and shares, Figure 6's
directions and trends, the horizon study's windows) is one of :data:`WORDS`, picked by
:func:`verdict` from the side of 0 its 95 % interval lies on; a word is never chosen from
whether some other column happens to be empty. ``tests/repro/test_verdicts.py`` checks every
rendered verdict against its CSV row.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any


@dataclass(frozen=True)
class Words:
    """What a verdict says when the interval lies above 0, below 0, or contains 0."""

    above: str
    below: str
    neither: str

    def all(self) -> tuple[str, str, str]:
        return self.above, self.below, self.neither


#: Fixed minus adaptive (what the adaptive policy closes): positive = the adaptive is faster.
CLOSED = Words("significantly faster", "significantly slower", "no significant difference")
#: Fixed minus oracle (the gap): positive = knowing the pace helps.
GAP = Words(
    "the oracle is significantly faster",
    "the oracle is significantly slower",
    "no significant gap",
)
#: The goal "at least half of the gap closed" (the share's interval against 50 %).
HALF = Words("met", "not met", "undecided (its interval contains 50 %)")
#: Optimized against a baseline, by a test after Holm (Figure 6, the horizon's windows).
DIRECTION = Words("better", "worse", "n.s.")
#: One horizon's gap minus another's, paired over the instances.
GAP_DIFFERENCE = Words(
    "significantly larger", "significantly smaller", "not significantly different"
)
#: A paper number's read-off range against our interval (:func:`meets`).
INSIDE = Words("outside (ours above)", "outside (ours below)", "inside")
#: A value against the paper's (a point comparison, no interval: the participant model's F).
LEVEL = Words("above", "below", "equal to")
#: A slope against its claimed sign (used by the trend verdict, with the cells' ranks).
TREND = Words("supported", "contradicted", "not shown")

WORDS = frozenset(
    w for x in (CLOSED, GAP, HALF, DIRECTION, GAP_DIFFERENCE, INSIDE, LEVEL, TREND) for w in x.all()
)


def _num(x: Any) -> float:
    """A CSV cell or a Python value as a float (blank or None: NaN)."""
    return math.nan if x is None or x == "" else float(x)


def side(low: Any, high: Any, at: float = 0.0) -> int:
    """1 when the interval ``[low, high]`` lies above ``at``, -1 below it, 0 when it contains
    it or is missing."""
    lo, hi = _num(low), _num(high)
    return 1 if lo > at else -1 if hi < at else 0


def verdict(low: Any, high: Any, words: Words, at: float = 0.0) -> str:
    """The word of ``words`` for the side of ``at`` the interval ``[low, high]`` lies on."""
    s = side(low, high, at)
    return words.above if s > 0 else words.below if s < 0 else words.neither


def meets(low: Any, high: Any, value: Any, halfwidth: Any = 0.0, tol: float = 0.01) -> str:
    """:data:`INSIDE`'s word: whether ``[value - halfwidth, value + halfwidth]`` meets our
    interval ``[low, high]`` (``tol``: below the paper's last digit), i.e. whether the
    interval of the differences ``[low - value - h, high - value + h]`` contains 0."""
    v, h = _num(value), _num(halfwidth) + tol
    return verdict(_num(low) - v - h, _num(high) - v + h, INSIDE)


def tested(significant: bool, estimate: Any, words: Words) -> str:
    """A test's verdict: the estimate's side when the test rejects, else ``words.neither``
    (the degenerate interval ``[estimate, estimate]`` of a significant test)."""
    return verdict(estimate, estimate, words) if significant else words.neither


__all__ = [
    "CLOSED",
    "DIRECTION",
    "GAP",
    "GAP_DIFFERENCE",
    "HALF",
    "INSIDE",
    "LEVEL",
    "TREND",
    "WORDS",
    "Words",
    "meets",
    "side",
    "tested",
    "verdict",
]
