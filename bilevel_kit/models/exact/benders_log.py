"""What the logic-based Benders loops of ``cpsat`` and ``milp`` share (docs/formulations.md,
"One driver for cpsat and milp"): the incumbent, the master's bounds proven for 0/90-degree
plans (``lower``) and every plan (``lower_any``), the proof, the kits' packing verdicts, cuts
and repair. They differ in the master's solver and the objective's unit: CP-SAT's integer
grid, compared exactly (``tol`` 0), or MILP's seconds, within the relative tolerance ``tol``."""

from __future__ import annotations

from collections.abc import Callable, Iterable, Sequence
from typing import Generic, TypeVar

from ...instance import Instance
from ..common import NoGoodCuts, kit_order
from ..packing import ANY_ANGLE
from ..packing_oracle import WHY_TIME, Fit

#: A task in a master's kit: CP-SAT's task index or MILP's task id.
T = TypeVar("T", int, str)
#: The master's objective: CP-SAT's scaled integer time or MILP's seconds.
N = TypeVar("N", int, float)


class BendersLog(Generic[T, N]):
    """One loop's incumbent ``kits`` (objective ``obj``), proven bounds and cuts; ``left()``
    its seconds left. A backend names its kits' tasks and scores repaired kits."""

    def __init__(
        self,
        instance: Instance,
        cuts: NoGoodCuts,
        left: Callable[[], float],
        kits: list[list[T]] | None,
        obj: N | None,
        tol: float = 0.0,
    ) -> None:
        self.instance = instance
        self.cuts = cuts
        self.left = left
        self.kits: list[list[T]] | None = kits
        self.obj: N | None = obj
        self.tol = tol
        self.lower: N | None = None
        self.lower_any: N | None = None
        self.proven = False
        self.infeasible = False
        self.iterations = 0

    def task_ids(self, kit: Sequence[T]) -> list[str]:
        raise NotImplementedError  # the task ids of one of the master's kits

    def scored(self, kits: list[list[str]]) -> tuple[list[list[T]], N]:
        raise NotImplementedError  # kits of task ids as the master's, with their objective

    def improve(self, kits: list[list[T]], obj: N) -> None:
        self.kits, self.obj = kits, obj

    def counts(self, kit: Sequence[T]) -> dict[str, int]:
        return dict(self.instance.kit_parts(self.task_ids(kit)))

    def accepts(self, obj: N) -> bool:
        """Is a packable master solution of objective ``obj`` as good as the incumbent?"""
        return self.obj is None or obj <= self.obj + self.tol * max(1.0, abs(obj))

    def beats(self, obj: N) -> bool:
        """Is a repaired plan of objective ``obj`` better than the incumbent?"""
        return self.obj is None or obj < self.obj - self.tol * max(1.0, abs(obj))

    def closed(self) -> bool:
        """Does the proven bound reach the incumbent (it is optimal)?"""
        obj, lower = self.obj, self.lower
        return obj is not None and lower is not None and lower >= obj - self.tol * abs(obj)

    def record_bound(self, bound: N) -> None:
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
        self.proven, self.lower = True, self.obj
        if self.cuts.scope == ANY_ANGLE:
            self.lower_any = self.obj

    def master_infeasible(self) -> None:
        """The master (C <= U) has no solution: without an unproven cut the incumbent is
        optimal (none: there is no plan)."""
        if self.cuts.unproven == 0:
            if self.kits is not None:
                self.proved()
            else:
                self.infeasible = True

    def verdicts(self, kits: Iterable[Sequence[T]]) -> list[Fit]:
        """Does each kit fit (the oracle's answer; unknown past the time limit)?"""
        packer = self.cuts.packer
        out: list[Fit] = []
        for kit in kits:
            if self.left() <= 0:  # out of time: the rest stays unknown
                out.append(Fit(None, why=WHY_TIME))
                continue
            counts = self.counts(kit)
            fit = packer.verdict(counts)
            if fit.fits is None:  # a hard packing: one more try with a longer limit
                longer = 10 * packer.pack_tl  # (reproducible: not from the clock)
                if not packer.deterministic:
                    longer = max(packer.pack_tl, min(longer, self.left() / 3))
                fit = packer.verdict(counts, longer)
            out.append(fit)
        return out

    def cut(self, kits: Sequence[Sequence[T]], verdicts: list[Fit]) -> bool:
        """Cut the kits that do not fit and, time left, repair them into an incumbent; False
        when the loop is done: the incumbent proven optimal, or nothing new to cut (only
        possible with unknown packings)."""
        new = self.cuts.cut_kits(map(self.counts, kits), verdicts)
        if self.left() > 0:
            self.repair(kits)
        if self.closed():
            self.proved()
            return False
        return bool(new)

    def repair(self, kits: Iterable[Sequence[T]]) -> None:
        """Split the kits that do not fit (each in the human's order) greedily into kits that
        do; keep the result if it beats the incumbent."""
        split: list[list[str]] = []
        for kit in kits:
            parts = self.cuts.packer.split(kit_order(self.instance, self.task_ids(kit)))
            if parts is None:
                return
            split += parts
        if split:
            repaired, obj = self.scored(split)
            if self.beats(obj):
                self.improve(repaired, obj)

    def cut_counts(self) -> dict[str, int]:
        """The ``extra`` counts of the cuts that limit the proof
        (:attr:`..common.NoGoodCuts.scope`)."""
        return {"unproven_cuts": self.cuts.unproven, "axis_aligned_cuts": self.cuts.axis_only}
