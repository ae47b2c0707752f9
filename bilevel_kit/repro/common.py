"""Constants and small helpers shared by the reproductions: the paper's numbers
(docs/paper-data.md), the conditions, the instance, participant seeds and the paper's idle time.
"""

from __future__ import annotations

import hashlib
import json
import sys
from collections.abc import Mapping, Sequence
from dataclasses import asdict
from pathlib import Path
from typing import Any

from ..errors import UsageError
from ..experiments.cells import Record, is_failed, run_cells_counted, split_failed
from ..heuristics.cross_entropy import CEParams
from ..instance import Instance, load
from ..sim import SimulationError

#: What ``bilevel_kit.repro`` re-exports from here.
__all__ = [
    "CONDITIONS",
    "DEFAULT_FREE",
    "DEFAULT_INSTANCE",
    "DEFAULT_TARGETS",
    "FIG6_GRID",
    "FIG6_REPAIR",
    "FIG6_REPS",
    "FIG6_SUPPLIED",
    "FIG6_UNITS",
    "LABELS",
    "METRICS",
    "METRIC_LABELS",
    "OPT",
    "PAPER_ACTIVE",
    "PAPER_CI",
    "PAPER_F",
    "PAPER_MEANS",
    "PAPER_N",
    "QUICK_CE",
    "QUICK_MATS",
    "QUICK_MTTFS",
    "QUICK_REPS",
    "QUICK_UNITS",
    "READOFF",
    "RESULTS_DIR",
    "SHORT",
    "SINGLE",
    "WHOLE",
    "announce",
    "file_digest",
    "load_instance",
    "paper_idle",
    "participant_seeds",
]

#: The paper's table (the repository's copy; ``paper_repro`` lives next to it).
DEFAULT_INSTANCE = Path(__file__).resolve().parents[2] / "instances" / "hrc_table.json"
#: The committed results of the reproductions (``paper_repro/results``), among them the one
#: calibration every study reads (:mod:`.calibrated`).
RESULTS_DIR = Path(__file__).resolve().parents[2] / "paper_repro" / "results"

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


def _readoff() -> float:
    """Half-width (s) of the read-off uncertainty of a Fig. 5 bar: the largest gap between the
    difference of two read-off bars and the exact centre of the paper's Tukey interval for that
    difference (four checks: ST-WA and OPT-WA, total and idle; a Tukey interval is centred on
    the difference of the two means)."""
    gaps = [
        abs(PAPER_MEANS[m][c] - PAPER_MEANS[m][WHOLE] - sum(PAPER_CI[m][c]) / 2)
        for m in PAPER_CI
        for c in PAPER_CI[m]
    ]
    return max(gaps)


#: Read-off half-width of the Fig. 5 means (s): a paper mean ``v`` stands for ``[v - h, v + h]``.
READOFF = _readoff()

#: (metric, condition, paper value) the calibration fits; the rest are predictions.
DEFAULT_TARGETS: tuple[tuple[str, str, float], ...] = (
    ("idle", WHOLE, PAPER_MEANS["idle"][WHOLE]),
    ("idle", SINGLE, PAPER_MEANS["idle"][SINGLE]),
)
#: The within-participant fitting target: the paper's repeated-measures F of total task time.
F_TARGET: tuple[str, float] = ("total", PAPER_F["total"])
#: The co-located study's delivery time: "the absence of delivery distance (the human and robot
#: were co-located across a table)", Section VI. Declared, not fitted.
STUDY_DELIVERY = 0.0
#: Calibration cohort (its own seed stream) and evaluation cohort sizes, in studies of 18.
CALIBRATION_STUDIES = 10
EVALUATION_STUDIES = 200
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
#: ``quick=True`` for Figure 6: the same experiment (10 tables per run, the paper's CE) on a
#: reduced grid with 3 replications. ``QUICK_CE`` is the user study's quick CE (tests only).
QUICK_MATS = (30.0, 120.0)
QUICK_MTTFS = (60.0,)
QUICK_UNITS = FIG6_UNITS
QUICK_REPS = 3
QUICK_CE = CEParams(samples=40, elite=8, max_iter=15, patience=3)

METRICS = {"total": "total_time", "idle": "human_idle"}
METRIC_LABELS = {"total": "total task time", "idle": "human idle time"}


