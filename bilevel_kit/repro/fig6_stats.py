"""Figure 6's claims tested (docs/reproduction.md, "Figure 6"): significance by direction, the
trends as regressions, and the power of the paper's test.

* **By direction.** A cell is *better* or *worse* (Optimized against the baseline) only when
  its test is significant, else *n.s.*, under three tests side by side: the paper's (one-way
  ANOVA over the three policies, then Tukey HSD, per cell, no correction over the cells), the
  paper's after Holm's correction over a panel's 16 cells, and a paired t-test over the
  replications (every policy sees the same seeds) after Holm over the cells.
* **Trends** ("most at low MAT", "most at high MAT"): the per-replication improvement
  ``100 (baseline_r - subject_r) / mean(baseline)`` of every grid cell regressed on MAT and
  MTTF by least squares per replication (the same seeds run in every cell: a replication is a
  cluster), and a t-test of the replications' slopes on replications - 1 degrees of freedom;
  the MAT slope per 30 s (the grid's step) with its 95 % interval, and Kendall's
  tau of the 16 cell means against MAT. A claim is *supported* when both agree with it (the
  slope's interval on the claimed side of 0 and tau significant with the claimed sign),
  *contradicted* when both disagree, else *not shown*: a slope alone is carried by the ends of
  the grid and says nothing about where the gain is largest (``peak_mat``: the MAT whose cells'
  mean improvement is largest, reported beside it).
* **Power.** The replications per policy the paper's unpaired test would need to detect a
  cell's observed difference with 80 % power: Tukey's critical value for three groups at
  ``3 (R - 1)`` degrees of freedom, a noncentral t with the cell's pooled SD of the three
  policies (the ANOVA gate is ignored, so it slightly flatters the test).
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from functools import cache
from typing import Any

import numpy as np

from .common import CONDITIONS, LABELS, METRIC_LABELS, METRICS, SINGLE, WHOLE
from .verdict import DIRECTION, TREND, side, tested, verdict

BETTER, WORSE, NS = DIRECTION.all()
#: Trend claims of the paper (Fig. 6 caption): baseline -> (claim, expected sign of the slope).
CLAIMS: dict[str, tuple[str, int]] = {
    SINGLE: ("largest at low MAT", -1),
    WHOLE: ("largest at high MAT", 1),
}
POWER = 0.8
ALPHA = 0.05
#: Degrees of freedom at which Tukey's critical value is computed; others are interpolated
#: in 1 / df (smooth there), since scipy's studentized range takes ~0.2 s a value.
_DF_GRID = (3, 6, 9, 12, 18, 27, 40, 60, 90, 150, 300, 1000, 100_000)


def holm(pvalues: Sequence[float | None]) -> list[bool]:
    """Holm's step-down rejections at ALPHA (a missing p is never rejected)."""
    from statsmodels.stats.multitest import multipletests

    ps = np.array([1.0 if p is None else float(p) for p in pvalues])
    return [bool(x) for x in multipletests(ps, alpha=ALPHA, method="holm")[0]] if len(ps) else []


def direction(significant: bool, pct: float | None) -> str:
    """better / worse / n.s. (:func:`.verdict.tested`: the sign of a significant gain)."""
    return tested(significant and pct is not None, pct, DIRECTION)


def add_directions(long_rows: list[dict[str, Any]]) -> None:
    """Per improvement row (one panel, one cell): ``dir_tukey``, ``dir_tukey_holm`` and
    ``dir_paired_holm`` (module docstring); Holm runs over a panel's delay cells (the no-delay
    reference is tested alone)."""
    for panel in dict.fromkeys(r["panel"] for r in long_rows):
        rows = [r for r in long_rows if r["panel"] == panel]
        grid = [r for r in rows if r["mat"] is not None]
        gate = [r["anova_p"] is not None and r["anova_p"] < ALPHA for r in grid]
        tk = holm([r["p_tukey"] for r in grid])
        pd = holm([r["p_paired"] for r in grid])
        for r, g, t, p in zip(grid, gate, tk, pd, strict=True):
            r["dir_tukey_holm"] = direction(g and t, r["pct"])
            r["dir_paired_holm"] = direction(p, r["pct"])
        for r in rows:
            r["dir_tukey"] = direction(bool(r["stars"]), r["pct"])
            if r["mat"] is None:
                r["dir_tukey_holm"] = r["dir_tukey"]
                p = r["p_paired"]
                r["dir_paired_holm"] = direction(p is not None and p < ALPHA, r["pct"])


