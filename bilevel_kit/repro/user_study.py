"""The simulated user study (paper Section V-A, Fig. 5 top) side by side with the paper.

18 simulated participants x {Whole Assembly, Single Task, Optimized}, one table, one tray
(the instance's ``trays: 1``: "the robot returned to its kitting task once the participant
retrieved the parts"); the timing calibrated on two of the paper's numbers
(:mod:`.calibration`); means, the repeated-measures ANOVA F and Tukey HSD CIs compared with the
paper's (docs/reproduction.md, docs/paper-data.md).
"""

from __future__ import annotations

import time
from collections.abc import Mapping, Sequence
from dataclasses import asdict, dataclass, replace
from pathlib import Path
from typing import Any

import numpy as np

from .. import atomic
from ..errors import UsageError
from ..experiments.cells import is_failed, run_cells, write_json
from ..experiments.tables import markdown_lines, write_csv
from ..instance import Instance
from ..layout.cross_entropy import CEParams
from ..plots import save_figure
from ..sim import SimParams, SimulationError, TimingModel
from .calibration import calibrate, condition_means, study_params, study_runs
from .common import (
    CONDITIONS,
    DEFAULT_FREE,
    DEFAULT_TARGETS,
    LABELS,
    METRIC_LABELS,
    METRICS,
    OPT,
    PAPER_ACTIVE,
    PAPER_CI,
    PAPER_F,
    PAPER_MEANS,
    PAPER_N,
    QUICK_CE,
    SHORT,
    SINGLE,
    WHOLE,
    load_instance,
    participant_seeds,
)
from .stats import anova_rm, overlap, tukey_pairs


