"""bilevel_kit: just-in-time robotic kitting as bilevel optimisation.

The public API: load an instance, solve it with a registered method, evaluate and check plans.

>>> from bilevel_kit import load, solve, check
>>> inst = load("instances/hrc_table.json")
>>> result = solve(inst, "single-task")
>>> check(inst, result.plan)
[]
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from .errors import BilevelKitError, InstanceError, KitDoesNotFit, SolutionError, UsageError
    from .instance import (
        Instance,
        InstanceBuilder,
        PartType,
        Task,
        Tray,
        load,
        topological_order,
    )
    from .methods import REGISTRY, MethodOutput, Result, register, solve
    from .plan import Kit, KitTimes, Placement, Plan, Timeline, evaluate
    from .validate import Violation, check

#: Where each name of the public API lives. They are imported on first use: the command line
#: imports this package before it can take Ctrl-C (docs/cli.md#interrupting-a-command), and
#: numpy and the rest come later, inside the command.
_EXPORTS = {
    **dict.fromkeys(
        ("BilevelKitError", "InstanceError", "KitDoesNotFit", "SolutionError", "UsageError"),
        "errors",
    ),
    **dict.fromkeys(
        ("Instance", "InstanceBuilder", "PartType", "Task", "Tray", "load", "topological_order"),
        "instance",
    ),
    **dict.fromkeys(("REGISTRY", "MethodOutput", "Result", "register", "solve"), "methods"),
    **dict.fromkeys(("Kit", "KitTimes", "Placement", "Plan", "Timeline", "evaluate"), "plan"),
    **dict.fromkeys(("Violation", "check"), "validate"),
}


def __getattr__(name: str) -> Any:
    module = _EXPORTS.get(name)
    if module is None:  # a submodule, e.g. ``bilevel_kit.plan``
        try:
            return importlib.import_module(f".{name}", __name__)
        except ModuleNotFoundError as exc:
            if exc.name != f"{__name__}.{name}":
                raise
            raise AttributeError(f"module {__name__!r} has no attribute {name!r}") from None
    value = getattr(importlib.import_module(f".{module}", __name__), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted({*globals(), *_EXPORTS})


__version__ = "0.1.0"

__all__ = [
    "REGISTRY",
    "BilevelKitError",
    "Instance",
    "InstanceBuilder",
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
