"""A CP-SAT run's live progress in seconds (:mod:`bilevel_kit.progress`).

The model works on scaled integer times (:mod:`.scaling`); the progress is in the instance's
seconds. On an exact grid a scaled objective is ``value x res`` exactly (human idle adds the
model's constant ``-sum h``); on a rounded-down grid the incumbent is recomputed on the real
times from its kits, and only makespan bounds are reported (they stay valid lower bounds, the
module docstring of :mod:`.scaling`), as :func:`.method.run` reports them at the end.

The embedded model's solutions are valid plans (the tray is in the model); a Benders master's
are not (their kits may not pack), so there only the bound is live, and only while every cut
is proven (``bound_valid``). Imported only when someone listens: it loads OR-Tools.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

from ortools.sat.python import cp_model

from ...plan import Kit, Plan, evaluate
from ...progress import Tracker
from ..common import kit_order
from .context import Context, Model
from .model import extract_kits


class Live:
    """Converts a run's scaled objectives and bounds to seconds and reports them."""

    def __init__(self, ctx: Context, tracker: Tracker, mdl: Model | None = None) -> None:
        self.ctx = ctx
        self.tracker = tracker
        self.mdl = mdl
        #: Are the master's bounds proofs (False after an unproven Benders cut)?
        self.bound_valid = True

    def seconds(self, scaled: int) -> float | None:
        """A scaled objective value in seconds (None when the grid is not exact)."""
        sc = self.ctx.sc
        if not sc.exact:
            return None
        const = -self.ctx.minimised.dropped(sc.h)  # the model's obj_const
        return round((scaled + const) * sc.res, 9)

    def real(self, kits: Sequence[Sequence[int]]) -> float:
        """The objective of ``kits`` (task indices) on the real times."""
        instance, ids = self.ctx.instance, self.ctx.ids
        plan = Plan(tuple(Kit(kit_order(instance, [ids[i] for i in kit])) for kit in kits))
        tl = evaluate(instance, plan)
        value = self.ctx.minimised.value(tl)
        assert value is not None  # the modelled objectives are functions of the timeline
        return value

    def kits(self, kits: Sequence[Sequence[int]] | None, scaled: int | None) -> None:
        """A valid plan's kits with their scaled objective."""
        if kits is None or scaled is None:
            return
        value = self.seconds(scaled)
        self.tracker.report(incumbent=self.real(kits) if value is None else value)

    def bound(self, scaled: float | None) -> None:
        """A proven lower bound on the scaled objective (ignored when it proves nothing)."""
        if scaled is None or not self.bound_valid:
            return
        lower = math.ceil(scaled - 1e-6)
        if self.ctx.minimised.is_makespan:  # valid on a rounded-down grid too (module doc)
            self.tracker.report(bound=round(lower * self.ctx.sc.res, 9))
        else:
            self.tracker.report(bound=self.seconds(lower))

    def attach(self, solver: Any, solutions_are_plans: bool) -> Callback:
        """Route the solver's new bounds here; the solution callback to pass to ``solve``."""
        solver.best_bound_callback = self.bound
        return Callback(self, solutions_are_plans)


class Callback(cp_model.CpSolverSolutionCallback):  # type: ignore[misc]
    """Reports each solution's objective (when solutions are plans) and the search's bound."""

    def __init__(self, live: Live, solutions_are_plans: bool) -> None:
        super().__init__()
        self.live = live
        self.plans = solutions_are_plans

    def on_solution_callback(self) -> None:
        live = self.live
        if self.plans and live.mdl is not None:
            obj = round(self.objective_value)
            value = live.seconds(obj)
            if value is None:
                value = live.real(extract_kits(live.mdl, self))
            live.tracker.report(incumbent=value)
        live.bound(self.best_objective_bound)
