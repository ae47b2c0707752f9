"""Reproduction of the paper's user study (Section V-A, Fig. 5 top) and Figure 6 (Section V-B).

The two entry points the CLI (``bilevel-kit repro user-study|fig6 [--quick]``) calls::

    run_user_study(out_dir="out/repro/user_study", quick=False, seed=0, jobs=1) -> dict
    run_fig6(out_dir="out/repro/fig6", quick=False, reps=None, jobs=1,
             delivery_time=None, seed=0) -> dict

Both take further keyword-only options (see their docstrings), write their results atomically
under ``out_dir`` and return a JSON-serialisable summary with the output paths under
``"files"``. ``paper_repro/user_study.py`` and ``paper_repro/fig6.py`` are thin command-line
wrappers; ``paper_repro/README.md`` documents the choices and the results.

Choices that apply to both (why, in short):

* **Human idle time.** The paper's idle time is the time the participant was *not actively
  assembling*, so taking the parts off the tray counts as idle. The simulation's
  ``human_idle`` counts the per-kit pickup ``o_H`` as work; the paper-comparable value is
  ``makespan - sum of the sampled task times`` = ``human_idle + n_kits * o_H``
  (:func:`paper_idle`). Every "idle" below is this one.
* **One tray** (``SimParams(buffer=0)``): the study's protocol, "the robot returned to its
  kitting task once the participant retrieved the parts". The Figure 6 simulation samples the
  study's times, so it keeps the protocol by default (``buffer=None`` lets the robot run
  ahead and stack kits at the human, docs/timeline.md).
* **Calibration.** The instance's robot pick times and the human's per-kit pickup time are
  guesses. :func:`calibrate` fits ``robot_scale`` and ``kit_overhead_human`` by least squares to
  two of the paper's numbers (Whole Assembly idle 270 s and Single Task idle 99 s); every
  other number of the study is a prediction. Figure 6 uses the same calibration.
"""

from __future__ import annotations

import hashlib
import io
import json
import math
import time
import warnings
from collections.abc import Callable, Iterator, Mapping, Sequence
from concurrent.futures import ProcessPoolExecutor, as_completed
from contextlib import contextmanager
from dataclasses import asdict, dataclass, field, replace
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from . import atomic
from .errors import UsageError
from .instance import Instance, load
from .layout.cross_entropy import CEParams
from .sim import SimParams, TimingModel, replicate

if TYPE_CHECKING:
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure

#: The paper's table (the repository's copy; ``paper_repro`` lives next to it).
DEFAULT_INSTANCE = Path(__file__).resolve().parent.parent / "instances" / "hrc_table.json"

WHOLE, SINGLE, OPT = "whole-assembly", "single-task", "optimized"
#: The study's conditions and the policies of Figure 6, in the paper's order.
CONDITIONS: tuple[str, ...] = (WHOLE, SINGLE, OPT)
LABELS = {WHOLE: "Whole Assembly", SINGLE: "Single Task", OPT: "Optimized"}
SHORT = {WHOLE: "WA", SINGLE: "ST", OPT: "OPT"}

#: The paper's user-study numbers (docs/paper-data.md; means read off Fig. 5, approximate).
PAPER_N = 18
PAPER_MEANS: dict[str, dict[str, float]] = {
    "total": {OPT: 467.0, SINGLE: 492.0, WHOLE: 637.0},
    "idle": {OPT: 98.0, SINGLE: 99.0, WHOLE: 270.0},
}
PAPER_F: dict[str, float] = {"total": 57.60, "idle": 709.87}
#: Tukey HSD 95% CIs of mean(condition) - mean(Whole Assembly).
PAPER_CI: dict[str, dict[str, tuple[float, float]]] = {
    "total": {SINGLE: (-188.211, -103.851), OPT: (-213.213, -128.853)},
    "idle": {SINGLE: (-184.465, -158.586), OPT: (-186.020, -160.141)},
}
PAPER_ACTIVE = (374.78, 61.14)  # mean, SD of the human's active time per table

#: (metric, condition, paper value) the calibration fits; the rest are predictions.
DEFAULT_TARGETS: tuple[tuple[str, str, float], ...] = (
    ("idle", WHOLE, PAPER_MEANS["idle"][WHOLE]),
    ("idle", SINGLE, PAPER_MEANS["idle"][SINGLE]),
)
#: Free TimingModel fields and their search boxes.
DEFAULT_FREE: dict[str, tuple[float, float]] = {
    "robot_scale": (0.5, 2.0),
    "kit_overhead_human": (0.0, 40.0),
}

#: Figure 6: the MAT and MTTF axes (s), the fed part types, the feeders' repair time.
FIG6_GRID = (30.0, 60.0, 90.0, 120.0)
FIG6_SUPPLIED = ("leg", "foot")
FIG6_REPAIR = 30.0
FIG6_UNITS = 10
FIG6_REPS = 30
#: ``quick=True``: a reduced grid, 2 units, 3 replications, a small CE.
QUICK_MATS = (30.0, 120.0)
QUICK_MTTFS = (60.0,)
QUICK_UNITS = 2
QUICK_REPS = 3
QUICK_CE = CEParams(samples=40, elite=8, max_iter=15, patience=3)

_METRICS = {"total": "total_time", "idle": "human_idle"}
_METRIC_LABELS = {"total": "total task time", "idle": "human idle time"}


def _instance(instance: str | Path | Instance | None) -> tuple[Instance, str]:
    """The instance and a path to it (cells carry the path, workers load it)."""
    if isinstance(instance, Instance):
        if not Path(instance.source).is_file():
            raise UsageError("pass the instance as a path so that cells can reload it")
        return instance, str(instance.source)
    path = Path(instance) if instance is not None else DEFAULT_INSTANCE
    if not path.exists():
        raise UsageError(
            f"instance file {path} not found (the reproductions need the repository's "
            "instances/hrc_table.json, or pass instance=PATH)"
        )
    return load(path), str(path)


def participant_seeds(seed: int, n: int) -> list[int]:
    """Run seeds of ``n`` participants / replications; disjoint blocks per ``seed``."""
    if seed < 0 or n < 1:
        raise UsageError(f"need seed >= 0 and n >= 1, got seed={seed}, n={n}")
    return [seed * 1_000_000 + i for i in range(n)]


