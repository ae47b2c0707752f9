"""The one calibration of the reproductions, computed once and committed (docs/reproduction.md).

``bilevel-kit repro calibrate`` runs the declared protocol of :mod:`.calibration` on its own
cohort (10 studies of 18, seed stream ``[seed, 15, 1]``) and a parametric bootstrap of it, and
writes ``calibration.csv`` (the parameters, the bootstrap's spread and the provenance),
``calibration_targets.csv`` (the paper's three targets, their read-off uncertainty, the fit's
residuals) and ``calibration_bootstrap.csv`` (one row per draw). The committed copies in
``paper_repro/results`` are what the user study, Figure 6, the horizon study and the adaptive
study read (:func:`load_calibration`): no study fits its own.

**The bootstrap** (why: the fit rests on three numbers of one study of 18, two of them read off
a figure). Draw b: (1) a synthetic replication of the paper's study from the fitted model
(18 participants, seed stream ``[seed, 15, 3]``) gives its Whole Assembly and Single Task idle
means and its F of total time; (2) each mean gets a uniform read-off error of
``+/- READOFF`` (:data:`.common.READOFF`); (3) the calibration cohort's studies are resampled
with replacement (the fit's own Monte Carlo error); (4) the protocol is refitted to these
targets on that cohort by Newton steps from the point fit. The user study pools fresh studies
over the draws for its intervals "with calibration" (:mod:`.user_study`).
"""

from __future__ import annotations

import time
from collections.abc import Mapping, Sequence
from dataclasses import asdict, dataclass, replace
from pathlib import Path
from typing import Any

import numpy as np

from .. import __version__, atomic
from ..errors import UsageError
from ..experiments.cells import run_cells, write_json
from ..experiments.tables import markdown_lines, read_csv, write_csv
from ..heuristics.cross_entropy import CEParams
from ..instance import load
from ..sim import SimParams, TimingModel
from ..sim.timing import WithinSubjectModel
from .calibration import (
    CALIBRATION,
    WITHIN_CAP,
    Cohort,
    TargetMeans,
    calibrate,
    draw_cohort,
    finite_jacobian,
    resampled,
    study_params,
    study_runs,
)
from .common import (
    CALIBRATION_STUDIES,
    DEFAULT_TARGETS,
    F_TARGET,
    METRICS,
    PAPER_ACTIVE,
    PAPER_N,
    QUICK_CE,
    READOFF,
    RESULTS_DIR,
    SINGLE,
    STUDY_DELIVERY,
    WHOLE,
    config_digest,
    file_digest,
    load_instance,
    succeeded,
)
from .stats import anova_rm

#: The files of a calibration, in its folder.
FILES = {
    "parameters": "calibration.csv",
    "targets": "calibration_targets.csv",
    "bootstrap": "calibration_bootstrap.csv",
}
#: Cohort stream tag of the bootstrap's synthetic replications of the paper's study.
BOOTSTRAP = 3
#: Bootstrap draws (``quick``: a few, for the tests).
DRAWS, QUICK_DRAWS = 50, 3


@dataclass(frozen=True)
class Draw:
    """One bootstrap draw's refitted parameters."""

    robot_scale: float
    kit_overhead_human: float
    within_cv: float


@dataclass(frozen=True)
class Calibration:
    """The fitted timing and participant model, its bootstrap draws and where it came from."""

    robot_scale: float
    kit_overhead_human: float
    within_cv: float
    learning: float
    total_cv: float
    draws: tuple[Draw, ...] = ()
    instance_sha1: str = ""
    quick: bool = False
    source: str = ""

    def timing(self, draw: Draw | None = None, base: TimingModel | None = None) -> TimingModel:
        """``base`` (default: the toolkit's) with the fitted (or the draw's) robot speed and
        ``o_H``."""
        d = draw or self
        return replace(
            base or TimingModel(),
            robot_scale=d.robot_scale,
            kit_overhead_human=d.kit_overhead_human,
        )

    def design(self, draw: Draw | None = None, learning: float | None = None) -> WithinSubjectModel:
        """The within-subject model at the fitted (or the draw's) ``within_cv``."""
        return WithinSubjectModel(
            total_cv=self.total_cv,
            within_cv=(draw or self).within_cv,
            learning=self.learning if learning is None else learning,
        )

    def check(self, instance_path: str | Path) -> None:
        """Refuse a calibration fitted on another version of the instance."""
        if self.instance_sha1 and file_digest(instance_path) != self.instance_sha1:
            raise UsageError(
                f"the calibration in {self.source} was fitted on another version of "
                f"{Path(instance_path).name}: rerun `bilevel-kit repro calibrate` (and copy its "
                "CSVs to paper_repro/results/)"
            )


