"""The paper's statistics (Section V): repeated-measures and one-way ANOVA, Tukey HSD, paired
t-tests (statsmodels and scipy, imported lazily), with NaN/inf reported as None.

The user study's Tukey intervals are within-subject (:func:`tukey_rm`): the paper's intervals
use the repeated-measures error term, df (3 - 1)(18 - 1) = 34, and its half-widths follow from
its F and its interval centres (:func:`paper_half_width` reproduces 42.181 s and 12.9394 s;
docs/reproduction.md, "The user study"). :func:`tukey_pairs` (independent groups, df 51) is
kept as a check."""

from __future__ import annotations

import math
import warnings
from collections.abc import Iterator, Mapping, Sequence
from contextlib import contextmanager
from functools import cache
from typing import Any

import numpy as np

from ..stochastic import estimate


@contextmanager
def quiet() -> Iterator[None]:
    """Silence the statistics' warnings on degenerate groups (Whole Assembly's idle time is
    the same for every participant; a policy may equal another): their inf/NaN become None."""
    with np.errstate(divide="ignore", invalid="ignore"), warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        yield


def finite(x: float) -> float | None:
    """JSON has no NaN/inf: None instead."""
    return float(x) if x is not None and math.isfinite(x) else None


def anova_rm(rows: Sequence[Mapping[str, Any]], col: str) -> dict[str, float | None]:
    """Repeated-measures one-way ANOVA (condition within participant), the paper's F(2, 34)."""
    import pandas as pd
    from statsmodels.stats.anova import AnovaRM

    df = pd.DataFrame([{k: r[k] for k in ("participant", "condition", col)} for r in rows])
    with quiet():
        tab = AnovaRM(df, depvar=col, subject="participant", within=["condition"]).fit()
    row = tab.anova_table.iloc[0]
    return {
        "F": finite(row["F Value"]),
        "df1": float(row["Num DF"]),
        "df2": float(row["Den DF"]),
        "p": finite(row["Pr > F"]),
    }


def tukey_pairs(
    values: Sequence[float], groups: Sequence[str], alpha: float = 0.05
) -> dict[tuple[str, str], dict[str, float | None]]:
    """Tukey HSD of every pair: ``{(a, b): diff = mean(a) - mean(b), lo, hi, p}`` for both
    orders of each pair (statsmodels reports ``mean(group2) - mean(group1)``)."""
    from statsmodels.stats.multicomp import pairwise_tukeyhsd

    with quiet():
        res = pairwise_tukeyhsd(np.asarray(values, float), np.asarray(groups), alpha=alpha)
    names = [str(g) for g in res.groupsunique]
    out: dict[tuple[str, str], dict[str, float | None]] = {}
    k = 0
    for i in range(len(names)):
        for j in range(i + 1, len(names)):
            d = float(res.meandiffs[k])
            lo, hi = (float(v) for v in res.confint[k])
            p = finite(float(res.pvalues[k]))
            out[(names[j], names[i])] = {"diff": d, "lo": finite(lo), "hi": finite(hi), "p": p}
            out[(names[i], names[j])] = {"diff": -d, "lo": finite(-hi), "hi": finite(-lo), "p": p}
            k += 1
    return out


@cache
def tukey_q(groups: int, df: float, alpha: float = 0.05) -> float:
    """The studentized range's upper ``alpha`` quantile for ``groups`` means at ``df``."""
    from scipy.stats import studentized_range

    return float(studentized_range.ppf(1 - alpha, groups, df))


def _pairs_of(
    names: Sequence[str], means: np.ndarray, half: float, p_of: Any
) -> dict[tuple[str, str], dict[str, float | None]]:
    """Every ordered pair ``(a, b)``: ``diff = mean(a) - mean(b)`` with ``diff -+ half``."""
    out: dict[tuple[str, str], dict[str, float | None]] = {}
    for i, a in enumerate(names):
        for j, b in enumerate(names):
            if i != j:
                d = float(means[i] - means[j])
                out[(a, b)] = {
                    "diff": d,
                    "lo": finite(d - half),
                    "hi": finite(d + half),
                    "p": p_of(abs(d)),
                }
    return out