def paper_idle(record: Mapping[str, Any]) -> float:
    """The paper's human idle time of a run: makespan minus the sampled task times (the
    per-kit pickup is not assembling, so it counts as idle)."""
    return float(record["makespan"]) - float(sum(record["human_times"].values()))


def _save_figure(fig: Figure, path: Path, dpi: int = 130) -> Path:
    """Write a figure atomically and close it."""
    import matplotlib.pyplot as plt

    with atomic.atomic_path(path) as tmp:
        fig.savefig(tmp, dpi=dpi, bbox_inches="tight")
    plt.close(fig)
    return path


def _write_csv(path: Path, rows: Sequence[Mapping[str, Any]]) -> Path:
    """CSV of plain rows (lists and dicts as JSON), written atomically."""
    import csv

    keys: list[str] = []
    for r in rows:
        keys += [k for k in r if k not in keys]
    buf = io.StringIO()
    w = csv.DictWriter(buf, fieldnames=keys, lineterminator="\n")
    w.writeheader()
    for r in rows:
        w.writerow({k: json.dumps(v) if isinstance(v, dict | list) else v for k, v in r.items()})
    atomic.write_text(path, buf.getvalue())
    return path


def _write_json(path: Path, obj: Any) -> Path:
    atomic.write_text(path, json.dumps(obj, indent=1, default=_json_default) + "\n")
    return path


def _json_default(o: Any) -> Any:
    if isinstance(o, np.generic):
        return o.item()
    if isinstance(o, tuple):
        return list(o)
    raise TypeError(f"not JSON serialisable: {type(o).__name__}")


@contextmanager
def _quiet() -> Iterator[None]:
    """Silence the statistics' warnings on degenerate groups (Whole Assembly's idle time is
    the same for every participant; a policy may equal another): their inf/NaN become None."""
    with np.errstate(divide="ignore", invalid="ignore"), warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        yield


def _finite(x: float) -> float | None:
    """JSON has no NaN/inf: None instead."""
    return float(x) if x is not None and math.isfinite(x) else None


# ---------------------------------------------------------------------------------------------
# User study
# ---------------------------------------------------------------------------------------------


def _study_params(timing: TimingModel, buffer: int | None, ce: CEParams | None) -> SimParams:
    return SimParams(units=1, buffer=buffer, timing=timing, ce=ce)


def study_runs(
    instance: Instance,
    params: SimParams,
    seeds: Sequence[int],
    conditions: Sequence[str] = CONDITIONS,
) -> list[dict[str, Any]]:
    """One row per participant x condition (participant p = run seed ``seeds[p]``, so every
    condition sees the same participant: a within-subjects design)."""
    rows: list[dict[str, Any]] = []
    for cond in conditions:
        for p, rec in enumerate(replicate(instance, cond, params, seeds=seeds), start=1):
            active = float(sum(rec["human_times"].values()))
            rows.append(
                {
                    "participant": p,
                    "seed": rec["seed"],
                    "condition": cond,
                    "speed": rec["speed"][0],
                    "total_time": rec["makespan"],
                    "human_idle": paper_idle(rec),
                    "human_idle_sim": rec["human_idle"],
                    "active_time": active,
                    "n_kits": rec["n_kits"],
                    "robot_idle": rec["robot_idle"],
                    "robot_blocked": rec["robot_blocked"],
                    "kits": rec["kits"],
                }
            )
    return rows


def _means(rows: Sequence[Mapping[str, Any]]) -> dict[str, dict[str, float]]:
    """Mean of each metric per condition."""
    out: dict[str, dict[str, float]] = {}
    for m, col in _METRICS.items():
        out[m] = {}
        for cond in dict.fromkeys(r["condition"] for r in rows):
            out[m][cond] = float(np.mean([r[col] for r in rows if r["condition"] == cond]))
    return out


def calibrate(
    instance: Instance,
    seeds: Sequence[int],
    *,
    base: TimingModel | None = None,
    buffer: int | None = 0,
    targets: Sequence[tuple[str, str, float]] = DEFAULT_TARGETS,
    free: Mapping[str, tuple[float, float]] = DEFAULT_FREE,
    grid: int = 11,
    refine: Sequence[int] = (7,),
    polish: bool = True,
) -> dict[str, Any]:
    """Least-squares fit of the ``free`` TimingModel fields to the paper's ``targets``.

    Why this way: each evaluation simulates the study's participants (common random numbers:
    the same seeds at every point) in the target conditions only, which takes ~10 ms, so a
    coarse grid over the whole box (``grid`` points per axis), grids of ``refine[i]`` points
    over +-1 step around the best point, and a finite-difference least-squares polish
    (:func:`scipy.optimize.least_squares`, the residuals are piecewise linear) is cheap and
    cannot get stuck in a far local minimum.

    Returns the fitted values (``values``), the model's value of each target (``fitted``), the
    residuals, the number of evaluations and the wall time.
    """
    from scipy.optimize import least_squares

    t0 = time.perf_counter()
    base = base or TimingModel()
    names = list(free)
    lo = np.array([free[n][0] for n in names], float)
    hi = np.array([free[n][1] for n in names], float)
    conds = list(dict.fromkeys(c for _, c, _ in targets))
    goal = np.array([v for _, _, v in targets], float)
    cache: dict[tuple[float, ...], np.ndarray] = {}

    def model(x: np.ndarray) -> np.ndarray:
        key = tuple(round(float(v), 12) for v in x)
        hit = cache.get(key)
        if hit is None:
            tm = replace(base, **dict(zip(names, key, strict=True)))
            means = _means(study_runs(instance, _study_params(tm, buffer, None), seeds, conds))
            hit = np.array([means[m][c] for m, c, _ in targets])
            cache[key] = hit
        return hit

    def sse(x: np.ndarray) -> float:
        return float(np.sum((model(x) - goal) ** 2))

    def grid_search(a: np.ndarray, b: np.ndarray, n: int) -> tuple[np.ndarray, np.ndarray]:
        axes = [np.linspace(a[i], b[i], n) for i in range(len(names))]
        pts = np.array(np.meshgrid(*axes, indexing="ij")).reshape(len(names), -1).T
        best = min(pts, key=sse)
        step = (b - a) / max(n - 1, 1)
        return best, step

    best, step = grid_search(lo, hi, grid)
    for n in refine:
        best, step = grid_search(np.maximum(lo, best - step), np.minimum(hi, best + step), n)
    if polish:
        res = least_squares(
            lambda x: model(x) - goal, best, bounds=(lo, hi), x_scale="jac", max_nfev=100
        )
        if sse(res.x) < sse(best):
            best = res.x
    # 6 decimals: stable across platforms (Figure 6's cell keys hash the timing), and far
    # below the noise of any reported number.
    best = np.clip(np.round(best, 6), lo, hi)
    fitted = model(best)
    return {
        "free": {n: list(free[n]) for n in names},
        "values": {n: float(v) for n, v in zip(names, best, strict=True)},
        "targets": [
            {
                "metric": m,
                "condition": c,
                "paper": float(v),
                "fitted": float(f),
                "residual": float(f - v),
            }
            for (m, c, v), f in zip(targets, fitted, strict=True)
        ],
        "rmse": float(math.sqrt(sse(best) / len(goal))),
        "evaluations": len(cache),
        "participants": len(seeds),
        "wall_s": time.perf_counter() - t0,
    }


