"""Figure 6 of the paper (Section V-B): percent improvement of Optimized over Single Task and
Whole Assembly on a MAT x MTTF grid of feeder delays, with the paper's significance marks
(docs/reproduction.md).

Each grid point is a :class:`Fig6Cell`, a pure function of its configuration
(:func:`fig6_cell`) run through the one resumable cell runner
(:func:`bilevel_kit.experiments.cells.run_cells_counted`): a rerun computes only the cells
whose file is missing, and the cells run wherever the sweep session says (docs/cluster.md).
"""

from __future__ import annotations

import time
from collections.abc import Mapping, Sequence
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from .. import atomic
from ..errors import UsageError
from ..experiments.cells import write_json
from ..experiments.tables import write_csv
from ..heuristics.cross_entropy import CEParams
from ..instance import Instance, load
from ..options import NoOptions
from ..plots import save_figure
from ..sim import POLICIES, SimParams, TimingModel, replicate
from .calibrated import load_calibration
from .common import (
    CONDITIONS,
    FIG6_GRID,
    FIG6_REPAIR,
    FIG6_REPS,
    FIG6_SUPPLIED,
    FIG6_UNITS,
    LABELS,
    METRIC_LABELS,
    METRICS,
    OPT,
    QUICK_MATS,
    QUICK_MTTFS,
    QUICK_REPS,
    SINGLE,
    WHOLE,
    announce,
    config_digest,
    load_instance,
    paper_idle,
    participant_seeds,
    run_study_cells,
)
from .fig6_stats import add_directions, pooled_sd, reps_for_power, trends, verdicts
from .stats import oneway, paired_p, stars, tukey_pairs


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
    trays: int | str | None = None
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
        return f"{self.label}__{config_digest(self)}"

    def sim_params(self, policy: str | None = None) -> SimParams:
        """The run parameters of the cell; for ``policy``, its options only if it takes any
        (``policy_options`` are meant for the extra policies, e.g. cpsat-rolling's time
        limit, not for the paper's three, which take none)."""
        options = dict(self.policy_options)
        if policy is not None and POLICIES.spec(policy).options_class() is NoOptions:
            options = {}
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
            trays=self.trays,
            policy_options=options,
        )


def fig6_cell(cell: Fig6Cell) -> dict[str, Any]:
    """Simulate one cell: a pure function of the cell returning a plain record (per policy
    and replication: total time, paper idle, kits, waits). Wall times are kept apart under
    ``wall_s`` (the only part that differs between two computations)."""
    inst = load(cell.instance)
    runs: dict[str, dict[str, list[Any]]] = {}
    wall: dict[str, float] = {}
    for pol in cell.policies:
        t0 = time.perf_counter()
        recs = replicate(inst, pol, cell.sim_params(pol), seeds=cell.seeds)
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


def comparisons(policies: Sequence[str]) -> list[tuple[str, str]]:
    """(subject, baseline) pairs: the paper's two, plus "X over optimized" for extra policies."""
    pairs = [(OPT, b) for b in (SINGLE, WHOLE) if OPT in policies and b in policies]
    pairs += [(x, OPT) for x in policies if x not in CONDITIONS and OPT in policies]
    return pairs


def _policy_stats(row: dict[str, Any], runs: Mapping[str, Mapping[str, Any]]) -> None:
    """Per-policy means and SDs of each metric, and the mean number of kits."""
    for m, col in METRICS.items():
        for p in runs:
            v = np.asarray(runs[p][col], float)
            row[f"{m}_mean:{p}"] = float(v.mean())
            row[f"{m}_sd:{p}"] = float(v.std(ddof=1)) if len(v) > 1 else 0.0
    for p in runs:
        row[f"kits_mean:{p}"] = float(np.mean(runs[p]["n_kits"]))


