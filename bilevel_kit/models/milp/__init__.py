"""The exact whole-horizon schedule as a Pyomo MILP (registered method ``milp``).

:mod:`.model` (the Pyomo model and its Benders cuts), :mod:`.solver` (running HiGHS in a child
process, :mod:`.highs_child`, or any Pyomo solver; shared with ``bilevel-milp``),
:mod:`.method` (the registered entry and the Python :func:`solve`; the steps of a run are
:mod:`..exact.driver`'s, the ``extra`` keys are listed in docs/formulations.md, "One driver for
cpsat and milp"), :mod:`.options` (its options), :mod:`.benders` (the Benders loop and the live
progress), :mod:`.warm` (the incumbent with several assembly stations,
docs/timeline.md#several-stations; one station is the S = 1 case of :mod:`.model`). The
formulation is in docs/formulations.md. Importing this package loads neither Pyomo nor a
solver.
"""

from ...objectives import MODEL_OBJECTIVES as OBJECTIVES  # the registry's
from .method import milp, run, solve
from .model import canonical_kits, human_order, kit_cap
from .options import MARGIN, TRAY_MODES, MilpOptions
from .solver import SOLVER_OPTIONS, SolveInfo, ensure_ortools, make_solver, run_solver

__all__ = [
    "MARGIN",
    "OBJECTIVES",
    "SOLVER_OPTIONS",
    "TRAY_MODES",
    "MilpOptions",
    "SolveInfo",
    "canonical_kits",
    "ensure_ortools",
    "human_order",
    "kit_cap",
    "make_solver",
    "milp",
    "run",
    "run_solver",
    "solve",
]