def load_calibration(
    folder: str | Path | None = None, instance: str | Path | None = None
) -> Calibration:
    """The calibration in ``folder`` (default: the committed one, ``paper_repro/results``),
    checked against ``instance`` (default: the paper's table)."""
    base = Path(folder) if folder is not None else RESULTS_DIR
    path = base / FILES["parameters"]
    if not path.is_file():
        raise UsageError(
            f"no calibration at {path}: run `bilevel-kit repro calibrate` (its folder is "
            "out/repro/calibration) and pass --calibration DIR, or use the committed one"
        )
    values = {r["name"]: r["value"] for r in read_csv(path)}
    draws: tuple[Draw, ...] = ()
    boot = base / FILES["bootstrap"]
    if boot.is_file():
        draws = tuple(
            Draw(float(r["robot_scale"]), float(r["kit_overhead_human"]), float(r["within_cv"]))
            for r in read_csv(boot)
        )
    cal = Calibration(
        robot_scale=float(values["robot_scale"]),
        kit_overhead_human=float(values["kit_overhead_human"]),
        within_cv=float(values["within_cv"]),
        learning=float(values["learning"]),
        total_cv=float(values["total_cv"]),
        draws=draws,
        instance_sha1=values.get("instance_sha1", ""),
        quick=values.get("quick") == "True",
        source=str(base),
    )
    cal.check(instance if instance is not None else load_instance(None)[1])
    return cal


@dataclass(frozen=True)
class CalibrationDraw:
    """One bootstrap draw: refit the protocol to ``targets`` (Whole Assembly idle, Single Task
    idle, F of total time) on the calibration cohort's studies ``index``, by Newton steps from
    ``start`` with the point fit's ``jacobian``."""

    instance: str
    draw: int
    seed: int
    studies: int
    index: tuple[int, ...]
    targets: tuple[float, float, float]
    start: tuple[float, float]
    jacobian: tuple[tuple[float, ...], ...]
    grid: int
    ce: dict[str, Any] | None
    learning: float

    def key(self) -> str:
        return f"draw{self.draw:03d}__{config_digest(self)}"


def calibration_draw(cell: CalibrationDraw) -> dict[str, Any]:
    """The refit of one draw (:class:`CalibrationDraw`)."""
    inst = load(cell.instance)
    cohort = resampled(draw_cohort(cell.seed, cell.studies, PAPER_N, CALIBRATION), list(cell.index))
    wa, st, f = cell.targets
    cal = calibrate(
        inst,
        cohort,
        design=WithinSubjectModel(learning=cell.learning),
        delivery_time=STUDY_DELIVERY,
        targets=(("idle", WHOLE, wa), ("idle", SINGLE, st)),
        f_target=(F_TARGET[0], f),
        grid=cell.grid,
        ce=CEParams(**cell.ce) if cell.ce is not None else None,
        start=cell.start,
        jacobian=np.array(cell.jacobian),
    )
    return {
        "key": cell.key(),
        "draw": cell.draw,
        "targets": list(cell.targets),
        "values": cal["values"],
        "within_cv": cal["within_cv"],
        "at_bound": cal["at_bound"],
        "evaluations": cal["evaluations"],
    }


def _synthetic_targets(
    inst: Any, params: SimParams, design: WithinSubjectModel, seed: int, n: int
) -> np.ndarray:
    """(n, 3): per synthetic replication of the paper's study (``[seed, 15, BOOTSTRAP]``) its
    Whole Assembly and Single Task idle means, each plus a uniform read-off error, and its F
    of total time."""
    cohort = draw_cohort(seed, n, PAPER_N, BOOTSTRAP)
    rows = study_runs(inst, params, design, cohort)
    rng = np.random.default_rng(np.random.SeedSequence([seed, 15, BOOTSTRAP, 1]))
    noise = rng.uniform(-READOFF, READOFF, (n, 2))
    out = np.zeros((n, 3))
    idle = METRICS["idle"]
    for j in range(n):
        sub = [r for r in rows if r["study"] == j]
        for k, cond in enumerate((WHOLE, SINGLE)):
            out[j, k] = np.mean([r[idle] for r in sub if r["condition"] == cond]) + noise[j, k]
        out[j, 2] = anova_rm(sub, METRICS[F_TARGET[0]])["F"] or np.inf
    return out


def _draw_cells(
    cal: Mapping[str, Any], jac: np.ndarray, synth: np.ndarray, setup: _Setup
) -> list[CalibrationDraw]:
    """One cell per draw: its synthetic targets and its resampled calibration studies."""
    rng = np.random.default_rng(np.random.SeedSequence([setup.seed, 15, BOOTSTRAP, 2]))
    index = rng.integers(0, setup.studies, (len(synth), setup.studies))
    return [
        CalibrationDraw(
            instance=setup.path,
            draw=b,
            seed=setup.seed,
            studies=setup.studies,
            index=tuple(int(i) for i in index[b]),
            targets=(round(synth[b, 0], 6), round(synth[b, 1], 6), round(synth[b, 2], 6)),
            start=(cal["values"]["robot_scale"], cal["values"]["kit_overhead_human"]),
            jacobian=tuple(tuple(round(float(v), 9) for v in row) for row in jac),
            grid=setup.grid,
            ce=asdict(setup.ce) if setup.ce is not None else None,
            learning=setup.learning,
        )
        for b in range(len(synth))
    ]


