"""The options of the registered method ``milp`` (:mod:`.method`) and what each does with
several assembly stations (docs/formulations.md, "Options with several stations"), with the
seconds a run keeps back from its time limit."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

from ...options import option
from ..exact.driver import check_hint
from ..exact.options import (
    Fallback,
    fallback_field,
    hint_field,
    objective_field,
    search_field,
)
from ..exact.station_options import HONOURED, declare

TRAY_MODES: tuple[str, ...] = ("auto", "benders")
#: Seconds kept back from the time limit for extraction and the final layouts.
MARGIN = 0.2


@dataclass(frozen=True)
class MilpOptions:
    """Options of the registered method ``milp``."""

    solver: str = option(
        "highs",
        "highs (HiGHS in a child process) or any Pyomo solver name (cbc, glpk, gurobi, scip ...)",
    )
    objective: str = objective_field()
    tray: Literal["auto", "benders"] = option(
        "auto",
        "auto (milp has no embedded tray: benders) or benders: Benders cuts, seeded "
        "for the task pairs that do not fit (one station)",
    )
    log: bool = option(False, "print the MILP solver's log")
    hint: str = hint_field()
    fallback: Fallback = fallback_field()  # noqa: RUF009 (a field() with a str default)
    search: float = search_field()

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
        "search": HONOURED,
    },
)
