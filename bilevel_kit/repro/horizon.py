"""Beyond the paper: what the greedy horizon costs (docs/reproduction.md, "The horizon study").

The paper names its limited horizon as a limitation ("with more compute power or longer
planning times, our approach can generate more optimal kits", Section VI). With exact optima,
an exact greedy decision (:mod:`bilevel_kit.heuristics.greedy_search`) and the simulator the
toolkit can say how much.

**Part A, planning.** ``greedy-ce`` with ``horizon = N`` (the paper's N, Section IV-A) for
N = 1..12 on the table (one tray), 2 and 5 table units (made by the ``table`` generator of
:mod:`bilevel_kit.generate`) and the instances of ``instances/generated`` (a file identical to a
generated unit instance is not run twice). Per (instance, N): makespan, human idle, kits, the
plan's wall time, the checker's verdict, and the gap ``(makespan - reference) / makespan`` to
the exact ``cpsat`` reference, solved once per instance within a documented time limit: the
proven optimum when CP-SAT's status is optimal (``reference = "optimum"``), else the best lower
bound (``reference = "bound"``: the gap is then an upper bound on the true gap). Every cell is
a :class:`~bilevel_kit.experiments.compare.CompareCell` run by the one cell runner, so the
study resumes where it stopped.

**Part B, simulation.** The exact rolling policy ``cpsat-rolling`` with its ``window`` option
(the same window under supply delays: ``supply_window`` = ``window``) against ``optimized``
(the paper's greedy policy, N = 5) in the same runs (common random numbers) on the Figure 6
setting (10 tables per run, the calibrated timing, one tray) at no supply delay and at Figure 6
delay cells: total time, the paper's idle time, kits and the planning time per decision. Each
(delay cell, policy, window) is a :class:`~bilevel_kit.repro.fig6.Fig6Cell` of one policy.

``quick``: the same experiment on fewer points (the table and 2 units, fewer N and windows,
one delay cell, one replication, a shorter reference limit); every
output says so.
"""

from __future__ import annotations

import json
import time
from collections.abc import Mapping, Sequence
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

import numpy as np

from .. import atomic
from ..errors import UsageError
from ..experiments.cells import Record, is_failed, run_cells_counted, write_json
from ..experiments.compare import CompareCell, compare_cell
from ..experiments.tables import write_csv
from ..sim import POLICIES, TimingModel
from .common import (
    DEFAULT_INSTANCE,
    FIG6_UNITS,
    OPT,
    load_instance,
    participant_seeds,
    run_study_cells,
)
from .fig6 import Fig6Cell, calibrated_timing, fig6_cell
from .horizon_tables import (
    horizon_summary,
    mean_gap_by_n,
    planning_markdown,
    typed_rows,
    window_markdown,
)
from .stats import paired_p

GREEDY, EXACT, ROLLING = "greedy-ce", "cpsat", "cpsat-rolling"

#: Part A: the horizons, the table units, the instance folder, the time limits (s).
HORIZONS: tuple[int, ...] = tuple(range(1, 13))
TABLE_UNITS: tuple[int, ...] = (2, 5)
GENERATED_DIR = DEFAULT_INSTANCE.parent / "generated"
#: Per greedy plan: a cap, not a budget (the slowest plan measured takes a few seconds);
#: past it the remaining kits are single tasks and the row says ``time_limit_hit``.
PLAN_TIME_LIMIT = 60.0
#: The exact reference: CP-SAT (2 workers, warm-started) once per instance.
REFERENCE_TIME_LIMIT = 60.0
#: Part B: the rolling policy's windows, the delay cells (a MAT x MTTF grid, s), replications.
WINDOWS: tuple[int, ...] = (4, 8, 12, 16, 20, 24)
SIM_MATS: tuple[float, ...] = (60.0, 90.0)
SIM_MTTFS: tuple[float, ...] = (60.0,)
#: Replications of Part B: 30 give the paired test 80 % power for a gain of half its paired SD
#: (at 3, the gains under delays could not be told from none).
SIM_REPS = 30
#: ``quick``: the same experiment on fewer points.
QUICK_HORIZONS: tuple[int, ...] = (1, 2, 4, 5, 6, 8, 12)  # 5: the default
QUICK_TABLE_UNITS: tuple[int, ...] = (2,)
QUICK_REFERENCE_TIME_LIMIT = 20.0
QUICK_WINDOWS: tuple[int, ...] = (4, 12, 24)
QUICK_SIM_MATS: tuple[float, ...] = (60.0,)
QUICK_SIM_REPS = 1

