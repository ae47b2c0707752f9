"""The paper's user-study numbers as three kinds, and our prediction intervals for them
(docs/reproduction.md, "The user study").

* **fitted**: the calibration's targets (Whole Assembly and Single Task idle, F of total time);
* **implied**: arithmetic of the fitted targets and the paper's own inputs. A session's active
  time has the same distribution in every condition, so a condition's mean total time is its
  idle mean plus the paper's mean active time, and the centre of a Tukey interval (the
  difference of two means) of two fitted conditions is the difference of their idle targets;
* **predicted**: everything else. Only two are independent: Optimized's mean idle time and the
  idle residual (participant x condition), measured by the idle Tukey half-width
  ``q sqrt(MS_error / 18)``. The others follow them, and the table names what each follows:
  Optimized's mean total time and the centres of the OPT-WA intervals are Optimized's idle
  mean plus constants; F of idle time is the idle conditions' mean square (Optimized's idle
  mean and the fitted ones) over the idle residual; the total-time half-width is
  ``q sqrt(MS_conditions / (F n))`` of the fitted F and the centres, one of them Optimized's
  (:func:`.stats.paper_half_width` reproduces the paper's half-widths from its F and centres).

A Tukey interval is reported as its centre and its half-width (the same information as its two
ends): a centre may be implied while its width is predicted, and Tukey's half-width is the same
for every pair of a metric (one predicted number per metric, not two). The intervals are the
paper's within-subject Tukey (:func:`.stats.tukey_rm`, df 34); the independent-groups
``pairwise_tukeyhsd`` (df 51) is the check column ``check_median``.

The paper's Fig. 5 means are read off a figure: each stands for ``[v - h, v + h]`` with
``h = READOFF`` (:data:`.common.READOFF`), and a paper number counts as inside our interval
when that range meets it. F and the Tukey intervals are published exactly.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from functools import cache
from typing import Any

import numpy as np

from .common import (
    CONDITIONS,
    DEFAULT_TARGETS,
    F_TARGET,
    LABELS,
    METRIC_LABELS,
    METRICS,
    OPT,
    PAPER_ACTIVE,
    PAPER_CI,
    PAPER_F,
    PAPER_MEANS,
    READOFF,
    SHORT,
    SINGLE,
    WHOLE,
)
from .stats import anova_rm, tukey_pairs, tukey_rm
from .verdict import INSIDE, meets

FITTED, IMPLIED, PREDICTED = "fitted", "implied", "predicted"
#: The Tukey pairs of the paper (condition, baseline).
PAIRS = ((SINGLE, WHOLE), (OPT, WHOLE))


def _pair(a: str, b: str) -> str:
    return f"{SHORT[a]}-{SHORT[b]}"


def paper_numbers(
    targets: Sequence[tuple[str, str, float]], f_target: tuple[str, float] | None
) -> list[dict[str, Any]]:
    """Every number of the paper's user study with its kind (module docstring): ``key`` (how
    to read it off a study summary), ``quantity``, ``paper``, ``readoff``, ``kind``,
    ``implied`` (the arithmetic value of an implied number) and ``follows`` (the predicted
    number a dependent prediction moves with; empty for an independent one)."""
    fitted_idle = {c: v for m, c, v in targets if m == "idle"}
    free = [c for c in (OPT, SINGLE, WHOLE) if c not in fitted_idle]
    out: list[dict[str, Any]] = []

    def add(key: tuple[Any, ...], quantity: str, paper: float, **kw: Any) -> None:
        out.append(
            {
                "key": key,
                "quantity": quantity,
                "paper": paper,
                "readoff": 0.0,
                "kind": PREDICTED,
                "implied": None,
                "follows": "",
                **kw,
            }
        )

    for m in ("total", "idle"):
        for c in (OPT, SINGLE, WHOLE):
            q = f"mean {METRIC_LABELS[m]}, {LABELS[c]} (s)"
            kw: dict[str, Any] = {"readoff": READOFF}
            if m == "idle" and c in fitted_idle:
                kw["kind"] = FITTED
            elif m == "total" and c in fitted_idle:
                kw.update(kind=IMPLIED, implied=fitted_idle[c] + PAPER_ACTIVE[0])
            elif m == "total":
                kw["follows"] = _idle_name(c)
            add(("mean", m, c), q, PAPER_MEANS[m][c], **kw)
    residual = _half_name("idle")
    f_fitted = {m: f_target is not None and f_target[0] == m for m in ("total", "idle")}
    for m in ("total", "idle"):
        kind = FITTED if f_fitted[m] else PREDICTED
        kw = {} if kind == FITTED else {"follows": _joined(free, residual)}
        q = f"repeated-measures F(2, 34), {METRIC_LABELS[m]}"
        add(("F", m), q, PAPER_F[m], kind=kind, **kw)
    for m in ("total", "idle"):
        for a, b in PAIRS:
            lo, hi = PAPER_CI[m][a]
            q = f"Tukey 95% CI {_pair(a, b)} centre, {METRIC_LABELS[m]} (s)"
            if a in fitted_idle and b in fitted_idle:
                kw = {"kind": IMPLIED, "implied": fitted_idle[a] - fitted_idle[b]}
            else:
                kw = {"follows": _joined([c for c in (a, b) if c in free])}
            add(("centre", m, _pair(a, b)), q, (lo + hi) / 2, **kw)
        lo, hi = PAPER_CI[m][PAIRS[-1][0]]
        # the idle half-width is the idle residual itself; the total one is q sqrt(MS / (F n))
        # of the fitted F and the centres (without a fitted F it is a residual of its own)
        kw = {"follows": _joined(free)} if m == "total" and f_fitted[m] else {}
        add(("half", m, _pair(*PAIRS[-1])), _half_name(m) + " (s)", (hi - lo) / 2, **kw)
    return out


def _half_name(m: str) -> str:
    return f"Tukey 95% CI half-width (every pair), {METRIC_LABELS[m]}"


def _joined(conditions: Sequence[str], *more: str) -> str:
    """What a dependent prediction follows: the free conditions' idle means and ``more``."""
    return "; ".join([*(_idle_name(c) for c in conditions), *(x for x in more if x)])


