"""The simulated user study (paper Section V-A, Fig. 5 top) against the paper's numbers.

18 simulated participants x {Whole Assembly, Single Task, Optimized} in counterbalanced order,
one table, one tray, co-located (d = 0: "the absence of delivery distance"). The timing and the
within-participant variance come from the one committed calibration (:mod:`.calibrated`);
``n_studies`` (default 200) fresh studies at its values give, for every paper number
(:mod:`.predictions`: fitted, implied or predicted), our median and the 95 % prediction
interval of the participants' variation, and as many studies pooled over the calibration's
bootstrap draws the interval that adds the calibration's uncertainty (docs/reproduction.md,
docs/paper-data.md).
"""

from __future__ import annotations

import time
from collections.abc import Mapping, Sequence
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

import numpy as np

from .. import atomic
from ..errors import UsageError
from ..experiments.cells import run_cells, write_json
from ..experiments.tables import read_csv, write_csv
from ..heuristics.cross_entropy import CEParams
from ..instance import Instance
from ..plots import save_figure
from ..sim import SimParams
from ..sim.timing import WithinSubjectModel
from .calibrated import QUICK_DRAWS, Calibration, load_calibration
from .calibration import EVALUATION, Cohort, draw_cohort, resampled, study_params, study_runs
from .common import (
    DEFAULT_TARGETS,
    EVALUATION_STUDIES,
    F_TARGET,
    PAPER_N,
    QUICK_CE,
    READOFF,
    STUDY_DELIVERY,
    load_instance,
    succeeded,
)
from .predictions import (
    FITTED,
    IMPLIED,
    inside_count,
    prediction_table,
    summaries_of,
    summarize_study,
)
from .sensitivity import predicted_only, run_settings, setting_cells
from .within import explain

#: Fresh studies per sensitivity setting.
SENSITIVITY_STUDIES = 50


def parameter_table(cal: Calibration, d: float, trays: Any) -> list[dict[str, Any]]:
    """Every parameter of the study model with its value, role and source."""
    design = cal.design()
    where = "calibration.csv, `bilevel-kit repro calibrate`"
    rows = [
        ("robot_scale", cal.robot_scale, "fitted", f"step 1: idle means ({where})"),
        ("kit_overhead_human (s)", cal.kit_overhead_human, "fitted", "step 1, same targets"),
        (
            "within_cv (participant x condition)",
            cal.within_cv,
            "fitted",
            "step 2: median F(2, 34) of total time, at its bound",
        ),
        ("total_cv (a session's active time)", cal.total_cv, "paper", "Sec. VI"),
        (
            "speed_sd (participant, log)",
            design.speed_sd,
            "derived",
            "what is left of total_cv after within_cv and learning",
        ),
        ("learning (per session)", cal.learning, "assumed", "not reported; counterbalanced"),
        ("delivery_time d (s)", d, "declared", "co-located: 'absence of delivery distance'"),
        (
            "trays",
            trays if trays is not None else "unlimited",
            "paper",
            "robot returns once the participant retrieved the parts",
        ),
        (
            "robot_cv, task_cv",
            0.0,
            "assumed",
            "deterministic picks; per-task noise folded into the session factor",
        ),
    ]
    return [
        {
            "parameter": n,
            "value": round(float(v), 6) if isinstance(v, float) else v,
            "role": r,
            "source": s,
        }
        for n, v, r, s in rows
    ]


def format_study_markdown(result: Mapping[str, Any]) -> str:
    """The prediction table, the parameters and the sensitivity as Markdown."""
    from .report import (
        model_sensitivity_markdown,
        parameters_markdown,
        predictions_markdown,
        sensitivity_markdown,
        within_markdown,
    )

    quick = " (quick: a reduced run, not the committed result)" if result["quick"] else ""
    lines = [
        f"Simulated user study{quick}: {result['n_studies']} studies of "
        f"{result['n_participants']} participants x 3 conditions at the calibration, "
        f"the same studies again over its {result['draws_used']} bootstrap draws, 1 table, "
        f"d = {result['delivery_time']:g} s, trays = {result['trays'] or 'unlimited'}, "
        f"evaluation seed {result['seed']}.",
        "",
        predictions_markdown(result["table"]),
        "",
        parameters_markdown(result["parameters"]),
        "",
        within_markdown(result["within"]),
    ]
    if result.get("sensitivity"):
        lines += ["", sensitivity_markdown(result["sensitivity"])]
        lines += ["", model_sensitivity_markdown(result["model_sensitivity"])]
    return "\n".join(lines) + "\n"