def _anova_rm(rows: Sequence[Mapping[str, Any]], col: str) -> dict[str, float | None]:
    """Repeated-measures one-way ANOVA (condition within participant), the paper's F(2, 34)."""
    import pandas as pd
    from statsmodels.stats.anova import AnovaRM

    df = pd.DataFrame([{k: r[k] for k in ("participant", "condition", col)} for r in rows])
    with _quiet():
        tab = AnovaRM(df, depvar=col, subject="participant", within=["condition"]).fit()
    row = tab.anova_table.iloc[0]
    return {
        "F": _finite(row["F Value"]),
        "df1": float(row["Num DF"]),
        "df2": float(row["Den DF"]),
        "p": _finite(row["Pr > F"]),
    }


def tukey_pairs(
    values: Sequence[float], groups: Sequence[str], alpha: float = 0.05
) -> dict[tuple[str, str], dict[str, float | None]]:
    """Tukey HSD of every pair: ``{(a, b): diff = mean(a) - mean(b), lo, hi, p}`` for both
    orders of each pair (statsmodels reports ``mean(group2) - mean(group1)``)."""
    from statsmodels.stats.multicomp import pairwise_tukeyhsd

    with _quiet():
        res = pairwise_tukeyhsd(np.asarray(values, float), np.asarray(groups), alpha=alpha)
    names = [str(g) for g in res.groupsunique]
    out: dict[tuple[str, str], dict[str, float | None]] = {}
    k = 0
    for i in range(len(names)):
        for j in range(i + 1, len(names)):
            d = float(res.meandiffs[k])
            lo, hi = (float(v) for v in res.confint[k])
            p = _finite(float(res.pvalues[k]))
            out[(names[j], names[i])] = {"diff": d, "lo": _finite(lo), "hi": _finite(hi), "p": p}
            out[(names[i], names[j])] = {"diff": -d, "lo": _finite(-hi), "hi": _finite(-lo), "p": p}
            k += 1
    return out


def _overlap(a: tuple[float | None, float | None], b: tuple[float, float]) -> bool | None:
    if a[0] is None or a[1] is None:
        return None
    return a[0] <= b[1] and b[0] <= a[1]


def summarize_study(rows: Sequence[Mapping[str, Any]]) -> dict[str, Any]:
    """Per-condition means and SDs, the repeated-measures F and the Tukey CIs, next to the
    paper's numbers."""
    conds = [c for c in CONDITIONS if any(r["condition"] == c for r in rows)]
    per: dict[str, dict[str, float]] = {}
    for c in conds:
        sub = [r for r in rows if r["condition"] == c]
        per[c] = {"n": len(sub)}
        for m, col in (*_METRICS.items(), ("active", "active_time")):
            v = np.array([r[col] for r in sub], float)
            per[c][f"{m}_mean"] = float(v.mean())
            per[c][f"{m}_sd"] = float(v.std(ddof=1)) if len(v) > 1 else 0.0
        per[c]["n_kits_mean"] = float(np.mean([r["n_kits"] for r in sub]))
    anova = {m: _anova_rm(rows, col) for m, col in _METRICS.items()}
    tukey: dict[str, dict[str, Any]] = {}
    for m, col in _METRICS.items():
        pairs = tukey_pairs([r[col] for r in rows], [r["condition"] for r in rows])
        tukey[m] = {}
        for a, b in ((SINGLE, WHOLE), (OPT, WHOLE), (OPT, SINGLE)):
            if (a, b) not in pairs:
                continue
            t = dict(pairs[(a, b)])
            paper = PAPER_CI[m].get(a) if b == WHOLE else None
            t["paper"] = list(paper) if paper else None
            t["overlap"] = _overlap((t["lo"], t["hi"]), paper) if paper else None
            tukey[m][f"{SHORT[a]}-{SHORT[b]}"] = t
    return {"conditions": per, "anova": anova, "tukey": tukey}


def _quantity(summary: Mapping[str, Any], key: tuple[str, ...]) -> Any:
    """One reported quantity of a study summary: a mean, an F or a CI ``[lo, hi]``."""
    kind, m, c = key
    if kind == "mean":
        return summary["conditions"][c][f"{m}_mean"]
    if kind == "F":
        return summary["anova"][m]["F"]
    t = summary["tukey"][m].get(c)
    return None if t is None or t["lo"] is None else [t["lo"], t["hi"]]


def _table_keys(summary: Mapping[str, Any]) -> list[tuple[str, str, str]]:
    keys = [
        ("mean", m, c)
        for m in ("total", "idle")
        for c in (OPT, SINGLE, WHOLE)
        if c in summary["conditions"]
    ]
    keys += [("F", m, "") for m in ("total", "idle")]
    keys += [
        ("ci", m, k)
        for m in ("total", "idle")
        for k in ("ST-WA", "OPT-WA")
        if k in summary["tukey"][m]
    ]
    return keys


