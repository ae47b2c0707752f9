"""Experiments: one resumable cell runner on a serial or Dask executor (:mod:`.cells`), the
``compare`` cells (:mod:`.compare`), the ``simulate --reps`` cells (:mod:`.replications`) and
one CSV/Markdown table writer (:mod:`.tables`)."""

from .cells import (
    Cell,
    DaskExecutor,
    Executor,
    SerialExecutor,
    SweepReport,
    SweepSession,
    error_record,
    is_failed,
    json_default,
    make_executor,
    run_cells,
    run_cells_counted,
    run_sweep,
    sweep_session,
    write_json,
)
from .compare import CompareCell, add_best_bound_gap, compare_cell
from .tables import (
    COMPARE_COLUMNS,
    format_markdown,
    format_table,
    markdown_lines,
    table_rows,
    text_lines,
    write_csv,
)

__all__ = [
    "COMPARE_COLUMNS",
    "Cell",
    "CompareCell",
    "DaskExecutor",
    "Executor",
    "SerialExecutor",
    "SweepReport",
    "SweepSession",
    "add_best_bound_gap",
    "compare_cell",
    "error_record",
    "format_markdown",
    "format_table",
    "is_failed",
    "json_default",
    "make_executor",
    "markdown_lines",
    "run_cells",
    "run_cells_counted",
    "run_sweep",
    "sweep_session",
    "table_rows",
    "text_lines",
    "write_csv",
    "write_json",
]