#: Columns of ``horizon.csv`` (Part A) and ``horizon_window.csv`` (Part B), in order.
PLANNING_COLUMNS = (
    "instance",
    "instance_file",
    "n_tasks",
    "horizon",
    "makespan",
    "human_idle",
    "n_kits",
    "plan_time_s",
    "time_limit_s",
    "time_limit_hit",
    "beam_epochs",
    "valid",
    "violations",
    "reference",
    "reference_makespan",
    "cpsat_status",
    "cpsat_makespan",
    "cpsat_time_limit_s",
    "cpsat_time_s",
    "gap_pct",
    "quick",
)
WINDOW_COLUMNS = (
    "label",
    "mat",
    "mttf",
    "units",
    "reps",
    "policy",
    "window",
    "total_mean",
    "total_sd",
    "idle_mean",
    "idle_sd",
    "kits_mean",
    "decisions",
    "plan_s_per_decision",
    "total_pct_over_optimized",
    "total_pct_ci_low",
    "total_pct_ci_high",
    "idle_pct_over_optimized",
    "p_paired_total",
    "direction",
    "quick",
)

#: Set once this process has loaded the compiled CE kernel (:func:`_warm_up`).
_WARM: list[bool] = []


# ---------------------------------------------------------------------------------------------
# Part A: planning
# ---------------------------------------------------------------------------------------------


def planning_instances(
    out: Path, units: Sequence[int], generated: bool, instances: Sequence[str] | None = None
) -> list[str]:
    """The instance files of Part A: ``instances`` if given; else the table, its ``units``
    (written under ``out/instances`` by the ``table`` generator) and, with ``generated``, the
    files of ``instances/generated`` that are not one of those units already."""
    if instances is not None:
        missing = [p for p in instances if not Path(p).is_file()]
        if missing:
            raise UsageError(f"instance file(s) not found: {', '.join(missing)}")
        return [str(p) for p in dict.fromkeys(instances)]
    from ..generate import generate

    paths = [str(load_instance(None)[1])]
    docs = []
    for k in units:
        doc = generate("table", k)
        docs.append(doc)
        path = out / "instances" / f"{doc['name']}.json"
        text = json.dumps(doc, indent=2, allow_nan=False) + "\n"
        if not path.exists() or path.read_text() != text:  # same bytes: cells keep their keys
            atomic.write_text(path, text)
        paths.append(str(path))
    if generated:
        for path in sorted(GENERATED_DIR.glob("*.json")):
            if json.loads(path.read_text()) not in docs:
                paths.append(str(path))
    return paths


def _warm_up(instance: str) -> None:
    """Load the compiled CE kernel once per process before a plan is timed (its first call
    costs about a second that is no part of any plan's planning time)."""
    if _WARM:
        return
    from ..heuristics.cross_entropy import CEParams, arrange
    from ..instance import load

    inst = load(instance)
    arrange(
        inst,
        dict(inst.tasks[0].parts),
        rng=0,
        params=CEParams(samples=8, elite=2, max_iter=2, patience=1),
    )
    _WARM.append(True)


def horizon_cell(cell: CompareCell) -> Record:
    """One solve of Part A (greedy-ce at one N, or the cpsat reference): the ``compare``
    record (metrics, status, bound, the checker's verdict) without the plan's layouts, plus
    the kits' tasks and the method's own flags (greedy's time limit and beam epochs, cpsat's
    warm start)."""
    _warm_up(cell.instance)
    rec = compare_cell(cell)
    sol = rec.pop("solution", None) or {}
    extra = sol.get("extra", {})
    rec["kits"] = [k["tasks"] for k in sol.get("kits", [])]
    for k in ("time_limit_hit", "beam_epochs", "rest_capped", "hint_method"):
        if k in extra:
            rec[k] = extra[k]
    return rec