def _family_tests(
    row: dict[str, Any], runs: Mapping[str, Mapping[str, Any]]
) -> dict[tuple[str, str], tuple[float | None, dict[tuple[str, str], Any]]]:
    """One-way ANOVA and Tukey HSD over the paper's policies and over all of them."""
    pols = list(runs)
    families = {"paper": [p for p in CONDITIONS if p in pols], "all": pols}
    tests: dict[tuple[str, str], tuple[float | None, dict[tuple[str, str], Any]]] = {}
    for fam, members in families.items():
        for m, col in METRICS.items():
            groups = [np.asarray(runs[p][col], float) for p in members]
            f, pv = oneway(groups)
            row[f"anova_F_{m}:{fam}"] = f
            row[f"anova_p_{m}:{fam}"] = pv
            vals = [x for g in groups for x in g]
            labels = [p for p, g in zip(members, groups, strict=True) for _ in g]
            tk = tukey_pairs(vals, labels) if len(groups) > 1 and len(vals) > len(groups) else {}
            tests[(fam, m)] = (pv, tk)
    return tests


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
    cell = record["cell"]
    runs = record["runs"]
    row: dict[str, Any] = {
        "label": "reference"
        if cell["mat"] is None
        else f"MAT {cell['mat']:g}, MTTF {cell['mttf']:g}",
        "mat": cell["mat"],
        "mttf": cell["mttf"],
        "units": cell["units"],
        "reps": len(cell["seeds"]),
    }
    _policy_stats(row, runs)
    tests = _family_tests(row, runs)
    for subj, base in comparisons(list(runs)):
        fam = "paper" if subj in CONDITIONS else "all"
        for m in METRICS:
            mb, ms = row[f"{m}_mean:{base}"], row[f"{m}_mean:{subj}"]
            pct = 100.0 * (mb - ms) / mb if mb > 0 else None
            pv, tk = tests[(fam, m)]
            p = tk.get((subj, base), {}).get("p")
            name = f"{subj}_over_{base}"
            row[f"pct_{m}:{name}"] = pct
            row[f"p_tukey_{m}:{name}"] = p
            row[f"stars_{m}:{name}"] = stars(p) if pv is not None and pv < 0.05 else ""
            a, b = np.asarray(runs[subj][METRICS[m]]), np.asarray(runs[base][METRICS[m]])
            row[f"p_paired_{m}:{name}"] = paired_p(a, b)
    return row


def format_fig6_markdown(rows: Sequence[Mapping[str, Any]]) -> str:
    """Each comparison as a MAT x MTTF Markdown table of ``% stars`` and the paired test's
    direction (:func:`.report_sim.fig6_markdown` of :func:`improvements`)."""
    from .report_sim import fig6_markdown

    return fig6_markdown(improvements(rows))


def _grid_defaults(
    quick: bool,
    reps: int | None,
    mats: Sequence[float] | None,
    mttfs: Sequence[float] | None,
    units: int | None,
    ce: CEParams | None,
) -> tuple[int, Sequence[float], Sequence[float], int, CEParams | None]:
    """The paper's grid, or the reduced one with ``quick``, where not given."""
    if reps is None:
        reps = QUICK_REPS if quick else FIG6_REPS
    if quick:  # the same experiment (10 tables, the paper's CE), fewer cells and replications
        mats = QUICK_MATS if mats is None else mats
        mttfs = QUICK_MTTFS if mttfs is None else mttfs
    mats = FIG6_GRID if mats is None else mats
    mttfs = FIG6_GRID if mttfs is None else mttfs
    units = FIG6_UNITS if units is None else units
    return reps, mats, mttfs, units, ce


def improvements(rows: Sequence[Mapping[str, Any]]) -> list[dict[str, Any]]:
    """Long format, one row per panel and cell: the percent improvement, the Tukey p, the
    paper's stars, the paired-test p, the direction under each test and the replications the
    paper's test would need for 80 % power (:mod:`.fig6_stats`; ``fig6_improvements.csv``)."""
    pols = [k.split(":", 1)[1] for k in rows[0] if k.startswith("total_mean:")]
    out: list[dict[str, Any]] = []
    for subj, base in comparisons(pols):
        name = f"{subj}_over_{base}"
        family = [p for p in CONDITIONS if p in pols] if subj in CONDITIONS else pols
        for m in METRICS:
            panel = f"{METRIC_LABELS[m]}, {LABELS.get(subj, subj)} over {LABELS.get(base, base)}"
            for r in rows:
                pct = r[f"pct_{m}:{name}"]
                diff = r[f"{m}_mean:{base}"] - r[f"{m}_mean:{subj}"]
                out.append(
                    {
                        "panel": panel,
                        "mat": r["mat"],
                        "mttf": r["mttf"],
                        "reps": r["reps"],
                        "units": r["units"],
                        "pct": None if pct is None else round(pct, 3),
                        "p_tukey": r[f"p_tukey_{m}:{name}"],
                        "anova_p": r[f"anova_p_{m}:{'paper' if subj in CONDITIONS else 'all'}"],
                        "stars": r[f"stars_{m}:{name}"],
                        "p_paired": r[f"p_paired_{m}:{name}"],
                        "r80": reps_for_power(diff, pooled_sd(r, m, family)),
                    }
                )
    add_directions(out)
    return out


