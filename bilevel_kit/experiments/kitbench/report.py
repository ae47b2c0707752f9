"""Markdown of KitBench: a run's gap tables, and the library's records and size table.

docs/kitbench.md and instances/kitbench/README.md hold blocks between
``<!-- kitbench:NAME -->`` and ``<!-- /kitbench:NAME -->``; :func:`render_blocks` rewrites them
from the index, and a test fails when a page disagrees with it, so the published records can
never drift from ``index.csv``.
"""

from __future__ import annotations

import statistics
from collections.abc import Callable, Sequence
from typing import Any

from ..tables import block_names, fill_blocks, markdown_lines, marked_blocks
from .library import SHARES, Record, trays_text

#: The size steps of the size table: (label, largest task count in the step).
SIZE_STEPS = (
    ("≤ 15", 15),
    ("16-35", 35),
    ("36-75", 75),
    ("76-175", 175),
    ("176-375", 375),
    ("376-750", 750),
    ("> 750", 10**9),
)


def _pct(value: float | None) -> str:
    return "-" if value is None else f"{100 * value:.2f}"


def _secs(value: float | None) -> str:
    return "-" if value is None else f"{value:,.2f}"


def run_markdown(
    rows: Sequence[dict[str, Any]],
    table: Sequence[dict[str, Any]],
    methods: Sequence[str],
    time_limit: float | None,
) -> str:
    """A run's summary per method and its per-instance gaps, as Markdown."""
    instances = list(dict.fromkeys(str(r["instance"]) for r in rows))
    limit = "no time limit" if time_limit is None else f"{time_limit:g} s per solve"
    lines = [
        f"# KitBench run: {len(instances)} instances x {len(methods)} methods, {limit}",
        "",
        "Certified gap = (objective - bound) / objective, to the best bound known (the "
        "library's or this run's); above best-known = (objective - best_known) / best_known, "
        "to the best plan known (the library's or this run's). A cell without a valid plan "
        "is never within a share.",
        "",
    ]
    header = ["method", "cells", "plans", "refused"]
    header += [f"within {s:.0%} of best-known" for s in SHARES]
    header += [
        "median above best-known (%)",
        "worst above best-known (%)",
        "median certified gap (%)",
        "worst certified gap (%)",
        "certified optimal",
        "median time (s)",
    ]
    body = [
        [
            t["method"],
            str(t["cells"]),
            str(t["plans"]),
            str(t["refused"]),
            *(_pct(t[f"within_{s:.0%}"]) + " %" for s in SHARES),
            _pct(t["median_above_best_known"]),
            _pct(t["max_above_best_known"]),
            _pct(t["median_certified_gap"]),
            _pct(t["max_certified_gap"]),
            str(t["certified_optimal"]),
            _secs(t["median_wall_s"]),
        ]
        for t in table
    ]
    lines += markdown_lines(header, body)
    lines += ["", "## Per instance: above best-known (%) / certified gap (%)", ""]
    cell = {(str(r["instance"]), str(r["method"])): r for r in rows}
    first = {str(r["instance"]): r for r in reversed(rows)}
    header = ["instance", "tasks", "best-known (s)", "best bound (s)", *methods]
    body = []
    for name in instances:
        ref = first[name]
        body.append(
            [name, str(ref["tasks"]), _secs(ref["best_known"]), _secs(ref["best_bound"])]
            + [_pair(cell.get((name, m))) for m in methods]
        )
    lines += markdown_lines(header, body)
    return "\n".join(lines) + "\n"


def _pair(row: dict[str, Any] | None) -> str:
    if row is None:
        return ""
    if row["makespan"] is None:
        return str(row["status"])
    return f"{_pct(row['above_best_known'])} / {_pct(row['certified_gap'])}"


# ---------------------------------------------------------------------------------------------
# The library's tables
# ---------------------------------------------------------------------------------------------


def records_markdown(records: Sequence[Record]) -> str:
    """The table of records, one row per instance."""
    header = [
        "instance",
        "family",
        "tasks",
        "trays",
        "d (s)",
        "tray",
        "best-known (s)",
        "best bound (s)",
        "status",
        "certified gap (%)",
        "plan by",
        "bound by",
    ]
    body = [
        [
            f"`{r.instance}`",
            r.family,
            str(r.tasks),
            trays_text(r.trays),
            f"{r.delivery_time:g}",
            r.tray,
            _secs(r.best_known),
            _secs(r.best_bound),
            r.status,
            _pct(r.gap),
            _by(r.plan),
            _by(r.bound),
        ]
        for r in records
    ]
    return "\n".join(markdown_lines(header, body)) + "\n"


def _by(prov: Any) -> str:
    if prov is None:
        return "-"
    limit = "" if prov.time_limit is None else f" {prov.time_limit:g} s"
    return f"{prov.method}{limit}"


def size_step(tasks: int) -> str:
    return next(label for label, top in SIZE_STEPS if tasks <= top)


def sizes_markdown(records: Sequence[Record]) -> str:
    """Instances per family x size step, each cell ``one tray + unlimited``."""
    families = list(dict.fromkeys(r.family for r in records))
    header = ["family (tasks)", *(label for label, _ in SIZE_STEPS), "total"]
    body = []
    for fam in [*families, "all"]:
        mine = [r for r in records if fam in ("all", r.family)]
        cells = []
        for label, _ in SIZE_STEPS:
            step = [r for r in mine if size_step(r.tasks) == label]
            one = sum(r.trays == 1 for r in step)
            cells.append(f"{one} + {len(step) - one}" if step else "")
        body.append([fam, *cells, str(len(mine))])
    note = "Each cell: instances with one tray + with unlimited trays."
    return note + "\n\n" + "\n".join(markdown_lines(header, body)) + "\n"


def status_markdown(records: Sequence[Record]) -> str:
    """How many records are optimal, and the median and worst certified gap of the open."""
    open_gaps = [r.gap for r in records if r.status == "open" and r.gap is not None]
    optimal = sum(r.status == "optimal" for r in records)
    text = f"{optimal} of {len(records)} records are proven optimal"
    if open_gaps:
        text += (
            f"; the certified gap of the {len(open_gaps)} open ones: median "
            f"{_pct(statistics.median(open_gaps))} %, worst {_pct(max(open_gaps))} %"
        )
    return text + ".\n"


BLOCKS: dict[str, Callable[[Sequence[Record]], str]] = {
    "records": records_markdown,
    "sizes": sizes_markdown,
    "status": status_markdown,
}
_BLOCK = marked_blocks("kitbench")


def render_blocks(text: str, records: Sequence[Record]) -> str:
    """``text`` with every ``kitbench:NAME`` block rendered from ``records``."""

    def render(name: str) -> str | None:
        block = BLOCKS.get(name)
        return None if block is None else block(records)

    return fill_blocks(_BLOCK, text, render)


def blocks_in(text: str) -> list[str]:
    return block_names(_BLOCK, text)