def side_by_side(
    summary: Mapping[str, Any],
    calibration: Mapping[str, Any],
    replicates: Sequence[Mapping[str, Any]] = (),
) -> list[dict[str, Any]]:
    """Rows of the paper-vs-ours table; ``role`` says what was fitted and what is predicted.

    ``replicates``: summaries of repeated simulated studies (new participants, same
    calibration); each row then gets the median and 5-95% range of the quantity over them
    (for a CI: the fraction of studies whose CI overlaps the paper's), i.e. how far the
    paper's number is from what an 18-participant study of this model would give.
    """
    fitted = {(t["metric"], t["condition"]) for t in calibration["targets"]}
    rows: list[dict[str, Any]] = []
    for key in _table_keys(summary):
        kind, m, c = key
        ours = _quantity(summary, key)
        row: dict[str, Any] = {
            "quantity": "",
            "paper": None,
            "ours": None,
            "ours_sd": None,
            "role": "predicted",
            "ci_overlap": None,
        }
        if kind == "mean":
            row.update(
                quantity=f"mean {_METRIC_LABELS[m]}, {LABELS[c]} (s)",
                paper=PAPER_MEANS[m][c],
                ours=round(ours, 1),
                ours_sd=round(summary["conditions"][c][f"{m}_sd"], 1),
                role="fitted" if (m, c) in fitted else "predicted",
            )
        elif kind == "F":
            a = summary["anova"][m]
            row.update(
                quantity=f"repeated-measures F({a['df1']:.0f}, {a['df2']:.0f}), "
                f"{_METRIC_LABELS[m]}",
                paper=PAPER_F[m],
                ours=None if ours is None else round(ours, 2),
            )
        else:
            t = summary["tukey"][m][c]
            row.update(
                quantity=f"Tukey 95% CI {c}, {_METRIC_LABELS[m]} (s)",
                paper=[round(v, 1) for v in t["paper"]],
                ours=None if ours is None else [round(v, 1) for v in ours],
                ci_overlap=t["overlap"],
            )
        if replicates:
            vals = [_quantity(r, key) for r in replicates]
            vals = [v for v in vals if v is not None]
            row["studies"] = len(replicates)
            if kind == "ci":
                paper = PAPER_CI[m][OPT if c.startswith("OPT") else SINGLE]
                lo = np.array([v[0] for v in vals])
                hi = np.array([v[1] for v in vals])
                row["studies_median"] = [
                    round(float(np.median(lo)), 1),
                    round(float(np.median(hi)), 1),
                ]
                row["studies_overlap_frac"] = (
                    float(np.mean([_overlap((a, b), paper) for a, b in zip(lo, hi, strict=True)]))
                    if vals
                    else None
                )
            elif vals:
                q = np.percentile(vals, [5, 50, 95])
                row["studies_median"] = round(float(q[1]), 2)
                row["studies_p5"] = round(float(q[0]), 2)
                row["studies_p95"] = round(float(q[2]), 2)
        rows.append(row)
    return rows


def _fmt(v: Any) -> str:
    if v is None:
        return "-"
    if isinstance(v, bool):
        return "yes" if v else "no"
    if isinstance(v, list | tuple):
        return "[" + ", ".join(f"{x:.1f}" for x in v) + "]"
    if isinstance(v, float):
        return f"{v:.2f}" if abs(v) < 100 and v != round(v) else f"{v:.1f}"
    return str(v)


def format_study_markdown(result: Mapping[str, Any]) -> str:
    """The side-by-side table and the calibration as Markdown."""
    cal = result["calibration"]
    vals = ", ".join(f"`{k}` = {v:.4g}" for k, v in cal["values"].items())
    fit = "; ".join(
        f"{LABELS[t['condition']]} {t['metric']} {t['paper']:g} s -> {t['fitted']:.2f} s"
        for t in cal["targets"]
    )
    k = result.get("n_studies", 1)
    rep = k > 1
    lines = [
        f"Simulated user study: {result['n_participants']} participants x 3 conditions, "
        f"1 table, d = {result['delivery_time']:g} s, buffer = {result['buffer']}, "
        f"seed {result['seed']}.",
        "",
        f"Calibrated: {vals} (fitted to: {fit}; {cal['evaluations']} evaluations).",
        "",
        "| quantity | paper | ours (SD) | role | our CI overlaps the paper's |"
        + (f" {k} studies: median [5%, 95%] or CI overlap rate |" if rep else ""),
        "|---|---|---|---|---|" + ("---|" if rep else ""),
    ]
    for r in result["table"]:
        ours = _fmt(r["ours"])
        if r["ours_sd"] is not None:
            ours += f" ({r['ours_sd']:.1f})"
        line = (
            f"| {r['quantity']} | {_fmt(r['paper'])} | {ours} | {r['role']} | "
            f"{_fmt(r['ci_overlap'])} |"
        )
        if rep:
            if "studies_overlap_frac" in r:
                extra = (
                    f"{_fmt(r['studies_median'])}, overlap in "
                    f"{100 * r['studies_overlap_frac']:.0f}%"
                )
            elif "studies_median" in r:
                extra = f"{r['studies_median']:.1f} [{r['studies_p5']:.1f}, {r['studies_p95']:.1f}]"
            else:
                extra = "-"
            line += f" {extra} |"
        lines.append(line)
    per = result["summary"]["conditions"]
    act = ", ".join(
        f"{SHORT[c]} {per[c]['active_mean']:.1f} ({per[c]['active_sd']:.1f})" for c in per
    )
    lines += [
        "",
        f"Human active time per table (input, paper {PAPER_ACTIVE[0]} s, SD {PAPER_ACTIVE[1]}):"
        f" {act}.",
    ]
    return "\n".join(lines) + "\n"


