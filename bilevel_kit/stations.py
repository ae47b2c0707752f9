"""Several assembly stations served by one robot (docs/timeline.md#several-stations).

The evaluator (:mod:`bilevel_kit.plan`) and the checker take stations themselves; this module
holds what methods and bounds share about them: a station's tasks as an instance of their own
(:func:`station_instance`, whose closed-form bounds hold for that station's completion), the
value of an objective of the registry :mod:`bilevel_kit.objectives` (:func:`objective_of`;
their closed-form bounds, model expressions and horizons are the registry's too) and the
refusal of a method whose spec does not declare ``supports_stations``
(:class:`bilevel_kit.methods.MethodSpec`).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from .instance.model import station_instance
from .objectives import get as get_objective

__all__ = ["objective_of", "station_instance"]

if TYPE_CHECKING:
    from .plan import Timeline


def objective_of(timeline: Timeline, objective: str) -> float:
    """The value of ``objective`` on ``timeline`` in seconds: the registry's evaluation
    (:data:`bilevel_kit.objectives.OBJECTIVES`; with one station ``sum_completion`` is the
    makespan, ``human_idle`` is the timeline's, the sum over the stations)."""
    value = get_objective(objective).value(timeline)
    if value is None:
        raise ValueError(f"{objective!r} is not a function of the timeline")
    return value
