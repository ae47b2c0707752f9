"""Pieces both exact schedule models share (CP-SAT and the MILP).

The transitive reduction of the precedence graph, the human's order inside a kit, groups of
interchangeable precedence chains (for symmetry breaking), the kit positions a task can take,
the packing oracle under a run's time budget, the no-good cuts of the Benders loops, a cheap
feasible plan that gives an upper bound and a warm start, and the ``extra`` entries of a plan
(docs/formulations.md).
"""

from __future__ import annotations

import itertools
import time
from collections.abc import Callable, Collection, Iterable, Mapping, Sequence
from typing import Any, NamedTuple, TypeVar

from ..instance import Instance, topological_order
from ..methods import Status
from ..plan import Kit, Placement, Plan, Timeline, evaluate
from . import packing_oracle
from .budget import Budget
from .packing import ANY_ANGLE, AXIS_ALIGNED
from .packing_oracle import Fit

T = TypeVar("T")


def reduced_edges(instance: Instance) -> list[tuple[str, str]]:
    """The transitive reduction of the precedence graph (same order relation, fewer edges)."""
    anc, pred = instance.ancestors, instance.predecessors
    out = []
    for a, b in dict.fromkeys(instance.precedence):
        if not any(a in anc[c] for c in pred[b] if c != a):
            out.append((a, b))
    return out


def chain_groups_idx(
    n: int, edges: Sequence[tuple[int, int]], sig: Sequence[Any]
) -> list[list[list[int]]]:
    """Groups (>= 2) of interchangeable precedence chains in the reduced graph.

    A chain follows links a -> b where a has exactly one successor and b exactly one
    predecessor. Two chains with equal task signatures, equal predecessors of the head and
    equal successors of the tail can be swapped: an automorphism of the whole problem.
    """
    succ: list[list[int]] = [[] for _ in range(n)]
    pred: list[list[int]] = [[] for _ in range(n)]
    for a, b in edges:
        succ[a].append(b)
        pred[b].append(a)

    def linked(a: int, b: int) -> bool:
        return len(succ[a]) == 1 and len(pred[b]) == 1 and succ[a][0] == b

    groups: dict[Any, list[list[int]]] = {}
    for v in range(n):
        if len(pred[v]) == 1 and linked(pred[v][0], v):
            continue  # not a head
        chain = [v]
        while len(succ[chain[-1]]) == 1 and linked(chain[-1], succ[chain[-1]][0]):
            chain.append(succ[chain[-1]][0])
        key = (frozenset(pred[v]), frozenset(succ[chain[-1]]), tuple(sig[c] for c in chain))
        groups.setdefault(key, []).append(chain)
    return [sorted(g) for g in groups.values() if len(g) >= 2]


def chain_groups(instance: Instance) -> list[list[list[str]]]:
    """:func:`chain_groups_idx` on task ids; a task's signature is (robot time, human time,
    parts), so swapping two chains of a group changes nothing."""
    ids = [t.id for t in instance.tasks]
    idx = instance.index
    edges = [(idx[a], idx[b]) for a, b in reduced_edges(instance)]
    sig = [
        (
            instance.robot_time(t),
            instance.human_time(t),
            tuple(sorted(instance.task_by_id[t].parts)),
        )
        for t in ids
    ]
    return [
        [[ids[i] for i in chain] for chain in g] for g in chain_groups_idx(len(ids), edges, sig)
    ]


def relabel_chains(pos: Mapping[T, int], groups: Iterable[Sequence[Sequence[T]]]) -> dict[T, int]:
    """The kit of every task (``pos``) once the interchangeable chains of each group (listed
    in task order, as :func:`chain_groups_idx` gives them) are relabelled so that their kit
    vectors are in lexicographic order: the exact models' symmetry breaking. Kit contents stay
    the same multisets."""
    new = dict(pos)
    for group in groups:
        vectors = sorted(tuple(pos[t] for t in chain) for chain in group)
        for chain, vec in zip(group, vectors, strict=True):
            for t, k in zip(chain, vec, strict=True):
                new[t] = k
    return new


