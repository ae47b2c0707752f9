"""The exact models against ``lns`` at the same time limit
(docs/kitbench.md#exact-models-against-lns-at-the-same-limit): per instance, each exact
method's excess over ``lns``'s makespan in one pass, and the share of instances within the
goal of issue 37 (at most 0.1 % above ``lns``, or better). The pass's ``_run.json`` (what
``bench run`` wrote, with the wall time and load averages added) says what ran.

The rows are a pass's result rows (``bench run``'s ``results.csv``, committed as
``bench/results/kitbench_LABEL.csv``, read by :func:`.profiles.read_rows`); the reference is
the same pass's ``lns`` cell of each instance, so every number compares one code version on
one machine state at one limit. A method without a valid plan where ``lns`` has one is never
within the goal (its excess is infinite); an instance where ``lns`` has no plan has no excess.
"""

from __future__ import annotations

import json
import math
import statistics
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

from ...objectives import relative_gap
from ..tables import block_names, fill_blocks, markdown_lines, marked_blocks
from .profiles import methods_of, plan_makespan, read_rows

Row = Mapping[str, Any]
#: The reference method and the goal of issue 37: at most 0.1 % above it.
REFERENCE = "lns"
GOAL = 0.001
#: Task counts of issue 37's proof goals (every record up to 60 tasks proven at 60 s, up to 130
#: at ten minutes) and the largest certified gap it allows at 60 s up to 130 tasks.
PROOF_SIZES = (60, 130)
OPEN_GOAL = 0.01
#: Slack of the comparison: equal plans computed in another order differ in the last bits.
_EPS = 1e-12


def number(value: Any) -> float | None:
    """A number of a pass's rows or cells: ``None`` when empty (no bound, no time), as the
    CSV writes it."""
    return None if value in (None, "") else float(value)


def excess(makespan: float | None, reference: float | None) -> float | None:
    """(makespan - reference) / reference; ``inf`` without a plan, ``None`` without a
    reference (negative: better than the reference)."""
    if reference is None or reference <= 0:
        return None
    return math.inf if makespan is None else (makespan - reference) / reference


def versus_rows(
    rows: Sequence[Row], methods: Sequence[str], reference: str = REFERENCE
) -> list[dict[str, Any]]:
    """Per instance (in the rows' order): the reference's makespan and, per method, its
    makespan, status, bound and excess over the reference; with the best bound of the pass."""
    cells = {(r["instance"], r["method"]): r for r in rows}
    out = []
    for name in dict.fromkeys(r["instance"] for r in rows):
        ref = plan_makespan(cells.get((name, reference)))
        mine = [cells.get((name, m)) for m in (reference, *methods)]
        bounds = [b for c in mine if c is not None and (b := number(c.get("bound"))) is not None]
        row: dict[str, Any] = {
            "instance": name,
            "tasks": int(next(c for c in mine if c is not None)["tasks"]),
            reference: ref,
            f"{reference}_status": mine[0]["status"] if mine[0] is not None else None,
            "best_bound": max(bounds) if bounds else None,
        }
        for m in methods:
            cell = cells.get((name, m))
            row[m] = plan_makespan(cell)
            row[f"{m}_status"] = cell["status"] if cell is not None else None
            row[f"{m}_bound"] = number(cell.get("bound")) if cell is not None else None
            row[f"{m}_excess"] = excess(row[m], ref)
        out.append(row)
    return out


def versus_summary(
    table: Sequence[Row], methods: Sequence[str], goal: float = GOAL
) -> dict[str, dict[str, Any]]:
    """Per method: instances compared, those within ``goal`` of the reference (or better),
    those strictly better, those it proved optimal, the median and worst excess, and the
    misses (name, excess) worst first."""
    out = {}
    for m in methods:
        xs = [(r["instance"], r[f"{m}_excess"]) for r in table if r[f"{m}_excess"] is not None]
        values = [x for _, x in xs]
        misses = sorted(((n, x) for n, x in xs if x > goal + _EPS), key=lambda t: -t[1])
        out[m] = {
            "instances": len(xs),
            "within": len(xs) - len(misses),
            "better": sum(x < -_EPS for x in values),
            "optimal": sum(r[f"{m}_status"] == "optimal" for r in table),
            "median": statistics.median(values) if values else None,
            "worst": max(values) if values else None,
            "misses": misses,
        }
    return out


