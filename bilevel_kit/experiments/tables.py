"""The one writer of result tables: CSV files and Markdown/fixed-width tables.

CSV: every key of every row (in first-seen order) is a column; lists and dicts are written as
JSON; the file is written atomically (:mod:`bilevel_kit.atomic`). Markdown: a header row, a
``|---|`` rule and one line per row (:func:`markdown_lines`), used by ``compare`` and the paper
reproductions alike. Generated blocks of a documentation page, between ``<!-- TAG:NAME -->``
and ``<!-- /TAG:NAME -->``, are rewritten in place (:func:`marked_blocks`, :func:`fill_blocks`).
"""

from __future__ import annotations

import csv
import io
import json
import math
import re
from collections.abc import Callable, Collection, Mapping, Sequence
from pathlib import Path
from typing import Any

from .. import atomic


def read_csv(path: str | Path) -> list[dict[str, str]]:
    """A CSV file's rows as dicts of strings (UTF-8; the reader of :func:`write_csv`'s files
    and of the committed result tables)."""
    with open(path, newline="", encoding="utf-8") as fh:
        return list(csv.DictReader(fh))


def write_csv(
    path: str | Path,
    records: Sequence[Mapping[str, Any]],
    *,
    exclude: Collection[str] = ("solution",),
    line_end: str = "\r\n",
) -> Path:
    """All record fields but ``exclude`` as CSV (lists and dicts as JSON), written atomically.

    ``line_end``: the csv module's default ``"\\r\\n"`` (``compare``, ``simulate``) or ``"\\n"``
    (the reproductions' files).
    """
    keys: list[str] = []
    for r in records:
        keys += [k for k in r if k not in keys and k not in exclude]
    buf = io.StringIO()
    writer = csv.DictWriter(buf, fieldnames=keys, extrasaction="ignore", lineterminator=line_end)
    writer.writeheader()
    for r in records:
        writer.writerow(
            {
                k: json.dumps(v) if isinstance(v, dict | list) else v
                for k, v in r.items()
                if k not in exclude
            }
        )
    atomic.write_text(path, buf.getvalue())
    return Path(path)


def markdown_lines(header: Sequence[str], rows: Sequence[Sequence[str]]) -> list[str]:
    """A Markdown table, one string per line."""
    lines = ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    lines += ["| " + " | ".join(row) + " |" for row in rows]
    return lines


def text_lines(header: Sequence[str], rows: Sequence[Sequence[str]]) -> list[str]:
    """A fixed-width text table (columns separated by two spaces), one string per line."""
    widths = [max(len(x) for x in col) for col in zip(header, *rows, strict=True)]
    lines = ["  ".join(h.ljust(w) for h, w in zip(header, widths, strict=True))]
    lines.append("  ".join("-" * w for w in widths))
    lines += ["  ".join(c.ljust(w) for c, w in zip(row, widths, strict=True)) for row in rows]
    return lines


COMPARE_COLUMNS = [
    ("instance", "instance", "{}"),
    ("method", "method", "{}"),
    ("makespan", "makespan (s)", "{:.2f}"),
    ("human_idle", "human idle (s)", "{:.2f}"),
    ("n_kits", "kits", "{}"),
    ("status", "status", "{}"),
    # the lead figure first (docs/timeline.md#terms); the method's own bound and gap after it
    ("best_bound", "best bound (s)", "bound"),
    ("above_best", "above best bound (%)", "{:.2%}"),
    ("bound", "own bound (s)", "bound"),
    ("gap_own", "own gap (%)", "{:.2%}"),
    ("valid", "valid", "{}"),
    ("time_limit_hit", "limit hit", "yes/no"),
    ("wall_time_s", "time (s)", "{:.3f}"),
    ("instance_file", "file", "path"),  # several files may share an instance name
]


def _display_path(value: str) -> str:
    """A path relative to the working folder when it lies under it, else as given."""
    p = Path(value)
    try:
        return str(p.resolve().relative_to(Path.cwd().resolve()))
    except (ValueError, OSError):
        return str(value)


def bound_down(value: float, places: int = 2) -> float:
    """A lower bound rounded *down* to ``places`` decimals, so that it never shows above the
    makespan it bounds (rounded to nearest): a bound within the checker's 1e-6 s of 936.475
    showed as 936.48 beside a makespan of 936.47. 1e-6 of a unit absorbs the binary error of
    a bound equal to the makespan (936.47 * 100 is 93646.99999999999)."""
    scale = 10**places
    return math.floor(value * scale + 1e-6) / scale


def _cell_text(value: Any, fmt: str) -> str:
    if value is None:
        return "-"
    if fmt == "path":
        return _display_path(str(value))
    if fmt == "yes/no":
        return "yes" if value else "no"
    if fmt == "bound":
        return f"{bound_down(value):.2f}"
    if fmt == "{:.2%}":
        return f"{100 * value:.2f}"
    return fmt.format(value)


def table_rows(records: Sequence[dict[str, Any]]) -> tuple[list[str], list[list[str]]]:
    """Header and text cells of the ``compare`` table."""
    header = [h for _, h, _ in COMPARE_COLUMNS]
    rows = [
        [
            "no plan"
            if k == "valid" and r.get("valid") is None and r.get("status") != "error"
            else "INCONSISTENT"
            if k == "best_bound" and r.get("inconsistent")
            else _cell_text(r.get(k), f)
            for k, _, f in COMPARE_COLUMNS
        ]
        for r in records
    ]
    return header, rows


def format_table(records: Sequence[dict[str, Any]]) -> str:
    """A fixed-width text table of compare records."""
    return "\n".join(text_lines(*table_rows(records)))


def format_markdown(records: Sequence[dict[str, Any]]) -> str:
    """A Markdown table of compare records."""
    return "\n".join(markdown_lines(*table_rows(records))) + "\n"


def marked_blocks(tag: str) -> re.Pattern[str]:
    """The generated blocks ``<!-- TAG:NAME -->`` ... ``<!-- /TAG:NAME -->`` of a page; groups:
    the opening line, NAME, the body and the closing marker."""
    return re.compile(rf"(<!-- {tag}:(\w+) -->\n)(.*?)(<!-- /{tag}:\2 -->)", re.S)


def fill_blocks(blocks: re.Pattern[str], text: str, render: Callable[[str], str | None]) -> str:
    """``text`` with each block's body replaced by ``render(NAME)`` (None: left as it is)."""

    def fill(m: re.Match[str]) -> str:
        body = render(m.group(2))
        return m.group(0) if body is None else m.group(1) + body + m.group(4)

    return blocks.sub(fill, text)


def block_names(blocks: re.Pattern[str], text: str) -> list[str]:
    """The NAME of each block of ``text``, in order."""
    return [m.group(2) for m in blocks.finditer(text)]
