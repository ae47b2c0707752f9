"""The paper's statistics (Section V): repeated-measures and one-way ANOVA, Tukey HSD, paired
t-tests (statsmodels and scipy, imported lazily), with NaN/inf reported as None."""

from __future__ import annotations

import math
import warnings
from collections.abc import Iterator, Mapping, Sequence
from contextlib import contextmanager
from typing import Any

import numpy as np


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


def paired_p(a: np.ndarray, b: np.ndarray) -> float | None:
    """p of a paired t-test of ``a`` against ``b`` (None when undefined: one pair, or equal)."""
    from scipy.stats import ttest_rel

    with quiet():
        p = ttest_rel(a, b).pvalue if len(a) > 1 and np.any(a != b) else None
    return None if p is None else finite(float(p))