def _reference(rec: Mapping[str, Any]) -> tuple[str | None, float | None]:
    """("optimum", makespan) when CP-SAT proved its plan optimal, else ("bound", bound)."""
    if rec.get("status") == "optimal" and rec.get("makespan") is not None:
        return "optimum", float(rec["makespan"])
    if rec.get("bound") is not None:
        return "bound", float(rec["bound"])
    return None, None


def planning_rows(
    greedy: Sequence[Mapping[str, Any]], exact: Sequence[Mapping[str, Any]], quick: bool
) -> list[dict[str, Any]]:
    """One row per (instance, N): the greedy plan's measures and its gap to the reference."""
    refs = {r["instance_file"]: r for r in exact}
    rows = []
    for g in greedy:
        ref = refs.get(g["instance_file"], {})
        kind, value = _reference(ref)
        ms = g.get("makespan")
        gap = None if value is None or not ms else 100.0 * (ms - value) / ms
        rows.append(
            {
                "instance": g["instance"],
                "instance_file": Path(g["instance_file"]).name,
                "n_tasks": g["n_tasks"],
                "horizon": g["params"]["horizon"],
                "makespan": ms,
                "human_idle": g.get("human_idle"),
                "n_kits": g.get("n_kits"),
                "plan_time_s": g.get("wall_time_s"),
                "time_limit_s": g.get("time_limit"),
                "time_limit_hit": g.get("time_limit_hit"),
                "beam_epochs": g.get("beam_epochs"),
                "valid": g.get("valid"),
                "violations": g.get("violations"),
                "reference": kind,
                "reference_makespan": value,
                "cpsat_status": ref.get("status"),
                "cpsat_makespan": ref.get("makespan"),
                "cpsat_time_limit_s": ref.get("time_limit"),
                "cpsat_time_s": ref.get("wall_time_s"),
                "gap_pct": gap,
                "quick": quick,
            }
        )
    return rows


# ---------------------------------------------------------------------------------------------
# Part B: simulation
# ---------------------------------------------------------------------------------------------


def window_rows(records: Sequence[Mapping[str, Any]], quick: bool) -> list[dict[str, Any]]:
    """One row per (delay cell, policy, window): means, SDs, kits, planning time per decision
    (the policy's wall time over its decisions, amortised over the replications: a shared
    policy object memoises repeated decisions) and the percent improvement over Optimized in
    the same runs, ``100 (Optimized - policy) / Optimized`` (positive: better)."""
    rows: list[dict[str, Any]] = []
    base: dict[str, Mapping[str, Any]] = {}
    for rec in records:
        cell = rec["cell"]
        (pol,) = cell["policies"]
        run = rec["runs"][pol]
        total, idle = np.asarray(run["total_time"], float), np.asarray(run["human_idle"], float)
        decisions = int(np.sum(run["n_kits"]))
        label = "no delay" if cell["mat"] is None else f"MAT {cell['mat']:g}, MTTF {cell['mttf']:g}"
        row = {
            "label": label,
            "mat": cell["mat"],
            "mttf": cell["mttf"],
            "units": cell["units"],
            "reps": len(cell["seeds"]),
            "policy": pol,
            "window": cell["policy_options"].get("window") if pol == ROLLING else None,
            "total_mean": float(total.mean()),
            "total_sd": float(total.std(ddof=1)) if len(total) > 1 else 0.0,
            "idle_mean": float(idle.mean()),
            "idle_sd": float(idle.std(ddof=1)) if len(idle) > 1 else 0.0,
            "kits_mean": float(np.mean(run["n_kits"])),
            "decisions": decisions,
            "plan_s_per_decision": rec["wall_s"][pol] / max(1, decisions),
            "quick": quick,
            "_total": total,
        }
        if pol == OPT:
            base[label] = row
        rows.append(row)
    for row in rows:
        ref = base.get(row["label"])
        if ref is None:
            continue
        for m in ("total", "idle"):
            mb = ref[f"{m}_mean"]
            row[f"{m}_pct_over_optimized"] = 100.0 * (mb - row[f"{m}_mean"]) / mb if mb else None
        if row["policy"] != OPT:
            row.update(_paired_gain(ref["_total"], row["_total"]))
    _holm_directions([r for r in rows if r["policy"] != OPT and "p_paired_total" in r])
    for row in rows:
        del row["_total"]
    return [{k: r.get(k) for k in WINDOW_COLUMNS} for r in rows]


