"""``bench run``: every (instance, method) of the library as one resumable cell, then the
gaps of each method to the records (docs/kitbench.md#running-a-method-against-the-library).

A cell (:class:`BenchCell`) solves one library instance with one method through the one cell
runner (:mod:`bilevel_kit.experiments.cells`: in process, on ``--jobs`` local workers or on a
Dask cluster), so an interrupted run resumes where it stopped. Its record carries the plan as a
solution document, the method's proven bound, the wall time, the seed and options, the commit
of the code and the date: everything ``bench update`` needs to merge it into the records.

Two gaps per row, as everywhere in the toolkit: the **certified gap** (objective - bound) /
objective to the best bound known (the library's or this run's, whichever is higher), and
**above best-known** (objective - best_known) / best_known to the best plan known (the
library's or this run's, whichever is lower).
"""

from __future__ import annotations

import statistics
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, ClassVar

from ..compare import SolveCell
from .library import OPTIMAL_RTOL, SHARES, Library, Record, now, trays_text

#: The ``format`` of a bench cell record (what ``bench update`` accepts).
CELL_FORMAT = "kitbench-cell/1"


@dataclass(frozen=True)
class BenchCell(SolveCell):
    """One solve of one library instance with one method."""

    instance: str  # path of the instance file
    method: str
    time_limit: float | None = None
    seed: int = 0
    params: dict[str, Any] = field(default_factory=dict)
    instance_sha256: str = ""  # the file's digest, filled in when the cell is made
    commit: str = ""  # the code's commit: recorded, not part of the key
    document: str = field(default="", repr=False)  # the file's text, filled in likewise

    #: the commit is recorded only: whether a saved cell's code is this code is the cell
    #: runner's check of the record's code identity (docs/cluster.md)
    unkeyed: ClassVar[tuple[str, ...]] = ("instance", "document", "commit")


def bench_cell(cell: BenchCell) -> dict[str, Any]:
    """Solve one cell; a method that declines the instance (a size it refuses, a kit it
    cannot lay out) gives a ``refused`` record, another reported error an ``error`` one."""
    from ...errors import BilevelKitError, KitDoesNotFit, UsageError
    from ...solution import result_to_dict

    inst = cell.load()
    record: dict[str, Any] = {
        "format": CELL_FORMAT,
        **cell.head(inst.name),
        "tasks": inst.n_tasks,
        "commit": cell.commit,
    }
    try:
        res = cell.solve(inst)
    except (UsageError, KitDoesNotFit) as exc:
        return {**record, "status": "refused", "error": str(exc), "date": now()}
    except BilevelKitError as exc:
        return {**record, "status": "error", "error": str(exc), "date": now()}
    violations = res.extra.get("violations", [])
    return {
        **record,
        "status": res.status_text,
        "makespan": res.makespan,
        "bound": res.makespan_bound,
        "wall_time_s": res.wall_time_s,
        "valid": None if res.plan is None else not violations,
        "violations": len(violations),
        "date": now(),
        "solution": None if res.plan is None else result_to_dict(res),
    }


def make_cells(
    library: Library,
    records: Sequence[Record],
    methods: Sequence[str],
    time_limit: float | None,
    seed: int,
    params: dict[str, dict[str, Any]],
    commit: str,
) -> list[BenchCell]:
    """One cell per (instance, method), instances in index order; the cells of one instance
    share its text, read once."""
    from ..compare import instance_fields

    cells = []
    for r in records:
        path = str(library.instance_path(r.instance))
        digest, text = instance_fields(path)
        cells += [
            BenchCell(
                path,
                m,
                time_limit,
                seed,
                dict(params.get(m, {})),
                instance_sha256=digest,
                commit=commit,
                document=text,
            )
            for m in methods
        ]
    return cells


# ---------------------------------------------------------------------------------------------
# Gaps, rows and the summary
# ---------------------------------------------------------------------------------------------


def _has_plan(cell: dict[str, Any]) -> bool:
    return cell.get("makespan") is not None and cell.get("valid") is True