def kit_order(instance: Instance, tasks: Collection[str]) -> tuple[str, ...]:
    """A topological order of a kit's tasks (ties by file order): the human's order."""
    members = set(tasks)
    anc = instance.ancestors
    left = sorted(members, key=instance.index.__getitem__)
    out: list[str] = []
    done: set[str] = set()
    while left:
        for t in left:
            if all(a in done for a in anc[t] if a in members):
                out.append(t)
                done.add(t)
                left.remove(t)
                break
        else:  # pragma: no cover - impossible for an acyclic graph
            raise ValueError("cycle inside a kit")
    return tuple(out)


def kit_positions(instance: Instance, K: int) -> list[int]:
    """How many of the K kit positions each task (in ``instance.tasks`` order) can take: task i
    is in one of the first ``n - |descendants(i)|`` kits, since every later kit needs a task."""
    n = instance.n_tasks
    n_desc = dict.fromkeys(instance.task_by_id, 0)
    for t in instance.tasks:
        for a in instance.ancestors[t.id]:
            n_desc[a] += 1
    return [min(K, n - n_desc[t.id]) for t in instance.tasks]


def assignment_cells(instance: Instance, K: int) -> int:
    """Number of (task, kit position) variables of the exact models with K positions
    (:func:`kit_positions`); their models grow with it."""
    return sum(kit_positions(instance, K))


def plan_extra(
    plan: Plan, real: Timeline, bound: float, closed: float, model_bound: float | None
) -> dict[str, Any]:
    """The ``extra`` entries of an exact model's plan (``real``: its timeline): the gap to the
    makespan ``bound``, makespan, human idle, kit count, the closed-form bound and the model's
    own bound."""
    from ..methods import gap

    return {
        "gap": gap(real.makespan, bound) or 0.0,
        "makespan": real.makespan,
        "human_idle": real.human_idle,
        "n_kits": len(plan.kits),
        "bound_closed_form": closed,
        "bound_model": model_bound,
    }


def pack_time_limit(budget: Budget) -> float:
    """Seconds one packing call may take: 5 % of the time limit, within [0.2, 2] s."""
    return max(0.2, min(2.0, 0.05 * budget.time_limit))


def unfit_outcome(unfit: tuple[str, str], extra: dict[str, Any]) -> Status:
    """A task whose parts alone do not fit (``(task, scope)`` of
    :meth:`Packer.task_not_fitting`): no plan at all (infeasible) when that is proven
    at any angle, else none with 0/90-degree layouts (unknown: one at other angles may exist;
    docs/formulations.md#what-optimal-means). ``extra`` gets the ``reason``."""
    task, scope = unfit
    if scope == ANY_ANGLE:
        extra["reason"] = f"the parts of task {task!r} alone do not fit the tray"
        return Status.INFEASIBLE
    extra.update(
        reason=f"the parts of task {task!r} alone have no 0/90-degree layout on the tray "
        "(a layout at other angles may exist)",
        infeasible_axis_aligned=True,
        proof_scope=AXIS_ALIGNED,
    )
    return Status.UNKNOWN


