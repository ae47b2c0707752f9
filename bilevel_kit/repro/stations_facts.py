"""The stations study's facts for docs/stations.md (``stations.*``), computed from its committed
CSVs (``stations.csv``, ``stations_served.csv``) and, for the capacity bound's times per unit,
from the line instances' nominal times (:func:`.stations.products_per_unit`), so that no number
in the page's prose is typed by hand (:mod:`.template`)."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

from .stations import LABELS, LINES, PLANNING, PLANNING_REPS, UNITS, products_per_unit
from .stations_stats import THRESHOLDS
from .stations_tables import per_rep

Row = Mapping[str, Any]
Facts = dict[str, str]


def _settled(verdict: str) -> int | None:
    """The stations a verdict serves, ``None`` when it is unsettled."""
    return None if "unsettled" in verdict else int(verdict)


def _names(pairs: Sequence[tuple[str, str]]) -> str:
    return ", ".join(f"{LABELS.get(p, p)} on the {line} line" for line, p in pairs) or "none"


def served_facts(served: Sequence[Row]) -> Facts:
    """Counts of the verdicts at the reproduction's idle and 10 %, parts in stock, and how the
    means sit against the capacity bound."""
    main = [
        r
        for r in served
        if r["idle_def"] == "paper" and int(r["threshold"]) == 10 and r["delay"] == "none"
    ]
    verdicts = {(str(r["line"]), str(r["policy"])): _settled(str(r["verdict"])) for r in main}
    paper = [r for r in served if r["idle_def"] == "paper" and str(r["bound"]) != ""]
    over = [r for r in paper if max(per_rep(r)) > int(r["bound"])]
    feeders = [r for r in served if r["delay"] == "feeders" and r["idle_def"] == "paper"]
    out: Facts = {
        "stations.pairs": str(len(main)),
        "stations.serve0": str(sum(v == 0 for v in verdicts.values())),
        "stations.serve1": _names([k for k, v in verdicts.items() if v == 1]),
        "stations.serve2": _names([k for k, v in verdicts.items() if v is not None and v >= 2]),
        "stations.unsettled": _names([k for k, v in verdicts.items() if v is None]),
        "stations.bound.rows": str(len(paper)),
        "stations.bound.over": str(len(over)),
        "stations.feeders.max": str(max(max(per_rep(r)) for r in feeders)) if feeders else "-",
    }
    return out


def metric_facts(rows: Sequence[Row]) -> Facts:
    """Single Task on the table line at S = 1, parts in stock, under both idle definitions
    (the old page's metric was the steady one), and the throughput the shared feeders allow."""
    by = {(r["line"], r["delay"], r["policy"], int(r["stations"])): r for r in rows}
    st = by[("table", "none", "single-task", 1)]
    out: Facts = {
        "stations.st1.idle": f"{float(st['idle']):.1f} %",
        "stations.st1.idle_ci": f"[{float(st['idle_low']):.1f}, {float(st['idle_high']):.1f}]",
        "stations.st1.steady": f"{float(st['idle_steady']):.1f} %",
        "stations.reps": str(max(int(r["reps"]) for r in rows)),
        "stations.planning_reps": str(PLANNING_REPS),
        "stations.units": str(UNITS),
        "stations.thresholds": ", ".join(f"{100 * t:.0f}" for t in THRESHOLDS) + " %",
        "stations.grid": ", ".join(str(s) for s in sorted({int(r["stations"]) for r in rows})),
    }
    out["stations.cell_s"] = f"{sum(float(r['wall_s']) for r in rows):,.0f}"
    out["stations.ran"] = _planning_ran(rows)
    for line in LINES:
        fed = [float(r["throughput"]) for r in rows if r["line"] == line and r["delay"] != "none"]
        stock = [float(r["throughput"]) for r in rows if r["line"] == line and r["delay"] == "none"]
        out[f"stations.{line}.feeders_max"] = f"{max(fed):.1f}" if fed else "-"
        out[f"stations.{line}.stock_max"] = f"{max(stock):.1f}" if stock else "-"
    return out


def _planning_ran(rows: Sequence[Mapping[str, str]]) -> str:
    """Which lines the planning policies ran on: a committed CSV may hold a partial run (each
    cell is computed alone), and the page must say so rather than imply every line."""
    left = {
        policy: [
            x for x in LINES if not any(r["line"] == x and r["policy"] == policy for r in rows)
        ]
        for policy in PLANNING
    }
    if not any(left.values()):
        return "cpsat-rolling and Optimized ran on every line"
    parts = []
    for policy in PLANNING:
        ran = [x for x in LINES if x not in left[policy]]
        text = f"{policy.replace('optimized', 'Optimized')} on the {', '.join(ran) or 'no'} line"
        parts.append(
            text
            + ("s" if len(ran) != 1 else "")
            + (f" (not yet: {', '.join(left[policy])})" if left[policy] else "")
        )
    return " and ".join(parts) + "; `bilevel-kit repro stations` computes the rest"


def bound_facts() -> Facts:
    """The nominal seconds per unit behind the capacity bound (:mod:`.stations_stats`)."""
    out: Facts = {}
    for line in ("table", "stool", "chair"):
        for policy, tag in (("whole-assembly", "wa"), ("single-task", "st")):
            (unit,) = products_per_unit(line, policy, 1)
            for key in ("robot", "human", "task"):
                out[f"stations.{line}.{tag}.{key}"] = f"{unit[key]:.0f}"
    return out


def stations_facts(rows: Sequence[Row], served: Sequence[Row]) -> Facts:
    """Every ``stations.*`` fact (the module docstring)."""
    return {**metric_facts(rows), **served_facts(served), **bound_facts()}


__all__ = ["stations_facts"]
