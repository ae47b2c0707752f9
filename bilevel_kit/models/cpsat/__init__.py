"""The exact whole-horizon schedule as a CP-SAT model (registered method ``cpsat``).

One module per step: :mod:`.scaling` (integer time grid), :mod:`.model` (the schedule model),
:mod:`.tray` (embedded rectangles, Benders cuts, the tray mode), :mod:`.embedded` and
:mod:`.benders` (the two ways to solve it), :mod:`.warm` (the warm start), :mod:`.method` (the
registered entry, its options and the Python :func:`solve`), :mod:`.conclude` (the result and
the claims a run may make). The formulation is in
docs/formulations.md; the steps of a run are :mod:`..exact.driver`'s, the result's ``extra``
keys are listed in docs/formulations.md, "One driver for cpsat and milp".
Importing this package loads no OR-Tools.
"""

from ...objectives import MODEL_OBJECTIVES as OBJECTIVES  # the registry's
from .method import (
    TRAY_MODES,
    CpsatOptions,
    ScheduleOptions,
    cpsat,
    run,
    solve,
)
from .scaling import Scaled, released_makespan, scale_times
from .tray import AUTO_EMBEDDED_MAX_RECTS
from .warm import HINT_METHODS, best_heuristic_plan

__all__ = [
    "AUTO_EMBEDDED_MAX_RECTS",
    "HINT_METHODS",
    "OBJECTIVES",
    "TRAY_MODES",
    "CpsatOptions",
    "Scaled",
    "ScheduleOptions",
    "best_heuristic_plan",
    "cpsat",
    "released_makespan",
    "run",
    "scale_times",
    "solve",
]
