"""Small formatting helpers of the reproduction's tables and facts (CSV strings and Python
values alike)."""

from __future__ import annotations

from typing import Any

from ..experiments.tables import read_csv


def f(x: Any, nd: int = 1) -> str:
    """A number as text with ``nd`` decimals (CSV strings and Python values alike)."""
    if x is None or x == "":
        return "-"
    try:
        return f"{float(x):.{nd}f}"
    except (TypeError, ValueError):
        return str(x)


def yes(x: Any) -> bool:
    """A CSV or Python truth value."""
    return str(x).lower() in ("true", "1", "yes")


def nd_of(quantity: str) -> int:
    """Decimals of a user-study quantity: F with two, seconds with one."""
    return 2 if "F(2, 34)" in quantity else 1


#: A CSV file's rows as dicts of strings.
read_rows = read_csv
