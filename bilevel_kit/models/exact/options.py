"""The options ``cpsat`` and ``milp`` share, declared once so that each has one default, one
meaning and one check in both (docs/formulations.md, "One driver for cpsat and milp")."""

from __future__ import annotations

from typing import Literal

from ...objectives import model_objectives
from ...options import option

#: Option ``search``'s default share (docs/formulations.md, "Branch, bound and remember"):
#: off, so that a run builds its model as before unless asked (``-p search=0.3``).
SEARCH_DEFAULT = 0.0

Fallback = Literal["lns", "none"]


def objective_field() -> str:
    """Option ``objective``: a modelled objective of the registry, a plugin's too (checked
    when parsed, when the registry is complete)."""
    return option(
        "makespan",
        "minimise makespan, (stations) sum_completion, human_idle, or a plugin's objective",
        choices=model_objectives,
    )


def hint_field() -> str:
    """Option ``hint``: the warm start (:func:`.driver.check_hint` checks it)."""
    return option(
        "auto",
        "warm start: auto (best of single-task, whole-assembly, greedy-ce), a "
        "method name, or none; its plan is the incumbent when better than the quick plan",
    )


def fallback_field() -> Fallback:
    """Option ``fallback``: the LNS around the model (docs/formulations.md, "The LNS first",
    "The LNS after the model") and what a run without a model returns ("Model too large")."""
    default: Fallback = "lns"
    return option(
        default,
        "lns: the LNS from the plan before the model, after its share, and when no model "
        "is built (too large, too slow); none: the model alone, the plan when none is "
        "built (several stations: cpsat runs lns's station search, milp returns the plan; "
        "extra['lns_first'], extra['lns_after'], extra['fallback'])",
    )


def search_field() -> float:
    """Option ``search``: the share of the time left before the model that the ideal search
    (:mod:`.search_first`) gets; 0: none."""
    return option(
        SEARCH_DEFAULT,
        "share of the time left before the model for the ideal search from the "
        "incumbent (branch, bound and remember; makespan), e.g. 0.3; 0: none",
        min=0.0,
        max=1.0,
    )
