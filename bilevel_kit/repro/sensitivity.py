"""What the user study's predictions depend on (docs/reproduction.md, "Sensitivity").

* **Delivery time and tray rule** (``user_study_sensitivity.csv``): d in {0, 2, 5} s and
  unlimited trays. Step 1 of the protocol is refitted at each (the robot's speed absorbs d),
  ``within_cv`` kept: these are what-if fits, not the calibration the studies use.
* **The model's assumptions** (``user_study_model_sensitivity.csv``): the learning effect
  (not reported by the paper; the whole protocol refitted at each value, since the learning
  share bounds ``within_cv``) and the unpublished weights W1..W7 (each scaled by 1/2 and 2,
  and the alternatives the paper's silence leaves open). The weights only change Optimized's
  plans, and the calibration's targets are Whole Assembly's and Single Task's, so the
  calibration is kept; W1 (precedence is a hard constraint) and W7 (no part is ever missing in
  the study) cannot matter, and the table shows that they do not.

Every setting is a cell of the one cell runner, evaluated on the same fresh studies (common
random numbers), so the settings differ by their effect, not by their draws.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import asdict, dataclass, replace
from pathlib import Path
from typing import Any

from ..experiments.cells import run_cells
from ..heuristics.cross_entropy import CEParams
from ..instance import DEFAULT_WEIGHTS, load
from ..sim.timing import WithinSubjectModel
from .calibrated import Calibration
from .calibration import CALIBRATION, EVALUATION, calibrate, draw_cohort, study_params, study_runs
from .common import (
    CALIBRATION_STUDIES,
    DEFAULT_TARGETS,
    F_TARGET,
    PAPER_N,
    config_digest,
    succeeded,
)
from .predictions import PREDICTED, inside_count, prediction_table, summaries_of

#: Delivery times and tray rules of the what-if fits.
DELIVERY: tuple[tuple[float, int | str], ...] = ((0.0, 1), (2.0, 1), (5.0, 1), (0.0, "unlimited"))
#: Learning effects other than the assumed one.
LEARNING: tuple[float, ...] = (0.0, 0.025, 0.10)
#: Each weight is scaled by these.
WEIGHT_FACTORS: tuple[float, ...] = (0.5, 2.0)
#: Alternatives the paper leaves open (docs/errata.md: the weights are not published).
ALTERNATIVES: dict[str, dict[str, float]] = {
    "W2..W6 all 1": {"W2": 1.0, "W3": 1.0, "W4": 1.0, "W5": 1.0, "W6": 1.0},
    "no kit-size reward (W2 = 0)": {"W2": 0.0},
    "no layout term (W5 = 0)": {"W5": 0.0},
}


@dataclass(frozen=True)
class SettingCell:
    """One setting: refit what it needs, then evaluate ``studies`` fresh studies."""

    instance: str
    group: str  # "delivery", "learning", "weights" or "reference"
    label: str
    calibration: tuple[float, float, float, float]  # robot_scale, o_H, within_cv, learning
    seed: int
    studies: int
    delivery_time: float = 0.0
    trays: int | str | None = None
    learning: float | None = None
    weights: dict[str, float] | None = None
    ce: dict[str, Any] | None = None
    quick: bool = False

    def key(self) -> str:
        slug = "".join(ch if ch.isalnum() else "_" for ch in self.label)[:40]
        return f"{self.group}_{slug}__{config_digest(self)}"


def _fit(cell: SettingCell, inst: Any, ce: CEParams | None) -> tuple[Any, WithinSubjectModel]:
    """The timing and design of a setting: the calibration's, refitted where the setting
    changes what the calibration fits."""
    rs, oh, w, learning = cell.calibration
    design = WithinSubjectModel(within_cv=w, learning=learning)
    timing = Calibration(rs, oh, w, learning, design.total_cv).timing()
    if cell.group not in ("delivery", "learning"):
        return timing, design
    n_cal = 2 if cell.quick else CALIBRATION_STUDIES
    cohort = draw_cohort(cell.seed, n_cal, PAPER_N, CALIBRATION)
    grid = 3 if cell.quick else 5
    if cell.group == "delivery":  # step 1 only, within_cv kept
        cal = calibrate(
            inst,
            cohort,
            design=design,
            trays=cell.trays,
            delivery_time=cell.delivery_time,
            f_target=None,
            grid=grid,
        )
        return replace(timing, **cal["values"]), design
    design = WithinSubjectModel(learning=float(cell.learning or 0.0))
    cal = calibrate(
        inst, cohort, design=design, delivery_time=0.0, grid=grid, ce=ce, start=(rs, oh)
    )
    return replace(timing, **cal["values"]), replace(design, within_cv=cal["within_cv"])


def setting_cell(cell: SettingCell) -> dict[str, Any]:
    """Rows of one setting: every paper number's median and interval over the fresh studies
    (the participants' variation only), and the predicted count inside."""
    inst = load(cell.instance)
    ce = CEParams(**cell.ce) if cell.ce is not None else None
    timing, design = _fit(cell, inst, ce)
    params = study_params(timing, cell.trays, ce, cell.delivery_time)
    if cell.weights:
        params = replace(params, weights=dict(cell.weights))
    cohort = draw_cohort(cell.seed, cell.studies, PAPER_N, EVALUATION)
    rows = study_runs(inst, params, design, cohort)
    table = prediction_table(summaries_of(rows, cell.studies), DEFAULT_TARGETS, F_TARGET)
    k, n = inside_count(table)
    head = {
        "group": cell.group,
        "setting": cell.label,
        "delivery_time": cell.delivery_time,
        "trays": cell.trays if cell.trays is not None else 1,
        "learning": design.learning,
        "within_cv": round(design.within_cv, 6),
        "robot_scale": timing.robot_scale,
        "kit_overhead_human": timing.kit_overhead_human,
        "inside_count": f"{k}/{n}",
    }
    keep = ("quantity", "kind", "paper", "readoff", "median", "pi_low", "pi_high", "inside")
    return {"key": cell.key(), "rows": [{**head, **{k: r[k] for k in keep}} for r in table]}


def setting_cells(
    path: str, cal: Calibration, seed: int, studies: int, ce: CEParams | None, quick: bool
) -> tuple[list[SettingCell], list[SettingCell]]:
    """The delivery/tray cells and the model cells (reference, learning, weights)."""
    common: dict[str, Any] = {
        "instance": path,
        "calibration": (cal.robot_scale, cal.kit_overhead_human, cal.within_cv, cal.learning),
        "seed": seed,
        "studies": studies,
        "ce": asdict(ce) if ce is not None else None,
        "quick": quick,
    }
    delivery = [
        SettingCell(
            group="delivery", label=f"d = {d:g} s, trays {t}", delivery_time=d, trays=t, **common
        )
        for d, t in DELIVERY
    ]
    model = [
        SettingCell(group="reference", label=f"as calibrated (learning {cal.learning:g})", **common)
    ]
    model += [
        SettingCell(group="learning", label=f"learning {v:g}", learning=v, **common)
        for v in LEARNING
    ]
    for w in DEFAULT_WEIGHTS:
        for f in WEIGHT_FACTORS:
            label = f"{w} x {f:g} ({DEFAULT_WEIGHTS[w] * f:g})"
            model.append(
                SettingCell(
                    group="weights", label=label, weights={w: DEFAULT_WEIGHTS[w] * f}, **common
                )
            )
    model += [
        SettingCell(group="weights", label=name, weights=w, **common)
        for name, w in ALTERNATIVES.items()
    ]
    return delivery, model


def run_settings(
    cells: Sequence[SettingCell],
    jobs: int,
    progress: bool | None,
    desc: str,
    cell_dir: str | Path | None = None,
) -> list[dict[str, Any]]:
    """Every setting's rows, in cell order (saved under ``cell_dir``: a rerun reuses them)."""
    records = run_cells(
        cells, setting_cell, cell_dir=cell_dir, jobs=jobs, progress=progress, desc=desc
    )
    return [row for r in succeeded(records, "setting(s)") for row in r["rows"]]


def predicted_only(rows: Sequence[Mapping[str, Any]]) -> list[dict[str, Any]]:
    """The predicted numbers' rows (the model sensitivity's table)."""
    return [dict(r) for r in rows if r["kind"] == PREDICTED]


__all__ = ["DELIVERY", "LEARNING", "SettingCell", "run_settings", "setting_cell", "setting_cells"]
