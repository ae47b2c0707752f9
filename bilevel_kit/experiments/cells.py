"""The one resumable cell runner: a cell is a pure function of (config, seed).

Why: ``compare``, ``repro fig6`` (and later a Dask cluster) must scale out and resume after an
interruption. A cell therefore holds only plain data (an instance path, a method or a grid
point, options, seeds) and has a stable :meth:`Cell.key` (a digest of its configuration); the
function turns it into a JSON-serialisable record, saved as ``<cell_dir>/<key>.json`` through
:mod:`bilevel_kit.atomic` as soon as it finishes. A rerun skips every cell whose file exists.

Where the cells run is a small pluggable piece, an :class:`Executor`: :class:`SerialExecutor`
(in order, in this process) or :class:`ProcessExecutor` (a process pool, ``jobs`` workers).
"""

from __future__ import annotations

import json
from collections.abc import Callable, Iterator, Sequence
from concurrent.futures import ProcessPoolExecutor, as_completed
from pathlib import Path
from typing import Any, Protocol, TypeVar

import numpy as np

from .. import atomic

C = TypeVar("C", bound="Cell")
Record = dict[str, Any]


class Cell(Protocol):
    """A unit of work: plain data with a stable, file-name-safe key."""

    def key(self) -> str: ...


class Executor(Protocol):
    """Runs ``fn`` on cells and yields ``(index, record)`` as each one finishes."""

    def run(
        self, fn: Callable[[Any], Record], cells: Sequence[Any]
    ) -> Iterator[tuple[int, Record]]: ...


class SerialExecutor:
    """Every cell in order, in this process."""

    def run(
        self, fn: Callable[[Any], Record], cells: Sequence[Any]
    ) -> Iterator[tuple[int, Record]]:
        for i, cell in enumerate(cells):
            yield i, fn(cell)


class ProcessExecutor:
    """A pool of ``jobs`` worker processes (``fn`` and the cells must pickle)."""

    def __init__(self, jobs: int) -> None:
        self.jobs = jobs

    def run(
        self, fn: Callable[[Any], Record], cells: Sequence[Any]
    ) -> Iterator[tuple[int, Record]]:
        with ProcessPoolExecutor(max_workers=min(self.jobs, len(cells))) as ex:
            futures = {ex.submit(fn, cell): i for i, cell in enumerate(cells)}
            for fut in as_completed(futures):
                yield futures[fut], fut.result()


def make_executor(jobs: int = 1, n_cells: int = 2) -> Executor:
    """Serial for one job (or a single cell), else a process pool."""
    return SerialExecutor() if jobs <= 1 or n_cells <= 1 else ProcessExecutor(jobs)


def json_default(o: Any) -> Any:
    """JSON for numpy scalars and tuples inside records."""
    if isinstance(o, np.generic):
        return o.item()
    if isinstance(o, tuple):
        return list(o)
    raise TypeError(f"not JSON serialisable: {type(o).__name__}")


def write_json(path: str | Path, obj: Any) -> Path:
    """``obj`` as indented JSON, written atomically."""
    atomic.write_text(path, json.dumps(obj, indent=1, default=json_default) + "\n")
    return Path(path)


def run_cells_counted(
    cells: Sequence[Any],
    fn: Callable[[Any], Record],
    *,
    cell_dir: str | Path | None = None,
    jobs: int = 1,
    executor: Executor | None = None,
    progress: bool | None = None,
    desc: str = "cells",
) -> tuple[list[Record], int]:
    """Run ``fn`` on every cell without a saved record; return all records, in cell order,
    and how many were computed now.

    Records of cells already saved under ``cell_dir`` are read back; new ones are saved as
    soon as they finish (an interrupted run loses only the cells in flight). Without
    ``cell_dir`` nothing is saved. ``executor`` (default: :func:`make_executor` of ``jobs``)
    decides where cells run; ``progress=None`` shows a bar only on a terminal.
    """
    from tqdm import tqdm

    folder = Path(cell_dir) if cell_dir is not None else None
    if folder is not None:
        folder.mkdir(parents=True, exist_ok=True)
    paths = [folder / f"{c.key()}.json" if folder is not None else None for c in cells]
    records: list[Record | None] = [None] * len(cells)
    todo = []
    for i, p in enumerate(paths):
        if p is not None and p.exists():
            records[i] = json.loads(p.read_text())
        else:
            todo.append(i)
    ex = executor if executor is not None else make_executor(jobs, len(todo))
    bar = tqdm(total=len(todo), desc=desc, disable=None if progress is None else not progress)
    try:
        for j, rec in ex.run(fn, [cells[i] for i in todo]):
            i = todo[j]
            path = paths[i]
            if path is not None:
                write_json(path, rec)
            records[i] = rec
            bar.update()
    finally:
        bar.close()
    return [r for r in records if r is not None], len(todo)


def run_cells(
    cells: Sequence[Any],
    fn: Callable[[Any], Record],
    *,
    cell_dir: str | Path | None = None,
    progress: bool | None = None,
    desc: str = "cells",
    jobs: int = 1,
    executor: Executor | None = None,
) -> list[Record]:
    """The records of :func:`run_cells_counted` (resumable under ``cell_dir``)."""
    return run_cells_counted(
        cells,
        fn,
        cell_dir=cell_dir,
        jobs=jobs,
        executor=executor,
        progress=progress,
        desc=desc,
    )[0]
