"""The large-neighbourhood search's start plans (:mod:`.method`, step 1).

The baselines (single-task, whole-assembly); the topological order and the Johnson-priority
order (:func:`..common.johnson_topological_order`), each cut into kits of a fixed number of
tasks (split further where a kit does not fit) and cut exactly for one tray (:mod:`..segment`:
exact with one tray, a candidate otherwise); and greedy-ce within its share of the time limit
(when that share is at least :data:`GREEDY_MIN_S`).
Fits are decided by :class:`.fit.FastFit`.
"""

from __future__ import annotations

from collections.abc import Sequence

from ...errors import BilevelKitError
from ...instance import Instance, topological_order
from ...plan import Kit, Plan, evaluate
from ..budget import Budget
from ..common import johnson_topological_order, kit_order, split_greedily
from .fit import FastFit

#: The quick heuristics tried first (no time limit: each is linear in the tasks).
BASELINES = ("single-task", "whole-assembly")
#: Tasks per kit of the fixed-size cuts.
SIZES = (1, 2, 3, 4, 6, 8, 12, 16, 24)
#: The share of the time limit the cuts of the two orders may use together.
CUT_SHARE = 0.25
#: greedy-ce starts only up to this many tasks (beyond, within its share of a time limit it
#: leaves most tasks in single-task kits).
GREEDY_TASKS = 200
#: greedy-ce starts only when its share is at least this (s): its first call in a process loads
#: its compiled kernels (measured 3-5 s under load: 5.4 s for a 1 s share on 12 stool tasks).
GREEDY_MIN_S = 2.0
#: After its budget, the exact cut keeps growing segments with the shelf packer alone for this
#: many times the budget's length.
SHELF_GRACE = 0.25
#: Seconds a packing call of the cuts may take (an undecided segment counts as not fitting).
PROBE_S = 0.05


def start_plans(
    instance: Instance,
    fit: FastFit,
    budget: Budget,
    *,
    greedy: bool,
    share: float,
    seed: int,
) -> list[tuple[str, Plan]]:
    """Every start plan found within the budget, named by where it comes from."""
    from ..cpsat.warm import best_heuristic_plan

    out: list[tuple[str, Plan]] = []
    for name in BASELINES:
        plan, _ = best_heuristic_plan(instance, (name,), seed=seed)
        if plan is not None:
            out.append((name, plan))
    orders = [
        ("topological", topological_order(instance)),
        ("johnson", johnson_topological_order(instance)),
    ]
    end = min(budget.deadline, budget.start + CUT_SHARE * budget.time_limit)
    for (name, order), part in zip(orders, (0.6, 1.0), strict=True):
        cuts = Budget(budget.time_limit, start=budget.start, deadline=_part(end, part))
        for label, kits in _cuts(instance, order, fit, cuts):
            out.append((f"{name} {label}", Plan(tuple(Kit(tuple(k)) for k in kits))))
    left = min(share * budget.time_limit, budget.remaining())
    if greedy and left >= GREEDY_MIN_S and instance.n_tasks <= GREEDY_TASKS:
        try:
            plan, _ = best_heuristic_plan(instance, ("greedy-ce",), seed=seed, time_limit=left)
        except BilevelKitError:
            plan = None
        if plan is not None:
            out.append(("greedy-ce", plan))
    return out


def _part(end: float, part: float) -> float:
    """The deadline ``part`` of the way from now to ``end``."""
    import time

    now = time.perf_counter()
    return now + part * max(0.0, end - now)


def _cuts(
    instance: Instance, order: Sequence[str], fit: FastFit, budget: Budget
) -> list[tuple[str, list[list[str]]]]:
    """The exact one-tray cut of ``order`` and its best fixed-size cut (each when found)."""
    out = []
    probes = Budget(budget.time_limit, start=budget.start, deadline=_part(budget.deadline, 0.8))
    cut = exact_cut(instance, order, fit, probes)
    if cut is not None:
        out.append(("one-tray cut", cut))
    best: tuple[float, list[list[str]]] | None = None
    for size in SIZES:
        if budget.expired() or size > len(order):
            break
        kits = _fixed(instance, order, size, fit, budget)
        if kits is None:
            break
        ms = evaluate(instance, Plan(tuple(Kit(tuple(k)) for k in kits))).makespan
        if best is None or ms < best[0]:
            best = (ms, kits)
    if best is not None:
        out.append(("fixed cut", best[1]))
    return out


def exact_cut(
    instance: Instance, order: Sequence[str], fit: FastFit, budget: Budget
) -> list[list[str]] | None:
    """The best cut of ``order`` into contiguous kits under the one-tray recursion
    (:func:`..segment.one_tray_cut`); past the budget a segment grows only while the shelf
    packer lays it out (the packing oracle is no longer asked), and past
    :data:`SHELF_GRACE` times the budget's length it stops growing."""
    import time

    from ..segment import fit_extents, one_tray_cut

    if not order:
        return None
    now = time.perf_counter()
    grace = budget.deadline + SHELF_GRACE * max(0.0, budget.deadline - now)

    def fits(b: int, c: int) -> bool:
        return fit.fits(order[b:c], PROBE_S, oracle=not budget.expired())

    ext = fit_extents(len(order), fits, grace)
    return None if ext is None else one_tray_cut(instance, order, ext)[1]


def _fixed(
    instance: Instance, order: Sequence[str], size: int, fit: FastFit, budget: Budget
) -> list[list[str]] | None:
    """``order`` in kits of ``size`` tasks, each split greedily until it fits (None: a task
    does not fit, or the budget ran out)."""
    kits: list[list[str]] = []
    for a in range(0, len(order), size):
        if budget.expired():
            return None
        part = kit_order(instance, order[a : a + size])
        split = split_greedily(part, lambda k: fit.fits(k, PROBE_S), fit.fits)
        if split is None:
            return None
        kits += split
    return kits