def _paired_gain(base: np.ndarray, other: np.ndarray) -> dict[str, float | None]:
    """The paired improvement over Optimized in % of its mean total time, its 95 % t-interval
    and the paired t-test's p."""
    from scipy.stats import t

    d = 100.0 * (base - other) / float(base.mean())
    n, m = len(d), float(d.mean())
    half = float(t.ppf(0.975, n - 1) * d.std(ddof=1) / np.sqrt(n)) if n > 1 else float("nan")
    return {
        "total_pct_ci_low": m - half if n > 1 else None,
        "total_pct_ci_high": m + half if n > 1 else None,
        "p_paired_total": paired_p(other, base),
    }


def _holm_directions(rows: Sequence[dict[str, Any]]) -> None:
    """``direction``: better / n.s. / worse than Optimized by the paired test after Holm over
    every window and delay cell of the study."""
    from .fig6_stats import direction, holm

    for r, sig in zip(rows, holm([r["p_paired_total"] for r in rows]), strict=True):
        r["direction"] = direction(sig, r["total_pct_over_optimized"])


# ---------------------------------------------------------------------------------------------
# The study
# ---------------------------------------------------------------------------------------------


def format_horizon_markdown(
    rows: Sequence[Mapping[str, Any]], window: Sequence[Mapping[str, Any]], head: str
) -> str:
    """``horizon.md``: ``head``, Part A's tables and, with Part B, its table."""
    out = [head, "", planning_markdown(rows)]
    if window:
        out += ["", "cpsat-rolling against Optimized in the same runs (positive: better):", ""]
        out.append(window_markdown(window))
    return "\n".join(out) + "\n"


def _checked_windows(windows: Sequence[int]) -> tuple[int, ...]:
    for w in windows:
        POLICIES.spec(ROLLING).parse({"window": w})  # a clear error for a bad window
    return tuple(dict.fromkeys(int(w) for w in windows))


def run_horizon(
    out_dir: str | Path = "out/repro/horizon",
    quick: bool = False,
    jobs: int = 1,
    seed: int = 0,
    *,
    horizons: Sequence[int] | None = None,
    instances: Sequence[str] | None = None,
    reference_time_limit: float | None = None,
    windows: Sequence[int] | None = None,
    mats: Sequence[float] | None = None,
    mttfs: Sequence[float] | None = None,
    reps: int | None = None,
    units: int = FIG6_UNITS,
    simulation: bool = True,
    timing: TimingModel | None = None,
    calibration: str | Path | None = None,
    progress: bool | None = None,
) -> dict[str, Any]:
    """The horizon study (module docstring); defaults: the full grid, or the quick one.

    ``instances``: Part A's instance files (default: the table, 2 and 5 units, and
    ``instances/generated``). ``simulation=False`` skips Part B; ``units``: its tables per run
    (Figure 6's 10). ``timing``: Part B's timing model (default: the one calibration;
    ``calibration``: its folder, None for the committed one).
    Cells are saved under ``out_dir/cells/`` (a rerun computes only the missing ones). Writes
    ``horizon.csv``, ``horizon_window.csv`` (with Part B), ``horizon.md``, ``horizon.png`` and
    ``horizon.json``; returns the summary with the output paths under ``"files"`` and the cell
    counts (``computed``, ``reused``, ``failed``).
    """
    t0 = time.perf_counter()
    out = Path(out_dir)
    grid = _grid(quick, jobs, horizons, reference_time_limit, windows, mats, mttfs, reps)
    paths = planning_instances(
        out, QUICK_TABLE_UNITS if quick else TABLE_UNITS, not quick, instances
    )
    part_a = _run_planning(paths, grid, out, quick, seed, jobs, progress)
    part_b, cal = _Part([], 0, 0, []), None
    if simulation:
        part_b, timing, cal = _run_simulation(
            grid, out, quick, seed, units, timing, jobs, progress, calibration
        )
    total = part_a.cells + part_b.cells
    computed = part_a.computed + part_b.computed
    result: dict[str, Any] = {
        "quick": quick,
        "seed": seed,
        "horizons": list(grid.horizons),
        "instances": paths,
        "plan_time_limit_s": PLAN_TIME_LIMIT,
        "reference_time_limit_s": grid.ref_tl,
        "windows": list(grid.windows) if simulation else [],
        "delay_cells": [[a, b] for a in grid.mats for b in grid.mttfs] if simulation else [],
        "reps": grid.reps if simulation else 0,
        "units": units if simulation else None,
        "timing": asdict(timing) if timing is not None else None,
        "calibration": cal,
        "cells": total,
        "computed": computed,
        "reused": total - computed,
        "failed": part_a.failed + part_b.failed,
        "summary": horizon_summary(part_a.rows),
    }
    files = _write_outputs(out, part_a.rows, part_b.rows, quick, grid.ref_tl, (units, grid.reps))
    result["wall_s"] = time.perf_counter() - t0
    result["files"] = {k: str(v) for k, v in {**files, "json": out / "horizon.json"}.items()}
    write_json(out / "horizon.json", result)
    return result