@dataclass(frozen=True)
class _Setup:
    """The run's settings: instance, seed, calibration studies, grid, CE, draws, learning, quick."""

    path: str
    seed: int
    studies: int
    grid: int
    ce: CEParams | None
    draws: int
    learning: float
    quick: bool


def run_calibration(
    out_dir: str | Path = "out/repro/calibration",
    quick: bool = False,
    seed: int = 0,
    jobs: int = 1,
    *,
    draws: int | None = None,
    instance: str | Path | None = None,
    learning: float = WithinSubjectModel().learning,
    progress: bool | None = None,
) -> dict[str, Any]:
    """Fit the protocol once and bootstrap it (module docstring); ``quick``: 2 calibration
    studies, a coarse grid, a small CE and 3 draws (for the tests). Draws are cells of the one
    cell runner, saved under ``out_dir/cells`` (a rerun computes only the missing ones) and run
    on ``jobs`` workers. Writes the three CSVs, ``calibration.md`` and ``calibration.json``."""
    t0 = time.perf_counter()
    inst, path = load_instance(instance)
    setup = _Setup(
        path,
        seed,
        2 if quick else CALIBRATION_STUDIES,
        3 if quick else 5,
        QUICK_CE if quick else None,
        draws if draws is not None else (QUICK_DRAWS if quick else DRAWS),
        learning,
        quick,
    )
    if setup.draws < 2:
        raise UsageError(f"need at least 2 bootstrap draws, got {setup.draws}")
    cohort = draw_cohort(seed, setup.studies, PAPER_N, CALIBRATION)
    cal = calibrate(
        inst,
        cohort,
        design=WithinSubjectModel(learning=learning),
        delivery_time=STUDY_DELIVERY,
        grid=setup.grid,
        ce=setup.ce,
    )
    design = WithinSubjectModel(within_cv=cal["within_cv"], learning=learning)
    timing = replace(TimingModel(), **cal["values"])
    jac = _jacobian(inst, cohort, design, cal)
    params = study_params(timing, None, setup.ce, STUDY_DELIVERY)
    synth = _synthetic_targets(inst, params, design, seed, setup.draws)
    cells = _draw_cells(cal, jac, synth, setup)
    records = run_cells(
        cells,
        calibration_draw,
        cell_dir=Path(out_dir) / "cells",
        jobs=jobs,
        progress=progress,
        desc="calibration draws",
    )
    succeeded(records, "bootstrap draw(s)")
    result = _result(cal, design, records, setup, inst.name)
    result["wall_s"] = time.perf_counter() - t0
    _write(Path(out_dir), result)
    return result


def _jacobian(
    inst: Any, cohort: Cohort, design: WithinSubjectModel, cal: Mapping[str, Any]
) -> np.ndarray:
    """d (Whole Assembly idle, Single Task idle) / d (robot_scale, o_H) at the fit."""
    model = TargetMeans(inst, cohort, design, TimingModel(), None, STUDY_DELIVERY, DEFAULT_TARGETS)
    return finite_jacobian(model, np.array([cal["values"][n] for n in model.names]))


def _quantiles(v: Sequence[float]) -> dict[str, float]:
    a = np.asarray(v, float)
    sd = float(a.std(ddof=1)) if len(a) > 1 else 0.0
    return {"sd": sd, "low": float(np.quantile(a, 0.025)), "high": float(np.quantile(a, 0.975))}


def _result(
    cal: Mapping[str, Any],
    design: WithinSubjectModel,
    records: Sequence[Mapping[str, Any]],
    setup: _Setup,
    name: str,
) -> dict[str, Any]:
    """The summary: parameter rows, target rows, draw rows and the provenance."""
    draws = [
        {
            "draw": r["draw"],
            "target_wa_idle": r["targets"][0],
            "target_st_idle": r["targets"][1],
            "target_f_total": r["targets"][2],
            "robot_scale": r["values"]["robot_scale"],
            "kit_overhead_human": r["values"]["kit_overhead_human"],
            "within_cv": r["within_cv"],
            "at_bound": r["at_bound"],
        }
        for r in sorted(records, key=lambda r: r["draw"])
    ]
    return {
        "quick": setup.quick,
        "seed": setup.seed,
        "parameters": _parameter_rows(cal, design, draws, setup),
        "targets": _target_rows(cal, draws),
        "draws": draws,
        "instance": name,
        "evaluations": cal["evaluations"] + sum(r["evaluations"] for r in records),
    }