def plot_user_study(summary: Mapping[str, Any], ax: Axes | None = None, paper: bool = True) -> Axes:
    """The analogue of Fig. 5 (top): mean total task time and human idle time per condition,
    error bars = 1 SD over participants; the paper's bars as black diamonds."""
    import matplotlib.pyplot as plt

    if ax is None:
        _, ax = plt.subplots(figsize=(6.0, 3.8))
    per = summary["conditions"]
    conds = [c for c in (OPT, SINGLE, WHOLE) if c in per]
    colors = {OPT: "#2e7d32", SINGLE: "#1565c0", WHOLE: "#c62828"}
    width = 0.8 / len(conds)
    for g, m in enumerate(("total", "idle")):
        for i, c in enumerate(conds):
            x = g + (i - (len(conds) - 1) / 2) * width
            ax.bar(
                x,
                per[c][f"{m}_mean"],
                width * 0.92,
                yerr=per[c][f"{m}_sd"],
                capsize=3,
                color=colors.get(c, "0.5"),
                label=LABELS.get(c, c) if g == 0 else None,
                gid=f"bar:{m}:{c}",
            )
            if paper and c in PAPER_MEANS[m]:
                ax.plot(
                    x,
                    PAPER_MEANS[m][c],
                    "D",
                    color="black",
                    ms=5,
                    zorder=5,
                    label="paper (Fig. 5)" if g == 0 and i == 0 else None,
                    gid=f"paper:{m}:{c}",
                )
    ax.set_xticks([0, 1], ["Total task time", "Human idle time"])
    ax.set_ylabel("time (s)")
    ax.set_title("Simulated user study (error bars: 1 SD)")
    ax.grid(axis="y", alpha=0.3)
    ax.legend(fontsize=8)
    return ax


def run_user_study(
    out_dir: str | Path = "out/repro/user_study",
    quick: bool = False,
    seed: int = 0,
    jobs: int = 1,
    *,
    instance: str | Path | None = None,
    n_participants: int = PAPER_N,
    n_studies: int | None = None,
    buffer: int | None = 0,
    targets: Sequence[tuple[str, str, float]] = DEFAULT_TARGETS,
    free: Mapping[str, tuple[float, float]] = DEFAULT_FREE,
    timing: TimingModel | None = None,
    ce: CEParams | None = None,
) -> dict[str, Any]:
    """Simulate the user study (18 participants x WA/ST/OPT, one table, co-located).

    Steps: calibrate ``free`` against ``targets`` on the study's own participants (skipped
    when ``timing`` is given), run the three conditions with the fitted timing, and compare
    with the paper: means, repeated-measures ANOVA F, Tukey HSD CIs and their overlap.
    ``n_studies`` (default 20, quick 2) repeats the study with new participants (same
    calibration) to show the sampling spread of every predicted number; the first study is
    the reported one.

    ``quick``: a coarse 5 x 5 calibration grid (plus the polish), 2 studies and a small CE.
    ``jobs`` is accepted for symmetry with :func:`run_fig6`; the study runs in one process
    (it takes seconds).

    Writes to ``out_dir``: ``user_study_runs.csv`` (study x participant x condition),
    ``user_study_summary.csv`` (the side-by-side table), ``user_study.md``,
    ``user_study.json`` (everything returned) and ``fig5_top.png``. Returns the summary dict.
    """
    t0 = time.perf_counter()
    inst, _ = _instance(instance)
    out = Path(out_dir)
    if n_studies is None:
        n_studies = 2 if quick else 20
    if n_studies < 1 or n_participants < 2:
        raise UsageError("need n_studies >= 1 and n_participants >= 2")
    all_seeds = participant_seeds(seed, n_participants * n_studies)
    seeds = all_seeds[:n_participants]
    if timing is None:
        grid, refine = (5, ()) if quick else (11, (7,))
        cal = calibrate(
            inst, seeds, buffer=buffer, targets=targets, free=free, grid=grid, refine=refine
        )
        timing = replace(TimingModel(), **cal["values"])
    else:
        conds = list(dict.fromkeys(c for _, c, _ in targets))
        means = _means(study_runs(inst, _study_params(timing, buffer, None), seeds, conds))
        cal = {
            "free": {},
            "values": {n: getattr(timing, n) for n in free},
            "targets": [
                {
                    "metric": m,
                    "condition": c,
                    "paper": v,
                    "fitted": means[m][c],
                    "residual": means[m][c] - v,
                }
                for m, c, v in targets
            ],
            "evaluations": 0,
            "given": True,
        }
    if ce is None and quick:
        ce = QUICK_CE
    params = _study_params(timing, buffer, ce)
    rows = study_runs(inst, params, all_seeds)  # one policy object per condition: shared cache
    for r in rows:
        r["study"], r["participant"] = divmod(r["participant"] - 1, n_participants)
        r["participant"] += 1
    studies = [[r for r in rows if r["study"] == j] for j in range(n_studies)]
    summary = summarize_study(studies[0])
    replicates = [summarize_study(st) for st in studies] if n_studies > 1 else []
    d = params.delivery_time if params.delivery_time is not None else inst.delivery_time
    result: dict[str, Any] = {
        "instance": inst.name,
        "quick": quick,
        "seed": seed,
        "n_participants": n_participants,
        "n_studies": n_studies,
        "delivery_time": d,
        "buffer": buffer,
        "timing": asdict(timing),
        "ce": asdict(ce) if ce is not None else None,
        "calibration": cal,
        "summary": summary,
        "table": side_by_side(summary, cal, replicates),
    }
    files = {
        "runs_csv": _write_csv(out / "user_study_runs.csv", rows),
        "summary_csv": _write_csv(out / "user_study_summary.csv", result["table"]),
    }
    ax = plot_user_study(summary)
    files["figure"] = _save_figure(ax.figure, out / "fig5_top.png")
    result["wall_s"] = time.perf_counter() - t0
    atomic.write_text(out / "user_study.md", format_study_markdown(result))
    files["markdown"] = out / "user_study.md"
    files["json"] = out / "user_study.json"
    result["files"] = {k: str(v) for k, v in files.items()}
    _write_json(out / "user_study.json", result)
    return result


# ---------------------------------------------------------------------------------------------
# Figure 6
# ---------------------------------------------------------------------------------------------


def _file_digest(path: str) -> str:
    return hashlib.sha1(Path(path).read_bytes()).hexdigest()[:12]