class Packer:
    """The packing oracle under the run's budget: every call gets at most ``pack_tl``
    seconds and never more than what is left. ``deterministic``: every call is limited by
    CP-SAT's deterministic time instead, :func:`.packing_oracle.deterministic_limits` of its
    seconds, with the wall-clock safety net (still within what is left of the budget), so
    its verdicts do not depend on the machine load (docs/simulation.md#determinism)."""

    def __init__(
        self,
        instance: Instance,
        pack_tl: float,
        budget: Budget,
        resolution: float = 1.0,
        *,
        deterministic: bool = False,
    ) -> None:
        from ..reachability import reach_grid

        self.instance = instance
        self.res = resolution
        self.pack_tl = pack_tl
        self.budget = budget
        self.deterministic = deterministic
        self.reach = reach_grid(instance)
        self.known: list[tuple[dict[str, int], packing_oracle.TypedLayout]] = []

    def sub(self, pack_tl: float, budget: Budget) -> Packer:
        """A packer for a sub-step: ``pack_tl`` s per call within ``budget``, the same grid and
        kind of limit."""
        return Packer(self.instance, pack_tl, budget, self.res, deterministic=self.deterministic)

    def _tl(self, limit: float | None = None) -> float:
        limit = self.pack_tl if limit is None else limit
        return max(0.02, min(limit, self.budget.remaining()))

    def limits(
        self, limit: float | None = None, deterministic: bool | None = None
    ) -> dict[str, Any]:
        """The oracle's keywords for a call of ``limit`` s (None: ``pack_tl``), deterministic
        when asked (None: as the packer is)."""
        limit = self.pack_tl if limit is None else limit
        if not (self.deterministic if deterministic is None else deterministic):
            return {"time_limit": self._tl(limit)}
        dtime, net = packing_oracle.deterministic_limits(limit)
        return {"deterministic_time": dtime, "time_limit": self._tl(net)}

    def learn(self, counts: Mapping[str, int], layout: Sequence[Placement]) -> None:
        """A valid layout of ``counts`` known from elsewhere (a warm start's kit, which may
        have parts at any angle): this packer answers "fits" for it and its sub-multisets."""
        typed: packing_oracle.TypedLayout = {}
        for p in layout:
            typed.setdefault(p.type, []).append((p.x, p.y, p.theta))
        self.known.append(({k: n for k, n in counts.items() if n > 0}, typed))

    def verdict(
        self,
        counts: Mapping[str, int],
        limit: float | None = None,
        deterministic: bool | None = None,
    ) -> Fit:
        """The oracle's answer (:func:`.packing_oracle.fit_verdict`): "no" only with a proof;
        "fits" at once for a multiset within one of :meth:`learn`'s."""
        for known, typed in self.known:
            if all(known.get(k, 0) >= n for k, n in counts.items() if n > 0):
                return Fit(True, {k: typed[k][:n] for k, n in counts.items() if n > 0})
        return self.grid_verdict(counts, limit, deterministic)

    def grid_verdict(
        self,
        counts: Mapping[str, int],
        limit: float | None = None,
        deterministic: bool | None = None,
    ) -> Fit:
        """The oracle's answer alone: its layouts lie on a packing grid at 0 or 90 degrees
        (what the embedded model's hints need), never one of :meth:`learn`'s."""
        return packing_oracle.fit_verdict(
            self.instance.tray,
            self.instance.part_types,
            dict(counts),
            resolution=self.res,
            reach=self.reach,
            **self.limits(limit, deterministic),
        )

    def counts(
        self,
        counts: Mapping[str, int],
        limit: float | None = None,
        deterministic: bool | None = None,
    ) -> tuple[bool | None, Any]:
        fit = self.verdict(counts, limit, deterministic)
        return fit.fits, fit.layout

    def fits(self, tasks: Sequence[str]) -> bool | None:
        return self.counts(dict(self.instance.kit_parts(tasks)))[0]

    def task_not_fitting(self) -> tuple[str, str] | None:
        """A task whose parts alone provably do not fit the tray, with the proof's scope (then
        no plan exists, or none with 0/90-degree layouts); stops (None) once the budget has
        expired."""
        for t in self.instance.tasks:
            if not self.deterministic and self.budget.expired():
                return None
            fit = self.verdict(self.instance.kit_parts([t.id]))
            if fit.fits is False:
                return t.id, fit.scope or AXIS_ALIGNED
        return None

    def split(self, kit: Sequence[str]) -> list[list[str]] | None:
        """Cut a kit (in human order) greedily into consecutive sub-kits that fit; None if a
        single task does not fit (or is unknown)."""
        return split_greedily(kit, self.fits)

    def minimal_nofit(
        self,
        counts: Mapping[str, int],
        until: float,
        scope: str = AXIS_ALIGNED,
        deterministic: bool | None = None,
    ) -> dict[str, int]:
        """Deletion filter: drop parts (smallest types first) while the rest provably does not
        fit, with a proof of ``scope`` (one for every layout stays one); stops early at
        ``until`` (a larger non-fitting multiset is still a valid cut); ``deterministic`` as
        in :meth:`verdict`. A reproducible packer (``self.deterministic``) ignores ``until``:
        at most one call per part, each limited by deterministic time
        (docs/simulation.md#determinism)."""
        cur = {k: n for k, n in counts.items() if n > 0}
        clock = not self.deterministic
        for t in sorted(cur, key=lambda q: (self.instance.part_types[q].area, q)):
            while cur.get(t, 0) > 0 and (not clock or time.perf_counter() < until):
                trial = dict(cur)
                trial[t] -= 1
                if trial[t] == 0:
                    del trial[t]
                fit = self.verdict(trial, deterministic=deterministic) if trial else Fit(True)
                if fit.fits is not False or (scope == ANY_ANGLE and fit.scope != ANY_ANGLE):
                    break
                cur = trial
        return cur

    def layout(self, tasks: Sequence[str]) -> tuple[Placement, ...] | None:
        """The oracle's layout of a kit, else the shelf packer's (when reachability is not
        enforced: the shelf packer ignores it), else None."""
        from ..heuristics.shelf import shelf_pack

        ok, typed = self.counts(self.instance.kit_parts(tasks))
        if ok and typed is not None:
            return packing_oracle.typed_to_placements(self.instance, tasks, typed)
        if self.reach is not None:
            return None
        items = [
            (f"{t}:{p}:{j}", self.instance.part_types[p])
            for t in tasks
            for p, n in self.instance.task_by_id[t].parts
            for j in range(1, n + 1)
        ]
        return shelf_pack(self.instance.tray, items)