def summarize_study(rows: Sequence[Mapping[str, Any]]) -> dict[str, Any]:
    """Per-condition means and SDs, the repeated-measures F and the Tukey CIs, next to the
    paper's numbers."""
    conds = [c for c in CONDITIONS if any(r["condition"] == c for r in rows)]
    per: dict[str, dict[str, float]] = {}
    for c in conds:
        sub = [r for r in rows if r["condition"] == c]
        per[c] = {"n": len(sub)}
        for m, col in (*METRICS.items(), ("active", "active_time")):
            v = np.array([r[col] for r in sub], float)
            per[c][f"{m}_mean"] = float(v.mean())
            per[c][f"{m}_sd"] = float(v.std(ddof=1)) if len(v) > 1 else 0.0
        per[c]["n_kits_mean"] = float(np.mean([r["n_kits"] for r in sub]))
    anova = {m: anova_rm(rows, col) for m, col in METRICS.items()}
    tukey: dict[str, dict[str, Any]] = {}
    for m, col in METRICS.items():
        pairs = tukey_pairs([r[col] for r in rows], [r["condition"] for r in rows])
        tukey[m] = {}
        for a, b in ((SINGLE, WHOLE), (OPT, WHOLE), (OPT, SINGLE)):
            if (a, b) not in pairs:
                continue
            t = dict(pairs[(a, b)])
            paper = PAPER_CI[m].get(a) if b == WHOLE else None
            t["paper"] = list(paper) if paper else None
            t["overlap"] = overlap((t["lo"], t["hi"]), paper) if paper else None
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
                quantity=f"mean {METRIC_LABELS[m]}, {LABELS[c]} (s)",
                paper=PAPER_MEANS[m][c],
                ours=round(ours, 1),
                ours_sd=round(summary["conditions"][c][f"{m}_sd"], 1),
                role="fitted" if (m, c) in fitted else "predicted",
            )
        elif kind == "F":
            a = summary["anova"][m]
            row.update(
                quantity=f"repeated-measures F({a['df1']:.0f}, {a['df2']:.0f}), {METRIC_LABELS[m]}",
                paper=PAPER_F[m],
                ours=None if ours is None else round(ours, 2),
            )
        else:
            t = summary["tukey"][m][c]
            row.update(
                quantity=f"Tukey 95% CI {c}, {METRIC_LABELS[m]} (s)",
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
                    float(np.mean([overlap((a, b), paper) for a, b in zip(lo, hi, strict=True)]))
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


def _study_row(r: Mapping[str, Any], rep: bool) -> list[str]:
    """The Markdown cells of one side-by-side row."""
    ours = _fmt(r["ours"])
    if r["ours_sd"] is not None:
        ours += f" ({r['ours_sd']:.1f})"
    cells = [r["quantity"], _fmt(r["paper"]), ours, r["role"], _fmt(r["ci_overlap"])]
    if rep:
        if "studies_overlap_frac" in r:
            extra = (
                f"{_fmt(r['studies_median'])}, overlap in {100 * r['studies_overlap_frac']:.0f}%"
            )
        elif "studies_median" in r:
            extra = f"{r['studies_median']:.1f} [{r['studies_p5']:.1f}, {r['studies_p95']:.1f}]"
        else:
            extra = "-"
        cells.append(extra)
    return cells


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
    header = ["quantity", "paper", "ours (SD)", "role", "our CI overlaps the paper's"]
    if rep:
        header.append(f"{k} studies: median [5%, 95%] or CI overlap rate")
    lines = [
        f"Simulated user study: {result['n_participants']} participants x 3 conditions, "
        f"1 table, d = {result['delivery_time']:g} s, trays = {result['trays'] or 'unlimited'}, "
        f"seed {result['seed']}.",
        "",
        f"Calibrated: {vals} (fitted to: {fit}; {cal['evaluations']} evaluations).",
        "",
        *markdown_lines(header, [_study_row(r, rep) for r in result["table"]]),
    ]
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


def _given_calibration(
    inst: Instance,
    seeds: Sequence[int],
    timing: TimingModel,
    trays: int | str | None,
    targets: Sequence[tuple[str, str, float]],
    free: Mapping[str, tuple[float, float]],
) -> dict[str, Any]:
    """The calibration record of a given timing: the model's value of each target."""
    conds = list(dict.fromkeys(c for _, c, _ in targets))
    means = condition_means(study_runs(inst, study_params(timing, trays, None), seeds, conds))
    return {
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


def _study_calibration(
    inst: Instance,
    seeds: Sequence[int],
    timing: TimingModel | None,
    trays: int | str | None,
    targets: Sequence[tuple[str, str, float]],
    free: Mapping[str, tuple[float, float]],
    quick: bool,
) -> tuple[TimingModel, dict[str, Any]]:
    """Fit the timing on the study's participants, or report how a given one fits."""
    if timing is not None:
        return timing, _given_calibration(inst, seeds, timing, trays, targets, free)
    grid, refine = (5, ()) if quick else (11, (7,))
    cal = calibrate(inst, seeds, trays=trays, targets=targets, free=free, grid=grid, refine=refine)
    return replace(TimingModel(), **cal["values"]), cal


def _write_study(
    out: Path, result: dict[str, Any], rows: Sequence[Mapping[str, Any]], t0: float
) -> None:
    """Write the study's CSVs, figure, Markdown and JSON; ``result["files"]`` lists them."""
    from .plots import plot_user_study

    files = {
        "runs_csv": write_csv(out / "user_study_runs.csv", rows, exclude=(), line_end="\n"),
        "summary_csv": write_csv(
            out / "user_study_summary.csv", result["table"], exclude=(), line_end="\n"
        ),
    }
    ax = plot_user_study(result["summary"])
    files["figure"] = save_figure(ax.figure, out / "fig5_top.png", dpi=130)
    result["wall_s"] = time.perf_counter() - t0
    atomic.write_text(out / "user_study.md", format_study_markdown(result))
    files["markdown"] = out / "user_study.md"
    files["json"] = out / "user_study.json"
    result["files"] = {k: str(v) for k, v in files.items()}
    write_json(out / "user_study.json", result)


@dataclass(frozen=True)
class StudyCell:
    """One repetition of the study: every condition on its participants' seeds."""

    instance: Instance
    params: SimParams
    seeds: tuple[int, ...]
    study: int

    def key(self) -> str:
        return f"study{self.study}"


def study_cell(cell: StudyCell) -> dict[str, Any]:
    """The rows of one study (:func:`study_runs`), tagged with the study's number."""
    rows = study_runs(cell.instance, cell.params, cell.seeds)
    for r in rows:
        r["study"] = cell.study
    return {"study": cell.study, "rows": rows}


def _study_rows(
    inst: Instance, params: SimParams, seeds: list[int], n: int, jobs: int
) -> list[dict[str, Any]]:
    """All studies' rows (one cell per study), in the order of one :func:`study_runs` call
    over all seeds: condition, then study, then participant."""
    cells = [
        StudyCell(inst, params, tuple(seeds[j * n : (j + 1) * n]), j)
        for j in range(len(seeds) // n)
    ]
    records = run_cells(cells, study_cell, jobs=jobs, desc="user-study studies")
    failed = [r for r in records if is_failed(r)]
    if failed:
        raise SimulationError(f"{len(failed)} study(ies) failed: {failed[0]['error']}")
    rows = [row for r in records for row in r["rows"]]
    order = {c: i for i, c in enumerate(dict.fromkeys(row["condition"] for row in rows))}
    rows.sort(key=lambda row: (order[row["condition"]], row["study"], row["participant"]))
    return rows


def run_user_study(
    out_dir: str | Path = "out/repro/user_study",
    quick: bool = False,
    seed: int = 0,
    jobs: int = 1,
    *,
    instance: str | Path | None = None,
    n_participants: int = PAPER_N,
    n_studies: int | None = None,
    trays: int | str | None = None,
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

    ``trays`` overrides the instance's (the study's table: one tray; ``"unlimited"`` lets the
    robot run ahead). ``quick``: a coarse 5 x 5 calibration grid (plus the polish), 2 studies
    and a small CE. The studies are cells of the one cell runner (not saved: they take
    seconds), on ``jobs`` local workers or the sweep session's executor (docs/cluster.md); the
    calibration runs here.

    Writes to ``out_dir``: ``user_study_runs.csv`` (study x participant x condition),
    ``user_study_summary.csv`` (the side-by-side table), ``user_study.md``,
    ``user_study.json`` (everything returned) and ``fig5_top.png``. Returns the summary dict.
    """
    t0 = time.perf_counter()
    inst, _ = load_instance(instance)
    if n_studies is None:
        n_studies = 2 if quick else 20
    if n_studies < 1 or n_participants < 2:
        raise UsageError("need n_studies >= 1 and n_participants >= 2")
    all_seeds = participant_seeds(seed, n_participants * n_studies)
    seeds = all_seeds[:n_participants]
    timing, cal = _study_calibration(inst, seeds, timing, trays, targets, free, quick)
    if ce is None and quick:
        ce = QUICK_CE
    params = study_params(timing, trays, ce)
    rows = _study_rows(inst, params, all_seeds, n_participants, jobs)
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
        "trays": inst.with_overrides(trays=trays).trays,
        "timing": asdict(timing),
        "ce": asdict(ce) if ce is not None else None,
        "calibration": cal,
        "summary": summary,
        "table": side_by_side(summary, cal, replicates),
    }
    _write_study(Path(out_dir), result, rows, t0)
    return result