def _parameter_rows(
    cal: Mapping[str, Any],
    design: WithinSubjectModel,
    draws: Sequence[Mapping[str, Any]],
    setup: _Setup,
) -> list[dict[str, Any]]:
    """``calibration.csv``: name, value, role, the bootstrap's SD and 95 % range, source."""
    coh = f"calibration cohort: seed {setup.seed}, {setup.studies} studies x {PAPER_N}"
    at = f"{sum(bool(d['at_bound']) for d in draws)} of {len(draws)} draws at the bound"
    rows: list[tuple[str, Any, str, str]] = [
        ("robot_scale", cal["values"]["robot_scale"], "fitted", f"step 1: idle means; {coh}"),
        ("kit_overhead_human", cal["values"]["kit_overhead_human"], "fitted", "step 1"),
        ("within_cv", cal["within_cv"], "fitted", f"step 2: median F of total time; {at}"),
        (
            "within_cv_bound",
            cal["max_within_cv"],
            "derived",
            f"{WITHIN_CAP:g} x the SD that leaves the participant's speed no variance",
        ),
        ("at_bound", cal["at_bound"], "derived", "step 2 ended at its bound"),
        ("total_cv", design.total_cv, "paper", f"{PAPER_ACTIVE[1]} / {PAPER_ACTIVE[0]} s, Sec. VI"),
        ("learning", design.learning, "assumed", "per session; not reported"),
        ("speed_sd", design.speed_sd, "derived", "the participant's own speed (log SD)"),
        ("delivery_time", STUDY_DELIVERY, "declared", "co-located study"),
        ("readoff", READOFF, "derived", "half-width of a Fig. 5 read-off (common.READOFF)"),
        ("draws", len(draws), "bootstrap", "parametric bootstrap draws"),
    ]
    boot = {
        n: _quantiles([d[n] for d in draws])
        for n in ("robot_scale", "kit_overhead_human", "within_cv")
    }
    out = [
        {"name": n, "value": v, "role": role, **boot.get(n, {}), "source": src}
        for n, v, role, src in rows
    ]
    cmd = "bilevel-kit repro calibrate" + (" --quick" if setup.quick else "")
    prov = {
        "command": f"{cmd} --seed {setup.seed}",
        "instance": Path(setup.path).name,
        "instance_sha1": file_digest(setup.path),
        "package_version": __version__,
        "quick": setup.quick,
    }
    out += [{"name": k, "value": v, "role": "provenance"} for k, v in prov.items()]
    return out


def _target_rows(
    cal: Mapping[str, Any], draws: Sequence[Mapping[str, Any]]
) -> list[dict[str, Any]]:
    """``calibration_targets.csv``: the three targets, their read-off half-width, the fit's
    value and residual, and the spread of the bootstrap's synthetic targets."""
    synth = {
        "idle whole-assembly": "target_wa_idle",
        "idle single-task": "target_st_idle",
        "total ": "target_f_total",
    }
    out = []
    for t in cal["targets"]:
        key = synth[f"{t['metric']} {t['condition']}"]
        q = _quantiles([d[key] for d in draws])
        out.append(
            {
                "quantity": "mean" if t["condition"] else "F",
                "metric": t["metric"],
                "condition": t["condition"],
                "paper": t["paper"],
                "readoff": READOFF if t["condition"] else 0.0,
                "fitted": t["fitted"],
                "residual": t["residual"],
                "bootstrap_low": q["low"],
                "bootstrap_high": q["high"],
            }
        )
    return out


def _write(out: Path, result: dict[str, Any]) -> None:
    files = {
        name: write_csv(out / file, result[key], exclude=(), line_end="\n")
        for name, file, key in (
            ("parameters_csv", FILES["parameters"], "parameters"),
            ("targets_csv", FILES["targets"], "targets"),
            ("bootstrap_csv", FILES["bootstrap"], "draws"),
        )
    }
    quick = " (QUICK: a reduced run, never committed)" if result["quick"] else ""
    body = [
        [str(r["name"]), str(r["value"]), str(r["role"]), str(r.get("source", ""))]
        for r in result["parameters"]
    ]
    text = f"Calibration{quick}\n\n" + "\n".join(
        markdown_lines(["name", "value", "role", "source"], body)
    )
    atomic.write_text(out / "calibration.md", text + "\n")
    files["markdown"] = out / "calibration.md"
    files["json"] = out / "calibration.json"
    result["files"] = {k: str(v) for k, v in files.items()}
    write_json(out / "calibration.json", result)


__all__ = ["Calibration", "Draw", "load_calibration", "run_calibration"]