class NoGoodCuts:
    """The cuts of a logic-based Benders loop (``cpsat`` and ``milp``): a part multiset that
    does not fit is cut from every kit by ``add``, once; shrunk first to a minimal non-fitting
    multiset when the misfit is proven. A cut from an unknown packing (a time limit, or a "no"
    of an inexact packing grid) is unproven (a heuristic: after one, the master's bound is no
    proof); ``unproven`` counts them, ``axis_only`` the cuts proven for 0/90-degree layouts
    only (after one, the bound holds for such plans only: :attr:`scope`)."""

    def __init__(
        self,
        packer: Packer,
        budget: Budget,
        margin: float,
        add: Callable[[dict[str, int]], None],
    ) -> None:
        self.packer = packer
        self.budget = budget
        self.margin = margin
        self.add = add
        self.seen: set[frozenset[tuple[str, int]]] = set()
        self.unproven = 0
        self.axis_only = 0

    @property
    def scope(self) -> str | None:
        """For which plans the master is a relaxation: every plan (:data:`.packing.ANY_ANGLE`),
        those with 0/90-degree layouts (:data:`.packing.AXIS_ALIGNED`), or None (an unproven
        cut: no proof at all)."""
        if self.unproven:
            return None
        return AXIS_ALIGNED if self.axis_only else ANY_ANGLE

    def cut(self, counts: Mapping[str, int], scope: str | None) -> bool:
        """Cut ``counts`` (shrunk when proven, ``scope`` not None) unless the same cut was
        added before."""
        mini = (
            self.packer.minimal_nofit(counts, self.budget.share(1 / 4, self.margin), scope)
            if scope is not None
            else dict(counts)
        )
        key = frozenset(mini.items())
        if key in self.seen:
            return False
        self.seen.add(key)
        self.add(mini)
        self.unproven += scope is None
        self.axis_only += scope == AXIS_ALIGNED
        return True

    def cut_kits(self, kits: Iterable[Mapping[str, int]], verdicts: Iterable[Fit]) -> int:
        """Cut the part multisets of the kits that do not fit (a proven "no") or may not
        (unknown: unproven); how many cuts are new."""
        new = 0
        for counts, fit in zip(kits, verdicts, strict=True):
            if fit.fits is not True:
                new += self.cut(counts, fit.scope if fit.fits is False else None)
        return new

    def seed_pairs(self) -> None:
        """Cut every pair of tasks (distinct part multisets) that provably does not fit
        together, while a tenth of the time left lasts (a reproducible packer: every pair,
        each call limited by deterministic time, docs/simulation.md#determinism)."""
        instance = self.packer.instance
        seed_until = self.budget.share(0.1, self.margin)
        clock = not self.packer.deterministic
        reps = list(
            {frozenset(instance.kit_parts([t.id]).items()): t.id for t in instance.tasks}.values()
        )
        for a, b in itertools.combinations_with_replacement(reps, 2):
            if clock and time.perf_counter() > seed_until:
                break
            counts = instance.kit_parts([a, b])
            fit = self.packer.verdict(counts)
            if fit.fits is False:
                self.cut(counts, fit.scope or AXIS_ALIGNED)


