"""The within-subject model explained by its numbers (docs/reproduction.md, "The participant
model"): how a session's log-variance splits between the participant, the participant x
condition term and learning; how strongly a participant's active times in two conditions
correlate; and where the difference between our repeated-measures F and the paper's comes
from, the condition means or the residual (participant x condition) variance.

A repeated-measures F is ``MS_conditions / MS_residual``. The paper's ``MS_conditions`` follows
from its Fig. 5 means (``n * sum (mean_c - grand)^2 / (k - 1)``) and its ``MS_residual`` from
its F; ours are medians over the fresh studies. Swapping one of the two for the paper's shows
which one makes the F differ: the share of ``log(F_ours / F_paper)`` each accounts for.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

from ..sim.timing import WithinSubjectModel
from .common import CONDITIONS, METRIC_LABELS, METRICS, PAPER_F, PAPER_MEANS, SHORT


def _matrix(rows: Sequence[Mapping[str, Any]], col: str) -> np.ndarray:
    """participants x conditions of one study (CONDITIONS order)."""
    parts = sorted({int(r["participant"]) for r in rows})
    y = np.full((len(parts), len(CONDITIONS)), np.nan)
    for r in rows:
        y[parts.index(int(r["participant"])), CONDITIONS.index(r["condition"])] = r[col]
    return y


def mean_squares(y: np.ndarray) -> tuple[float, float]:
    """``(MS_conditions, MS_residual)`` of a participants x conditions matrix (the
    repeated-measures ANOVA's, so their ratio is its F)."""
    n, k = y.shape
    g = y.mean()
    ss_cond = n * float(np.sum((y.mean(axis=0) - g) ** 2))
    ss_subj = k * float(np.sum((y.mean(axis=1) - g) ** 2))
    ss_err = float(np.sum((y - g) ** 2)) - ss_cond - ss_subj
    return ss_cond / (k - 1), ss_err / ((n - 1) * (k - 1))


def paper_mean_squares(metric: str, n: int) -> tuple[float, float]:
    """The paper's ``MS_conditions`` (its Fig. 5 means, ``n`` participants) and the
    ``MS_residual`` its F implies."""
    means = np.array([PAPER_MEANS[metric][c] for c in CONDITIONS])
    ms_cond = n * float(np.sum((means - means.mean()) ** 2)) / (len(means) - 1)
    return ms_cond, ms_cond / PAPER_F[metric]


def variance_shares(design: WithinSubjectModel) -> dict[str, float]:
    """Shares of a session's log-variance: the participant's own speed, participant x
    condition, learning by session position."""
    learn = float(np.var(np.log(design.learning_factors)))
    parts = {
        "participant": design.speed_var,
        "participant x condition": design.within_cv**2,
        "learning": learn,
    }
    total = sum(parts.values())
    return {k: v / total for k, v in parts.items()}


def _q(v: Sequence[float]) -> tuple[float, float, float]:
    a = np.asarray(v, float)
    return float(np.median(a)), float(np.quantile(a, 0.025)), float(np.quantile(a, 0.975))


def _row(
    quantity: str,
    metric: str,
    ours: Any,
    *,
    low: Any = None,
    high: Any = None,
    paper: Any = None,
    detail: str = "",
) -> dict[str, Any]:
    return {
        "quantity": quantity,
        "metric": metric,
        "ours": ours,
        "low": low,
        "high": high,
        "paper": paper,
        "detail": detail,
    }


def explain(
    rows: Sequence[Mapping[str, Any]],
    design: WithinSubjectModel,
    bound: float,
    fit: Mapping[str, Any],
) -> list[dict[str, Any]]:
    """``user_study_within.csv``: the variance shares, the bound step 2 hit, the correlation
    of a participant's active times between conditions (median and 95 % range over the
    studies), and the F decomposition per metric (module docstring). ``fit``: the F target's
    row of the calibration (paper value and the calibration cohort's median F)."""
    out = [
        _row(f"share of a session's log-variance: {k}", "", round(v, 4))
        for k, v in variance_shares(design).items()
    ]
    out.append(
        _row(
            "within_cv (participant x condition, log SD)",
            "",
            round(design.within_cv, 6),
            high=round(bound, 6),
            detail="fitted; high = the bound of step 2",
        )
    )
    out.append(
        _row(
            "calibration cohort's median F of total time at the fit",
            "total",
            round(float(fit["fitted"]), 2),
            paper=fit["paper"],
            detail="step 2's target",
        )
    )
    studies = sorted({int(r["study"]) for r in rows})
    by_study = {j: [r for r in rows if int(r["study"]) == j] for j in studies}
    active = {j: _matrix(by_study[j], "active_time") for j in studies}
    for a in range(len(CONDITIONS)):
        for b in range(a + 1, len(CONDITIONS)):
            cs = [float(np.corrcoef(active[j][:, a], active[j][:, b])[0, 1]) for j in studies]
            med, lo, hi = _q(cs)
            pair = f"{SHORT[CONDITIONS[a]]} vs {SHORT[CONDITIONS[b]]}"
            out.append(
                _row(
                    f"correlation of active time, {pair}",
                    "",
                    round(med, 3),
                    low=round(lo, 3),
                    high=round(hi, 3),
                    detail="across participants, per study",
                )
            )
    n = active[studies[0]].shape[0]
    for m, col in METRICS.items():
        out += _f_rows(m, [mean_squares(_matrix(by_study[j], col)) for j in studies], n)
    return out


def _f_rows(metric: str, ms: Sequence[tuple[float, float]], n: int) -> list[dict[str, Any]]:
    """The F decomposition of one metric (module docstring)."""
    cond, err = (float(np.median([x[i] for x in ms])) for i in (0, 1))
    p_cond, p_err = paper_mean_squares(metric, n)
    excess = math.log((cond / err) / PAPER_F[metric])
    from_cond = math.log(cond / p_cond) / excess if excess else float("nan")
    label = METRIC_LABELS[metric]
    return [
        _row(
            "MS conditions (median over studies)",
            metric,
            round(cond, 1),
            paper=round(p_cond, 1),
            detail=f"paper: from the Fig. 5 means of {label}",
        ),
        _row(
            "MS residual (participant x condition)",
            metric,
            round(err, 1),
            paper=round(p_err, 1),
            detail="paper: its MS conditions / its F",
        ),
        _row("residual SD (s)", metric, round(math.sqrt(err), 2), paper=round(math.sqrt(p_err), 2)),
        _row("F from the medians", metric, round(cond / err, 2), paper=PAPER_F[metric]),
        _row(
            "F with the paper's means and our residual",
            metric,
            round(p_cond / err, 2),
            paper=PAPER_F[metric],
        ),
        _row(
            "F with our means and the paper's residual",
            metric,
            round(cond / p_err, 2),
            paper=PAPER_F[metric],
        ),
        _row(
            "share of log(F ours / F paper) from the condition means",
            metric,
            round(from_cond, 3),
            detail="the rest: the residual",
        ),
    ]


__all__ = ["explain", "mean_squares", "paper_mean_squares", "variance_shares"]
