"""The master <-> packing loop of ``milp`` (logic-based Benders, :mod:`.method`'s module
docstring; docs/formulations.md, "MILP schedule") and the run's live progress in seconds of
its objective (:mod:`bilevel_kit.progress`)."""

from __future__ import annotations

import functools
from collections.abc import Mapping, Sequence
from typing import Any

from ... import progress
from ...instance import Instance
from ...objectives import Objective, human_times
from ...plan import Plan, evaluate
from ...stations import objective_of
from ..budget import Budget
from ..common import NoGoodCuts, Packer
from ..exact.benders_log import BendersLog
from ..packing import ANY_ANGLE
from .model import Master, add_cut, extract, objective_value, set_start
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


class Benders(BendersLog[str, float]):
    """The master <-> packing loop (module docstring): the incumbent ``kits`` (objective
    ``obj``), the master's proven bounds and the cuts in
    :class:`..exact.benders_log.BendersLog`, in seconds within the solver's tolerance."""

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
        cuts = NoGoodCuts(packer, budget, MARGIN, functools.partial(add_cut, master))
        left = functools.partial(budget.remaining, MARGIN)
        super().__init__(instance, cuts, left, inc, inc_obj, TOL)
        self.live = live
        self.master = master
        self.budget = budget
        self.options = options

    def task_ids(self, kit: Sequence[str]) -> list[str]:
        return list(kit)

    def scored(self, kits: list[list[str]]) -> tuple[list[list[str]], float]:
        return kits, objective_value(self.instance, kits, self.options.objective)

    def run(
        self, opt: Any, seed: int, solver_options: Mapping[str, Any] | None
    ) -> SolveInfo | None:
        """Solve the master until its solution packs, it is proven or the time is up; the
        last solve's info."""
        info: SolveInfo | None = None
        while self.left() > 0.05:
            self.iterations += 1
            if self.kits is not None:
                set_start(self.master, self.instance, self.kits)
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
                warmstart=self.kits is not None,
                on_bounds=self.live.on_bounds if proof and self.live.tracker.active else None,
            )
            go_on = self.step(info)
            self.live.model_values(self.obj, self.lower_any)
            if not go_on:
                break
        return info

    def step(self, info: SolveInfo) -> bool:
        """Use one master solution; False when the loop is done."""
        if info.infeasible:
            self.master_infeasible()
            return False
        if info.bound is not None:
            self.record_bound(info.bound)
        if not info.has_solution:
            return False
        kits = extract(self.master)
        verdicts = self.verdicts(kits)
        if all(v.fits is True for v in verdicts):
            _, obj = self.scored(kits)
            if self.accepts(obj):
                self.improve(kits, obj)
            self.proven = info.optimal and self.cuts.unproven == 0
            if self.proven and self.cuts.scope == ANY_ANGLE:
                self.lower_any = self.lower
            return False  # optimal, or the master ran out of time on a packable incumbent
        if self.left() <= 0.05:  # no time for another master solve: no cuts, no repair
            return False
        return self.cut(kits, verdicts)
