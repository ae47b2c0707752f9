"""The horizon study's tables (docs/reproduction.md, "The horizon study"): the per-instance
summary, the mean gap by N, and their Markdown, from the rows of ``horizon.csv`` and
``horizon_window.csv`` (as computed, or read back with :func:`typed_rows`). Shared by
:mod:`.horizon` and the README renderer (:mod:`.report`)."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

from ..experiments.tables import markdown_lines


def horizon_summary(rows: Sequence[Mapping[str, Any]]) -> list[dict[str, Any]]:
    """Per instance: the gap at the shortest N, the best N (the shortest with the least gap),
    the share of the gap it closes, the gap at the longest N and the plan times there."""
    out = []
    for inst in dict.fromkeys(r["instance_file"] for r in rows):
        rs = sorted(
            (r for r in rows if r["instance_file"] == inst and r["gap_pct"] is not None),
            key=lambda r: r["horizon"],
        )
        if not rs:
            continue
        first, last = rs[0], rs[-1]
        best = min(rs, key=lambda r: (round(r["gap_pct"], 9), r["horizon"]))
        g0 = first["gap_pct"]
        out.append(
            {
                "instance": first["instance"],
                "instance_file": inst,
                "reference": first["reference"],
                "n_first": first["horizon"],
                "gap_first_pct": g0,
                "best_n": best["horizon"],
                "gap_best_pct": best["gap_pct"],
                "closed_pct": 100.0 * (g0 - best["gap_pct"]) / g0 if g0 > 1e-9 else None,
                "n_last": last["horizon"],
                "gap_last_pct": last["gap_pct"],
                "plan_time_best_s": best["plan_time_s"],
                "plan_time_last_s": last["plan_time_s"],
            }
        )
    return out


def mean_gap_by_n(rows: Sequence[Mapping[str, Any]]) -> dict[int, float]:
    """The mean gap (%) over the instances at each N, over the instances that have a gap at
    every N of the grid (so that every mean is over the same instances)."""
    ns = sorted({int(r["horizon"]) for r in rows})
    gaps: dict[str, dict[int, float]] = {}
    for r in rows:
        if r["gap_pct"] is not None:
            gaps.setdefault(str(r["instance_file"]), {})[int(r["horizon"])] = float(r["gap_pct"])
    full = [g for g in gaps.values() if len(g) == len(ns)]
    return {n: float(np.mean([g[n] for g in full])) for n in ns} if full else {}


def _pct(x: Any, nd: int = 1) -> str:
    return "-" if x is None else f"{x:.{nd}f}"


def planning_markdown(rows: Sequence[Mapping[str, Any]]) -> str:
    """Part A as Markdown: per instance the gap at the shortest, the best and the longest N
    and the plan times there; then the mean gap over the instances by N."""
    summary = horizon_summary(rows)
    if not summary:
        return "(no planning rows)"
    n0, n1 = summary[0]["n_first"], summary[0]["n_last"]
    out = markdown_lines(
        [
            "instance",
            "reference",
            f"gap at N = {n0} (%)",
            "best N",
            "gap there (%)",
            "gap closed (%)",
            f"gap at N = {n1} (%)",
            f"plan time at best N / N = {n1} (s)",
        ],
        [
            [
                s["instance"],
                s["reference"],
                _pct(s["gap_first_pct"]),
                str(s["best_n"]),
                _pct(s["gap_best_pct"]),
                _pct(s["closed_pct"], 0),
                _pct(s["gap_last_pct"]),
                f"{s['plan_time_best_s']:.2f} / {s['plan_time_last_s']:.2f}",
            ]
            for s in summary
        ],
    )
    mean = mean_gap_by_n(rows)
    if mean and len(summary) > 1:
        out += ["", f"Mean gap over the {len(summary)} instances by N:", ""]
        out += markdown_lines(
            ["N", *(str(n) for n in mean)], [["gap (%)", *(_pct(g, 2) for g in mean.values())]]
        )
    return "\n".join(out)


def window_markdown(rows: Sequence[Mapping[str, Any]]) -> str:
    """Part B as Markdown: per delay cell and policy (window), cpsat-rolling against
    Optimized in the same runs."""
    return "\n".join(
        markdown_lines(
            [
                "delay",
                "policy (window)",
                "total time (s)",
                "vs Optimized (%)",
                "idle (s)",
                "kits",
                "s per decision",
            ],
            [
                [
                    r["label"],
                    r["policy"] + (f" ({r['window']})" if r["window"] is not None else ""),
                    f"{r['total_mean']:.0f}",
                    _pct(r["total_pct_over_optimized"]),
                    f"{r['idle_mean']:.0f}",
                    f"{r['kits_mean']:.1f}",
                    f"{r['plan_s_per_decision']:.3f}",
                ]
                for r in rows
            ],
        )
    )


def typed_rows(rows: Sequence[Mapping[str, str]]) -> list[dict[str, Any]]:
    """Rows read back from ``horizon.csv`` or ``horizon_window.csv`` as values: ``""`` is
    None, ``True``/``False`` booleans, N and windows integers, other numbers floats."""
    out = []
    for r in rows:
        row: dict[str, Any] = {}
        for k, v in r.items():
            if v == "":
                row[k] = None
            elif v in ("True", "False"):
                row[k] = v == "True"
            elif k in ("horizon", "window", "n_tasks", "n_kits", "units", "reps", "decisions"):
                row[k] = int(float(v))
            else:
                try:
                    row[k] = float(v)
                except ValueError:
                    row[k] = v
        out.append(row)
    return out
