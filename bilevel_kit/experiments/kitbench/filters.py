"""``--filter EXPR``: which library instances a command takes (docs/kitbench.md#filters).

A small, safe syntax, parsed here and never evaluated: terms separated by commas, all of which
must hold, e.g. ``family=intree|sparse,tasks<=130,trays=1``. A term is ``KEY OP VALUE``:

* numeric keys (``tasks``, ``delivery_time``, ``best_known``, ``best_bound``, ``gap``) take
  ``=``, ``!=``, ``<``, ``<=``, ``>``, ``>=`` and a number;
* ``trays`` takes the same with an integer or ``unlimited`` (larger than every integer);
* text keys (``instance``, ``family``, ``tray``, ``status``) take ``=`` or ``!=`` and one or
  more alternatives separated by ``|``, each a name or a shell pattern (``table_*``).

A record without the value (no plan yet: no ``best_known``) fails every numeric term on it.
"""

from __future__ import annotations

import fnmatch
import math
import operator
import re
from collections.abc import Callable, Sequence
from dataclasses import dataclass

from ...errors import UsageError
from .library import Record

NUMERIC = ("tasks", "delivery_time", "best_known", "best_bound", "gap")
TEXT = ("instance", "family", "tray", "status")
KEYS = (*TEXT, *NUMERIC, "trays")
_OPS: dict[str, Callable[[float, float], bool]] = {
    "<=": operator.le,
    ">=": operator.ge,
    "!=": operator.ne,
    "=": operator.eq,
    "<": operator.lt,
    ">": operator.gt,
}
_TERM = re.compile(r"^\s*([a-z_]+)\s*(<=|>=|!=|=|<|>)\s*(\S.*?)\s*$")


@dataclass(frozen=True)
class Term:
    """One ``KEY OP VALUE`` of a filter."""

    key: str
    op: str
    value: float | tuple[str, ...]

    def holds(self, rec: Record) -> bool:
        if self.key in TEXT:
            assert isinstance(self.value, tuple)
            text = str(getattr(rec, self.key))
            hit = any(fnmatch.fnmatchcase(text, pattern) for pattern in self.value)
            return hit if self.op == "=" else not hit
        got = _number_of(rec, self.key)
        assert isinstance(self.value, float)
        return got is not None and _OPS[self.op](got, self.value)


def _number_of(rec: Record, key: str) -> float | None:
    if key == "trays":
        return math.inf if rec.trays is None else float(rec.trays)
    value = getattr(rec, key)
    return None if value is None else float(value)


def _term(text: str) -> Term:
    m = _TERM.match(text)
    if m is None:
        raise UsageError(
            f"--filter: {text!r} is not KEY OP VALUE (OP one of = != < <= > >=), "
            "e.g. family=intree,tasks<=130,trays=1"
        )
    key, op, value = m.groups()
    if key not in KEYS:
        raise UsageError(f"--filter: unknown key {key!r}; the keys are {', '.join(KEYS)}")
    if key in TEXT:
        if op not in ("=", "!="):
            raise UsageError(f"--filter: {key} is text: use = or != (got {op!r} in {text!r})")
        return Term(key, op, tuple(v.strip() for v in value.split("|") if v.strip()))
    if key == "trays" and value == "unlimited":
        return Term(key, op, math.inf)
    try:
        number = float(value)
    except ValueError:
        number = math.nan
    if not math.isfinite(number):
        what = "an integer or 'unlimited'" if key == "trays" else "a number"
        raise UsageError(f"--filter: {key} takes {what}, got {value!r}")
    return Term(key, op, number)


def parse_filter(text: str | None) -> tuple[Term, ...]:
    """The terms of a filter expression (none: everything passes)."""
    if text is None or not text.strip():
        return ()
    return tuple(_term(part) for part in text.split(",") if part.strip())


def select(records: Sequence[Record], terms: Sequence[Term]) -> list[Record]:
    """The records every term holds for, in their order."""
    return [r for r in records if all(t.holds(r) for t in terms)]