@dataclass(frozen=True)
class Fig6Cell:
    """One cell of the Figure 6 grid: every policy run on the same seeds (common random
    numbers). ``mat = None``: the no-delay reference (every part always available)."""

    instance: str
    mat: float | None
    mttf: float | None
    seeds: tuple[int, ...]
    policies: tuple[str, ...] = CONDITIONS
    units: int = FIG6_UNITS
    delivery_time: float | None = None
    supplied: tuple[str, ...] = FIG6_SUPPLIED
    repair_time: float = FIG6_REPAIR
    buffer: int | None = 0
    timing: dict[str, Any] = field(default_factory=dict)
    ce: dict[str, Any] | None = None
    policy_seed: int = 0
    policy_options: dict[str, Any] = field(default_factory=dict)

    @property
    def label(self) -> str:
        return "reference" if self.mat is None else f"mat{self.mat:g}_mttf{self.mttf:g}"

    def key(self) -> str:
        """A stable file name: the grid point plus a digest of the whole configuration and
        of the instance file's content (not its path, so a moved checkout still resumes)."""
        cfg = {k: v for k, v in asdict(self).items() if k != "instance"}
        cfg["instance_sha1"] = _file_digest(self.instance)
        blob = json.dumps(cfg, sort_keys=True, default=str)
        return f"{self.label}__{hashlib.sha1(blob.encode()).hexdigest()[:10]}"

    def sim_params(self) -> SimParams:
        mat = {t: self.mat for t in self.supplied} if self.mat is not None else {}
        return SimParams(
            units=self.units,
            delivery_time=self.delivery_time,
            mat=mat,
            mttf=self.mttf if self.mat is not None else None,
            repair_time=self.repair_time,
            use_instance_supply=False,
            timing=TimingModel(**self.timing),
            ce=CEParams(**self.ce) if self.ce is not None else None,
            policy_seed=self.policy_seed,
            buffer=self.buffer,
            policy_options=dict(self.policy_options),
        )


def fig6_cell(cell: Fig6Cell) -> dict[str, Any]:
    """Simulate one cell: a pure function of the cell returning a plain record (per policy
    and replication: total time, paper idle, kits, waits). Wall times are kept apart under
    ``wall_s`` (the only part that differs between two computations)."""
    inst = load(cell.instance)
    params = cell.sim_params()
    runs: dict[str, dict[str, list[Any]]] = {}
    wall: dict[str, float] = {}
    for pol in cell.policies:
        t0 = time.perf_counter()
        recs = replicate(inst, pol, params, seeds=cell.seeds)
        wall[pol] = time.perf_counter() - t0
        runs[pol] = {
            "seed": [r["seed"] for r in recs],
            "total_time": [r["makespan"] for r in recs],
            "human_idle": [paper_idle(r) for r in recs],
            "human_idle_sim": [r["human_idle"] for r in recs],
            "n_kits": [r["n_kits"] for r in recs],
            "robot_wait": [r["robot_wait"] for r in recs],
            "robot_blocked": [r["robot_blocked"] for r in recs],
        }
    return {"key": cell.key(), "cell": asdict(cell), "runs": runs, "wall_s": wall}


def run_cells_parallel(
    cells: Sequence[Any],
    fn: Callable[[Any], dict[str, Any]],
    cell_dir: str | Path,
    *,
    jobs: int = 1,
    progress: bool | None = None,
    desc: str = "cells",
) -> tuple[list[dict[str, Any]], int]:
    """Run ``fn`` on every cell whose ``cell_dir/<key>.json`` does not exist yet, saving each
    record atomically as soon as it finishes (so an interrupted run loses only the cells in
    flight); ``jobs > 1`` uses a process pool. Returns the records of all cells, in order,
    read back from their files, and the number computed now."""
    from tqdm import tqdm

    folder = Path(cell_dir)
    folder.mkdir(parents=True, exist_ok=True)
    paths = [folder / f"{c.key()}.json" for c in cells]
    todo = [i for i, p in enumerate(paths) if not p.exists()]
    bar = tqdm(total=len(todo), desc=desc, disable=None if progress is None else not progress)

    def save(i: int, rec: dict[str, Any]) -> None:
        atomic.write_text(paths[i], json.dumps(rec, indent=1, default=_json_default) + "\n")
        bar.update()

    try:
        if jobs <= 1 or len(todo) <= 1:
            for i in todo:
                save(i, fn(cells[i]))
        else:
            with ProcessPoolExecutor(max_workers=min(jobs, len(todo))) as ex:
                futures = {ex.submit(fn, cells[i]): i for i in todo}
                for fut in as_completed(futures):
                    save(futures[fut], fut.result())
    finally:
        bar.close()
    return [json.loads(p.read_text()) for p in paths], len(todo)


def stars(p: float | None) -> str:
    """The paper's marks: * p < .05, ** p < .001."""
    if p is None:
        return ""
    return "**" if p < 0.001 else "*" if p < 0.05 else ""


def comparisons(policies: Sequence[str]) -> list[tuple[str, str]]:
    """(subject, baseline) pairs: the paper's two, plus "X over optimized" for extra policies."""
    pairs = [(OPT, b) for b in (SINGLE, WHOLE) if OPT in policies and b in policies]
    pairs += [(x, OPT) for x in policies if x not in CONDITIONS and OPT in policies]
    return pairs


