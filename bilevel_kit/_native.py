"""Load order of native libraries that clash.

OR-Tools and highspy (pulled in by cvxpy, and by Pyomo's HiGHS interface) each ship their own
``libhighs.so.1``; whichever is loaded first wins, and importing the other afterwards fails
with an undefined symbol. With OR-Tools loaded first, cvxpy still works (it solves with
Clarabel and simply does not offer HiGHS), so every module that imports cvxpy calls
:func:`ortools_first` before it. The MILP runs HiGHS in a separate process for the same reason.
"""

from __future__ import annotations


def ortools_first() -> None:
    """Import OR-Tools' CP-SAT before anything that may load highspy (idempotent, cheap)."""
    from ortools.sat.python import cp_model  # noqa: F401
