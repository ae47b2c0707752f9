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
from typing import Any

from .. import stoppable
from ..common import NoGoodCuts, kit_order
from ..exact.keys import MASTER_SOLVES
from ..packing import ANY_ANGLE
from ..packing_oracle import WHY_TIME, Fit
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
    it = 0
    while ctx.left() > 0.01:
        it += 1
        if not loop.iterate(solver):
            break
    loop.state.info = {
        MASTER_SOLVES: it,
        "unproven_cuts": loop.cuts.unproven,
        "axis_aligned_cuts": loop.cuts.axis_only,
    }
    loop.state.scope = loop.cuts.scope
    return loop.state


class _Benders:
    """The loop's state: the incumbent and the cuts (how many are unproven)."""

    def __init__(self, ctx: Context, mdl: Model, incumbent: list[list[int]] | None) -> None:
        self.ctx = ctx
        self.mdl = mdl
        obj = None if incumbent is None else scaled_objective(ctx.sc, incumbent, ctx.objective)
        self.state = State(incumbent, obj)
        self.cuts = NoGoodCuts(ctx.packer, ctx.budget, MARGIN, functools.partial(add_cut, mdl))

    def counts(self, kit: list[int]) -> dict[str, int]:
        ids = self.ctx.ids
        return dict(self.ctx.instance.kit_parts([ids[i] for i in kit]))

    def verdicts(self, kits: list[list[int]]) -> list[Fit]:
        """Does each kit fit (the oracle's answer; unknown past the time limit)?"""
        packer = self.ctx.packer
        out: list[Fit] = []
        for kit in kits:
            if self.ctx.left() <= 0:  # out of time: the rest stays unknown
                out.append(Fit(None, why=WHY_TIME))
                continue
            counts = self.counts(kit)
            fit = packer.verdict(counts)
            if fit.fits is None:  # a hard packing: one more try with a longer limit
                longer = 10 * packer.pack_tl  # (reproducible: not from the clock)
                if not packer.deterministic:
                    longer = max(packer.pack_tl, min(longer, self.ctx.left() / 3))
                fit = packer.verdict(counts, longer)
            out.append(fit)
        return out

    def repair(self, kits: list[list[int]]) -> None:
        """Split the kits that do not fit; keep the result if it beats the incumbent."""
        ctx, state = self.ctx, self.state
        ids = ctx.ids
        repaired: list[list[int]] = []
        for kit in kits:
            parts = ctx.packer.split(list(kit_order(ctx.instance, [ids[i] for i in kit])))
            if parts is None:
                repaired = []
                break
            repaired += [[ctx.instance.index[t] for t in q] for q in parts]
        if repaired:
            repaired = canonical(repaired, ctx.groups)
            obj = scaled_objective(ctx.sc, repaired, ctx.objective)
            if state.obj is None or obj < state.obj:
                self.improve(repaired, obj)

    def improve(self, kits: list[list[int]], obj: int) -> None:
        """A new incumbent (packable kits of scaled objective ``obj``)."""
        self.state.kits, self.state.obj = kits, obj
        if self.ctx.live is not None:
            self.ctx.live.kits(kits, obj)

    def iterate(self, solver: Any) -> bool:
        """One master solve and its packing checks; False when the loop is done."""
        from ortools.sat.python import cp_model

        state, mdl = self.state, self.mdl
        if state.kits is not None:
            hint(mdl, self.ctx.sc, state.kits)
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
        state.status_name = solver.status_name(st)
        if st == cp_model.INFEASIBLE:
            # the master holds C <= U, so without an unproven cut the incumbent is optimal
            state.infeasible = state.kits is None and self.cuts.unproven == 0
            if state.kits is not None and self.cuts.unproven == 0:
                self.proved()
            return False
        if st not in (cp_model.OPTIMAL, cp_model.FEASIBLE):
            return False
        self.record_bound(math.ceil(solver.best_objective_bound - 1e-6))
        kits = extract_kits(mdl, solver)
        verdicts = self.verdicts(kits)
        if all(v.fits is True for v in verdicts):
            obj = round(solver.objective_value)
            if state.obj is None or obj <= state.obj:
                self.improve(kits, obj)
            best = obj if state.obj is None else state.obj
            if (st == cp_model.OPTIMAL and self.cuts.unproven == 0) or (
                state.lower is not None and state.lower >= best
            ):
                self.proved()
            return False  # optimal, or the master ran out of time on a packable incumbent
        if self.ctx.left() <= 0.01:  # no time for another master solve: no cuts, no repair
            return False
        new = self.cuts.cut_kits(map(self.counts, kits), verdicts)
        if self.ctx.left() > 0:
            self.repair(kits)
        if state.obj is not None and state.lower is not None and state.lower >= state.obj:
            self.proved()
            return False
        return bool(new)  # nothing new to cut: only possible with unknown packings

    def record_bound(self, bound: int) -> None:
        """A master's bound: a proof for 0/90-degree plans while every cut is proven, and for
        every plan while every cut holds at any angle (:attr:`.common.NoGoodCuts.scope`)."""
        state, scope = self.state, self.cuts.scope
        if scope is None:  # after an unproven cut the master bound is no proof
            return
        state.lower = bound if state.lower is None else max(state.lower, bound)
        if scope == ANY_ANGLE:
            state.lower_any = bound if state.lower_any is None else max(state.lower_any, bound)

    def proved(self) -> None:
        """The incumbent is optimal for the plans the cuts' scope covers."""
        state = self.state
        state.proven, state.lower = True, state.obj
        if self.cuts.scope == ANY_ANGLE:
            state.lower_any = state.obj