def tukey_rm(
    rows: Sequence[Mapping[str, Any]], col: str, alpha: float = 0.05
) -> dict[tuple[str, str], dict[str, float | None]]:
    """Within-subject Tukey HSD (the paper's): every pair ``(a, b)`` of conditions with
    ``diff = mean(a) - mean(b)``, ``lo``, ``hi`` and ``p``. The error term is the
    repeated-measures ANOVA's (participant x condition residual, from the sums of squares,
    df (k - 1)(n - 1)); the half-width is ``q(k, df) sqrt(MS_error / n)`` for every pair.
    Needs every participant in every condition."""
    from scipy.stats import studentized_range

    names = sorted({str(r["condition"]) for r in rows})
    people = sorted({r["participant"] for r in rows})
    y = np.full((len(people), len(names)), np.nan)
    pi, ci = {p: i for i, p in enumerate(people)}, {c: j for j, c in enumerate(names)}
    for r in rows:
        y[pi[r["participant"]], ci[str(r["condition"])]] = float(r[col])
    if np.isnan(y).any():
        raise ValueError("tukey_rm needs every participant in every condition")
    n, k = y.shape
    resid = y - y.mean(1, keepdims=True) - y.mean(0, keepdims=True) + y.mean()
    df = (k - 1) * (n - 1)
    se = math.sqrt(float((resid**2).sum()) / df / n)
    half = tukey_q(k, df, alpha) * se

    def p_of(d: float) -> float | None:
        if se == 0:
            return 0.0 if d > 0 else None
        with quiet():
            return finite(float(studentized_range.sf(d / se, k, df)))

    return _pairs_of(names, y.mean(0), half, p_of)


def paper_half_width(
    centres: Sequence[float], f_value: float, n: int, alpha: float = 0.05
) -> float:
    """The half-width of a within-subject Tukey interval implied by the ANOVA's ``f_value`` and
    the intervals' ``centres`` (every condition minus one baseline): ``MS_conditions`` from the
    means, ``MS_error = MS_conditions / F``, half = ``q(k, (k - 1)(n - 1)) sqrt(MS_error / n)``.
    For the paper's F and centres it gives its half-widths (paper, Section V-A)."""
    means = np.array([0.0, *centres])
    k = len(means)
    ms_cond = n * float(means.var(ddof=1))
    return tukey_q(k, (k - 1) * (n - 1), alpha) * math.sqrt(ms_cond / f_value / n)


def overlap(a: tuple[float | None, float | None], b: tuple[float, float]) -> bool | None:
    if a[0] is None or a[1] is None:
        return None
    return a[0] <= b[1] and b[0] <= a[1]


def stars(p: float | None) -> str:
    """The paper's marks: * p < .05, ** p < .001."""
    if p is None:
        return ""
    return "**" if p < 0.001 else "*" if p < 0.05 else ""


def oneway(groups: Sequence[np.ndarray]) -> tuple[float | None, float | None]:
    """One-way ANOVA ``(F, p)`` over ``groups`` (None, None for fewer than two groups)."""
    from scipy.stats import f_oneway

    with quiet():
        a = f_oneway(*groups) if len(groups) > 1 else None
    if a is None:
        return None, None
    return finite(float(a.statistic)), finite(float(a.pvalue))


def t_interval(
    x: Sequence[float] | np.ndarray, low: float = -math.inf, high: float = math.inf
) -> tuple[float, float, float]:
    """Mean and its 95 % t-interval (:func:`bilevel_kit.stochastic.estimate`; the mean twice
    with one value), cut to the metric's possible range ``[low, high]``: a t-interval of a few
    values near a bound crosses it (an idle share of -1.6 %, a station count of -0.36), which
    no run can give."""
    e = estimate(x)
    if e.n < 2:
        return e.mean, e.mean, e.mean
    return e.mean, max(low, e.low), min(high, e.high)


def paired_p(a: np.ndarray, b: np.ndarray) -> float | None:
    """p of a paired t-test of ``a`` against ``b`` (None when undefined: one pair, or equal)."""
    from scipy.stats import ttest_rel

    with quiet():
        p = ttest_rel(a, b).pvalue if len(a) > 1 and np.any(a != b) else None
    return None if p is None else finite(float(p))