def _check_fig6(
    inst: Instance, policies: Sequence[str], jobs: int, policy_options: Mapping[str, Any]
) -> None:
    """Fail early: unknown policies, missing fed types, bad ``jobs`` or policy options."""
    unknown = [p for p in policies if p not in POLICIES]
    if unknown:
        raise UsageError(f"unknown policy(ies) {unknown}; policies are {', '.join(POLICIES)}")
    missing = [t for t in FIG6_SUPPLIED if t not in inst.part_types]
    if missing:
        raise UsageError(f"the instance has no part type(s) {missing} to feed")
    if jobs < 1:
        raise UsageError(f"jobs must be >= 1, got {jobs}")
    for p in policies:
        spec = POLICIES.spec(p)
        if spec.options_class() is not NoOptions:
            spec.parse(policy_options)


def _write_fig6_outputs(
    out: Path,
    rows: Sequence[Mapping[str, Any]],
    records: Sequence[Mapping[str, Any]],
    policies: Sequence[str],
    quick: bool,
) -> dict[str, Path]:
    """The CSVs (cells, improvements, verdicts, trends), Markdown and figures of Figure 6 (one
    extra figure per extra policy)."""
    from .plots import plot_fig6
    from .report_sim import fig6_markdown, trends_markdown, verdicts_markdown

    long_rows = improvements(rows)
    verdict = verdicts(long_rows)
    trend = trends(records, comparisons(policies))
    files = {
        "csv": write_csv(out / "fig6_cells.csv", rows, exclude=(), line_end="\n"),
        "markdown": out / "fig6.md",
        "figure": save_figure(plot_fig6(rows, quick=quick), out / "fig6.png", dpi=130),
    }
    for name, table in (("improvements", long_rows), ("verdicts", verdict), ("trends", trend)):
        if table:
            path = out / f"fig6_{name}.csv"
            files[f"{name}_csv"] = write_csv(path, table, exclude=(), line_end="\n")
    r0 = rows[0]
    head = (
        f"Figure 6{' (QUICK: a reduced run, fewer cells and replications)' if quick else ''}: "
        f"R = {r0['reps']} replications, {r0['units']} tables per run. \\* p < .05, "
        "\\*\\* p < .001: one-way ANOVA over the three policies, then Tukey HSD (per cell, no "
        "correction over the cells, as the paper); ▲/▼: significantly better/worse by the "
        "paired t-test after Holm over the panel's cells.\n\n"
    )
    parts = [head + fig6_markdown(long_rows), verdicts_markdown(verdict)]
    if trend:
        parts.append(trends_markdown(trend))
    atomic.write_text(out / "fig6.md", "\n\n".join(parts) + "\n")
    for x in policies:
        if x not in CONDITIONS and OPT in policies:
            fig = plot_fig6(rows, subject=x, baselines=(OPT,), quick=quick)
            path = out / f"fig6_{x}_over_optimized.png"
            files[f"figure_{x}"] = save_figure(fig, path, dpi=130)
    return files


def calibrated_timing(
    calibration: str | Path | None = None, instance: str | Path | None = None
) -> tuple[TimingModel, dict[str, Any]]:
    """Figure 6's timing: the one calibration's robot speed and ``o_H``
    (:func:`.calibrated.load_calibration`, default the committed one; fitted on the co-located
    study, d = 0), one participant per table with the paper's total SD. Returns the timing and
    the calibration's values and source (for the run's JSON)."""
    cal = load_calibration(calibration, instance)
    keep = ("robot_scale", "kit_overhead_human", "within_cv", "instance_sha1", "quick", "source")
    return cal.timing(), {k: getattr(cal, k) for k in keep}


