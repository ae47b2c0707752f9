"""CP-SAT solves that Ctrl-C and SIGTERM stop at once, and that leave the signals alone.

OR-Tools catches SIGINT during a solve by default (``catch_sigint_signal``): it replaces the
process's handler, stops the search as if its time limit were reached (so the command would go
on with a partial result as if it were complete) and, once the solve returns, leaves SIGINT at
its default action, so that the next Ctrl-C kills the process without any cleanup. Every
CP-SAT solve of the package goes through :func:`solve`, which switches that off and runs the
solve with :func:`bilevel_kit.interrupt.run_stoppable`: a signal stops the search and is
raised in the main thread (docs/cli.md#interrupting-a-command).
"""

from __future__ import annotations

from typing import Any

from ..interrupt import run_stoppable


def solve(solver: Any, model: Any, callback: Any = None) -> Any:
    """``solver.solve(model, callback)`` (an OR-Tools ``CpSolver``), stopped by a signal."""
    solver.parameters.catch_sigint_signal = False
    if callback is None:
        return run_stoppable(lambda: solver.solve(model), solver.stop_search)
    return run_stoppable(lambda: solver.solve(model, callback), solver.stop_search)
