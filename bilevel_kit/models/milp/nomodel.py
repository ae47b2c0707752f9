"""When ``milp`` builds no model: too large or too slow to build (:func:`buildable`), and
what it does with the time left then (:func:`handoff`: the LNS from the quick plan,
docs/formulations.md, "Model too large")."""

from __future__ import annotations

from typing import Any

from ...instance import Instance
from ...plan import Plan
from ..budget import Budget, no_model_reason
from ..common import Packer, assignment_cells

#: Peak memory per task x kit variable of the Pyomo model (measured 5-9 kB on in-trees of
#: 60-120 tasks; HiGHS runs in a child process); bench/results/scale.md.
BYTES_PER_CELL = 12_000
#: Time per task x kit variable to build the Pyomo model (measured 0.7-0.8 ms) and write it
#: for the HiGHS child (about 1.3 ms more: 7 s for 5,263 variables on a loaded machine).
BUILD_S_PER_CELL = 2.5e-3


def buildable(
    instance: Instance, K: int, budget: Budget, margin: float, extra: dict[str, Any], has_plan: bool
) -> bool:
    """Whether to build the model with K kits: False (with a ``reason``) when it would exceed
    the memory limit (a UsageError when there is no plan to return instead) or would not be
    built and solved within the time left (less ``margin``)."""
    cells = assignment_cells(instance, K)
    if instance.stations:  # with the station and tray-pair binaries
        from .stations import model_cells

        cells = model_cells(instance, K)
    extra["model_cells"] = cells
    what = f"task x kit variables ({instance.n_tasks} tasks, K = {K})"
    costs = (BYTES_PER_CELL, BUILD_S_PER_CELL)
    why = no_model_reason("milp", cells, costs, what, budget, margin, has_plan)
    if why is None:
        return True
    kind, reason = why
    keep = "the quick plan is returned" + (" with the proven bound" if kind == "too_large" else "")
    extra.update(reason=f"{reason}; {keep}", build_time_s=0.0, termination=kind)
    return False


def handoff(
    instance: Instance,
    kits: list[list[str]],
    plan: Plan,
    packer: Packer,
    *,
    bound: float,
    seed: int,
    time_limit: float,
    extra: dict[str, Any],
) -> list[list[str]]:
    """``kits`` (the incumbent, whose plan is ``plan``), or the kits of the better plan the LNS
    finds from it within ``time_limit`` s (:func:`..lns.fallback.improve`; their layouts
    taught to ``packer``, which lays the result out). ``extra`` gets ``improved_by`` (``lns``
    or None) and ``fallback`` (what happened)."""
    from ..lns.fallback import improve

    better, info = improve(instance, plan, bound=bound, seed=seed, time_limit=time_limit)
    extra.update(improved_by=None, fallback=info)
    if better is None:
        return kits
    for kit in better.kits:
        if kit.layout:
            packer.learn(instance.kit_parts(kit.tasks), kit.layout)
    extra["improved_by"] = "lns"
    return [list(k.tasks) for k in better.kits if k.tasks]