def references(
    records: Sequence[Record], cells: Sequence[dict[str, Any]]
) -> dict[str, tuple[float | None, float | None]]:
    """Per instance, the best-known makespan and best bound over the library and the run."""
    out = {r.instance: (r.best_known, r.best_bound) for r in records}
    for c in cells:
        name = c.get("instance")
        if name not in out:
            continue
        best, bound = out[name]
        if _has_plan(c):
            best = c["makespan"] if best is None else min(best, c["makespan"])
        if c.get("bound") is not None and c.get("status") not in ("error", "refused"):
            bound = c["bound"] if bound is None else max(bound, c["bound"])
        out[name] = (best, bound)
    return out


def result_rows(records: Sequence[Record], cells: Sequence[dict[str, Any]]) -> list[dict[str, Any]]:
    """One row per cell: what it found and its two gaps (see the module docstring)."""
    by_name = {r.instance: r for r in records}
    refs = references(records, cells)
    rows = []
    for c in cells:
        rec = by_name.get(c.get("instance", ""))
        best, bound = refs.get(c.get("instance", ""), (None, None))
        ms = c.get("makespan") if _has_plan(c) else None
        rows.append(
            {
                "instance": c.get("instance"),
                "family": rec.family if rec else None,
                "tasks": c.get("tasks"),
                "trays": trays_text(rec.trays) if rec else None,
                "delivery_time": rec.delivery_time if rec else None,
                "tray": rec.tray if rec else None,
                "method": c.get("method"),
                "status": c.get("status"),
                "makespan": ms,
                "bound": c.get("bound"),
                "wall_time_s": c.get("wall_time_s"),
                "valid": c.get("valid"),
                "best_known": best,
                "best_bound": bound,
                "above_best_known": None if ms is None or not best else (ms - best) / best,
                "certified_gap": None if ms is None or bound is None else max(0.0, 1 - bound / ms),
                "library_best_known": rec.best_known if rec else None,
                "library_best_bound": rec.best_bound if rec else None,
                "error": c.get("error"),
            }
        )
    return rows


def summary(rows: Sequence[dict[str, Any]], methods: Sequence[str]) -> list[dict[str, Any]]:
    """Per method: cells, plans, shares within 1 % and 5 % of the best-known (of all its
    cells: no plan is never within), median and worst of both gaps, proven optimal plans."""
    out = []
    for m in methods:
        mine = [r for r in rows if r["method"] == m]
        above = [r["above_best_known"] for r in mine if r["above_best_known"] is not None]
        cert = [r["certified_gap"] for r in mine if r["certified_gap"] is not None]
        n = len(mine)
        row: dict[str, Any] = {
            "method": m,
            "cells": n,
            "plans": len(above),
            "refused": sum(r["status"] == "refused" for r in mine),
        }
        for s in SHARES:
            row[f"within_{s:.0%}"] = sum(a <= s for a in above) / n if n else None
        row["median_above_best_known"] = statistics.median(above) if above else None
        row["max_above_best_known"] = max(above) if above else None
        row["median_certified_gap"] = statistics.median(cert) if cert else None
        row["max_certified_gap"] = max(cert) if cert else None
        row["certified_optimal"] = sum(g <= OPTIMAL_RTOL for g in cert)
        walls = [r["wall_time_s"] for r in mine if r["wall_time_s"] is not None]
        row["median_wall_s"] = statistics.median(walls) if walls else None
        out.append(row)
    return out


def profile_ratios(
    rows: Sequence[dict[str, Any]], methods: Sequence[str]
) -> dict[str, list[float]]:
    """Per method, makespan / best-known of every instance (inf: no plan): the data of the
    Dolan-More performance profile."""
    return {
        m: [
            1.0 + r["above_best_known"] if r["above_best_known"] is not None else float("inf")
            for r in rows
            if r["method"] == m
        ]
        for m in methods
    }


# ---------------------------------------------------------------------------------------------
# The run
# ---------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class BenchRun:
    """What ``bench run`` computed: the rows, the per-method summary and the files written."""

    rows: list[dict[str, Any]]
    summary: list[dict[str, Any]]
    files: list[Path]
    failed: int
    all_failed: str | None = None  # the line of a run whose every cell failed