def scope_claims(scope: str | None) -> dict[str, Any]:
    """What a model's proof covers (docs/formulations.md#what-optimal-means), as ``extra``
    entries: ``proof_scope`` and, when it is not every plan, a ``status_reason``."""
    if scope == ANY_ANGLE:
        return {"proof_scope": ANY_ANGLE}
    if scope == AXIS_ALIGNED:
        return {
            "proof_scope": AXIS_ALIGNED,
            "status_reason": "a kit was excluded by a proof for 0/90-degree layouts only and "
            "parts at other angles may fit it: the model's optimality and bound "
            "(optimal_axis_aligned, bound_axis_aligned) hold for 0/90-degree plans, 'bound' "
            "for every plan",
        }
    return {
        "proof_scope": None,
        "status_reason": "a kit was excluded without a proof (a packing time limit, or no "
        "layout on an inexact packing grid); the bound is the last one proven",
    }


def claim_scope(extra: dict[str, Any], scope: str | None) -> None:
    """Put :func:`scope_claims` in ``extra``: a conclusion states its own claims, so an
    earlier ``status_reason`` (the model's, before the conclusion of an LNS after it or of the
    incumbent kept by :func:`.exact.driver.never_worse`) goes when this one has none."""
    extra.pop("status_reason", None)
    extra.update(scope_claims(scope))


def split_greedily(
    kit: Sequence[str],
    fits: Callable[[list[str]], bool | None],
    alone: Callable[[list[str]], bool | None] | None = None,
) -> list[list[str]] | None:
    """``kit`` (in human order) cut greedily into consecutive sub-kits that ``fits``; None if
    a single task does not fit ``alone`` (None: ``fits``) or is unknown. One rule for the
    exact methods' packer and the LNS's start plans."""
    alone = fits if alone is None else alone
    out: list[list[str]] = []
    cur: list[str] = []
    for t in kit:
        if cur and fits([*cur, t]):
            cur.append(t)
            continue
        if cur:
            out.append(cur)
        if not alone([t]):
            return None
        cur = [t]
    if cur:
        out.append(cur)
    return out


def johnson_topological_order(instance: Instance) -> list[str]:
    """A topological order that takes, among the ready tasks, the first in Johnson's order of
    the jobs (r_i, h_i) (:func:`bilevel_kit.bounds.johnson_order`): without precedence it is
    Johnson's order, whose single-task kits attain the flow-shop bound when d = 0 and there
    are no overheads."""
    from ..bounds import johnson_order

    ids = [t.id for t in instance.tasks]
    rank = {
        ids[j]: k
        for k, j in enumerate(
            johnson_order(
                [instance.robot_time(i) for i in ids], [instance.human_time(i) for i in ids]
            )
        )
    }
    return topological_order(instance, rank)


