"""The simulated user study (paper Section V-A, Fig. 5 top) against the paper's numbers.

18 simulated participants x {Whole Assembly, Single Task, Optimized} in counterbalanced order,
one table, one tray, co-located (d = 0: "the absence of delivery distance"). The timing and the
within-participant variance are fitted on a calibration cohort (:mod:`.calibration`); then
``n_studies`` (default 200) fresh studies give, for every paper number, our median and 95 %
prediction interval, and whether the paper's value is inside (docs/reproduction.md,
docs/paper-data.md).
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
from ..experiments.tables import write_csv
from ..heuristics.cross_entropy import CEParams
from ..instance import Instance
from ..plots import save_figure
from ..sim import SimParams, SimulationError, TimingModel
from ..sim.timing import WithinSubjectModel
from .calibration import (
    CALIBRATION,
    EVALUATION,
    Cohort,
    calibrate,
    draw_cohort,
    study_params,
    study_runs,
)
from .common import (
    CALIBRATION_STUDIES,
    CONDITIONS,
    DEFAULT_FREE,
    DEFAULT_TARGETS,
    EVALUATION_STUDIES,
    F_TARGET,
    LABELS,
    METRIC_LABELS,
    METRICS,
    OPT,
    PAPER_CI,
    PAPER_F,
    PAPER_MEANS,
    PAPER_N,
    QUICK_CE,
    SHORT,
    SINGLE,
    STUDY_DELIVERY,
    WHOLE,
    load_instance,
)
from .stats import anova_rm, tukey_pairs

#: Delivery times and tray rules of the sensitivity runs (each refits step 1).
SENSITIVITY: tuple[tuple[float, int | str], ...] = (
    (0.0, 1),
    (2.0, 1),
    (5.0, 1),
    (0.0, "unlimited"),
)


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
    for m, col in METRICS.items():
        pairs = tukey_pairs([r[col] for r in rows], [r["condition"] for r in rows])
        tukey[m] = {
            f"{SHORT[a]}-{SHORT[b]}": dict(pairs[(a, b)])
            for a, b in ((SINGLE, WHOLE), (OPT, WHOLE), (OPT, SINGLE))
            if (a, b) in pairs
        }
    return {"conditions": per, "anova": anova, "tukey": tukey}


def paper_numbers(
    fitted: Sequence[tuple[str, str]] = (),
) -> list[dict[str, Any]]:
    """Every number of the paper's user study: ``key`` (how to read it off a study summary),
    ``quantity``, ``paper`` and ``role`` (``fitted`` for the calibration's targets)."""
    out: list[dict[str, Any]] = []
    for m in ("total", "idle"):
        for c in (OPT, SINGLE, WHOLE):
            out.append(
                {
                    "key": ("mean", m, c),
                    "quantity": f"mean {METRIC_LABELS[m]}, {LABELS[c]} (s)",
                    "paper": PAPER_MEANS[m][c],
                    "role": "fitted" if (m, c) in fitted else "predicted",
                }
            )
    for m in ("total", "idle"):
        out.append(
            {
                "key": ("F", m, ""),
                "quantity": f"repeated-measures F(2, 34), {METRIC_LABELS[m]}",
                "paper": PAPER_F[m],
                "role": "fitted" if (m, "F") in fitted else "predicted",
            }
        )
    for m in ("total", "idle"):
        for c, pair in ((SINGLE, "ST-WA"), (OPT, "OPT-WA")):
            for i, end in enumerate(("lower", "upper")):
                out.append(
                    {
                        "key": ("ci", m, pair, i),
                        "quantity": f"Tukey 95% CI {pair} {end} end, {METRIC_LABELS[m]} (s)",
                        "paper": PAPER_CI[m][c][i],
                        "role": "predicted",
                    }
                )
    return out


def _value(summary: Mapping[str, Any], key: tuple[Any, ...]) -> float | None:
    """One paper quantity of a study summary: a mean, an F or one end of a Tukey CI."""
    if key[0] == "mean":
        return summary["conditions"][key[2]][f"{key[1]}_mean"]
    if key[0] == "F":
        return summary["anova"][key[1]]["F"]
    t = summary["tukey"][key[1]].get(key[2])
    return None if t is None else t["lo" if key[3] == 0 else "hi"]


def prediction_table(
    summaries: Sequence[Mapping[str, Any]], fitted: Sequence[tuple[str, str]]
) -> list[dict[str, Any]]:
    """For every paper number: our median and 95 % prediction interval over the studies
    (2.5 % and 97.5 % quantiles), and whether the paper's value is inside."""
    rows: list[dict[str, Any]] = []
    for q in paper_numbers(fitted):
        vals = np.array([v for s in summaries if (v := _value(s, q["key"])) is not None], float)
        med, lo, hi = (float(np.quantile(vals, x)) for x in (0.5, 0.025, 0.975))
        rows.append(
            {
                "quantity": q["quantity"],
                "paper": q["paper"],
                "role": q["role"],
                "median": round(med, 2),
                "pi_low": round(lo, 2),
                "pi_high": round(hi, 2),
                # 0.01 s: the fitted rows' residuals, far below the paper's last digit
                "inside": bool(lo - 0.01 <= q["paper"] <= hi + 0.01),
                "studies": len(vals),
            }
        )
    return rows


def inside_count(table: Sequence[Mapping[str, Any]]) -> tuple[int, int]:
    """(predicted rows whose paper value is inside our interval, predicted rows)."""
    pred = [r for r in table if r["role"] == "predicted"]
    return sum(bool(r["inside"]) for r in pred), len(pred)


def _fitted_keys(cal: Mapping[str, Any]) -> list[tuple[str, str]]:
    return [
        (t["metric"], t["condition"] or "F")
        for t in cal["targets"]
        if t.get("condition") is not None
    ]


def parameter_table(
    timing: TimingModel, design: WithinSubjectModel, cal: Mapping[str, Any], d: float, trays: Any
) -> list[dict[str, Any]]:
    """Every parameter of the study model with its value, role and source."""
    fit_means = ", ".join(
        f"{LABELS[t['condition']]} {t['metric']} {t['paper']:g} s"
        for t in cal["targets"]
        if t["condition"]
    )
    coh = cal["cohort"]
    where = f"calibration cohort seed {coh['seed']}, {coh['studies']} x {coh['participants']}"
    rows = [
        ("robot_scale", timing.robot_scale, "fitted", f"step 1: {fit_means} ({where})"),
        ("kit_overhead_human (s)", timing.kit_overhead_human, "fitted", "step 1, same targets"),
        (
            "within_cv (participant x condition)",
            design.within_cv,
            "fitted" if cal.get("f_target") else "given",
            f"step 2: median F(2, 34) of {cal.get('f_target') or '-'} ({where})",
        ),
        (
            "total_cv (a session's active time)",
            design.total_cv,
            "paper",
            "61.14 / 374.78 s, Sec. VI",
        ),
        (
            "speed_sd (participant, log)",
            design.speed_sd,
            "derived",
            "what is left of total_cv after within_cv and learning",
        ),
        ("learning (per session)", design.learning, "assumed", "not reported; counterbalanced"),
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
    from .report import parameters_markdown, predictions_markdown, sensitivity_markdown

    quick = " (quick: a reduced run, not the committed result)" if result["quick"] else ""
    lines = [
        f"Simulated user study{quick}: {result['n_studies']} studies of "
        f"{result['n_participants']} participants x 3 conditions, 1 table, "
        f"d = {result['delivery_time']:g} s, trays = {result['trays'] or 'unlimited'}, "
        f"evaluation seed {result['seed']}.",
        "",
        predictions_markdown(result["table"]),
        "",
        parameters_markdown(result["parameters"]),
    ]
    if result.get("sensitivity"):
        lines += ["", sensitivity_markdown(result["sensitivity"])]
    return "\n".join(lines) + "\n"


def _calibrate(
    inst: Instance,
    cohort: Cohort,
    design: WithinSubjectModel,
    base: TimingModel,
    trays: int | str | None,
    delivery_time: float,
    quick: bool,
    **fit: Any,
) -> dict[str, Any]:
    """:func:`.calibration.calibrate` on the quick or the full grid; ``fit``: its further
    arguments (``f_target=None``: step 1 alone, ``within_cv`` kept)."""
    return calibrate(
        inst,
        cohort,
        design=design,
        base=base,
        trays=trays,
        delivery_time=delivery_time,
        grid=3 if quick else 5,
        **fit,
    )


def _summaries(rows: Sequence[Mapping[str, Any]], n_studies: int) -> list[dict[str, Any]]:
    """:func:`summarize_study` of each study 0 .. n_studies - 1 of ``rows``."""
    return [summarize_study([r for r in rows if r["study"] == j]) for j in range(n_studies)]


@dataclass(frozen=True)
class _Protocol:
    """The settings the calibration and the sensitivity runs share: the instance, its tray
    rule and delivery time, the grid size (``quick``), the CE parameters, and the calibration
    cohort's seed, size and participants."""

    inst: Instance
    trays: int | str | None
    delivery_time: float
    quick: bool
    ce: CEParams | None
    n_participants: int
    calibration_seed: int
    calibration_studies: int

    def calibration_cohort(self) -> Cohort:
        return draw_cohort(
            self.calibration_seed, self.calibration_studies, self.n_participants, CALIBRATION
        )

    def calibrate(
        self, cohort: Cohort, design: WithinSubjectModel, base: TimingModel, **fit: Any
    ) -> dict[str, Any]:
        """:func:`_calibrate` at the protocol's tray rule and delivery time."""
        return _calibrate(
            self.inst, cohort, design, base, self.trays, self.delivery_time, self.quick, **fit
        )


def _sensitivity(
    proto: _Protocol, design: WithinSubjectModel, base: TimingModel, seed: int, n_studies: int
) -> list[dict[str, Any]]:
    """Refit step 1 at each (d, trays) of :data:`SENSITIVITY` (``within_cv`` kept) and
    evaluate ``n_studies`` fresh studies: the predicted medians and the inside count."""
    inst, quick, ce = proto.inst, proto.quick, proto.ce
    out: list[dict[str, Any]] = []
    cal_cohort = proto.calibration_cohort()
    cohort = draw_cohort(seed, n_studies, proto.n_participants, EVALUATION)
    for d, trays in SENSITIVITY:
        cal = _calibrate(inst, cal_cohort, design, base, trays, d, quick, f_target=None)
        tm = replace(base, **cal["values"])
        rows = study_runs(inst, study_params(tm, trays, ce, d), design, cohort)
        table = prediction_table(
            _summaries(rows, n_studies), [*_fitted_keys(cal), (F_TARGET[0], "F")]
        )
        k, n = inside_count(table)
        for r in table:
            out.append(
                {
                    "delivery_time": d,
                    "trays": trays,
                    "robot_scale": tm.robot_scale,
                    "kit_overhead_human": tm.kit_overhead_human,
                    "quantity": r["quantity"],
                    "paper": r["paper"],
                    "role": r["role"],
                    "median": r["median"],
                    "pi_low": r["pi_low"],
                    "pi_high": r["pi_high"],
                    "inside": r["inside"],
                    "inside_count": f"{k}/{n}",
                }
            )
    return out


def _write_study(out: Path, result: dict[str, Any], rows: Sequence[Mapping[str, Any]]) -> None:
    """Write the study's CSVs, figure, Markdown and JSON; ``result["files"]`` lists them."""
    from .plots import plot_user_study

    files = {
        "runs_csv": write_csv(out / "user_study_runs.csv", rows, exclude=("kits",), line_end="\n"),
        "summary_csv": write_csv(
            out / "user_study_predictions.csv", result["table"], exclude=(), line_end="\n"
        ),
        "parameters_csv": write_csv(
            out / "user_study_parameters.csv", result["parameters"], exclude=(), line_end="\n"
        ),
    }
    if result.get("sensitivity"):
        files["sensitivity_csv"] = write_csv(
            out / "user_study_sensitivity.csv", result["sensitivity"], exclude=(), line_end="\n"
        )
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
    inst: Instance, params: SimParams, design: WithinSubjectModel, cohort: Cohort, jobs: int
) -> list[dict[str, Any]]:
    """All studies' rows (one cell per study), in the order of one :func:`study_runs` call over
    the whole cohort: study, then condition, then participant."""
    cells = [
        StudyCell(
            inst,
            params,
            design,
            replace(
                cohort,
                z_speed=cohort.z_speed[j : j + 1],
                z_within=cohort.z_within[j : j + 1],
                run_seeds=cohort.run_seeds[j : j + 1],
            ),
            j,
        )
        for j in range(cohort.n_studies)
    ]
    records = run_cells(cells, study_cell, jobs=jobs, desc="user-study studies")
    failed = [r for r in records if is_failed(r)]
    if failed:
        raise SimulationError(f"{len(failed)} study(ies) failed: {failed[0]['error']}")
    return [row for r in sorted(records, key=lambda r: r["study"]) for row in r["rows"]]


def run_user_study(
    out_dir: str | Path = "out/repro/user_study",
    quick: bool = False,
    seed: int = 0,
    jobs: int = 1,
    *,
    instance: str | Path | None = None,
    n_participants: int = PAPER_N,
    n_studies: int | None = None,
    calibration_seed: int = 0,
    calibration_studies: int | None = None,
    trays: int | str | None = None,
    delivery_time: float = STUDY_DELIVERY,
    design: WithinSubjectModel | None = None,
    targets: Sequence[tuple[str, str, float]] = DEFAULT_TARGETS,
    f_target: tuple[str, float] | None = F_TARGET,
    free: Mapping[str, tuple[float, float]] = DEFAULT_FREE,
    sensitivity: bool | None = None,
    ce: CEParams | None = None,
) -> dict[str, Any]:
    """Simulate the user study and predict every paper number (module docstring).

    Steps: draw a calibration cohort (``calibration_seed``, ``calibration_studies`` studies,
    default 10; quick 2) and fit on it (:func:`.calibration.calibrate`: ``robot_scale`` and
    ``o_H`` to ``targets``, ``within_cv`` to ``f_target``; None keeps ``design``'s); then draw
    ``n_studies`` fresh studies (``seed``; default 200, quick 5) and tabulate, for each paper
    number, the median and 95 % prediction interval over them. ``sensitivity`` (default: not
    quick) repeats the evaluation at d in {0, 2, 5} s and with unlimited trays, refitting
    step 1 each time, on 50 studies (quick: 3).

    ``trays`` overrides the instance's (the study's table: one tray); ``delivery_time``: 0, the
    co-located study. ``quick``: small cohorts, a coarse grid and a small CE (for tests).
    The evaluation studies are cells of the one cell runner (not saved: they take seconds), on
    ``jobs`` local workers or the sweep session's executor (docs/cluster.md); the calibration
    runs here.

    Writes to ``out_dir``: ``user_study_runs.csv`` (study x participant x condition),
    ``user_study_predictions.csv`` (the table), ``user_study_parameters.csv``,
    ``user_study_sensitivity.csv``, ``user_study.md``, ``user_study.json`` and
    ``fig5_top.png``. Returns the summary dict.
    """
    t0 = time.perf_counter()
    inst, _ = load_instance(instance)
    n_studies, calibration_studies = _study_sizes(
        quick, n_studies, calibration_studies, n_participants
    )
    if sensitivity is None:
        sensitivity = not quick
    if ce is None and quick:
        ce = QUICK_CE
    proto = _Protocol(
        inst, trays, delivery_time, quick, ce, n_participants, calibration_seed, calibration_studies
    )
    base = TimingModel()
    fit = {"targets": targets, "free": free}
    cal, design, timing = _fit(proto, design or WithinSubjectModel(), base, fit, f_target)
    cohort = draw_cohort(seed, n_studies, n_participants, EVALUATION)
    params = study_params(timing, trays, ce, delivery_time)
    rows = _study_rows(inst, params, design, cohort, jobs)
    summaries = _summaries(rows, n_studies)
    eff_trays = inst.with_overrides(trays=trays).trays
    result: dict[str, Any] = {
        "instance": inst.name,
        "quick": quick,
        "seed": seed,
        "n_participants": n_participants,
        "n_studies": n_studies,
        "delivery_time": delivery_time,
        "trays": eff_trays,
        "timing": asdict(timing),
        "design": asdict(design),
        "ce": asdict(ce) if ce is not None else None,
        "calibration": cal,
        **_predictions(summaries, cal, timing, design, delivery_time, eff_trays),
    }
    if sensitivity:
        result["sensitivity"] = _sensitivity(proto, design, base, seed, 3 if quick else 50)
    result["wall_s"] = time.perf_counter() - t0
    _write_study(Path(out_dir), result, rows)
    return result


def _study_sizes(
    quick: bool, n_studies: int | None, calibration_studies: int | None, n_participants: int
) -> tuple[int, int]:
    """The number of evaluation and of calibration studies (defaults: 200 and 10, quick 5 and
    2), checked with the cohort size: a prediction interval needs two studies at least."""
    if n_studies is None:
        n_studies = 5 if quick else EVALUATION_STUDIES
    if calibration_studies is None:
        calibration_studies = 2 if quick else CALIBRATION_STUDIES
    if n_studies < 2 or calibration_studies < 1 or n_participants < 2:
        raise UsageError("need n_studies >= 2, calibration_studies >= 1, n_participants >= 2")
    return n_studies, calibration_studies


def _fit(
    proto: _Protocol,
    design: WithinSubjectModel,
    base: TimingModel,
    fit: Mapping[str, Any],
    f_target: tuple[str, float] | None,
) -> tuple[dict[str, Any], WithinSubjectModel, TimingModel]:
    """Step 1 of the protocol on the calibration cohort: ``robot_scale`` and ``o_H`` to the
    targets and ``within_cv`` to ``f_target`` (``fit``: the targets and the free parameters);
    with ``f_target``, step 1 again at the fitted ``within_cv`` so that the reported values are
    the final ones. Returns the calibration record, the design and the timing."""
    cohort = proto.calibration_cohort()
    cal = proto.calibrate(cohort, design, base, f_target=f_target, ce=proto.ce, **fit)
    cal["f_target"] = f"{f_target[0]} {f_target[1]:g}" if f_target else None
    design = replace(design, within_cv=cal["within_cv"])
    timing = replace(base, **cal["values"])
    if f_target is not None:
        cal1 = proto.calibrate(cohort, design, timing, f_target=None, **fit)
        timing = replace(timing, **cal1["values"])
        cal["values"] = cal1["values"]
        cal["targets"] = cal1["targets"] + [t for t in cal["targets"] if not t["condition"]]
    return cal, design, timing


def _predictions(
    summaries: Sequence[Mapping[str, Any]],
    cal: Mapping[str, Any],
    timing: TimingModel,
    design: WithinSubjectModel,
    delivery_time: float,
    trays: int | None,
) -> dict[str, Any]:
    """The result's tables: each paper number's prediction, how many fall inside, the
    parameters, and the share of studies where OPT vs ST is not significant."""
    table = prediction_table(summaries, _fitted_keys(cal))
    return {
        "table": table,
        "inside": dict(zip(("inside", "predicted"), inside_count(table), strict=True)),
        "parameters": parameter_table(timing, design, cal, delivery_time, trays),
        "opt_vs_st_not_significant": float(
            np.mean([(s["tukey"]["total"]["OPT-ST"]["p"] or 1) >= 0.05 for s in summaries])
        ),
    }


__all__ = [
    "format_study_markdown",
    "inside_count",
    "paper_numbers",
    "prediction_table",
    "run_user_study",
    "summarize_study",
]
