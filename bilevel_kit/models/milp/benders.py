"""The master <-> packing loop of ``milp`` (logic-based Benders, :mod:`.method`'s module
docstring; docs/formulations.md, "MILP schedule") and the run's live progress in seconds of
its objective (:mod:`bilevel_kit.progress`)."""

from __future__ import annotations

import functools
from collections.abc import Mapping
from typing import Any

from ... import progress
from ...instance import Instance
from ...objectives import Objective, human_times
from ...plan import Plan, evaluate
from ...stations import objective_of
from ..budget import Budget
from ..common import NoGoodCuts, Packer
from ..packing import ANY_ANGLE
from ..packing_oracle import WHY_TIME, Fit
from .model import Master, add_cut, extract, human_order, objective_value, set_start
from .options import MARGIN, MilpOptions
from .solver import TOL, SolveInfo, run_solver


class Live:
    """The run's live progress (:mod:`bilevel_kit.progress`) in seconds of its objective: the
    master's objective is the makespan, or ``C - o_H m`` = human idle + ``sum h``."""

    def __init__(self, tracker: progress.Tracker, instance: Instance, objective: Objective) -> None:
        self.tracker = tracker
        self.instance = instance
        self.objective = objective
        self.offset = float(objective.dropped(human_times(instance)))

    def seconds(self, value: float | None) -> float | None:
        return None if value is None else value - self.offset

    def bound(self, dual: float | None) -> float | None:
        """A solver's dual bound in seconds, less :data:`.solver.TOL` (it holds up to the
        solver's tolerances: 39.0000000000025 for an optimum of 39)."""
        return None if dual is None else self.seconds(dual - TOL * max(1.0, abs(dual)))

    def model_values(
        self, inc_obj: float | None, lower: float | None, stage: str | None = None
    ) -> None:
        """The incumbent's model objective and a master's proven bound (None: not known)."""
        self.tracker.report(self.seconds(inc_obj), self.bound(lower), stage)

    def on_bounds(self, primal: float | None, dual: float | None) -> None:
        """A master's bounds while it runs: only the dual one counts (see the caller)."""
        self.tracker.report(bound=self.bound(dual))

    def final(self, plan: Plan, bound: float | None, extra: dict[str, Any]) -> None:
        """The result's own numbers (the last report)."""
        if not self.tracker.active:
            return
        tl = evaluate(self.instance, plan)
        # the result's own bound (the makespan) or the one in extra (objectives.py)
        _, lower, _, _ = self.objective.stated({"bound": bound}, extra)
        self.tracker.report(objective_of(tl, self.objective.name), lower)