def _common(
    path: str,
    seed: int,
    reps: int,
    policies: Sequence[str],
    units: int,
    delivery_time: float | None,
    trays: int | str | None,
    timing: TimingModel,
    ce: CEParams | None,
) -> dict[str, Any]:
    """The fields every cell of a run shares."""
    return {
        "instance": path,
        "seeds": tuple(participant_seeds(seed, reps)),
        "policies": tuple(policies),
        "units": int(units),
        "delivery_time": delivery_time,
        "trays": trays,
        "timing": asdict(timing),
        "ce": asdict(ce) if ce is not None else None,
    }


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
    trays: int | str | None = None,
    timing: TimingModel | None = None,
    calibration: str | Path | None = None,
    ce: CEParams | None = None,
    policy_options: Mapping[str, Any] | None = None,
    progress: bool | None = None,
) -> dict[str, Any]:
    """Figure 6: MAT x MTTF grid for the leg and foot feeders plus a no-delay reference cell.

    Defaults: MAT, MTTF in {30, 60, 90, 120} s, 10 tables per run, ``reps`` = 30 replications
    (``None``: 30, or 3 when ``quick``), the instance's delivery time (``delivery_time``
    overrides it), the instance's trays (the study's table: one; ``trays`` overrides it, e.g.
    ``"unlimited"``), and the timing of the one calibration (:func:`calibrated_timing`:
    ``calibration`` a folder, default the committed one; or pass ``timing``).
    ``quick``: the same experiment, smaller: MAT {30, 120} x MTTF {60}, 3 replications (still
    10 tables per run and the paper's CE); every output says it was quick.
    ``policies``: the paper's three by default; an extra registered policy (e.g.
    ``"cpsat-rolling"``) adds "X over optimized" comparisons and a figure.
    ``seed`` picks the replication seeds (the same in every cell: common random numbers).

    Cells are saved one JSON each under ``out_dir/cells/`` as they finish; a rerun computes
    only the missing ones (``jobs`` > 1: a Dask ``LocalCluster``; inside
    :func:`~bilevel_kit.experiments.cells.sweep_session`, its executor). Writes
    ``fig6_cells.csv``, ``fig6.md``, ``fig6.png`` (four heatmaps),
    ``fig6_<X>_over_optimized.png`` per extra policy and ``fig6.json``. Returns the summary
    dict (rows, calibration, files, counts). Cells that raised are listed under ``"failed"``
    (their error records are in ``cells/``, retried on a rerun); then only the CSV of the
    other rows and ``fig6.json`` are written.
    """
    t0 = time.perf_counter()
    inst, path = load_instance(instance)
    out = Path(out_dir)
    reps, mats, mttfs, units, ce = _grid_defaults(quick, reps, mats, mttfs, units, ce)
    policies = tuple(dict.fromkeys(policies))
    _check_fig6(inst, policies, jobs, policy_options or {})
    cal: dict[str, Any] | None = None
    if timing is None:
        timing, cal = calibrated_timing(calibration, path)
    common = _common(path, seed, reps, policies, units, delivery_time, trays, timing, ce)
    common["policy_options"] = dict(policy_options or {})
    cells = [Fig6Cell(mat=None, mttf=None, **common)]
    cells += [Fig6Cell(mat=float(a), mttf=float(b), **common) for a in mats for b in mttfs]
    if progress is not False:
        announce("fig6", cells, out / "cells", f"R = {reps}, {len(policies)} policies")
    records, failed, computed = run_study_cells(
        cells, fig6_cell, out, jobs=jobs, progress=progress, desc="fig6 cells"
    )
    rows = [{"quick": quick, **summarize_cell(r)} for r in records]
    result = {
        "instance": inst.name,
        "quick": quick,
        "seed": seed,
        "reps": reps,
        "units": units,
        "mats": list(mats),
        "mttfs": list(mttfs),
        "delivery_time": delivery_time if delivery_time is not None else inst.delivery_time,
        "trays": inst.with_overrides(trays=trays).trays,
        "policies": list(policies),
        "timing": asdict(timing),
        "calibration": cal,
        "cells": len(cells),
        "computed": computed,
        "reused": len(cells) - computed,
        "failed": failed,
        "simulation_wall_s": {p: sum(r["wall_s"].get(p, 0.0) for r in records) for p in policies},
        "rows": rows,
    }
    if failed:
        files = {"csv": write_csv(out / "fig6_cells.csv", rows, exclude=(), line_end="\n")}
    else:
        files = _write_fig6_outputs(out, rows, records, policies, quick)
    result["wall_s"] = time.perf_counter() - t0
    result["files"] = {k: str(v) for k, v in {**files, "json": out / "fig6.json"}.items()}
    write_json(out / "fig6.json", result)
    return result
