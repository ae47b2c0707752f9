"""The KitBench panel's sentences for docs/robust.md (:mod:`.robust_kitbench`), computed from
the committed ``robust_kitbench.csv`` so that no verdict and no number is typed by hand.

As in :mod:`.robust_facts`, the verdicts follow the 95 % paired VSS intervals, never a
threshold on the VSS's size: above 0 (planning for the spread pays), below 0 (it did worse)
or meeting 0 (no evidence either way). A VSS of exactly 0 where the SAA solve kept the
mean-value plan is told apart by whether that solve proved it: without a proof it says only
that the solve found nothing better within its budget.
"""

from __future__ import annotations

from collections.abc import Sequence

from .robust import SCENARIOS
from .robust_facts import Row, _pays, _worse, yes
from .robust_kitbench import kitbench_markdown


def _trays(trays: str) -> str:
    return f"{trays} tray{'' if trays == '1' else 's'}"


def _cell(r: Row) -> str:
    return f"{r['instance']}: {r['tasks']} tasks, {_trays(str(r['trays']))}"


def _tasks(rows: Sequence[Row]) -> str:
    """The task counts of ``rows``: one number or a range."""
    low, high = min(int(r["tasks"]) for r in rows), max(int(r["tasks"]) for r in rows)
    return f"{low} tasks" if low == high else f"{low} to {high} tasks"


def _counts(rows: Sequence[Row]) -> str:
    """How many intervals lie above 0, below 0 and meet 0, with the records' task counts."""
    pays, worse = [r for r in rows if _pays(r)], [r for r in rows if _worse(r)]
    meets = len(rows) - len(pays) - len(worse)
    where = f" (records of {_tasks(pays)})" if pays else ""
    return (
        f"the VSS interval lies above 0 in {len(pays)}{where}, below 0 in {len(worse)} and "
        f"meets 0 in {meets}"
    )


def _range(rows: Sequence[Row]) -> str:
    low = min(rows, key=lambda r: float(r["vss"]))
    high = max(rows, key=lambda r: float(r["vss"]))
    if float(low["vss"]) == float(high["vss"]):
        return f"the VSS is {float(low['vss']):.2f} s in each"
    return (
        f"the VSS ranges from {float(low['vss']):.2f} s ({float(low['vss_pct']):.2f} %; "
        f"{_cell(low)}) to {float(high['vss']):.2f} s ({float(high['vss_pct']):.2f} % of the "
        f"expected makespan; {_cell(high)})"
    )


def _kept(rows: Sequence[Row]) -> str:
    """The cells whose SAA solve kept the mean-value plan (VSS exactly 0), proven or not."""
    kept = [r for r in rows if float(r["vss"]) == 0.0 and yes(r["same_plan"])]
    if not kept:
        return ""
    open_ = [r for r in kept if not yes(r["saa_proven"])]
    out = (
        f"In {len(kept)} of the {len(rows)} records the SAA solve kept the mean-value plan "
        f"(VSS exactly 0), proven optimal on its scenarios in {len(kept) - len(open_)}"
    )
    if not open_:
        return out + "."
    return (
        f"{out}; in the other {len(open_)} (records of {_tasks(open_)}) zero says only that "
        "the solve found no better plan within its budget, not that none exists."
    )


def kitbench_advice(rows: Sequence[Row]) -> str:
    """The panel's answer: the verdict counts and the VSS's range over every record, the same
    per tray count, the kept plans, and how the solves ended."""
    cvs = ", ".join(f"{c:g}" for c in sorted({float(r["cv"]) for r in rows}))
    out = [f"Over the {len(rows)} records (CV {cvs}), {_counts(rows)}; {_range(rows)}."]
    for trays in dict.fromkeys(str(r["trays"]) for r in rows):
        mine = [r for r in rows if str(r["trays"]) == trays]
        out.append(
            f"With {_trays(trays)} ({len(mine)} records of {_tasks(mine)}), {_counts(mine)}; "
            f"{_range(mine)}."
        )
    out.append(_kept(rows))
    worse = [r for r in rows if _worse(r)]
    if worse:
        overfit = sum(yes(r["saa_proven"]) for r in worse)
        out.append(
            f"Where the VSS interval lies below 0 the SAA plan is worse out of sample "
            f"({'; '.join(_cell(r) for r in worse)}), {overfit} of them proven optimal on its "
            f"{SCENARIOS} scenarios: so few scenarios can overfit, which is why every plan is "
            "judged on the independent evaluation sample."
        )
    cut = [r for r in rows if int(r["safety_net_fired"]) > 0]
    if cut:
        out.append(
            f"The wall-clock safety net cut {sum(int(r['safety_net_fired']) for r in cut)} "
            f"solves in {len(cut)} of {len(rows)} cells, even computed again "
            f"({', '.join(_cell(r) for r in cut)}): those rows are not a pure function of "
            "their configuration and seed."
        )
    else:
        out.append(
            "Every solve stopped on its deterministic time limit or on a proof "
            f"(`safety_net_fired` is 0 in all {len(rows)} cells): each row is a pure function "
            "of its configuration and seed."
        )
    proven = [r for r in rows if yes(r["saa_proven"])]
    mean_proven = [r for r in rows if yes(r["mean_plan_proven"])]
    out.append(
        f"The mean-value solve proves its plan optimal for the mean times in "
        f"{len(mean_proven)} of {len(rows)} records, the SAA solve its plan on its scenarios "
        f"in {len(proven)}" + (f" (records of {_tasks(proven)})." if proven else ".")
    )
    return " ".join(s for s in out if s)


#: Table name -> (its CSV file, its renderer), merged into :data:`.report_sim.SIM_TABLES`.
ROBUST_KITBENCH_TABLES = {
    "robust_kitbench_advice": ("robust_kitbench.csv", kitbench_advice),
    "robust_kitbench_cells": ("robust_kitbench.csv", kitbench_markdown),
}