def _write_study(out: Path, result: dict[str, Any], rows: Sequence[Mapping[str, Any]]) -> None:
    """Write the study's CSVs, figure, Markdown and JSON; ``result["files"]`` lists them."""
    from .plots import plot_user_study

    files = {
        "runs_csv": write_csv(out / "user_study_runs.csv", rows, exclude=("kits",), line_end="\n")
    }
    for key, name in (
        ("table", "user_study_predictions.csv"),
        ("parameters", "user_study_parameters.csv"),
        ("summary", "user_study_summary.csv"),
        ("within", "user_study_within.csv"),
        ("sensitivity", "user_study_sensitivity.csv"),
        ("model_sensitivity", "user_study_model_sensitivity.csv"),
    ):
        if result.get(key):
            files[key] = write_csv(out / name, result[key], exclude=(), line_end="\n")
    ax = plot_user_study(result["table"], quick=result["quick"], studies=result["n_studies"])
    files["figure"] = save_figure(ax.figure, out / "fig5_top.png", dpi=130)
    atomic.write_text(out / "user_study.md", format_study_markdown(result))
    files["markdown"] = out / "user_study.md"
    files["json"] = out / "user_study.json"
    result["files"] = {k: str(v) for k, v in files.items()}
    write_json(out / "user_study.json", result)


@dataclass(frozen=True)
class StudyCell:
    """One simulated study: every condition for its cohort's participants."""

    instance: Instance
    params: SimParams
    design: WithinSubjectModel
    cohort: Cohort  # this study's draws only
    study: int

    def key(self) -> str:
        return f"study{self.study}"


def study_cell(cell: StudyCell) -> dict[str, Any]:
    """The rows of one study (:func:`study_runs`), tagged with the study's number."""
    rows = study_runs(cell.instance, cell.params, cell.design, cell.cohort)
    for r in rows:
        r["study"] = cell.study
    return {"study": cell.study, "rows": rows}


def _study_rows(
    inst: Instance,
    specs: Sequence[tuple[SimParams, WithinSubjectModel]],
    cohort: Cohort,
    jobs: int,
    desc: str,
    progress: bool | None = None,
) -> list[dict[str, Any]]:
    """All studies' rows (one cell per study; study ``j`` with ``specs[j]``), in the order of
    one :func:`study_runs` call over the whole cohort: study, then condition, then
    participant."""
    cells = [
        StudyCell(inst, params, design, resampled(cohort, [j]), j)
        for j, (params, design) in enumerate(specs)
    ]
    records = run_cells(cells, study_cell, jobs=jobs, progress=progress, desc=desc)
    ok = succeeded(records, "study(ies)")
    return [row for r in sorted(ok, key=lambda r: r["study"]) for row in r["rows"]]


def run_user_study(
    out_dir: str | Path = "out/repro/user_study",
    quick: bool = False,
    seed: int = 0,
    jobs: int = 1,
    *,
    instance: str | Path | None = None,
    calibration: Calibration | str | Path | None = None,
    n_participants: int = PAPER_N,
    n_studies: int | None = None,
    trays: int | str | None = None,
    delivery_time: float = STUDY_DELIVERY,
    sensitivity: bool | None = None,
    ce: CEParams | None = None,
    progress: bool | None = None,
) -> dict[str, Any]:
    """Simulate the user study and predict every paper number (module docstring).

    ``calibration``: the one calibration (default: the committed one,
    :func:`.calibrated.load_calibration`; a folder or a :class:`.calibrated.Calibration`).
    ``n_studies`` fresh studies (``seed``; default 200, quick 5) at the fitted values give the
    participants-only intervals; the same studies again, spread over the calibration's
    bootstrap draws (quick: its first 3), give the intervals with the calibration's
    uncertainty.
    ``sensitivity`` (default: not quick) adds the delivery/tray what-if fits and the model
    sensitivity (learning effect, weights; :mod:`.sensitivity`) on 50 studies each (quick 3).

    ``trays`` overrides the instance's (the study's table: one tray); ``delivery_time``: 0, the
    co-located study. ``quick``: few studies and a small CE (for tests). Studies are cells of
    the one cell runner (not saved: they take seconds), on ``jobs`` local workers or the sweep
    session's executor (docs/cluster.md).

    Writes to ``out_dir``: ``user_study_runs.csv`` (study x participant x condition),
    ``user_study_predictions.csv``, ``user_study_parameters.csv``, ``user_study_summary.csv``,
    ``user_study_within.csv``, with ``sensitivity`` ``user_study_sensitivity.csv`` and
    ``user_study_model_sensitivity.csv``, ``user_study.md``, ``user_study.json`` and
    ``fig5_top.png``. Returns the summary dict.
    """
    t0 = time.perf_counter()
    inst, path = load_instance(instance)
    cal = _calibration(calibration, path)
    n_studies = _study_sizes(quick, n_studies, n_participants)
    if sensitivity is None:
        sensitivity = not quick
    if ce is None and quick:
        ce = QUICK_CE
    design, timing = cal.design(), cal.timing()
    params = study_params(timing, trays, ce, delivery_time)
    cohort = draw_cohort(seed, n_studies, n_participants, EVALUATION)
    rows = _study_rows(
        inst, [(params, design)] * n_studies, cohort, jobs, "user-study studies", progress
    )
    summaries = summaries_of(rows, n_studies)
    draws = list(cal.draws[: QUICK_DRAWS if quick else None])
    specs = [(study_params(cal.timing(d), trays, ce, delivery_time), cal.design(d)) for d in draws]
    boot_rows = _draw_rows(inst, specs, cohort, jobs, progress)
    n_boot = n_studies if specs else 0
    eff_trays = inst.with_overrides(trays=trays).trays
    result: dict[str, Any] = {
        "instance": inst.name,
        "quick": quick,
        "seed": seed,
        "n_participants": n_participants,
        "n_studies": n_studies,
        "cal_studies": n_boot,
        "draws_used": len(draws),
        "delivery_time": delivery_time,
        "trays": eff_trays,
        "timing": asdict(timing),
        "design": asdict(design),
        "ce": asdict(ce) if ce is not None else None,
        "calibration": asdict(cal),
        **_predictions(summaries, summaries_of(boot_rows, n_boot), cal, delivery_time, eff_trays),
    }
    result["within"] = explain(rows, design, _bound(cal), _f_fit(cal))
    if sensitivity:
        n_sens = 3 if quick else SENSITIVITY_STUDIES
        delivery, model = setting_cells(path, cal, seed, n_sens, ce, quick)
        cells = Path(out_dir) / "cells"
        result["sensitivity"] = run_settings(
            delivery, jobs, progress, "user-study what-if fits", cells
        )
        result["model_sensitivity"] = predicted_only(
            run_settings(model, jobs, progress, "user-study model sensitivity", cells)
        )
    result["wall_s"] = time.perf_counter() - t0
    _write_study(Path(out_dir), result, rows)
    return result


