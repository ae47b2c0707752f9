"""What the benchmark scripts share: writing their result rows as CSV."""

from __future__ import annotations

import csv
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any


def write_rows(path: str | Path, rows: Sequence[Mapping[str, Any]]) -> Path:
    """``rows`` as CSV, the folder made if needed. Header: the first row's keys, then (sorted)
    the keys only later rows have (a failed case may carry other fields than a finished one;
    its missing cells stay empty)."""
    out = Path(path)
    out.parent.mkdir(parents=True, exist_ok=True)
    first = list(rows[0])
    extra = sorted({k for r in rows for k in r} - set(first))
    with open(out, "w", newline="") as fh:
        writer = csv.DictWriter(fh, fieldnames=first + extra)
        writer.writeheader()
        writer.writerows(rows)
    return out
