"""Performance profiles of a KitBench pass (docs/kitbench.md#performance-profiles), from the
pass's result rows (``bench run``'s ``results.csv``, committed as ``bench/results/kitbench_*.csv``)
against two references kept apart:

* **the same pass**: per instance, the best makespan any method of the pass found (Dolan and
  Moré's reference: one code version, one machine state, one time limit);
* **the records**: the library's best-known plans, which a pass may have set itself and which
  include longer runs (so a method that set most records is graded largely against itself).

A method without a valid plan on an instance is never within a factor of either reference.
"""

from __future__ import annotations

import math
import re
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

from ..tables import block_names, fill_blocks, marked_blocks, read_csv
from .library import Record

if TYPE_CHECKING:
    from matplotlib.figure import Figure

Row = Mapping[str, Any]
#: The shares the prose states: within 1 % and within 5 % of the reference.
LEVELS = (0.01, 0.05)


def read_rows(path: str | Path) -> list[dict[str, Any]]:
    """A pass's rows from its CSV: ``makespan`` a float (``None``: no plan), ``valid`` a bool."""
    rows: list[dict[str, Any]] = list(read_csv(path))
    for r in rows:
        r["makespan"] = float(r["makespan"]) if r.get("makespan") else None
        r["valid"] = r.get("valid") == "True"
    return rows


def plan_makespan(row: Row | None) -> float | None:
    """A cell's makespan when it has a valid plan, else None (no cell, no plan, invalid)."""
    if row is None or not row.get("valid") or row.get("makespan") is None:
        return None
    return float(row["makespan"])


def pass_best(rows: Sequence[Row]) -> dict[str, float]:
    """Per instance, the least valid makespan of any method in ``rows``."""
    best: dict[str, float] = {}
    for r in rows:
        ms = plan_makespan(r)
        if ms is not None:
            best[r["instance"]] = min(ms, best.get(r["instance"], math.inf))
    return best


def records_best(records: Sequence[Record]) -> dict[str, float]:
    """Per instance, the library's best-known makespan."""
    return {r.instance: r.best_known for r in records if r.best_known is not None}


def ratios(
    rows: Sequence[Row], methods: Sequence[str], reference: Mapping[str, float]
) -> dict[str, list[float]]:
    """Per method, makespan / reference on each of its instances (``inf``: no plan)."""
    out: dict[str, list[float]] = {m: [] for m in methods}
    for r in rows:
        if r["method"] in out:
            ms, ref = plan_makespan(r), reference.get(r["instance"])
            out[r["method"]].append(math.inf if ms is None or not ref else ms / ref)
    return out


def shares(by_method: Mapping[str, Sequence[float]]) -> dict[str, tuple[float, ...]]:
    """Per method, the share of its instances within each of :data:`LEVELS`."""
    return {
        m: tuple(sum(x <= 1 + lv + 1e-12 for x in xs) / len(xs) for lv in LEVELS)
        for m, xs in by_method.items()
        if xs
    }


def methods_of(rows: Sequence[Row]) -> list[str]:
    return list(dict.fromkeys(str(r["method"]) for r in rows))


def plans_set(records: Sequence[Record], method: str, time_limit: float) -> int:
    """The records whose best-known plan ``method`` made at ``time_limit`` seconds."""
    return sum(
        r.plan is not None and r.plan.method == method and r.plan.time_limit == time_limit
        for r in records
    )


def _shares_text(by: Mapping[str, tuple[float, ...]]) -> str:
    order = sorted(by, key=lambda m: (-by[m][0], -by[m][1], m))
    return ", ".join(f"{m} {by[m][0]:.0%} / {by[m][1]:.0%}".replace("%", " %") for m in order)


def profile_text(
    rows: Sequence[Row], records: Sequence[Record], time_limit: float, *, own_pass: bool = True
) -> str:
    """The prose of one pass (docs/kitbench.md): the shares within 1 % / 5 % against the best
    of the same pass (when the pass has more than one method) and against the records, and the
    records' plans each method of the pass made at its time limit."""
    methods = methods_of(rows)
    instances = len({r["instance"] for r in rows})
    parts = []
    if own_pass and len(methods) > 1:
        same = shares(ratios(rows, methods, pass_best(rows)))
        parts.append(f"against the best of the same pass: {_shares_text(same)}")
    rec = shares(ratios(rows, methods, records_best(records)))
    set_by = {m: plans_set(records, m, time_limit) for m in methods}
    made = ", ".join(f"{m} {n}" for m, n in sorted(set_by.items(), key=lambda x: -x[1]) if n)
    parts.append(
        f"against the {len(records)} records: {_shares_text(rec)} (records' plans made by "
        f"these methods at {time_limit:g} s: {made or 'none'})"
    )
    return (
        f"{instances} instances, {len(methods)} method(s); within 1 % / 5 %, "
        + "; ".join(parts)
        + "."
    )


def profile_figure(
    rows: Sequence[Row],
    records: Sequence[Record],
    title: str,
    extra: Sequence[Row] = (),
) -> Figure:
    """Two profiles of a pass side by side: against the best of the same pass, and against
    the records (``extra``: rows of a separate pass, drawn against the records only)."""
    import matplotlib.pyplot as plt

    from ...plots.bench import PROFILE_X, plot_profile

    fig, (left, right) = plt.subplots(1, 2, figsize=(12, 4.6), layout="constrained")
    methods = methods_of(rows)
    plot_profile(ratios(rows, methods, pass_best(rows)), ax=left, legend=False)
    left.set_title(f"{title}: against the best of the same pass")
    left.set_xlabel(PROFILE_X.replace("best-known", "the best of the pass"))
    both = [*rows, *({**r, "method": f"{r['method']} (own pass)"} for r in extra)]
    plot_profile(ratios(both, methods_of(both), records_best(records)), ax=right, legend=False)
    right.set_title(f"{title}: against the {len(records)} records")
    # one legend for both panels, under them (never over the curves); the right panel's
    # methods include the left's, in the same order and colours
    handles, labels = right.get_legend_handles_labels()
    fig.legend(handles, labels, loc="outside lower center", ncols=min(len(labels), 5))
    return fig


_BLOCK = marked_blocks("kitbench-profile")


def render_profile_blocks(text: str, records: Sequence[Record], results: str | Path) -> str:
    """``text`` with every ``kitbench-profile:LABEL`` block rendered by :func:`profile_text`
    from ``results/kitbench_LABEL.csv`` (its time limit: the label's leading number)."""

    def render(label: str) -> str:
        limit = float(re.match(r"\d+", label).group(0))  # type: ignore[union-attr]
        rows = read_rows(Path(results) / f"kitbench_{label}.csv")
        return profile_text(rows, records, limit) + "\n"

    return fill_blocks(_BLOCK, text, render)


def profile_blocks_in(text: str) -> list[str]:
    return block_names(_BLOCK, text)


__all__ = [
    "LEVELS",
    "methods_of",
    "pass_best",
    "plans_set",
    "profile_blocks_in",
    "profile_figure",
    "profile_text",
    "ratios",
    "read_rows",
    "records_best",
    "render_profile_blocks",
    "shares",
]