def quick_plan(
    instance: Instance,
    packer: Packer | None = None,
    *,
    max_size: int = 40,
    order: Sequence[str] | None = None,
    target: float | None = None,
) -> list[list[str]] | None:
    """A cheap feasible plan (an upper bound and a hint): the best of :func:`best_cut` of
    ``order`` (default: the topological order) and ``order`` cut into segments of a fixed
    size s (each split further until it fits), by the evaluator; stops once the packer's
    budget has expired and a plan is known, or a plan reaches ``target``. With one tray the
    cut comes first (it is the optimal cut of the order, so it beats every fixed size whose
    segments it saw fit); otherwise it is tried last, with the time left."""
    packer = packer or Packer(instance, 0.2, Budget(10.0))
    order = topological_order(instance) if order is None else list(order)
    best: tuple[float, list[list[str]]] | None = None

    def consider(kits: list[list[str]]) -> None:
        nonlocal best
        ms = evaluate(instance, Plan(tuple(Kit(tuple(k)) for k in kits))).makespan
        if best is None or ms < best[0] - 1e-9:
            best = (ms, kits)

    one_tray = instance.params_of().tray_limit == 1  # (one station: quick_plan's callers)
    if one_tray and (cut := best_cut(instance, order, packer)) is not None:
        consider(cut)
    clock = not packer.deterministic  # (reproducible: every size, each call limited by work)
    for s in range(1, min(len(order), max_size) + 1):
        if best is not None and (
            (clock and packer.budget.expired()) or (target is not None and best[0] <= target)
        ):
            break
        kits: list[list[str]] = []
        for a in range(0, len(order), s):
            parts = packer.split(list(kit_order(instance, order[a : a + s])))
            if parts is None:
                return best[1] if best else None
            kits += parts
        consider(kits)
    late = clock and packer.budget.expired()
    if not one_tray and not late and (cut := best_cut(instance, order, packer)):
        consider(cut)
    return best[1] if best else None


#: Seconds each packing call of :func:`best_cut` may take: its calls probe ever longer
#: segments, and a borderline one left undecided only ends that segment (the packing cache
#: retries an unknown verdict when a later caller allows more time).
CUT_PROBE_S = 0.05


def best_cut(instance: Instance, order: Sequence[str], packer: Packer) -> list[list[str]] | None:
    """The best cut of ``order`` into contiguous kits that fit the tray under the one-tray
    recursion (:mod:`.segment`: exact with one tray, a candidate otherwise), with the
    segments' fit decided by ``packer`` (an unknown verdict counts as not fitting; once the
    packer's budget has expired the segments stop growing, so the cut may be coarser); None if
    a task does not fit."""
    from .segment import fit_extents, one_tray_cut

    if not order:
        return None
    limit = min(packer.pack_tl, CUT_PROBE_S)

    def fits(b: int, c: int) -> bool:
        return packer.counts(instance.kit_parts(order[b:c]), limit)[0] is True

    # a reproducible packer: no clock, its calls are limited by deterministic time
    ext = fit_extents(len(order), fits, None if packer.deterministic else packer.budget.deadline)
    return None if ext is None else one_tray_cut(instance, order, ext)[1]


class Johnson(NamedTuple):
    """:func:`johnson_plan`'s answer."""

    kits: list[list[str]] | None  # None: no plan found
    optimal: bool  # it attains the closed-form bound


def johnson_plan(instance: Instance, packer: Packer) -> Johnson:
    """The quick plan on the Johnson-priority order (:func:`johnson_topological_order`), which
    stops once it attains the closed-form bound :func:`bilevel_kit.bounds.best_bound`, and
    whether it does (then it is optimal). The exact models' closed-form check computes it, and
    it is a candidate incumbent beside the topological order's quick plan: on
    ``wide_n50_s1_t1_tight_d30`` its one-tray cut is 1,327 s against 1,336 s
    (docs/formulations.md, "One driver for cpsat and milp")."""
    from ..bounds import best_bound

    bound = best_bound(instance)
    kits = quick_plan(
        instance, packer, order=johnson_topological_order(instance), target=bound + 1e-9
    )
    if kits is None:
        return Johnson(None, False)
    ms = evaluate(instance, Plan(tuple(Kit(tuple(k)) for k in kits))).makespan
    return Johnson(kits, ms <= bound + 1e-9)
