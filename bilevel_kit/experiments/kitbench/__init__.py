"""KitBench: a benchmark library of instances with certified best-known plans and bounds
(docs/kitbench.md).

:mod:`.library` reads and writes the library (instances, ``index.csv``, ``solutions/``),
:mod:`.filters` selects instances (``--filter``), :mod:`.run` runs methods against it as
resumable cells, :mod:`.verify` checks every record, :mod:`.update` merges a run's
improvements and :mod:`.report` renders its tables.
"""

from .filters import parse_filter, select
from .library import COLUMNS, OPTIMAL_RTOL, Library, Provenance, Record, code_version
from .report import records_markdown, render_blocks, sizes_markdown, status_markdown
from .run import BenchCell, BenchRun, bench_cell, read_cells, result_rows, run_bench, summary
from .update import Change, Merge, UpdateRefused, update
from .verify import Problem, verify

__all__ = [
    "COLUMNS",
    "OPTIMAL_RTOL",
    "BenchCell",
    "BenchRun",
    "Change",
    "Library",
    "Merge",
    "Problem",
    "Provenance",
    "Record",
    "UpdateRefused",
    "bench_cell",
    "code_version",
    "parse_filter",
    "read_cells",
    "records_markdown",
    "render_blocks",
    "result_rows",
    "run_bench",
    "select",
    "sizes_markdown",
    "status_markdown",
    "summary",
    "update",
    "verify",
]
