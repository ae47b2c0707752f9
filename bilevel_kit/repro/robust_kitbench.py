"""``bilevel-kit repro robust-kitbench``: the robust study (:mod:`.robust`) on KitBench up to
60 tasks (issue 41, docs/robust.md#kitbench-up-to-60-tasks).

One cell per KitBench record of at most :data:`MAX_TASKS` tasks (``instances/kitbench/
index.csv``, in its order), each with its own tray count and
delivery time, at each CV of :data:`CVS`: the robust study's cell
(:func:`.robust.cell_estimates`: the mean-value and SAA plans, their expected makespans on
1,000 evaluation scenarios, the paired VSS and EVPI) with its deterministic-time budgets and
its wall-clock safety net (``safety_net_fired``; a cut cell is computed once more, alone,
:func:`.robust.rerun_cut`). One change: the mean-value solve is hinted with the record's
best-known plan (``solutions/``), since the exact model alone finds no plan of some 25-task
records within its budget; the mean-value plan is the better of the two, never worse than
the record's. Writes ``robust_kitbench.csv``, ``robust_kitbench.md`` and
``robust_kitbench.json``.
"""

from __future__ import annotations

import time
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from .. import atomic
from ..errors import UsageError
from ..experiments.tables import markdown_lines, write_csv
from .robust import (
    EVALUATION,
    ROOT,
    SCENARIOS,
    WAIT_AND_SEE_N,
    cell_estimates,
    cell_key,
    rerun_cut,
    rows_of,
)
from .robust_facts import yes

LIBRARY = ROOT / "instances" / "kitbench"
#: The largest record taken (tasks, the index's ``tasks``: every unit's).
MAX_TASKS = 60
#: The largest record of a ``--quick`` run.
QUICK_TASKS = 12
#: The CV: the largest of the robust study, where its gains were largest
#: (docs/robust.md#results): if planning for the spread does not pay there, it pays at no CV
#: the study tried. One CV only, for the compute (docs/robust.md#kitbench-up-to-60-tasks).
CVS = (0.5,)


@dataclass(frozen=True)
class KitBenchCell:
    """One (record, cv, seed) point: the record's own tray count (None: unlimited)."""

    instance: str
    trays: int | None
    cv: float
    seed: int
    family: str = ""
    tasks: int = 0
    scenarios: int = SCENARIOS
    evaluation: int = EVALUATION
    wait_and_see: int = WAIT_AND_SEE_N
    #: the instance file's digest (:func:`.common.file_digest`): a changed file is a new cell
    digest: str = ""
    #: the best-known plan's file digest: the mean-value solve's hint, so an improved record
    #: (``bench update``) is a new cell too, never a saved cell of the old hint
    hint_digest: str = ""

    def key(self) -> str:
        return cell_key(self)


def kitbench_cell(cell: KitBenchCell) -> dict[str, Any]:
    """The robust study's cell on the record's instance file, as it stands, the mean-value
    solve hinted with the record's best-known plan (module docstring)."""
    from ..instance import load
    from ..solution import read

    t0 = time.process_time()
    inst = load(LIBRARY / f"{cell.instance}.json")
    best = read(_hint_path(cell.instance)).plan
    return cell_estimates(cell, inst, t0, start=best)


def _hint_path(instance: str) -> Path:
    """The record's best-known plan, the mean-value solve's hint."""
    return LIBRARY / "solutions" / f"{instance}.json"


def study_cells(
    cvs: Sequence[float] = CVS, seed: int = 0, max_tasks: int = MAX_TASKS
) -> list[KitBenchCell]:
    """Every record of at most ``max_tasks`` tasks (the index's order), at every CV."""
    from ..experiments.kitbench.library import Library
    from .common import file_digest

    records = [r for r in Library.at(LIBRARY).read() if r.tasks <= max_tasks]
    return [
        KitBenchCell(
            r.instance,
            r.trays,
            cv,
            seed,
            family=r.family,
            tasks=r.tasks,
            digest=file_digest(LIBRARY / f"{r.instance}.json"),
            hint_digest=file_digest(_hint_path(r.instance)),
        )
        for cv in cvs
        for r in records
    ]


