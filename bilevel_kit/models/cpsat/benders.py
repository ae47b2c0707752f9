"""Logic-based Benders: the master (area relaxation + no-good cuts) <-> packing of each kit.

Each kit of a master solution is packed by :mod:`~bilevel_kit.models.packing`; a part
multiset that is proven not to fit is shrunk to a minimal non-fitting one and cut from every
kit (:func:`.tray.add_cut`). The master is re-solved until its optimum packs (then it is
optimal for the full problem) or the time is up; kits that do not fit are split greedily to
keep an incumbent. A cut from a packing that timed out ("unproven") is a heuristic: after one,
the master's bound is no longer a proof.
"""

from __future__ import annotations

import functools
import math
from collections.abc import Sequence
from typing import Any

from .. import stoppable
from ..common import NoGoodCuts
from ..exact.benders_log import BendersLog
from ..exact.keys import MASTER_SOLVES
from ..packing import ANY_ANGLE
from .context import MARGIN, Context, Model, State
from .model import canonical, extract_kits, hint
from .scaling import scaled_objective
from .tray import add_cut

#: With several stations, the share of the time left that a master solve leaves to pack its
#: kits (measured: on `generate table --size 1 --stations 2` at 10 s the master's 612.7 s plan
#: was found but not packed in time without it, and greedy-ce's 628.7 s plan was returned).
STATION_PACK_SHARE = 0.1


def run_benders(ctx: Context, mdl: Model, solver: Any, incumbent: list[list[int]] | None) -> State:
    """Iterate master solves and packing checks (module docstring) within the budget."""
    loop = _Benders(ctx, mdl, incumbent)
    if not ctx.sc.station:  # with stations, as the MILP: pair cuts proven for 0/90-degree
        loop.cuts.seed_pairs()  # layouts only would limit every proof (docs/formulations.md)
    while ctx.left() > 0.01:
        loop.iterations += 1
        if not loop.iterate(solver):
            break
    return State(
        loop.kits,
        loop.obj,
        lower=loop.lower,
        proven=loop.proven,
        infeasible=loop.infeasible,
        lower_any=loop.lower_any,
        scope=loop.cuts.scope,
        status_name=loop.status_name,
        info={MASTER_SOLVES: loop.iterations, **loop.cut_counts()},
    )


class _Benders(BendersLog[int, int]):
    """The loop over CP-SAT masters: the incumbent and the cuts (how many are unproven) in
    :class:`..exact.benders_log.BendersLog`, on the scaled integer time grid."""

    def __init__(self, ctx: Context, mdl: Model, incumbent: list[list[int]] | None) -> None:
        obj = None if incumbent is None else scaled_objective(ctx.sc, incumbent, ctx.objective)
        cuts = NoGoodCuts(ctx.packer, ctx.budget, MARGIN, functools.partial(add_cut, mdl))
        super().__init__(ctx.instance, cuts, ctx.left, incumbent, obj)
        self.ctx = ctx
        self.mdl = mdl
        self.status_name = "UNKNOWN"

    def task_ids(self, kit: Sequence[int]) -> list[str]:
        ids = self.ctx.ids
        return [ids[i] for i in kit]

    def scored(self, kits: list[list[str]]) -> tuple[list[list[int]], int]:
        idx = self.ctx.instance.index
        out = canonical([[idx[t] for t in q] for q in kits], self.ctx.groups)
        return out, scaled_objective(self.ctx.sc, out, self.ctx.objective)

    def improve(self, kits: list[list[int]], obj: int) -> None:
        super().improve(kits, obj)
        if self.ctx.live is not None:
            self.ctx.live.kits(kits, obj)

    def iterate(self, solver: Any) -> bool:
        """One master solve and its packing checks; False when the loop is done."""
        from ortools.sat.python import cp_model

        mdl = self.mdl
        if self.kits is not None:
            hint(mdl, self.ctx.sc, self.kits)
        left = self.ctx.left()
        if self.ctx.sc.station:  # keep time to pack the master's kits, else a master solution
            left *= 1 - STATION_PACK_SHARE  # found late is lost (docs/formulations.md)
        solver.parameters.max_time_in_seconds = left
        live = self.ctx.live
        if live is not None:  # the master's bound holds for every plan only with such cuts
            live.bound_valid = self.cuts.scope == ANY_ANGLE
            live.tracker.report(stage=f"CP-SAT Benders, {self.mdl.n_cuts} cuts")
        st = stoppable.solve(solver, mdl.model, self.ctx.callback)
        self.ctx.left()  # (a reproducible run records a wall limit the solve ran into)
        self.status_name = solver.status_name(st)
        if st == cp_model.INFEASIBLE:
            self.master_infeasible()
            return False
        if st not in (cp_model.OPTIMAL, cp_model.FEASIBLE):
            return False
        self.record_bound(math.ceil(solver.best_objective_bound - 1e-6))
        kits = extract_kits(mdl, solver)
        verdicts = self.verdicts(kits)
        if all(v.fits is True for v in verdicts):
            obj = round(solver.objective_value)
            if self.accepts(obj):
                self.improve(kits, obj)
            best = obj if self.obj is None else self.obj
            if (st == cp_model.OPTIMAL and self.cuts.unproven == 0) or (
                self.lower is not None and self.lower >= best
            ):
                self.proved()
            return False  # optimal, or the master ran out of time on a packable incumbent
        if self.ctx.left() <= 0.01:  # no time for another master solve: no cuts, no repair
            return False
        return self.cut(kits, verdicts)