def _idle_name(c: str) -> str:
    return f"mean {METRIC_LABELS['idle']}, {LABELS[c]}"


def summarize_study(rows: Sequence[Mapping[str, Any]]) -> dict[str, Any]:
    """One study: per-condition means and SDs, the repeated-measures F and the Tukey CIs
    (``mean(a) - mean(b)``, the paper's sign convention)."""
    conds = [c for c in CONDITIONS if any(r["condition"] == c for r in rows)]
    per: dict[str, dict[str, float]] = {}
    for c in conds:
        sub = [r for r in rows if r["condition"] == c]
        per[c] = {"n": len(sub)}
        for m, col in (*METRICS.items(), ("active", "active_time")):
            v = np.array([r[col] for r in sub], float)
            per[c][f"{m}_mean"] = float(v.mean())
            per[c][f"{m}_sd"] = float(v.std(ddof=1)) if len(v) > 1 else 0.0
    anova = {m: anova_rm(rows, col) for m, col in METRICS.items()}
    tukey: dict[str, dict[str, Any]] = {}
    check: dict[str, dict[str, Any]] = {}
    for m, col in METRICS.items():
        within = tukey_rm(rows, col)
        groups = tukey_pairs([r[col] for r in rows], [r["condition"] for r in rows])
        for out, pairs in ((tukey, within), (check, groups)):
            out[m] = {
                f"{SHORT[a]}-{SHORT[b]}": dict(pairs[(a, b)])
                for a, b in ((SINGLE, WHOLE), (OPT, WHOLE), (OPT, SINGLE))
                if (a, b) in pairs
            }
    return {"conditions": per, "anova": anova, "tukey": tukey, "tukey_check": check}


def summaries_of(rows: Sequence[Mapping[str, Any]], n_studies: int) -> list[dict[str, Any]]:
    """:func:`summarize_study` of each study 0 .. n_studies - 1 of ``rows``."""
    by: dict[int, list[Mapping[str, Any]]] = {}
    for r in rows:
        by.setdefault(int(r["study"]), []).append(r)
    return [summarize_study(by[j]) for j in range(n_studies)]


