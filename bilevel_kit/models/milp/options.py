"""The options of the registered method ``milp`` (:mod:`.method`) and what each does with
several assembly stations (docs/formulations.md, "Options with several stations"), with the
seconds a run keeps back from its time limit."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Literal

from ...objectives import model_objectives
from ..exact.driver import check_hint
from ..exact.station_options import HONOURED, declare

TRAY_MODES: tuple[str, ...] = ("auto", "benders")
#: Seconds kept back from the time limit for extraction and the final layouts.
MARGIN = 0.2


@dataclass(frozen=True)
class MilpOptions:
    """Options of the registered method ``milp``."""

    solver: str = field(
        default="highs",
        metadata={
            "help": "highs (HiGHS in a child process) or any Pyomo solver name "
            "(cbc, glpk, gurobi, scip ...)"
        },
    )
    objective: str = field(
        default="makespan",
        metadata={  # the registry's modelled objectives, a plugin's too (checked when parsed)
            "help": "minimise makespan, (stations) sum of completions, human idle, or a "
            "plugin's objective",
            "choices": model_objectives,
        },
    )
    tray: Literal["auto", "benders"] = field(
        default="auto",
        metadata={
            "help": "auto (milp has no embedded tray: benders) or benders: Benders cuts, seeded "
            "for the task pairs that do not fit (one station)"
        },
    )
    log: bool = field(default=False, metadata={"help": "print the MILP solver's log"})
    hint: str = field(
        default="auto",
        metadata={
            "help": "warm start: auto (best of single-task, whole-assembly, greedy-ce), a "
            "method name, or none; its plan is the incumbent when better than the quick plan"
        },
    )

    fallback: Literal["lns", "none"] = field(
        default="lns",
        metadata={
            "help": "no model built (too large, too slow): lns from the plan, or none "
            "(several stations: the incumbent, the LNS does not model them; extra['fallback'])"
        },
    )

    def __post_init__(self) -> None:
        check_hint(self.hint, ("auto", "none"))


#: What the model with several stations (:mod:`.model`) does with each option
#: (docs/formulations.md, "Options with several stations"); every option is declared
#: (:func:`declare`). ``tray=auto`` and ``fallback=lns`` act as ``benders`` and ``none``
#: there, said in ``extra["tray_mode"]`` and ``extra["fallback"]``; a ``hint`` method that
#: does not support stations is refused (:func:`.warm.check_station_hint`).
STATION_OPTIONS = declare(
    MilpOptions,
    {
        "solver": HONOURED,
        "objective": HONOURED,
        "tray": HONOURED,
        "log": HONOURED,
        "fallback": HONOURED,
        "hint": HONOURED,
    },
)