def verdicts(long_rows: Sequence[Mapping[str, Any]]) -> list[dict[str, Any]]:
    """Per panel, over its delay cells: better / n.s. / worse under each test, and the verdict
    on "significant for most scenarios" (Optimized significantly better in more than half of
    the cells) by the paper's test and by the paired test after Holm."""
    out: list[dict[str, Any]] = []
    for panel in dict.fromkeys(r["panel"] for r in long_rows):
        cells = [r for r in long_rows if r["panel"] == panel and r["mat"] is not None]
        row: dict[str, Any] = {"panel": panel, "cells": len(cells), "reps": cells[0]["reps"]}
        for test in ("tukey", "tukey_holm", "paired_holm"):
            dirs = [r[f"dir_{test}"] for r in cells]
            for d, name in ((BETTER, "better"), (NS, "ns"), (WORSE, "worse")):
                row[f"{test}_{name}"] = dirs.count(d)
        for test in ("tukey", "paired_holm"):
            row[f"most_{test}"] = "yes" if row[f"{test}_better"] > len(cells) / 2 else "no"
        r80 = [r["r80"] for r in cells if r["pct"] is not None and r["pct"] > 0]
        row["r80_median_better"] = float(np.median([x for x in r80 if x])) if r80 else None
        row["cells_r80_le_100"] = sum(1 for x in r80 if x and x <= 100)
        out.append(row)
    return out


@cache
def _tukey_crit_grid() -> tuple[np.ndarray, np.ndarray]:
    from scipy.stats import studentized_range

    crit = [float(studentized_range.ppf(1 - ALPHA, 3, df)) / math.sqrt(2) for df in _DF_GRID]
    return 1.0 / np.array(_DF_GRID, float), np.array(crit)


def tukey_crit(df: float) -> float:
    """Tukey's critical |t| for three groups at ``df`` (interpolated in 1 / df)."""
    x, y = _tukey_crit_grid()
    return float(np.interp(1.0 / df, x[::-1], y[::-1]))


def power(diff: float, sd: float, reps: int) -> float:
    """Power of the unpaired Tukey comparison of two of three groups of ``reps``."""
    from scipy.stats import nct

    df = 3 * (reps - 1)
    ncp = abs(diff) / (sd * math.sqrt(2.0 / reps))
    c = tukey_crit(df)
    return float(nct.sf(c, df, ncp) + nct.cdf(-c, df, ncp))


def reps_for_power(diff: float, sd: float, target: float = POWER, cap: int = 100_000) -> int | None:
    """The fewest replications per policy giving ``target`` power (None: none up to ``cap``)."""
    if sd <= 0 or diff == 0:
        return None
    lo, hi = 2, 4
    while power(diff, sd, hi) < target:
        lo, hi = hi, hi * 2
        if hi > cap:
            return None
    while hi - lo > 1:
        mid = (lo + hi) // 2
        lo, hi = (mid, hi) if power(diff, sd, mid) < target else (lo, mid)
    return hi if power(diff, sd, lo) < target else lo


def pooled_sd(row: Mapping[str, Any], metric: str, policies: Sequence[str] = CONDITIONS) -> float:
    """The pooled SD of the policies in a cell row (equal group sizes)."""
    return math.sqrt(float(np.mean([float(row[f"{metric}_sd:{p}"]) ** 2 for p in policies])))


#: How the MAT slope is tested (written into fig6_trends.csv's ``slope_test`` column).
SLOPE_TEST = "t-test on the per-replication slopes, df = replications - 1"


def replication_slopes(
    y: np.ndarray, mat: np.ndarray, mttf: np.ndarray, groups: np.ndarray
) -> tuple[float, float, float, float, int]:
    """MAT slope per 30 s with its 95 % interval, p and degrees of freedom: each replication's
    least-squares slope over the grid (on MAT, and MTTF when it varies), then a one-sample
    t-test of those slopes (:data:`SLOPE_TEST`). The replications are the clusters (the same
    seeds run in every cell), so the test has replications - 1 degrees of freedom, not the
    normal approximation of cluster-robust errors with few clusters
    (paper_repro/README.md, "Trends, tested")."""
    from scipy.stats import t as student_t

    slopes = []
    for g in np.unique(groups):
        sel = groups == g
        cols = [np.ones(int(sel.sum())), mat[sel] / 30.0]
        if np.ptp(mttf) > 0:  # a one-MTTF grid (quick) has nothing to adjust for
            cols.append(mttf[sel] / 30.0)
        coef, *_ = np.linalg.lstsq(np.column_stack(cols), y[sel], rcond=None)
        slopes.append(float(coef[1]))
    s = np.asarray(slopes)
    df = len(s) - 1
    mean = float(s.mean())
    if df < 1:  # one replication: no interval
        return mean, math.nan, math.nan, math.nan, df
    se = float(s.std(ddof=1)) / math.sqrt(len(s))
    if se == 0:  # every replication has the same slope
        return mean, mean, mean, 0.0 if mean else 1.0, df
    half = float(student_t.ppf(1 - ALPHA / 2, df)) * se
    p = float(2 * student_t.sf(abs(mean) / se, df))
    return mean, mean - half, mean + half, p, df