def study_value(
    summary: Mapping[str, Any], key: tuple[Any, ...], tukey: str = "tukey"
) -> float | None:
    """One paper quantity of a study summary (:func:`summarize_study`); ``tukey="tukey_check"``
    reads the independent-groups Tukey instead of the within-subject one."""
    if key[0] == "mean":
        return summary["conditions"][key[2]][f"{key[1]}_mean"]
    if key[0] == "F":
        return summary["anova"][key[1]]["F"]
    t = summary[tukey][key[1]].get(key[2])
    if t is None or t["lo"] is None or t["hi"] is None:
        return None
    return (t["lo"] + t["hi"]) / 2 if key[0] == "centre" else (t["hi"] - t["lo"]) / 2


def _interval(
    summaries: Sequence[Mapping[str, Any]], key: tuple[Any, ...]
) -> tuple[float, float, float, int]:
    """Median, 2.5 % and 97.5 % quantiles of a quantity over the studies, and their count."""
    vals = np.array([v for s in summaries if (v := study_value(s, key)) is not None], float)
    med, lo, hi = (float(np.quantile(vals, x)) for x in (0.5, 0.025, 0.975))
    return med, lo, hi, len(vals)


def prediction_table(
    summaries: Sequence[Mapping[str, Any]],
    targets: Sequence[tuple[str, str, float]],
    f_target: tuple[str, float] | None,
    with_calibration: Sequence[Mapping[str, Any]] = (),
) -> list[dict[str, Any]]:
    """For every paper number: our median and 95 % prediction interval over ``summaries``
    (fresh studies at the fitted calibration: the participants' variation only) and, with
    ``with_calibration`` (fresh studies pooled over the calibration's bootstrap draws), the
    interval that adds the calibration's uncertainty and how much wider it is (%). ``inside``:
    the paper's value, widened by its read-off range, meets the widest interval given."""
    rows: list[dict[str, Any]] = []
    for q in paper_numbers(targets, f_target):
        med, lo, hi, n = _interval(summaries, q["key"])
        row = {k: v for k, v in q.items() if k != "key"}
        row.update(median=round(med, 2), pi_low=round(lo, 2), pi_high=round(hi, 2), studies=n)
        checks = [
            v
            for x in summaries
            if q["key"][0] in ("centre", "half") and "tukey_check" in x
            if (v := study_value(x, q["key"], "tukey_check")) is not None
        ]
        row["check_median"] = round(float(np.median(checks)), 2) if checks else None
        if with_calibration:
            _, clo, chi, cn = _interval(with_calibration, q["key"])
            width = hi - lo
            row.update(
                cal_low=round(clo, 2),
                cal_high=round(chi, 2),
                widened_pct=round(100 * ((chi - clo) / width - 1), 1) if width > 1e-9 else None,
                cal_studies=cn,
            )
            lo, hi = clo, chi
        # 0.01 s (meets' tolerance): the fitted rows' residuals, below the paper's last digit
        row["inside"] = meets(lo, hi, q["paper"], q["readoff"]) == INSIDE.neither
        rows.append(row)
    return rows


@cache
def _default_follows() -> dict[str, str]:
    return {n["quantity"]: n["follows"] for n in paper_numbers(DEFAULT_TARGETS, F_TARGET)}


def follows(row: Mapping[str, Any]) -> str:
    """What a predicted row follows, by the counting rule of this version (module docstring)
    for the calibration's targets, so that a table written by an earlier rule is counted the
    same way; a row of another quantity keeps its own ``follows``."""
    return _default_follows().get(str(row["quantity"]), str(row.get("follows") or ""))


def inside_count(table: Sequence[Mapping[str, Any]], independent: bool = False) -> tuple[int, int]:
    """(predicted rows whose paper value is inside our interval, predicted rows); only the
    independent predictions (nothing they :func:`follows`) with ``independent``."""
    pred = [r for r in table if r["kind"] == PREDICTED and not (independent and follows(r))]
    return sum(str(r["inside"]) in ("True", "true", "1") for r in pred), len(pred)


__all__ = [
    "FITTED",
    "IMPLIED",
    "PREDICTED",
    "follows",
    "inside_count",
    "paper_numbers",
    "prediction_table",
    "study_value",
    "summaries_of",
    "summarize_study",
]
