"""The large-neighbourhood search's start plans (:mod:`.method`, step 1).

The baselines (single-task, whole-assembly); the topological order and the Johnson-priority
order (:func:`..common.johnson_topological_order`), each cut into kits of a fixed number of
tasks (split further where a kit does not fit) and cut exactly for one tray (:mod:`..segment`:
exact with one tray, a candidate otherwise); and greedy-ce within its share of the time limit
(when that share is at least :data:`GREEDY_MIN_S`).
Fits are decided by :class:`.fit.FastFit`. With several stations (:mod:`.stations`): the
fixed-size cuts of each station's topological order interleaved by earliest need
(:func:`station_cuts`), and greedy-ce's plan with its single-task tail cut again
(:func:`recut_tail`).
"""

from __future__ import annotations

from collections.abc import Sequence

from ...errors import BilevelKitError
from ...heuristics.baselines import interleave
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
    cut_share: float = CUT_SHARE,
) -> list[tuple[str, Plan]]:
    """Every start plan found within the budget, named by where it comes from: the cuts of
    two task orders within ``cut_share`` of its time limit, greedy-ce's within ``share``."""
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
    end = min(budget.deadline, budget.start + cut_share * budget.time_limit)
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


# -- several stations (:mod:`.stations`) ------------------------------------------------------

#: Tasks per kit of the stations' fixed-size cuts: :data:`SIZES` and larger ones. Measured on
#: 1,800 sparse tasks on 3 stations (bench/results/lns_scale.md), where the robot serving three
#: humans is the bottleneck, the best cut held 32 tasks per kit: 23,592 s, against
#: 32,775-32,833 s for greedy-ce at 20 s.
STATION_SIZES = (*SIZES, 32, 48)


def station_cuts(instance: Instance, fit: FastFit, budget: Budget) -> list[tuple[int, float, Plan]]:
    """The fixed-size cuts with several stations: each station's tasks in topological order
    cut into kits of :data:`STATION_SIZES` tasks (split greedily where one does not fit), the
    stations' kits interleaved by earliest need (:func:`...heuristics.baselines.interleave`);
    (size, seconds it took, plan) for each size, smallest first, while the budget lasts."""
    import time

    order = topological_order(instance)
    queues: dict[str, list[str]] = {s: [] for s in instance.station_ids}
    for t in order:
        queues[instance.station_of(t)].append(t)
    out = []
    for size in STATION_SIZES:
        t0 = time.perf_counter()
        if budget.expired():
            break
        cut = _station_fixed(instance, queues, size, fit, budget)
        if cut is None:
            break
        out.append((size, time.perf_counter() - t0, interleave(instance, cut)))
    return out


def recut_tail(
    instance: Instance, plan: Plan, size: int, fit: FastFit, budget: Budget
) -> Plan | None:
    """``plan`` with each station's trailing single-task kits (what greedy-ce leaves when its
    time limit stops it) cut again into kits of ``size`` tasks in their order, interleaved by
    earliest need after the other kits (None: nothing to cut, or the budget ran out)."""
    tails, in_tail = _tails(instance, plan)
    if not any(len(t) > 1 for t in tails.values()):
        return None
    cut = _station_fixed(instance, tails, size, fit, budget)
    if cut is None:
        return None
    head = [k for k, tail in zip(plan.kits, in_tail, strict=True) if not tail]
    return interleave(instance, cut, head=head)


def _tails(instance: Instance, plan: Plan) -> tuple[dict[str, list[str]], list[bool]]:
    """Each station's tasks in its trailing single-task kits, in order, and which kits
    those are."""
    tails: dict[str, list[str]] = {s: [] for s in instance.station_ids}
    in_tail = [False] * len(plan.kits)
    closed: set[str] = set()  # stations whose tail has ended (a larger kit before it)
    for j in range(len(plan.kits) - 1, -1, -1):
        kit = plan.kits[j]
        s = instance.station_of(kit.tasks[0])
        if s in closed:
            continue
        if len(kit.tasks) == 1:
            tails[s].insert(0, kit.tasks[0])
            in_tail[j] = True
        else:
            closed.add(s)
    return tails, in_tail


def _station_fixed(
    instance: Instance, queues: dict[str, list[str]], size: int, fit: FastFit, budget: Budget
) -> dict[str, list[list[str]]] | None:
    """Each station's tasks (in ``queues``, in order) in kits of ``size`` tasks, each split
    greedily until it fits (a probe of :data:`PROBE_S` deterministic seconds); a kit of
    part-less tasks only joins its station's kit before it (after it, when first), which keeps
    the order and the fit. None: a task does not fit, or the budget ran out."""

    def fits(kit: list[str]) -> bool:
        return fit.counts(instance.kit_parts(kit), PROBE_S, deterministic=True) is True

    out: dict[str, list[list[str]]] = {}
    for s, tasks in queues.items():
        kits: list[list[str]] = []
        for a in range(0, len(tasks), size):
            if budget.expired():
                return None
            split = split_greedily(tasks[a : a + size], fits)
            if split is None:
                return None
            kits += split
        needy = [any(instance.needs_kit(t) for t in k) for k in kits]
        if any(needy):  # (a station of part-less tasks only keeps its part-less kits)
            merged: list[list[str]] = []
            carry: list[str] = []
            for kit, needs in zip(kits, needy, strict=True):
                if needs:
                    merged.append(carry + kit)
                    carry = []
                elif merged:
                    merged[-1] = merged[-1] + kit
                else:
                    carry += kit
            kits = merged
        out[s] = kits
    return out