def kitbench_rows(records: Sequence[Mapping[str, Any]]) -> list[dict[str, Any]]:
    """The robust study's rows (:func:`.robust.rows_of`) with each record's family and task
    count after its name."""
    out = []
    for rec, row in zip(records, rows_of(records), strict=True):
        cell = rec["cell"]
        out.append({"instance": row["instance"], "family": cell["family"], "tasks": cell["tasks"]})
        out[-1].update(row)
    return out


def kitbench_markdown(rows: Sequence[Mapping[str, Any]]) -> str:
    """Per record and CV: tasks, trays, the VSS [95 % paired interval], in % of the
    mean-value plan's expected makespan, and whether the SAA solve proved its plan."""
    head = ["instance", "tasks", "trays", "cv", "E mean-value plan (s)", "VSS (s)", "VSS (%)"]
    head += ["SAA proven", "SAA plan differs"]
    body = [
        [
            str(r["instance"]),
            str(r["tasks"]),
            str(r["trays"]),
            f"{float(r['cv']):g}",
            f"{float(r['mean_plan']):.1f}",
            f"{float(r['vss']):.2f} [{float(r['vss_low']):.2f}, {float(r['vss_high']):.2f}]",
            f"{float(r['vss_pct']):.2f}",
            "yes" if yes(r["saa_proven"]) else "no",
            "no" if yes(r["same_plan"]) else "yes",
        ]
        for r in rows
    ]
    return "\n".join(markdown_lines(head, body))


def heading(max_tasks: int, quick: bool) -> str:
    """The markdown's first line: the records it covers (a quick run's are fewer)."""
    quick_note = " (QUICK: a reduced run)" if quick else ""
    return (
        f"Robust planning on KitBench up to {max_tasks} tasks{quick_note}: VSS (s) = "
        f"E[mean-value plan] - E[SAA plan] on {EVALUATION} evaluation scenarios, mean "
        "[95 % paired interval].\n\n"
    )


def run_robust_kitbench(
    out_dir: str | Path = "out/repro/robust_kitbench",
    quick: bool = False,
    jobs: int = 1,
    seed: int = 0,
    *,
    cvs: Sequence[float] | None = None,
    progress: bool | None = None,
    **_: Any,
) -> dict[str, Any]:
    """The panel (module docstring); ``quick``: the records of at most :data:`QUICK_TASKS`
    tasks at CV 0.3.
    Cells are saved under ``out_dir/cells/`` (a rerun computes only the missing ones)."""
    from ..experiments.cells import write_json
    from .common import run_study_cells, study_summary

    t0 = time.perf_counter()
    grid = tuple(cvs) if cvs else ((0.3,) if quick else CVS)
    if min(grid) < 0:
        raise UsageError(f"bad robust-kitbench cv {grid}: cv >= 0")
    max_tasks = QUICK_TASKS if quick else MAX_TASKS
    cells = study_cells(grid, seed, max_tasks)
    out = Path(out_dir)
    ran = run_study_cells(
        cells, kitbench_cell, out, jobs=jobs, progress=progress, desc="robust-kitbench cells"
    )
    ran, retried = rerun_cut(cells, ran, out, progress, kitbench_cell)
    rows = kitbench_rows(ran[0])
    head = heading(max_tasks, quick)
    files = {
        "csv": write_csv(out / "robust_kitbench.csv", rows, exclude=(), line_end="\n"),
        "markdown": out / "robust_kitbench.md",
    }
    atomic.write_text(files["markdown"], head + kitbench_markdown(rows) + "\n")
    summary = study_summary(
        out, "robust_kitbench", ran, rows, files, t0=t0, quick=quick, seed=seed, cells=len(cells)
    )
    walls = [w for r in ran[0] for w in r.get("solve_wall_s", [])]
    summary.update(
        retried=retried,
        cut=[r["key"] for r in ran[0] if r.get("safety_net_fired", 1)],
        slowest_solve_wall_s=max(walls, default=None),
    )
    write_json(out / "robust_kitbench.json", summary)
    return summary
