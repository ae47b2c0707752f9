"""Experiments: one resumable cell runner (:mod:`.cells`), the ``compare`` cells
(:mod:`.compare`) and one CSV/Markdown table writer (:mod:`.tables`)."""

from .cells import (
    Cell,
    Executor,
    ProcessExecutor,
    SerialExecutor,
    json_default,
    make_executor,
    run_cells,
    run_cells_counted,
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
    "Executor",
    "ProcessExecutor",
    "SerialExecutor",
    "add_best_bound_gap",
    "compare_cell",
    "format_markdown",
    "format_table",
    "json_default",
    "make_executor",
    "markdown_lines",
    "run_cells",
    "run_cells_counted",
    "table_rows",
    "text_lines",
    "write_csv",
    "write_json",
]