def run_bench(
    library: Library,
    records: Sequence[Record],
    methods: Sequence[str],
    out: str | Path,
    *,
    time_limit: float | None,
    seed: int = 0,
    params: dict[str, dict[str, Any]] | None = None,
    manifest: dict[str, Any] | None = None,
) -> BenchRun:
    """Run every (record, method) cell under ``out/cells`` (resumable) and write
    ``results.csv``, ``results.md``, ``profile.png``, ``gap_size.png`` and ``run.json``."""
    from ..cells import all_failed_line, run_sweep, write_json
    from ..tables import write_csv
    from .library import code_version
    from .report import run_markdown

    folder = Path(out)
    commit = code_version()
    cells = make_cells(library, records, methods, time_limit, seed, params or {}, commit)
    write_json(
        folder / "run.json",
        {
            **(manifest or {}),
            "library": str(library.folder),
            "methods": list(methods),
            "time_limit": time_limit,
            "seed": seed,
            "params": params or {},
            "instances": [r.instance for r in records],
            "commit": commit,
            "started": now(),
        },
    )
    raw, _ = run_sweep(cells, bench_cell, cell_dir=folder / "cells", desc="bench")
    raw = [_named(c, r) for c, r in zip(cells, raw, strict=True)]
    rows = result_rows(records, raw)
    table = summary(rows, methods)
    files = [
        write_csv(folder / "results.csv", rows, line_end="\n"),
        folder / "results.md",
    ]
    from ...atomic import write_text

    write_text(files[1], run_markdown(rows, table, methods, time_limit))
    files += write_figures(rows, methods, folder, time_limit)
    failed = sum(c.get("status") == "error" for c in raw)
    return BenchRun(rows, table, files, failed, all_failed_line("bench", raw))


def _named(cell: BenchCell, record: dict[str, Any]) -> dict[str, Any]:
    """A cell's record with its instance and method even when the cell raised (an error
    record of the runner names neither; a library instance's name is its file's stem)."""
    if "method" in record:
        return record
    return {"instance": Path(cell.instance).stem, "method": cell.method, **record}


def write_figures(
    rows: Sequence[dict[str, Any]],
    methods: Sequence[str],
    folder: Path,
    time_limit: float | None,
    stem: str = "",
) -> list[Path]:
    """The performance profile and the gap-versus-size plot of a run's rows; a figure with
    nothing to draw (no plan at all; no plan with a bound) is not written."""
    from ... import plots

    limit = "no time limit" if time_limit is None else f"{time_limit:g} s per solve"
    files = []
    if any(r["above_best_known"] is not None for r in rows):
        ax = plots.plot_profile(profile_ratios(rows, methods))
        ax.set_title(f"KitBench performance profile ({limit})")
        files.append(plots.save_figure(ax.figure, folder / f"{stem}profile.png"))
    if any(r["certified_gap"] is not None and (r["tasks"] or 0) > 0 for r in rows):
        ax = plots.plot_gap_vs_size(rows, methods=methods)
        ax.set_title(f"KitBench: certified gap against size ({limit})")
        files.append(plots.save_figure(ax.figure, folder / f"{stem}gap_size.png"))
    return files


def read_cells(folder: str | Path) -> list[dict[str, Any]]:
    """The cell records of a run folder (``DIR/cells/*.json``), in file-name order, read as
    strictly as an instance (:func:`bilevel_kit.jsonio.read_json`): a bare ``NaN`` bound, a
    duplicate key or a file that is no JSON object is exit 2 naming the file and the field."""
    from ...errors import DocumentError, UsageError
    from ...jsonio import read_json

    cells = Path(folder) / "cells"
    if not cells.is_dir():
        raise UsageError(f"{folder}: not a bench run folder (no cells/ inside)")
    out = []
    for path in sorted(cells.glob("*.json")):
        if path.name.startswith("."):
            continue
        doc = read_json(path, DocumentError)
        if not isinstance(doc, dict):
            raise UsageError(f"{path}: $: not a bench cell record (not a JSON object)")
        out.append({**doc, "_file": str(path)})
    return out