@dataclass(frozen=True)
class _Grid:
    """The points of one run: the arguments given, else the full or the quick defaults."""

    horizons: tuple[int, ...]
    ref_tl: float
    windows: tuple[int, ...]
    mats: tuple[float, ...]
    mttfs: tuple[float, ...]
    reps: int


def _grid(
    quick: bool,
    jobs: int,
    horizons: Sequence[int] | None,
    reference_time_limit: float | None,
    windows: Sequence[int] | None,
    mats: Sequence[float] | None,
    mttfs: Sequence[float] | None,
    reps: int | None,
) -> _Grid:
    """Check the arguments and fill in the defaults (before any cell runs)."""
    if jobs < 1:
        raise UsageError(f"jobs must be >= 1, got {jobs}")
    hs = tuple(sorted(set(horizons or (QUICK_HORIZONS if quick else HORIZONS))))
    if hs[0] < 1:
        raise UsageError(f"horizons must be >= 1, got {hs}")
    return _Grid(
        horizons=hs,
        ref_tl=reference_time_limit
        or (QUICK_REFERENCE_TIME_LIMIT if quick else REFERENCE_TIME_LIMIT),
        windows=_checked_windows(windows or (QUICK_WINDOWS if quick else WINDOWS)),
        mats=tuple(mats or (QUICK_SIM_MATS if quick else SIM_MATS)),
        mttfs=tuple(mttfs or SIM_MTTFS),
        reps=reps or (QUICK_SIM_REPS if quick else SIM_REPS),
    )


@dataclass
class _Part:
    """What one part of the study yields: its table rows, its cell count, the cells computed
    now (the others were reused from ``cells/``) and the failed cells."""

    rows: list[dict[str, Any]]
    cells: int
    computed: int
    failed: list[dict[str, Any]]


def _run_planning(
    paths: Sequence[str],
    grid: _Grid,
    out: Path,
    quick: bool,
    seed: int,
    jobs: int,
    progress: bool | None,
) -> _Part:
    """Part A: the exact reference once per instance, then greedy-ce at each horizon."""
    cells = [CompareCell(p, EXACT, seed=seed, time_limit=grid.ref_tl) for p in paths]
    cells += [
        CompareCell(p, GREEDY, seed=seed, time_limit=PLAN_TIME_LIMIT, params={"horizon": n})
        for p in paths
        for n in grid.horizons
    ]
    recs, computed = run_cells_counted(
        cells, horizon_cell, cell_dir=out / "cells", jobs=jobs, progress=progress, desc="horizon"
    )
    failed = [
        {"key": c.key(), "error": r.get("error")}
        for c, r in zip(cells, recs, strict=True)
        if is_failed(r)
    ]
    ok = [r for r in recs if not is_failed(r)]
    rows = planning_rows(
        [r for r in ok if r["method"] == GREEDY], [r for r in ok if r["method"] == EXACT], quick
    )
    return _Part(rows, len(cells), computed, failed)


