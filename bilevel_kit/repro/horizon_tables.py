"""The horizon study's tables (docs/reproduction.md, "The horizon study"): the per-instance
summary, the mean gap by N, and their Markdown, from the rows of ``horizon.csv`` and
``horizon_window.csv`` (as computed, or read back with :func:`typed_rows`). Shared by
:mod:`.horizon` and the README renderer (:mod:`.report`)."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

from ..experiments.tables import markdown_lines
from ..instance import DEFAULT_HORIZON


def _closed(g0: float, g: float | None) -> float | None:
    """The share (%) of the gap at the shortest N that a horizon with gap ``g`` closes."""
    return None if g is None or g0 <= 1e-9 else 100.0 * (g0 - g) / g0


def horizon_summary(rows: Sequence[Mapping[str, Any]]) -> list[dict[str, Any]]:
    """Per instance: the gap at the shortest N; at the toolkit's default N (the paper's 5)
    the gap and the share of the first gap it closes; the best N chosen afterwards (the
    shortest with the least gap), its gap and share; the gap at the longest N and the plan
    times at the best and the longest N."""
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
        default = next((r for r in rs if r["horizon"] == DEFAULT_HORIZON), None)
        g0 = first["gap_pct"]
        g5 = None if default is None else default["gap_pct"]
        out.append(
            {
                "instance": first["instance"],
                "instance_file": inst,
                "reference": first["reference"],
                "n_first": first["horizon"],
                "gap_first_pct": g0,
                "gap_default_pct": g5,
                "closed_default_pct": _closed(g0, g5),
                "best_n": best["horizon"],
                "gap_best_pct": best["gap_pct"],
                "closed_pct": _closed(g0, best["gap_pct"]),
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


def paired_gap_difference(rows: Sequence[Mapping[str, Any]], n: int, m: int) -> dict[str, float]:
    """gap(N = n) - gap(N = m) paired over the instances that have both (points): the mean,
    its 95 % t-interval on instances - 1 degrees of freedom, and the count. The unit is the
    instance (one greedy-ce seed per plan): the interval is over instances, not over seeds
    (docs/reproduction.md, "The horizon study")."""
    from scipy.stats import t as student_t

    gaps: dict[str, dict[int, float]] = {}
    for r in rows:
        if r["gap_pct"] is not None:
            gaps.setdefault(str(r["instance_file"]), {})[int(r["horizon"])] = float(r["gap_pct"])
    d = np.array([g[n] - g[m] for g in gaps.values() if n in g and m in g])
    mean = float(d.mean())
    half = float(student_t.ppf(0.975, len(d) - 1)) * float(d.std(ddof=1)) / np.sqrt(len(d))
    return {"mean": mean, "low": mean - half, "high": mean + half, "instances": len(d)}


def _pct(x: Any, nd: int = 1) -> str:
    return "-" if x is None else f"{x:.{nd}f}"


def planning_markdown(rows: Sequence[Mapping[str, Any]]) -> str:
    """Part A as Markdown: per instance the gap at the shortest, the best and the longest N
    and the plan times there; then the mean gap over the instances by N."""
    summary = horizon_summary(rows)
    if not summary:
        return "(no planning rows)"
    n0, n1, d = summary[0]["n_first"], summary[0]["n_last"], DEFAULT_HORIZON
    out = markdown_lines(
        [
            "instance",
            "reference",
            f"gap at N = {n0} (%)",
            f"gap at N = {d} (%)",
            f"closed at N = {d} (%)",
            "best N (chosen afterwards)",
            "gap there (%)",
            "closed there (%)",
            f"gap at N = {n1} (%)",
            f"plan time at best N / N = {n1} (s)",
        ],
        [
            [
                s["instance"],
                s["reference"],
                _pct(s["gap_first_pct"]),
                _pct(s["gap_default_pct"]),
                _pct(s["closed_default_pct"], 0),
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


def _gain(r: Mapping[str, Any]) -> str:
    """``1.3 [0.4, 2.2] better``: the gain over Optimized (%), its 95 % interval and the
    paired test's direction after Holm (Optimized's own row: ``-``)."""
    if r["window"] is None:
        return "-"
    text = _pct(r["total_pct_over_optimized"], 2)
    if r.get("total_pct_ci_low") is not None:
        text += f" [{_pct(r['total_pct_ci_low'], 2)}, {_pct(r['total_pct_ci_high'], 2)}]"
    return f"{text} {r.get('direction') or ''}".rstrip()


def window_markdown(rows: Sequence[Mapping[str, Any]]) -> str:
    """Part B as Markdown: per delay cell and policy (window), cpsat-rolling against
    Optimized in the same runs: the gain with its 95 % interval and the paired test's
    direction after Holm over the study's comparisons."""
    return "\n".join(
        markdown_lines(
            [
                "delay",
                "policy (window)",
                "R",
                "total time (s)",
                "gain over Optimized (%) [95 % CI], paired + Holm",
                "idle (s)",
                "kits",
                "s per decision",
            ],
            [
                [
                    r["label"],
                    r["policy"] + (f" ({r['window']})" if r["window"] is not None else ""),
                    str(r["reps"]),
                    f"{r['total_mean']:.0f}",
                    _gain(r),
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