class Benders:
    """The master <-> packing loop (module docstring): the incumbent ``inc`` (objective
    ``inc_obj``), the master's proven bound ``lower`` and the cuts seen so far."""

    def __init__(
        self,
        instance: Instance,
        master: Master,
        packer: Packer,
        budget: Budget,
        options: MilpOptions,
        inc: list[list[str]] | None,
        inc_obj: float | None,
        live: Live,
    ) -> None:
        self.live = live
        self.instance = instance
        self.master = master
        self.packer = packer
        self.budget = budget
        self.options = options
        self.inc = inc
        self.inc_obj = inc_obj
        self.cuts = NoGoodCuts(packer, budget, MARGIN, functools.partial(add_cut, master))
        self.lower: float | None = None
        self.lower_any: float | None = None
        self.proven = False
        self.infeasible = False
        self.iterations = 0

    def left(self) -> float:
        return self.budget.remaining(MARGIN)

    def run(
        self, opt: Any, seed: int, solver_options: Mapping[str, Any] | None
    ) -> SolveInfo | None:
        """Solve the master until its solution packs, it is proven or the time is up; the
        last solve's info."""
        info: SolveInfo | None = None
        while self.left() > 0.05:
            self.iterations += 1
            if self.inc is not None:
                set_start(self.master, self.instance, self.inc)
            # the master's bound holds for every plan only while every cut does (its scope);
            # its solutions are no plans
            proof = self.cuts.scope == ANY_ANGLE
            stage = f"MILP ({self.options.solver}), {self.master.n_cuts} cuts"
            self.live.model_values(None, None, stage)
            info = run_solver(
                self.master.model,
                opt,
                self.options.solver,
                budget=self.budget.cut(MARGIN),
                seed=seed,
                log=self.options.log,
                objective=self.master.model.obj,
                options=solver_options,
                warmstart=self.inc is not None,
                on_bounds=self.live.on_bounds if proof and self.live.tracker.active else None,
            )
            go_on = self.step(info)
            self.live.model_values(self.inc_obj, self.lower_any)
            if not go_on:
                break
        return info

    def step(self, info: SolveInfo) -> bool:
        """Use one master solution; False when the loop is done."""
        instance, objective = self.instance, self.options.objective
        if info.infeasible:
            # the master holds C <= U: without unproven cuts the incumbent is optimal
            if self.cuts.unproven == 0:
                if self.inc is not None:
                    self.proved()
                else:
                    self.infeasible = True
            return False
        if info.bound is not None:
            self.record_bound(info.bound)
        if not info.has_solution:
            return False
        kits = extract(self.master)
        verdicts = self.verdicts(kits)
        if all(v.fits is True for v in verdicts):
            obj = objective_value(instance, kits, objective)
            if self.inc_obj is None or obj <= self.inc_obj + TOL * max(1.0, abs(obj)):
                self.inc, self.inc_obj = kits, obj
            self.proven = info.optimal and self.cuts.unproven == 0
            if self.proven and self.cuts.scope == ANY_ANGLE:
                self.lower_any = self.lower
            return False  # optimal, or the master ran out of time on a packable incumbent
        if self.left() <= 0.05:  # no time for another master solve: no cuts, no repair
            return False
        new = self.cuts.cut_kits(map(instance.kit_parts, kits), verdicts)
        if self.left() > 0:
            self.repair(kits)
        inc_obj, lower = self.inc_obj, self.lower
        if inc_obj is not None and lower is not None and lower >= inc_obj - TOL * abs(inc_obj):
            self.proved()
            return False
        return bool(new)  # nothing new to cut: only possible with unknown packings

    def record_bound(self, bound: float) -> None:
        """A master's bound: a proof for 0/90-degree plans while every cut is proven, and for
        every plan while every cut holds at any angle (:attr:`..common.NoGoodCuts.scope`)."""
        scope = self.cuts.scope
        if scope is None:  # after an unproven cut the master bound is no proof
            return
        self.lower = bound if self.lower is None else max(self.lower, bound)
        if scope == ANY_ANGLE:
            self.lower_any = bound if self.lower_any is None else max(self.lower_any, bound)

    def proved(self) -> None:
        """The incumbent is optimal for the plans the cuts' scope covers."""
        self.proven, self.lower = True, self.inc_obj
        if self.cuts.scope == ANY_ANGLE:
            self.lower_any = self.inc_obj

    def verdicts(self, kits: list[list[str]]) -> list[Fit]:
        """Does each kit fit (the oracle's answer; unknown past the time limit)?"""
        out: list[Fit] = []
        pack_tl = self.packer.pack_tl
        for kit in kits:
            if self.left() <= 0:  # out of time: the rest stays unknown
                out.append(Fit(None, why=WHY_TIME))
                continue
            counts = self.instance.kit_parts(kit)
            fit = self.packer.verdict(counts)
            if fit.fits is None:  # a hard packing: one more try with a longer limit
                fit = self.packer.verdict(counts, max(pack_tl, min(10 * pack_tl, self.left() / 3)))
            out.append(fit)
        return out

    def repair(self, kits: list[list[str]]) -> None:
        """Split the kits that do not fit; keep the result if it beats the incumbent."""
        repaired: list[list[str]] = []
        for kit in kits:
            parts = self.packer.split(human_order(self.instance, kit))
            if parts is None:
                repaired = []
                break
            repaired += parts
        if repaired:
            obj = objective_value(self.instance, repaired, self.options.objective)
            if self.inc_obj is None or obj < self.inc_obj - TOL * max(1.0, abs(obj)):
                self.inc, self.inc_obj = repaired, obj