def load_instance(instance: str | Path | Instance | None) -> tuple[Instance, str]:
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


def file_digest(path: str | Path) -> str:
    """The first 12 hex digits of a file's SHA-1: cell keys and the calibration's provenance
    name an instance by its content, not its path."""
    return hashlib.sha1(Path(path).read_bytes()).hexdigest()[:12]


def config_digest(cell: Any) -> str:
    """The first 10 hex digits of the SHA-1 of a cell dataclass's configuration, its
    ``instance`` file named by content (:func:`file_digest`), not by path: what a resumable
    cell's key ends with, so a moved checkout still resumes and a changed file is a new cell."""
    cfg = {k: v for k, v in asdict(cell).items() if k != "instance"}
    cfg["instance_sha1"] = file_digest(cell.instance)
    blob = json.dumps(cfg, sort_keys=True, default=str).encode()
    return hashlib.sha1(blob).hexdigest()[:10]


def succeeded(records: Sequence[dict[str, Any]], what: str) -> Sequence[dict[str, Any]]:
    """``records`` when no cell failed, else a :class:`~bilevel_kit.sim.SimulationError`
    counting the failed ``what`` (e.g. "study(ies)") with the first one's error: a study's
    numbers are all its cells' or none."""
    failed = [r for r in records if is_failed(r)]
    if failed:
        raise SimulationError(f"{len(failed)} {what} failed: {failed[0]['error']}")
    return records


def run_study_cells(
    cells: Sequence[Any],
    fn: Any,
    out: Path,
    *,
    jobs: int,
    progress: bool | None,
    desc: str,
) -> tuple[list[Record], list[Record], int]:
    """A study's cells run (resumable under ``out/cells``): the records that ran, the key and
    error of each failed one, and how many cells ran now: a study lists its failed cells
    beside its numbers (docs/cluster.md, exit codes)."""
    records, computed = run_cells_counted(
        cells, fn, cell_dir=out / "cells", jobs=jobs, progress=progress, desc=desc
    )
    ok, failed = split_failed(records)
    return ok, failed, computed


def study_summary(
    out: Path,
    name: str,
    ran: tuple[list[Record], list[Record], int],
    rows: list[dict[str, Any]],
    files: Mapping[str, Path],
    *,
    t0: float,
    quick: bool,
    seed: int,
    cells: int,
) -> dict[str, Any]:
    """A study's summary, written to ``out/NAME.json`` and returned: its settings, the cells
    that ran (:func:`run_study_cells`'s ``ran``), its rows, the CPU time summed over the cells
    (each records its own ``cpu_s``), the wall time since ``t0`` and every file it wrote."""
    import time

    from ..experiments.cells import write_json

    ok, failed, computed = ran
    result: dict[str, Any] = {
        "quick": quick,
        "seed": seed,
        "cells": cells,
        "computed": computed,
        "failed": failed,
        "rows": rows,
        "cpu_s": sum(float(r.get("cpu_s", 0.0)) for r in ok),
        "wall_s": time.perf_counter() - t0,
    }
    result["files"] = {k: str(v) for k, v in {**files, "json": out / f"{name}.json"}.items()}
    write_json(out / f"{name}.json", result)
    return result


def announce(what: str, cells: Sequence[Any], cell_dir: Path, detail: str) -> None:
    """One line on stderr before a sweep: how many cells there are and how many must be
    computed (the rest are read back), so a long run is never silent before its bar."""
    todo = sum(not (cell_dir / f"{c.key()}.json").exists() for c in cells)
    state = "all saved" if todo == 0 else f"{todo} to compute"
    print(f"{what}: {len(cells)} cells ({detail}), {state}", file=sys.stderr, flush=True)


def participant_seeds(seed: int, n: int) -> list[int]:
    """Run seeds of ``n`` participants / replications; disjoint blocks per ``seed``."""
    if seed < 0 or n < 1:
        raise UsageError(f"need seed >= 0 and n >= 1, got seed={seed}, n={n}")
    return [seed * 1_000_000 + i for i in range(n)]


def paper_idle(record: Mapping[str, Any]) -> float:
    """The paper's human idle time of a run: makespan minus the sampled task times (the
    per-kit pickup is not assembling, so it counts as idle)."""
    return float(record["makespan"]) - float(sum(record["human_times"].values()))