def summarize_cell(record: Mapping[str, Any]) -> dict[str, Any]:
    """One row of the Figure 6 table: per-policy means and SDs, and for each comparison the
    percent improvement ``100 * (mean(baseline) - mean(subject)) / mean(baseline)`` with the
    paper's tests: one-way ANOVA over the policies (the paper's three for the paper's
    comparisons, all policies for the extra ones) and Tukey HSD p-values; stars only when the
    ANOVA is significant too (a protected post-hoc test).

    Also ``p_paired_*``: a paired t-test of the two policies over the replications. Not the
    paper's test (it ignores that every policy saw the same seeds), but the sharper one for
    common random numbers; it is reported next to, never instead of, the paper's marks.
    """
    from scipy.stats import f_oneway, ttest_rel

    cell = record["cell"]
    runs = record["runs"]
    pols = list(runs)
    row: dict[str, Any] = {
        "label": "reference"
        if cell["mat"] is None
        else f"MAT {cell['mat']:g}, MTTF {cell['mttf']:g}",
        "mat": cell["mat"],
        "mttf": cell["mttf"],
        "units": cell["units"],
        "reps": len(cell["seeds"]),
    }
    for m, col in _METRICS.items():
        for p in pols:
            v = np.asarray(runs[p][col], float)
            row[f"{m}_mean:{p}"] = float(v.mean())
            row[f"{m}_sd:{p}"] = float(v.std(ddof=1)) if len(v) > 1 else 0.0
    for p in pols:
        row[f"kits_mean:{p}"] = float(np.mean(runs[p]["n_kits"]))
    families = {"paper": [p for p in CONDITIONS if p in pols], "all": pols}
    tests: dict[tuple[str, str], Any] = {}
    for fam, members in families.items():
        for m, col in _METRICS.items():
            groups = [np.asarray(runs[p][col], float) for p in members]
            with _quiet():
                a = f_oneway(*groups) if len(groups) > 1 else None
            pv = _finite(float(a.pvalue)) if a is not None else None
            row[f"anova_F_{m}:{fam}"] = _finite(float(a.statistic)) if a is not None else None
            row[f"anova_p_{m}:{fam}"] = pv
            vals = [x for g in groups for x in g]
            labels = [p for p, g in zip(members, groups, strict=True) for _ in g]
            tk = tukey_pairs(vals, labels) if len(groups) > 1 and len(vals) > len(groups) else {}
            tests[(fam, m)] = (pv, tk)
    for subj, base in comparisons(pols):
        fam = "paper" if subj in CONDITIONS else "all"
        for m in _METRICS:
            mb, ms = row[f"{m}_mean:{base}"], row[f"{m}_mean:{subj}"]
            pct = 100.0 * (mb - ms) / mb if mb > 0 else None
            pv, tk = tests[(fam, m)]
            p = tk.get((subj, base), {}).get("p")
            name = f"{subj}_over_{base}"
            row[f"pct_{m}:{name}"] = pct
            row[f"p_tukey_{m}:{name}"] = p
            row[f"stars_{m}:{name}"] = stars(p) if pv is not None and pv < 0.05 else ""
            a, b = np.asarray(runs[subj][_METRICS[m]]), np.asarray(runs[base][_METRICS[m]])
            with _quiet():
                paired = ttest_rel(a, b).pvalue if len(a) > 1 and np.any(a != b) else None
            row[f"p_paired_{m}:{name}"] = None if paired is None else _finite(float(paired))
    return row


def plot_fig6_panel(
    rows: Sequence[Mapping[str, Any]],
    metric: str,
    subject: str,
    baseline: str,
    ax: Axes | None = None,
) -> Axes:
    """One heatmap of Figure 6: percent improvement of ``subject`` over ``baseline`` in
    ``metric`` ("total" or "idle"), MAT on the y axis, MTTF on the x axis, annotated with the
    value and the significance stars; the no-delay reference cell in the title."""
    import matplotlib.pyplot as plt
    from matplotlib.colors import TwoSlopeNorm

    if ax is None:
        _, ax = plt.subplots(figsize=(4.6, 3.8))
    name = f"{subject}_over_{baseline}"
    grid = [r for r in rows if r["mat"] is not None]
    mats = sorted({r["mat"] for r in grid})
    mttfs = sorted({r["mttf"] for r in grid})
    z = np.full((len(mats), len(mttfs)), np.nan)
    marks = [["" for _ in mttfs] for _ in mats]
    for r in grid:
        i, j = mats.index(r["mat"]), mttfs.index(r["mttf"])
        v = r.get(f"pct_{metric}:{name}")
        z[i, j] = np.nan if v is None else v
        marks[i][j] = r.get(f"stars_{metric}:{name}", "")
    finite = z[np.isfinite(z)]
    span = max(1.0, float(np.abs(finite).max())) if finite.size else 1.0
    im = ax.imshow(
        z, origin="lower", cmap="RdYlGn", norm=TwoSlopeNorm(0.0, -span, span), aspect="auto"
    )
    for i in range(len(mats)):
        for j in range(len(mttfs)):
            if np.isfinite(z[i, j]):
                ax.text(
                    j,
                    i,
                    f"{z[i, j]:.1f}%\n{marks[i][j]}",
                    ha="center",
                    va="center",
                    fontsize=8,
                    color="white" if abs(z[i, j]) > 0.7 * span else "black",
                    gid=f"cell:{mats[i]:g}:{mttfs[j]:g}",
                )
    ax.set_xticks(range(len(mttfs)), [f"{v:g}" for v in mttfs])
    ax.set_yticks(range(len(mats)), [f"{v:g}" for v in mats])
    ax.set_xlabel("MTTF (s)")
    ax.set_ylabel("MAT (s)")
    title = (
        f"{_METRIC_LABELS[metric]}: {LABELS.get(subject, subject)} over "
        f"{LABELS.get(baseline, baseline)}"
    )
    ref = next((r for r in rows if r["mat"] is None), None)
    if ref is not None and ref.get(f"pct_{metric}:{name}") is not None:
        title += (
            f"\nno delay: {ref[f'pct_{metric}:{name}']:.1f}% "
            f"{ref.get(f'stars_{metric}:{name}', '')}"
        )
    ax.set_title(title, fontsize=9)
    ax.figure.colorbar(im, ax=ax, label="improvement (%)")
    return ax


def plot_fig6(
    rows: Sequence[Mapping[str, Any]],
    subject: str = OPT,
    baselines: Sequence[str] = (SINGLE, WHOLE),
) -> Figure:
    """Figure 6: a grid of heatmaps, one row per metric, one column per baseline."""
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(2, len(baselines), figsize=(5.0 * len(baselines), 8.0), squeeze=False)
    for i, m in enumerate(("total", "idle")):
        for j, b in enumerate(baselines):
            plot_fig6_panel(rows, m, subject, b, ax=axes[i][j])
    fig.tight_layout()
    return fig


def format_fig6_markdown(rows: Sequence[Mapping[str, Any]]) -> str:
    """Each comparison as a MAT x MTTF Markdown table of ``% stars``."""
    grid = [r for r in rows if r["mat"] is not None]
    mats = sorted({r["mat"] for r in grid})
    mttfs = sorted({r["mttf"] for r in grid})
    ref = next((r for r in rows if r["mat"] is None), None)
    pols = [k.split(":", 1)[1] for k in rows[0] if k.startswith("total_mean:")]
    out: list[str] = []
    for subj, base in comparisons(pols):
        name = f"{subj}_over_{base}"
        for m in _METRICS:
            out.append(
                f"**{_METRIC_LABELS[m]}, {LABELS.get(subj, subj)} over "
                f"{LABELS.get(base, base)} (%)**"
            )
            out.append("")
            out.append("| MAT \\ MTTF | " + " | ".join(f"{v:g}" for v in mttfs) + " |")
            out.append("|---|" + "---|" * len(mttfs))
            for a in mats:
                cells = []
                for b in mttfs:
                    r = next(x for x in grid if x["mat"] == a and x["mttf"] == b)
                    v = r[f"pct_{m}:{name}"]
                    cells.append("-" if v is None else f"{v:.1f} {r[f'stars_{m}:{name}']}")
                out.append(f"| {a:g} | " + " | ".join(c.strip() for c in cells) + " |")
            if ref is not None and ref[f"pct_{m}:{name}"] is not None:
                out.append("")
                out.append(
                    f"No delay (reference): {ref[f'pct_{m}:{name}']:.1f} "
                    f"{ref[f'stars_{m}:{name}']}".rstrip()
                )
            out.append("")
    return "\n".join(out)


