"""bilevel_kit: just-in-time robotic kitting as bilevel optimisation.

The public API: load an instance, solve it with a registered method, evaluate and check plans.

>>> from bilevel_kit import load, solve, check
>>> inst = load("instances/hrc_table.json")
>>> result = solve(inst, "single-task")
>>> check(inst, result.plan)
[]
"""

from .errors import BilevelKitError, InstanceError, KitDoesNotFit, SolutionError, UsageError
from .instance import Instance, PartType, Task, Tray, load, topological_order
from .methods import REGISTRY, MethodOutput, Result, register, solve
from .plan import Kit, KitTimes, Placement, Plan, Timeline, evaluate
from .validate import Violation, check

__version__ = "0.1.0"

__all__ = [
    "REGISTRY",
    "BilevelKitError",
    "Instance",
    "InstanceError",
    "Kit",
    "KitDoesNotFit",
    "KitTimes",
    "MethodOutput",
    "PartType",
    "Placement",
    "Plan",
    "Result",
    "SolutionError",
    "Task",
    "Timeline",
    "Tray",
    "UsageError",
    "Violation",
    "check",
    "evaluate",
    "load",
    "register",
    "solve",
    "topological_order",
]