def trend_verdict(sign: int, lo: float, hi: float, tau: float, tau_p: float) -> str:
    """supported / contradicted / not shown (module docstring): the slope's 95 % interval and
    the cells' rank trend must agree."""
    slope_side = side(lo, hi)
    rank_side = side(tau, tau) if tau_p < ALPHA else 0
    agree = slope_side if slope_side == rank_side else 0
    # the agreed side times the claimed sign: +1 with the claim, -1 against it
    return verdict(agree * sign, agree * sign, TREND)


def peak_mat(cell_mat: Sequence[float], cell_pct: Sequence[float]) -> float:
    """The MAT whose cells' mean improvement is largest."""
    by_mat: dict[float, list[float]] = {}
    for m, v in zip(cell_mat, cell_pct, strict=True):
        by_mat.setdefault(m, []).append(v)
    return max(by_mat, key=lambda m: float(np.mean(by_mat[m])))


def trends(
    records: Sequence[Mapping[str, Any]], pairs: Sequence[tuple[str, str]]
) -> list[dict[str, Any]]:
    """One row per (subject, baseline) pair with a claim and per metric: the MAT slope of the
    improvement (module docstring), Kendall's tau of the cell means and the verdict."""
    from scipy.stats import kendalltau

    grid = [r for r in records if r["cell"]["mat"] is not None]
    if len({r["cell"]["mat"] for r in grid}) < 2:
        return []  # one MAT (e.g. a single-cell run): no trend in MAT to test
    out = []
    for subj, base in pairs:
        if base not in CLAIMS or not grid:
            continue
        claim, sign = CLAIMS[base]
        for m, col in METRICS.items():
            ys, mats, mttfs, reps, cell_pct, cell_mat = [], [], [], [], [], []
            for rec in grid:
                b = np.asarray(rec["runs"][base][col], float)
                s = np.asarray(rec["runs"][subj][col], float)
                y = 100.0 * (b - s) / b.mean()
                ys.append(y)
                mats.append(np.full(len(y), rec["cell"]["mat"]))
                mttfs.append(np.full(len(y), rec["cell"]["mttf"]))
                reps.append(np.arange(len(y)))
                cell_pct.append(float(y.mean()))
                cell_mat.append(float(rec["cell"]["mat"]))
            slope, lo, hi, p, df = replication_slopes(
                np.concatenate(ys),
                np.concatenate(mats),
                np.concatenate(mttfs),
                np.concatenate(reps),
            )
            tau, tau_p = kendalltau(cell_mat, cell_pct)
            verdict = trend_verdict(sign, lo, hi, float(tau), float(tau_p))
            out.append(
                {
                    "panel": f"{METRIC_LABELS[m]}, {LABELS.get(subj, subj)} over "
                    f"{LABELS.get(base, base)}",
                    "claim": claim,
                    "expected_sign": sign,
                    "slope_per_30s": slope,
                    "ci_low": lo,
                    "ci_high": hi,
                    "p": p,
                    "df": df,
                    "slope_test": SLOPE_TEST,
                    "kendall_tau": float(tau),
                    "kendall_p": float(tau_p),
                    "peak_mat": peak_mat(cell_mat, cell_pct),
                    "cells": len(grid),
                    "reps": len(ys[0]),
                    "verdict": verdict,
                }
            )
    return out


__all__ = [
    "BETTER",
    "CLAIMS",
    "NS",
    "SLOPE_TEST",
    "WORSE",
    "add_directions",
    "holm",
    "peak_mat",
    "power",
    "replication_slopes",
    "reps_for_power",
    "trend_verdict",
    "trends",
    "verdicts",
]
