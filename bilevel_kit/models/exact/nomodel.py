"""When an exact method builds no model: too large or too slow to build (:func:`buildable`),
and what it does with the time left then (:func:`improve`: the LNS from the incumbent,
docs/formulations.md, "Model too large"). ``cpsat`` and ``milp`` differ only in their measured
costs (:class:`NoModelSpec`); the outcome is ``solver_status`` ``too_large`` or ``not_built`` in
both (:mod:`.keys`)."""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import Any

from ...instance import Instance
from ...plan import Plan
from ..budget import Budget, no_model_reason
from .keys import NOT_BUILT, TOO_LARGE, no_solve


@dataclass(frozen=True)
class NoModelSpec:
    """A backend's measured costs of a model."""

    owner: str  # the method's name, in the refusal's message
    bytes_per_cell: float  # peak memory per task x kit variable
    build_s_per_cell: float  # build time per task x kit variable
    kept: str  # what is returned instead ("the incumbent", "the quick plan")


#: ``cpsat``: peak memory 4.5-4.7 kB per variable above a 216 MB run of 14,000 variables,
#: 1.27 GB at 247,000 on a 500-task in-tree (model and a 2-worker solve); build time 90-120 us
#: per variable on in-trees of 60-500 tasks.
CPSAT = NoModelSpec("cpsat", 6_000, 150e-6, "the incumbent")
#: ``milp``: 5-9 kB per variable of the Pyomo model on in-trees of 60-120 tasks (HiGHS runs in
#: a child process; bench/results/scale.md); 0.7-0.8 ms to build it and about 1.3 ms more to
#: write it for the HiGHS child (7 s for 5,263 variables on a loaded machine).
MILP = NoModelSpec("milp", 12_000, 2.5e-3, "the incumbent")


def buildable(
    spec: NoModelSpec,
    instance: Instance,
    K: int,
    cells: int,
    budget: Budget,
    margin: float,
    extra: dict[str, Any],
    has_plan: bool,
) -> bool:
    """Whether to build the model of ``cells`` variables with K kits: False (with a
    ``reason``) when it would exceed the memory limit (a UsageError when there is no plan to
    return instead) or would not be built and solved within the time left (less ``margin``)."""
    extra["model_cells"] = cells
    what = f"task x kit variables ({instance.n_tasks} tasks, K = {K})"
    costs = (spec.bytes_per_cell, spec.build_s_per_cell)
    why = no_model_reason(spec.owner, cells, costs, what, budget, margin, has_plan)
    if why is None:
        return True
    kind, reason = why
    keep = f"{spec.kept} is returned" + (" with the proven bound" if kind == "too_large" else "")
    extra["reason"] = f"{reason}; {keep}"
    no_solve(extra, TOO_LARGE if kind == "too_large" else NOT_BUILT)
    return False


@dataclass(frozen=True)
class HandOff:
    """How long the LNS of :meth:`.backend.Backend.hand_off` may run: at most ``seconds``, and
    (the LNS first, :mod:`.lns_first`) ``stall`` windows in a row without improvement and
    ``windows`` windows in all (None: no such limit); ``cut_share``: ``lns``'s option of that
    name (None: its default), the share of ``seconds`` for its start plans cut from task
    orders."""

    seconds: float = math.inf
    stall: int | None = None
    windows: int | None = None
    cut_share: float | None = None

    def within(self, left: float) -> HandOff:
        """These limits with at most ``left`` seconds (the backend's time left)."""
        return replace(self, seconds=min(self.seconds, left))


#: The no-model hand-off: the whole time left, to a local optimum.
WHOLE = HandOff()


def improve(
    instance: Instance,
    plan: Plan,
    *,
    bound: float,
    seed: int,
    limit: HandOff,
    extra: dict[str, Any],
) -> Plan | None:
    """The better plan the LNS finds from ``plan`` (the incumbent) within ``limit`` (its
    seconds already the backend's time left at most; :func:`..lns.fallback.improve`), or None.
    ``extra`` gets ``improved_by`` (``lns`` or None) and ``fallback`` (what happened)."""
    from ..lns.fallback import improve as lns_improve

    better, info = lns_improve(
        instance,
        plan,
        bound=bound,
        seed=seed,
        time_limit=limit.seconds,
        stall=limit.stall,
        iterations=limit.windows,
        cut_share=limit.cut_share,
    )
    extra.update(improved_by=None, fallback=info)
    if better is not None:
        extra["improved_by"] = "lns"
    return better