def run_fig6(
    out_dir: str | Path = "out/repro/fig6",
    quick: bool = False,
    reps: int | None = None,
    jobs: int = 1,
    delivery_time: float | None = None,
    seed: int = 0,
    *,
    policies: Sequence[str] = CONDITIONS,
    instance: str | Path | None = None,
    mats: Sequence[float] | None = None,
    mttfs: Sequence[float] | None = None,
    units: int | None = None,
    buffer: int | None = 0,
    timing: TimingModel | None = None,
    calibration_seed: int = 0,
    ce: CEParams | None = None,
    policy_options: Mapping[str, Any] | None = None,
    progress: bool | None = None,
) -> dict[str, Any]:
    """Figure 6: MAT x MTTF grid for the leg and foot feeders plus a no-delay reference cell.

    Defaults: MAT, MTTF in {30, 60, 90, 120} s, 10 tables per run, ``reps`` = 30 replications
    (``None``: 30, or 3 when ``quick``), the instance's delivery time (``delivery_time``
    overrides it), one tray (``buffer=0``), and the timing calibrated on the user study
    (:func:`calibrate` with participants of ``calibration_seed``; pass ``timing`` to skip).
    ``quick``: MAT {30, 120} x MTTF {60}, 2 tables, 3 replications, a small CE.
    ``policies``: the paper's three by default; an extra registered policy (e.g.
    ``"cpsat-rolling"``) adds "X over optimized" comparisons and a figure.
    ``seed`` picks the replication seeds (the same in every cell: common random numbers).

    Cells are saved one JSON each under ``out_dir/cells/`` as they finish; a rerun computes
    only the missing ones (``jobs`` > 1: a process pool). Writes ``fig6_cells.csv``,
    ``fig6.md``, ``fig6.png`` (four heatmaps), ``fig6_<X>_over_optimized.png`` per extra
    policy and ``fig6.json``. Returns the summary dict (rows, calibration, files, counts).
    """
    t0 = time.perf_counter()
    inst, path = _instance(instance)
    out = Path(out_dir)
    if reps is None:
        reps = QUICK_REPS if quick else FIG6_REPS
    if quick:
        mats = QUICK_MATS if mats is None else mats
        mttfs = QUICK_MTTFS if mttfs is None else mttfs
        units = QUICK_UNITS if units is None else units
        ce = QUICK_CE if ce is None else ce
    mats = FIG6_GRID if mats is None else mats
    mttfs = FIG6_GRID if mttfs is None else mttfs
    units = FIG6_UNITS if units is None else units
    policies = tuple(dict.fromkeys(policies))
    from .sim import POLICIES

    unknown = [p for p in policies if p not in POLICIES]
    if unknown:
        raise UsageError(f"unknown policy(ies) {unknown}; policies are {', '.join(POLICIES)}")
    missing = [t for t in FIG6_SUPPLIED if t not in inst.part_types]
    if missing:
        raise UsageError(f"the instance has no part type(s) {missing} to feed")
    if jobs < 1:
        raise UsageError(f"jobs must be >= 1, got {jobs}")
    cal: dict[str, Any] | None = None
    if timing is None:
        grid, refine = (5, ()) if quick else (11, (7,))
        cal = calibrate(
            inst,
            participant_seeds(calibration_seed, PAPER_N),
            buffer=buffer,
            grid=grid,
            refine=refine,
        )
        timing = replace(TimingModel(), **cal["values"])
    seeds = tuple(participant_seeds(seed, reps))
    common = {
        "instance": path,
        "seeds": seeds,
        "policies": policies,
        "units": int(units),
        "delivery_time": delivery_time,
        "buffer": buffer,
        "timing": asdict(timing),
        "ce": asdict(ce) if ce is not None else None,
        "policy_options": dict(policy_options or {}),
    }
    cells = [Fig6Cell(mat=None, mttf=None, **common)]
    cells += [Fig6Cell(mat=float(a), mttf=float(b), **common) for a in mats for b in mttfs]
    records, computed = run_cells_parallel(
        cells, fig6_cell, out / "cells", jobs=jobs, progress=progress, desc="fig6 cells"
    )
    rows = [summarize_cell(r) for r in records]
    files = {
        "csv": _write_csv(out / "fig6_cells.csv", rows),
        "markdown": out / "fig6.md",
        "figure": _save_figure(plot_fig6(rows), out / "fig6.png"),
    }
    atomic.write_text(out / "fig6.md", format_fig6_markdown(rows))
    for x in policies:
        if x not in CONDITIONS and OPT in policies:
            fig = plot_fig6(rows, subject=x, baselines=(OPT,))
            files[f"figure_{x}"] = _save_figure(fig, out / f"fig6_{x}_over_optimized.png")
    cell_wall = {p: sum(r["wall_s"].get(p, 0.0) for r in records) for p in policies}
    result = {
        "instance": inst.name,
        "quick": quick,
        "seed": seed,
        "reps": reps,
        "units": units,
        "mats": list(mats),
        "mttfs": list(mttfs),
        "delivery_time": delivery_time if delivery_time is not None else inst.delivery_time,
        "buffer": buffer,
        "policies": list(policies),
        "timing": asdict(timing),
        "calibration": cal,
        "cells": len(cells),
        "computed": computed,
        "reused": len(cells) - computed,
        "simulation_wall_s": cell_wall,
        "rows": rows,
        "wall_s": time.perf_counter() - t0,
        "files": {k: str(v) for k, v in {**files, "json": out / "fig6.json"}.items()},
    }
    _write_json(out / "fig6.json", result)
    return result