def _run_simulation(
    grid: _Grid,
    out: Path,
    quick: bool,
    seed: int,
    units: int,
    timing: TimingModel | None,
    jobs: int,
    progress: bool | None,
    calibration: str | Path | None = None,
) -> tuple[_Part, TimingModel, dict[str, Any] | None]:
    """Part B: at no delay and at each delay cell, ``optimized`` and the rolling policy at
    each window; returns the part, the timing used and its calibration (None when given)."""
    _, table = load_instance(None)
    cal: dict[str, Any] | None = None
    if timing is None:
        timing, cal = calibrated_timing(calibration, table)
    common: dict[str, Any] = {
        "instance": table,
        "seeds": tuple(participant_seeds(seed, grid.reps)),
        "units": units,
        "timing": asdict(timing),
    }
    delays: list[tuple[float | None, float | None]] = [(None, None)]
    delays += [(float(a), float(b)) for a in grid.mats for b in grid.mttfs]
    sim_cells = []
    for mat, mttf in delays:
        sim_cells.append(Fig6Cell(mat=mat, mttf=mttf, policies=(OPT,), **common))
        sim_cells += [
            Fig6Cell(
                mat=mat,
                mttf=mttf,
                policies=(ROLLING,),
                policy_options={"window": w, "supply_window": w},
                **common,
            )
            for w in grid.windows
        ]
    ok, failed, computed = run_study_cells(
        sim_cells, fig6_cell, out, jobs=jobs, progress=progress, desc="horizon sim"
    )
    rows = window_rows(ok, quick)
    return _Part(rows, len(sim_cells), computed, failed), timing, cal


def _write_outputs(
    out: Path,
    rows: Sequence[Mapping[str, Any]],
    sim_rows: Sequence[Mapping[str, Any]],
    quick: bool,
    ref_tl: float,
    runs: tuple[int, int],
) -> dict[str, Path]:
    """The CSVs, the Markdown summary and the figure."""
    from ..plots import save_figure
    from .plots import plot_horizon

    files = {
        "csv": write_csv(
            out / "horizon.csv",
            [{k: r.get(k) for k in PLANNING_COLUMNS} for r in rows],
            exclude=(),
            line_end="\n",
        )
    }
    if sim_rows:
        files["window_csv"] = write_csv(
            out / "horizon_window.csv", sim_rows, exclude=(), line_end="\n"
        )
    head = (
        f"Horizon study{' (QUICK: a reduced run, fewer points)' if quick else ''}: greedy-ce at "
        f"horizon N against the exact cpsat reference (time limit {ref_tl:g} s per instance; "
        "'optimum' where proven, else its lower bound, so the gap is an upper bound); gap = "
        "(makespan - reference) / makespan."
        + (
            f" Simulation: {runs[0]} tables per run, R = {runs[1]} replications, one tray."
            if sim_rows
            else ""
        )
    )
    atomic.write_text(out / "horizon.md", format_horizon_markdown(rows, sim_rows, head))
    files["markdown"] = out / "horizon.md"
    if rows or sim_rows:
        mean = mean_gap_by_n(rows) if len({r["instance_file"] for r in rows}) > 1 else None
        fig = plot_horizon(rows, sim_rows, quick=quick, mean=mean)
        files["figure"] = save_figure(fig, out / "horizon.png")
    return files


__all__ = [
    "HORIZONS",
    "PLANNING_COLUMNS",
    "WINDOWS",
    "WINDOW_COLUMNS",
    "format_horizon_markdown",
    "horizon_cell",
    "horizon_summary",
    "mean_gap_by_n",
    "planning_instances",
    "planning_markdown",
    "planning_rows",
    "run_horizon",
    "typed_rows",
    "window_markdown",
    "window_rows",
]