def pass_proofs(
    table: Sequence[Row], sizes: Sequence[int] = PROOF_SIZES, open_goal: float = OPEN_GOAL
) -> dict[str, Any]:
    """What the pass itself proved (the records' goals of issue 37, counted on one pass): per
    size in ``sizes``, (instances proven optimal by some method of the pass, instances up to
    that many tasks); and the instances up to the largest size whose certified gap in the pass
    (its best plan against its best bound, :func:`...objectives.relative_gap`) is above
    ``open_goal``, with that gap, worst first (no plan or no bound: gap None, listed first)."""
    methods = [k.removesuffix("_status") for k in table[0] if k.endswith("_status")]
    proven = {
        r["instance"] for r in table if any(r.get(f"{m}_status") == "optimal" for m in methods)
    }
    counts = {}
    for size in sizes:
        names = [r["instance"] for r in table if r["tasks"] <= size]
        counts[size] = (sum(n in proven for n in names), len(names))
    wide = []
    for r in table:
        if r["tasks"] > max(sizes) or r["instance"] in proven:
            continue
        plans = [r[m] for m in methods if r.get(m) is not None]
        g = relative_gap(min(plans), r["best_bound"]) if plans else None
        if g is None or g > open_goal + _EPS:
            wide.append((r["instance"], g))
    wide.sort(key=lambda t: -math.inf if t[1] is None else -t[1])
    return {"proven": counts, "open": wide}


def proofs_text(table: Sequence[Row]) -> str:
    """The sentence of :func:`pass_proofs` ("": no instance up to the proof goals' sizes)."""
    p = pass_proofs(table)
    if not any(n for _, n in p["proven"].values()):
        return ""
    counts = ", ".join(
        f"{k} of the {n} up to {size} tasks" for size, (k, n) in p["proven"].items() if n
    )
    wide = ", ".join(
        f"`{n}` {'no certified gap' if g is None else f'{100 * g:.2f} %'}" for n, g in p["open"]
    )
    return (
        f"**The pass's proofs**: proven optimal by a method of the pass on {counts}; certified "
        f"gap of the pass (its best plan against its best bound) above {100 * OPEN_GOAL:g} % up "
        f"to {max(PROOF_SIZES)} tasks: {wide or 'none'}."
    )


def _pct(value: float | None) -> str:
    """Signed percent, 3 places ("-": no excess, "no plan": infinite)."""
    if value is None:
        return "-"
    if math.isinf(value):
        return "no plan"
    text = f"{100 * value:+.3f}"
    return "+0.000" if text in ("-0.000", "+0.000") else text


def _pct_unit(value: float | None) -> str:
    text = _pct(value)
    return text if text in ("-", "no plan") else f"{text} %"


def _secs(value: float | None) -> str:
    return "-" if value is None else f"{value:,.2f}"


def run_text(run: Mapping[str, Any]) -> str:
    """What ran: the command, its commit and start, and the wall time and load averages the
    pass's ``_run.json`` states (``wall_s``, ``load_average_before``/``_after``: 1, 5 and 15
    minutes, from ``uptime``)."""
    text = f"`{run['command']}` (commit `{run['commit']}`, started {run['started']})"
    if "wall_s" in run:
        text += f": {len(run['instances']) * len(run['methods'])} cells in {run['wall_s']:,.0f} s"
        text += " of wall time"
    if "load_average_before" in run:
        before, after = (
            " / ".join(f"{x:.2f}" for x in run[f"load_average_{k}"]) for k in ("before", "after")
        )
        text += f", load average (1 / 5 / 15 min) {before} before and {after} after"
    return text + "."