def _draw_rows(
    inst: Instance,
    specs: Sequence[tuple[SimParams, WithinSubjectModel]],
    cohort: Cohort,
    jobs: int,
    progress: bool | None,
) -> list[dict[str, Any]]:
    """The fresh studies again, study ``j`` at the calibration's draw ``j mod len(specs)``
    (``specs``: each draw's parameters and design). The same participants and seeds as at the
    fitted values (common random numbers), so an interval differs from the participants-only
    one by the calibration's uncertainty, not by other draws of the participants."""
    if not specs:
        return []
    pooled = [specs[j % len(specs)] for j in range(cohort.n_studies)]
    desc = "user-study studies over the calibration draws"
    return _study_rows(inst, pooled, cohort, jobs, desc, progress)


def _calibration(calibration: Calibration | str | Path | None, path: str) -> Calibration:
    """The calibration the study uses, checked against its instance."""
    if isinstance(calibration, Calibration):
        calibration.check(path)
        return calibration
    return load_calibration(calibration, path)


def _bound(cal: Calibration) -> float:
    from .calibration import within_bound

    return within_bound(cal.design())


def _f_fit(cal: Calibration) -> dict[str, Any]:
    """The F target's row of the calibration (the paper's F and the cohort's median at the
    fit), read from the calibration's folder."""
    path = Path(cal.source) / "calibration_targets.csv"
    if path.is_file():
        for r in read_csv(path):
            if r["quantity"] == "F":
                return {"paper": float(r["paper"]), "fitted": float(r["fitted"])}
    return {"paper": F_TARGET[1], "fitted": float("nan")}


def _study_sizes(quick: bool, n_studies: int | None, n_participants: int) -> int:
    """The number of evaluation studies (default 200, quick 5), checked with the cohort size:
    a prediction interval needs two studies at least."""
    if n_studies is None:
        n_studies = 5 if quick else EVALUATION_STUDIES
    if n_studies < 2 or n_participants < 2:
        raise UsageError("need n_studies >= 2 and n_participants >= 2")
    return n_studies


def _predictions(
    summaries: Sequence[Mapping[str, Any]],
    boot: Sequence[Mapping[str, Any]],
    cal: Calibration,
    delivery_time: float,
    trays: int | None,
) -> dict[str, Any]:
    """The result's tables: each paper number's prediction, the counts inside, the
    parameters, and the share of studies where OPT vs ST is not significant."""
    table = prediction_table(summaries, DEFAULT_TARGETS, F_TARGET, boot)
    k, n = inside_count(table)
    ki, ni = inside_count(table, independent=True)
    not_sig = float(np.mean([(s["tukey"]["total"]["OPT-ST"]["p"] or 1) >= 0.05 for s in summaries]))
    kinds = [r["kind"] for r in table]
    summary = {
        "studies": len(summaries),
        "cal_studies": len(boot),
        "predicted": n,
        "predicted_inside": k,
        "independent": ni,
        "independent_inside": ki,
        "implied": kinds.count(IMPLIED),
        "fitted": kinds.count(FITTED),
        "opt_vs_st_not_significant": round(not_sig, 4),
        "readoff": round(READOFF, 4),
    }
    return {
        "table": table,
        "inside": {"inside": k, "predicted": n, "independent_inside": ki, "independent": ni},
        "parameters": parameter_table(cal, delivery_time, trays),
        "summary": [{"key": key, "value": v} for key, v in summary.items()],
        "opt_vs_st_not_significant": not_sig,
    }


__all__ = ["format_study_markdown", "run_user_study", "summaries_of", "summarize_study"]
