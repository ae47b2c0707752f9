"""The embedded run: one CP-SAT solve of the model with the tray's rectangles inside it."""

from __future__ import annotations

import math
from typing import Any

from .. import stoppable
from ..exact.keys import MASTER_SOLVES
from ..packing import ANY_ANGLE
from .context import Context, Model, State
from .model import extract_kits, hint
from .scaling import scaled_objective
from .tray import embedded_layouts, grid_corners


def run_embedded(ctx: Context, mdl: Model, solver: Any, incumbent: list[list[int]] | None) -> State:
    """Solve once, warm-started from ``incumbent`` (its layouts hinted too); the solver's
    bound is a proof because the model holds the whole tray."""
    from ortools.sat.python import cp_model

    state = State(
        incumbent,
        None if incumbent is None else scaled_objective(ctx.sc, incumbent, ctx.objective),
    )
    if incumbent is not None:
        hint(mdl, ctx.sc, incumbent, grid_corners(ctx.instance, incumbent, ctx.packer))
    left = ctx.left()
    if left <= 0.01:
        return state
    # a large embedded model (10 tables: 7e4 variables, 1e5 constraints, 40 s of presolve)
    # overran its CP-SAT limit by 2.2 s of 57 s: keep 4 % more back here
    solver.parameters.max_time_in_seconds = 0.96 * left
    st = stoppable.solve(solver, mdl.model, ctx.callback)
    state.info = {MASTER_SOLVES: 1}
    ctx.left()  # (a reproducible run records a wall limit the solve ran into)
    state.status_name = solver.status_name(st)
    if st in (cp_model.OPTIMAL, cp_model.FEASIBLE):
        kits = extract_kits(mdl, solver)
        obj = round(solver.objective_value)
        if state.obj is None or obj <= state.obj:
            state.kits, state.obj = kits, obj
            state.layouts = embedded_layouts(ctx.instance, mdl, solver, kits, ctx.packer.res)
        _bound(state, ctx.embed_scope, math.ceil(solver.best_objective_bound - 1e-6))
        state.proven = st == cp_model.OPTIMAL
    elif st == cp_model.INFEASIBLE:
        # C <= U holds for the incumbent, so this only happens without one
        state.infeasible = incumbent is None
        state.proven = incumbent is not None
        _bound(state, ctx.embed_scope, state.obj)
    return state


def _bound(state: State, scope: str | None, lower: int | None) -> None:
    """The model's bound, with the scope of its tray (:attr:`.context.Context.embed_scope`):
    a proof for every plan, for 0/90-degree plans only, or none."""
    state.scope = scope
    state.lower = None if scope is None else lower
    state.lower_any = lower if scope == ANY_ANGLE else None