def versus_text(
    rows: Sequence[Row],
    run: Mapping[str, Any] | None = None,
    goal: float = GOAL,
    reference: str = REFERENCE,
) -> str:
    """The prose of one pass (docs/kitbench.md): what ran (``run``: its ``_run.json``), then
    per exact method the instances within the goal of the reference, strictly better, the
    median and worst excess and every miss."""
    methods = [m for m in methods_of(rows) if m != reference]
    table = versus_rows(rows, methods, reference)
    summary = versus_summary(table, methods, goal)
    parts = []
    for m in methods:
        s = summary[m]
        misses = ", ".join(f"`{n}` {_pct_unit(x)}" for n, x in s["misses"]) or "none"
        parts.append(
            f"**{m}** within {100 * goal:g} % of {reference} (or better) on {s['within']} of "
            f"{s['instances']} instances, better on {s['better']}, proven optimal on "
            f"{s['optimal']}; excess over {reference}: median {_pct_unit(s['median'])}, worst "
            f"{_pct_unit(s['worst'])}; missing the goal: {misses}."
        )
    head = f"Run: {run_text(run)}\n\n" if run else ""
    if table and (proofs := proofs_text(table)):
        parts.append(proofs)
    return (
        head + f"{len(table)} instances; excess = (makespan - {reference}'s) / {reference}'s, "
        "negative: better than " + reference + ".\n\n" + "\n\n".join(parts) + "\n"
    )


def versus_markdown(rows: Sequence[Row], reference: str = REFERENCE) -> str:
    """The per-instance table of one pass: the reference's makespan, each exact method's
    makespan, excess (%), status and bound, and the best bound of the pass."""
    methods = [m for m in methods_of(rows) if m != reference]
    header = ["instance", "tasks", f"{reference} (s)"]
    for m in methods:
        header += [f"{m} (s)", f"{m} excess (%)", f"{m} status", f"{m} bound (s)"]
    header.append("best bound of the pass (s)")
    body = []
    for r in versus_rows(rows, methods, reference):
        line = [f"`{r['instance']}`", str(r["tasks"]), _secs(r[reference])]
        for m in methods:
            line += [
                _secs(r[m]),
                _pct(r[f"{m}_excess"]),
                str(r[f"{m}_status"] or "-"),
                _secs(r[f"{m}_bound"]),
            ]
        body.append([*line, _secs(r["best_bound"])])
    return "\n".join(markdown_lines(header, body)) + "\n"


_TEXT = marked_blocks("kitbench-versus")
_TABLE = marked_blocks("kitbench-versus-table")


def render_versus_blocks(text: str, results: str | Path) -> str:
    """``text`` with every ``kitbench-versus:LABEL`` block rendered by :func:`versus_text` and
    every ``kitbench-versus-table:LABEL`` block by :func:`versus_markdown`, both from
    ``results/kitbench_LABEL.csv``."""

    def rows(label: str) -> list[dict[str, Any]]:
        return read_rows(Path(results) / f"kitbench_{label}.csv")

    def prose(label: str) -> str:
        meta = Path(results) / f"kitbench_{label}_run.json"
        return versus_text(rows(label), json.loads(meta.read_text()) if meta.exists() else None)

    text = fill_blocks(_TEXT, text, prose)
    return fill_blocks(_TABLE, text, lambda label: versus_markdown(rows(label)))


def versus_blocks_in(text: str) -> list[str]:
    return block_names(_TEXT, text) + block_names(_TABLE, text)


__all__ = [
    "GOAL",
    "REFERENCE",
    "excess",
    "pass_proofs",
    "proofs_text",
    "render_versus_blocks",
    "run_text",
    "versus_blocks_in",
    "versus_markdown",
    "versus_rows",
    "versus_summary",
    "versus_text",
]
