r"""Exact optimum of the paper's own objective on small instances (registered ``bilevel-milp``).

The greedy of :mod:`bilevel_kit.heuristics.greedy_ce` scores one kit at a time with the paper's
F (Eqs. 3-7) over a rolling window. This module turns F into a **whole-plan objective** and
minimises it exactly over all plans, by enumerating the kits (columns) and solving one
set-partitioning + sequencing MILP, so that the greedy's gap on its own objective (not only on
makespan) can be measured.

**The paper's objective of a plan** (:func:`paper_objective`). For kits k = 1..m in delivery
order with the section-2 timeline (R_k, H_k include the per-kit overheads):

.. math::

    J = \sum_{k=1}^{m} \Bigl[ -W_2 |S_k|
        + W_3 \bigl| d + R_k - B_{k-1} \bigr|
        + W_4 \bigl| d + R_{k+1} - H_k \bigr|
        - W_5 f(S_k) \Bigr]

* term (4) ``-W2 |S_k|``: the number of tasks in the kit (it sums to the constant -W2 n);
* term (5): :math:`B_{k-1}` = the human's remaining work on kit k-1 when the robot starts kit k,
  :math:`B_{k-1} = \mathrm{human\_end}_{k-1} - \mathrm{arrive}_{k-1}` (:math:`B_0 = 0`), the
  greedy's ``H_rem``;
* term (6): the greedy's window remainder :math:`K_{i+1:L}` is replaced by the plan's own next
  kit, :math:`R_{m+1} = 0` (as the greedy does when its window ends, d stays);
* term (7): :math:`f(S_k)` = the kit's fitness, given by ``fitness_of`` (a function of the kit);
* term (3) is 0 (precedence is hard) and the W7 term is 0 (offline: every part is available).

Absolute values as in docs/errata.md (``signed=True``: the printed signed form). Every plan,
in particular greedy-ce's, has a well-defined J, and :func:`paper_objective` is the one function
that computes it. (The greedy's own objective in its ``extra``, the sum of its per-epoch window
scores, differs in term 6, which there looks at a hypothetical window, not at the kit that
really came next.)

**The lower level** (:class:`LowerLevel`). f is a function of the kit's part multiset:
the best (largest) true Euclidean fitness among the valid layouts found by (i) the
cross-entropy arrangement exactly as greedy-ce computes it (same CE parameters, same seed
derived from the run's seed and the multiset), (ii) the CP-SAT packing ``fitness`` objective
(L1 surrogate, its layout's Euclidean fitness; ``lower="best"``) and (iii) the packing
oracle's feasibility layout. So for any kit, f >= the fitness greedy-ce's own layout has, and
with the same seed and CE parameters the optimum J* below is <= J of greedy-ce's plan under both
f and greedy's own layouts. The lower level itself is a non-convex continuous problem: "exact"
here means exact for the upper level given these kit values.

**Columns.** A kit must be *convex* in the precedence order (if a, c are in the kit and
a -> b -> c then b is too: b's kit lies between theirs), and must fit the tray. Convex sets are
enumerated by growth from singletons (every convex set arises from a smaller one by adding a
maximal element), pruned by the exact area bound (total part area <= tray area, necessary for
any layout); a kit is a column when its multiset fits (oracle "fits" or a valid CE layout).

**MILP.** Positions k = 0..K-1 (K = n), ``z[c,k]`` = column c is kit k, only where possible
(:math:`k \ge 1` if c has ancestors outside it; :math:`k \le n - |c| - |\mathrm{desc}(c)
\setminus c|`). With :math:`X_{ik} = \sum_{c \ni i} z_{ck}`, :math:`u_k = \sum_c z_{ck}`:

* partition :math:`\sum_k X_{ik} = 1`; :math:`u_k \le 1`, :math:`u_{k+1} \le u_k`;
* precedence (transitive reduction) :math:`\sum_{q \le k} X_{bq} \le \sum_{q \le k} X_{aq}`;
* interchangeable chains in lexicographic order (as in :mod:`bilevel_kit.models.milp`);
* :math:`R_k = \sum_c R_c z_{ck}`, :math:`H_k = \sum_c H_c z_{ck}`; term 5 exactly, with its
  positive and negative parts :math:`g_k = p_k - q_k = d u_k + R_k - B_{k-1}` (relaxed by
  :math:`M(1-u_k)` on unused positions, :math:`p_k + q_k \le M u_k`), complementarity by one
  binary :math:`s_k` (:math:`p_k \le M s_k`, :math:`q_k \le M(1-s_k)`), and the recursion
  :math:`B_k = q_k + H_k` (= :math:`\max(0, B_{k-1} - R_k - d) + H_k`, the timeline);
* term 6 likewise: :math:`p'_k - q'_k = d u_k + R_{k+1} - H_k` (0 on unused positions);
* minimise :math:`\sum_{c,k} (-W_2 |c| - W_5 f_c) z_{ck} + \sum_k W_3 (p_k + q_k)
  + W_4 (p'_k + q'_k)`.

**Trays.** With T trays the robot starts kit k at :math:`A_{k-1} + w_k` with the tray wait
:math:`w_k = \max(0, \mathrm{hs}_{k-T} + o_H - A_{k-1})` (docs/timeline.md), so
:math:`B_{k-1} = q_{k-1} + H_{k-1} - w_k` (the same backlog :func:`paper_terms` reads off the
evaluator's timeline). With one tray the human has started kit k - 1 when it arrived, so
:math:`w_k = q_{k-1} + o_H` and :math:`B_{k-1} = H_{k-1} - o_H`: linear, no new variable.
With T >= 2, :math:`y_k = q_{k-T} + o_H - \sum_{k-T < j < k} (w_j + R_j + d)` (the human start
of kit k - T is its arrival plus its wait :math:`q`) and :math:`w_k - v_k = y_k` with
complementarity by one binary, the big-M being the no-overlap horizon
:math:`\sum_i (r_i + h_i) + n (o_R + o_H + d)` that bounds every time of the timeline.

The big-M :math:`M = d + o_R + \sum r + n\,o_H + \sum h` bounds every |g| and B (derived from
the data). The exact complementarity makes J exact for any sign of the weights. A MIP start
is greedy-ce's plan (same seed and CE parameters) improved by :func:`local_search`.

**Size limit.** At most :data:`MAX_TASKS` tasks and :data:`MAX_COLUMNS` candidate kits
(convex and within the tray area, before the fit test); beyond either the method raises a
UsageError (both are parameters). The 12-task table has 2,400 convex kits (7^4 - 1: per leg
chain an interval or nothing), all of which fit its tray, 104 distinct multisets and about
9,800 binaries; HiGHS proves its optimum in about 100-250 s on a busy 2-core machine (the LP
relaxation is weak: root bound about 132 against J* = 195.6, so branching does the work).
Random instances of up to 6 tasks solve in well under a second.

**Result.** ``status`` refers to J: optimal (proven) / feasible / infeasible / unknown.
``bound`` is the closed-form *makespan* bound (the method does not minimise makespan).
``extra`` keys:

* ``plan_objective_J`` (J of the plan, by :func:`paper_objective`), ``plan_objective_J_milp``
  (J as the MILP computed it), ``plan_objective_J_bound`` (the MILP's bound on J*),
  ``plan_objective_J_gap`` (``|J - bound| / max(1, |J|)``), ``makespan`` (of the plan);
* ``solver``, ``lower``, ``candidates`` (convex kits within the tray area), ``columns`` (those
  that fit), ``multisets`` (kit values computed), ``binaries``, ``termination``;
* ``start_objective`` and ``local_search_objective``: J of the warm-start plan before and
  after :func:`local_search`, ``local_search_converged``: whether it reached a local optimum
  within its share of the time (only with a warm start; if not, the start and so the MILP's
  choice among plans of equal J depend on the machine's speed);
* ``incumbent``: ``milp`` (the MILP's solution) or ``warm start`` (the solver stopped without
  returning one, e.g. killed past the time limit: the local-search plan it was started from);
* ``lower_level_cut``: kit values computed with a packing limit cut short by the deadline
  (their layouts depend on the machine's speed; not memoised);
* ``lower_level_s``, ``milp_s``, ``wall_time_s``: seconds spent;
* ``reason`` when the run ends without a plan for a known reason.

**Time.** ``time_limit`` (default 60 s) covers the kit values, the local search (a tenth of
what is left) and the MILP, with 0.2 s kept back for the final plan. The kit values' packing
calls get at most :data:`LOWER_SHARE` of the time: past it the remaining values are computed
with cut packing limits (``lower_level_cut`` counts them), so the MILP always has time to load
its warm start (on the paper's table the full lower level takes about 55 s of a 60 s limit).
"""

from __future__ import annotations

import itertools
import math
import time
from collections.abc import Callable, Collection, Iterator, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any, Literal

import numpy as np

from ..bounds import best_bound
from ..errors import UsageError
from ..fitness import layout_fitness as layout_fitness_value
from ..heuristics import upper_level
from ..instance import Instance
from ..methods import MethodOutput, Status
from ..options import parse_options
from ..plan import Kit, Placement, Plan, evaluate, kit_durations
from . import packing
from .budget import Budget
from .common import chain_groups, reduced_edges
from .milp.model import canonical_kits, human_order
from .milp.solver import ensure_ortools, make_solver, run_solver

#: Largest number of tasks the column enumeration accepts (option ``max_tasks``).
MAX_TASKS = 16
#: Largest number of candidate kits (convex, within the tray area) (option ``max_columns``).
MAX_COLUMNS = 5000
#: Share of the time limit the kit values' packing calls may use (module docstring, Time).
LOWER_SHARE = 0.8
LOWER_MODES = ("ce", "best")
#: Seconds kept back from the time limit for the final plan.
MARGIN = 0.2

FitnessOf = Callable[[Kit], float]


# ---------------------------------------------------------------------------------------------
# The paper's objective of a whole plan
# ---------------------------------------------------------------------------------------------


def paper_terms(
    instance: Instance,
    plan: Plan,
    fitness_of: FitnessOf,
    *,
    weights: Mapping[str, float] | None = None,
    signed: bool = False,
) -> list[dict[str, float]]:
    """Per kit: the raw terms ``n_tasks``, ``diff5``, ``diff6``, ``fitness`` and the weighted
    ``score`` of :func:`paper_objective` (module docstring)."""
    w = {**instance.weights, **(weights or {})}
    tl = evaluate(instance, plan)
    r, h = np.array([kit_durations(instance, k.tasks) for k in plan.kits], dtype=float).T
    # H_rem when the robot starts kit k: the human's work left on kit k-1 (tray rule included)
    backlog = [0.0] + [
        prev.human_end - nxt.robot_start for prev, nxt in zip(tl.kits, tl.kits[1:], strict=False)
    ]
    diff5, diff6 = upper_level.plan_balance(
        r, h, np.array(backlog), delivery=instance.delivery_time, signed=signed
    )
    fit = np.array([float(fitness_of(k)) for k in plan.kits])
    n_tasks = np.array([len(k.tasks) for k in plan.kits], dtype=float)
    score = upper_level.objective(w, n_tasks=n_tasks, diff5=diff5, diff6=diff6, fitness=fit)
    return [
        {
            "n_tasks": float(n_tasks[k]),
            "diff5": float(diff5[k]),
            "diff6": float(diff6[k]),
            "fitness": float(fit[k]),
            "score": float(score[k]),
        }
        for k in range(len(plan.kits))
    ]


def paper_objective(
    instance: Instance,
    plan: Plan,
    fitness_of: FitnessOf,
    *,
    weights: Mapping[str, float] | None = None,
    signed: bool = False,
) -> float:
    """The paper's F as a whole-plan objective J (module docstring); smaller is better."""
    return sum(
        t["score"] for t in paper_terms(instance, plan, fitness_of, weights=weights, signed=signed)
    )


def layout_fitness(instance: Instance) -> FitnessOf:
    """``fitness_of`` that scores each kit by its own layout (Euclidean, with the instance's
    W6): the value greedy-ce itself saw for its kits."""
    w6 = instance.weights["W6"]

    def fitness(kit: Kit) -> float:
        return layout_fitness_value(kit.layout, w6)

    return fitness


# ---------------------------------------------------------------------------------------------
# The lower level, memoised by part multiset
# ---------------------------------------------------------------------------------------------

Multiset = tuple[tuple[str, int], ...]


@dataclass(frozen=True)
class KitValue:
    """The lower level's answer for one part multiset: ``fits`` (some valid layout is known),
    the best ``fitness`` (``-inf`` if none), its ``layout`` (part ids ``type-j``) and where it
    came from (``ce``, ``cpsat`` or ``oracle``)."""

    fits: bool
    fitness: float
    layout: tuple[Placement, ...]
    source: str


class LowerLevel:
    """Kit values f(multiset), each computed once (module docstring, "The lower level").

    ``lower="ce"``: CE and the oracle's layout; ``"best"``: also the CP-SAT packing fitness
    objective with ``pack_time_limit`` seconds per multiset. Call it on a :class:`Kit` to use
    it as ``fitness_of``.
    """

    def __init__(
        self,
        instance: Instance,
        *,
        seed: int = 0,
        lower: str = "best",
        pack_time_limit: float = 0.5,
        ce_params: Any = None,
    ) -> None:
        from ..heuristics.greedy_ce import GreedyCEPolicy, GreedyParams
        from ..reachability import reach_grid

        if lower not in LOWER_MODES:
            raise UsageError(f"lower must be one of {', '.join(LOWER_MODES)}, not {lower!r}")
        self.instance = instance
        self.lower = lower
        self.pack_time_limit = float(pack_time_limit)
        params = GreedyParams() if ce_params is None else GreedyParams(ce=ce_params)
        self._policy = GreedyCEPolicy(instance, params, seed)
        self._reach = reach_grid(instance)
        self._values: dict[Multiset, KitValue] = {}
        self.time_s = 0.0
        #: values computed with a packing limit cut by :attr:`deadline` (machine-speed dependent)
        self.n_cut = 0
        #: perf_counter time after which packing calls get only what is left (None: no end);
        #: a value computed with a cut packing limit is not memoised
        self.deadline: float | None = None

    def _limit(self, limit: float) -> tuple[float, bool]:
        """``limit`` cut to the time left before :attr:`deadline`; and whether it was cut."""
        if self.deadline is None:
            return limit, False
        left = max(0.02, self.deadline - time.perf_counter())
        return min(limit, left), left < limit

    @staticmethod
    def key(counts: Mapping[str, int]) -> Multiset:
        return tuple(sorted((t, int(n)) for t, n in counts.items() if n))

    def value(self, counts: Mapping[str, int]) -> KitValue:
        key = self.key(counts)
        hit = self._values.get(key)
        if hit is not None:
            return hit
        t0 = time.perf_counter()
        inst = self.instance
        w6 = inst.weights["W6"]
        cands: list[tuple[float, tuple[Placement, ...], str]] = []
        arr = self._policy.arrangement(dict(key))
        if arr.fits:
            cands.append((arr.fitness, arr.layout, "ce"))
        fit_tl, cut = self._limit(2.0)
        ok, typed = packing.fit_counts(
            inst.tray, inst.part_types, dict(key), time_limit=fit_tl, reach=self._reach
        )
        if ok and typed is not None:
            layout = tuple(
                Placement(
                    f"{t}-{j + 1}", t, x, y, th, inst.part_types[t].width, inst.part_types[t].height
                )
                for t, slots in sorted(typed.items())
                for j, (x, y, th) in enumerate(slots)
            )
            cands.append((layout_fitness_value(layout, w6), layout, "oracle"))
            if self.lower == "best" and len(layout) > 1:
                items = [(p.part, inst.part_types[p.type]) for p in layout]
                pack_tl, cut_pack = self._limit(self.pack_time_limit)
                cut = cut or cut_pack
                res = packing.pack(
                    inst.tray,
                    items,
                    objective="fitness",
                    time_limit=pack_tl,
                    workers=1,
                    w6=w6,
                    reach=self._reach,
                )
                if res.layout is not None and res.true_fitness is not None:
                    cands.append((res.true_fitness, res.layout, "cpsat"))
        if cands:
            fit, layout, src = max(cands, key=lambda c: c[0])
            val = KitValue(True, float(fit), layout, src)
        else:
            val = KitValue(False, float("-inf"), (), "none")
        if not cut:
            self._values[key] = val
        else:
            self.n_cut += 1
        self.time_s += time.perf_counter() - t0
        return val

    def __call__(self, kit: Kit) -> float:
        return self.value(self.instance.kit_parts(kit.tasks)).fitness

    @property
    def n_values(self) -> int:
        return len(self._values)


# ---------------------------------------------------------------------------------------------
# Columns
# ---------------------------------------------------------------------------------------------


def enumerate_kits(instance: Instance, max_columns: int = MAX_COLUMNS) -> list[frozenset[str]]:
    """Every convex task set whose total part area fits the tray area (module docstring);
    UsageError when there are more than ``max_columns``."""
    ids = [t.id for t in instance.tasks]
    n = len(ids)
    bit = {t: 1 << i for i, t in enumerate(ids)}
    anc = [0] * n
    desc = [0] * n
    for i, t in enumerate(ids):
        for a in instance.ancestors[t]:
            anc[i] |= bit[a]
            desc[ids.index(a)] |= bit[t]
    area = [
        sum(instance.part_types[p].area * c for p, c in instance.task_by_id[t].parts) for t in ids
    ]
    cap = instance.tray.area * (1 + 1e-12)

    def convex(mask: int) -> bool:
        up = down = 0
        for i in range(n):
            if mask >> i & 1:
                up |= desc[i]
                down |= anc[i]
        return (up & down) & ~mask == 0

    seen: dict[int, float] = {}
    frontier = []
    for i in range(n):
        if area[i] <= cap:
            seen[1 << i] = area[i]
            frontier.append(1 << i)
    while frontier:
        nxt = []
        for mask in frontier:
            for i in range(n):
                if mask >> i & 1:
                    continue
                new = mask | 1 << i
                if new in seen:
                    continue
                total = seen[mask] + area[i]
                if total > cap or not convex(new):
                    continue
                seen[new] = total
                nxt.append(new)
                if len(seen) > max_columns:
                    raise UsageError(
                        f"bilevel-milp: more than {max_columns} candidate kits on "
                        f"{instance.name!r} ({n} tasks); the exact column model is for small "
                        "instances (raise max_columns at your own risk)"
                    )
        frontier = nxt
    return [frozenset(ids[i] for i in range(n) if mask >> i & 1) for mask in seen]


@dataclass(frozen=True)
class Column:
    tasks: frozenset[str]
    robot: float  # R_c, overhead included
    human: float  # H_c, overhead included
    fitness: float
    lo: int  # earliest position
    hi: int  # latest position


def build_columns(
    instance: Instance, kits: Sequence[frozenset[str]], lower: LowerLevel, budget: Budget
) -> list[Column] | None:
    """Columns (kits that fit, with their data); None when the budget runs out first."""
    ids = [t.id for t in instance.tasks]
    n = len(ids)
    anc = instance.ancestors
    desc: dict[str, set[str]] = {t: set() for t in ids}
    for t in ids:
        for a in anc[t]:
            desc[a].add(t)
    out = []
    lower.deadline = budget.share(LOWER_SHARE)  # packing calls leave the MILP its share
    for s in sorted(kits, key=lambda s: (len(s), sorted(instance.index[t] for t in s))):
        if budget.expired():
            return None
        val = lower.value(instance.kit_parts(s))
        if not val.fits:
            continue
        r, h = kit_durations(instance, list(s))
        anc_out = set().union(*(anc[t] for t in s)) - s
        desc_out = set().union(*(desc[t] for t in s)) - s
        # positions 0..n-1, used ones first: a kit before c exists if c has ancestors
        # outside it; the kits before c hold at most n - |c| - |descendants outside c| tasks
        out.append(Column(s, r, h, val.fitness, 1 if anc_out else 0, n - len(s) - len(desc_out)))
    return out


# ---------------------------------------------------------------------------------------------
# A MIP start: local search on J
# ---------------------------------------------------------------------------------------------


def local_search(
    instance: Instance,
    kits: Sequence[Sequence[str]],
    lower: LowerLevel,
    deadline: float,
    *,
    signed: bool = False,
) -> tuple[list[list[str]], float, bool]:
    """First-improvement hill climbing on J (a good MIP start lets the MILP prune early);
    returns the kits, their J and whether a local optimum was reached before ``deadline``
    (else the start, hence possibly the MILP's choice among equal-J plans, depends on the
    machine's speed).

    Moves: a task to the previous or next kit or into a new kit of its own just before or
    after its kit, merging or swapping two adjacent kits. A plan is kept only if every kit fits
    and precedence holds between kits (which also makes every kit convex).
    """
    succ: dict[str, list[str]] = {t.id: [] for t in instance.tasks}
    for a, b in instance.precedence:
        succ[a].append(b)

    def value(plan: list[frozenset[str]]) -> float:
        for kit in plan:
            if not lower.value(instance.kit_parts(kit)).fits:
                return float("inf")
        where = {t: k for k, kit in enumerate(plan) for t in kit}
        if any(where[a] > where[b] for a in succ for b in succ[a]):
            return float("inf")
        p = Plan(tuple(Kit(human_order(instance, kit)) for kit in plan))
        return paper_objective(instance, p, lower, signed=signed)

    def neighbours(plan: list[frozenset[str]]) -> Iterator[list[frozenset[str]]]:
        m = len(plan)
        for k in range(m - 1):
            yield [*plan[:k], plan[k] | plan[k + 1], *plan[k + 2 :]]
            yield [*plan[:k], plan[k + 1], plan[k], *plan[k + 2 :]]
        for k, kit in enumerate(plan):
            for t in sorted(kit, key=instance.index.__getitem__):
                rest = kit - {t}
                one = frozenset({t})
                for j in (k - 1, k + 1):
                    if 0 <= j < m:
                        new = list(plan)
                        new[j] = plan[j] | one
                        new[k] = rest
                        yield [q for q in new if q]
                if rest:
                    yield [*plan[:k], one, rest, *plan[k + 1 :]]
                    yield [*plan[:k], rest, one, *plan[k + 1 :]]

    cur = [frozenset(k) for k in kits]
    best = value(cur)
    improved = True
    while improved and time.perf_counter() < deadline:
        improved = False
        for cand in neighbours(cur):
            v = value(cand)
            if v < best - 1e-9:
                cur, best, improved = cand, v, True
                break
    return [list(human_order(instance, k)) for k in cur], best, not improved


# ---------------------------------------------------------------------------------------------
# The method
# ---------------------------------------------------------------------------------------------


def _order(m: Any, instance: Instance, K: int) -> None:
    """Precedence on the reduced graph and interchangeable chains in lexicographic order, on
    the task-position variables X (module docstring)."""
    add = m.cons.add
    idx = instance.index
    for a_id, b_id in reduced_edges(instance):
        a, b = idx[a_id], idx[b_id]
        for k in range(K - 1):
            add(sum(m.X[b, q] for q in range(k + 1)) <= sum(m.X[a, q] for q in range(k + 1)))
    for group in chain_groups(instance) if K > 1 else []:
        chains = sorted([idx[t] for t in c] for c in group)
        length = len(chains[0])
        while length > 1 and K ** (length - 1) > 1e6:
            length -= 1
        for c1, c2 in itertools.pairwise(chains):
            add(
                sum(
                    K ** (length - 1 - j) * k * (m.X[c1[j], k] - m.X[c2[j], k])
                    for j in range(length)
                    for k in range(1, K)
                )
                <= 0
            )


def _model(
    instance: Instance, cols: Sequence[Column], signed: bool, weights: Mapping[str, float]
) -> tuple[Any, list[tuple[int, int]]]:
    """The set-partitioning + sequencing MILP of the module docstring (used kits first)."""
    import pyomo.environ as pyo

    ids = [t.id for t in instance.tasks]
    n = len(ids)
    K = n
    idx = instance.index
    d = instance.delivery_time
    big_m = (
        d
        + instance.kit_overhead_robot
        + sum(instance.robot_time(t) for t in ids)
        + n * instance.kit_overhead_human
        + sum(instance.human_time(t) for t in ids)
    )
    keys = [(c, k) for c, col in enumerate(cols) for k in range(col.lo, col.hi + 1)]
    m = pyo.ConcreteModel(name="kit_columns")
    m.z = pyo.Var(keys, domain=pyo.Binary)
    m.X = pyo.Var(range(n), range(K), bounds=(0.0, 1.0))
    m.p5 = pyo.Var(range(K), bounds=(0.0, big_m))
    m.q5 = pyo.Var(range(K), bounds=(0.0, big_m))
    m.s5 = pyo.Var(range(K), domain=pyo.Binary)
    m.p6 = pyo.Var(range(K), bounds=(0.0, big_m))
    m.q6 = pyo.Var(range(K), bounds=(0.0, big_m))
    m.s6 = pyo.Var(range(K), domain=pyo.Binary)
    m.cons = pyo.ConstraintList()
    add = m.cons.add
    at_k: list[list[int]] = [[] for _ in range(K)]
    holding: dict[tuple[int, int], list[int]] = {}
    for c, k in keys:
        at_k[k].append(c)
        for t in cols[c].tasks:
            holding.setdefault((idx[t], k), []).append(c)
    for i in range(n):
        for k in range(K):
            zs = holding.get((i, k), [])
            if zs:
                add(m.X[i, k] == sum(m.z[c, k] for c in zs))
            else:
                m.X[i, k].fix(0.0)
        add(sum(m.X[i, k] for k in range(K)) == 1)

    def used(k: int) -> Any:
        return sum(m.z[c, k] for c in at_k[k]) if k < K and at_k[k] else 0.0

    for k in range(K):
        if at_k[k]:
            add(used(k) <= 1)
            if k:
                add(used(k) <= used(k - 1))  # used kits first
    _order(m, instance, K)

    def robot(k: int) -> Any:
        return sum(cols[c].robot * m.z[c, k] for c in at_k[k]) if k < K and at_k[k] else 0.0

    def human(k: int) -> Any:
        return sum(cols[c].human * m.z[c, k] for c in at_k[k]) if at_k[k] else 0.0

    wait = _tray_waits(m, instance, K, used, robot)
    backlog: Any = 0.0
    for k in range(K):
        u = used(k)
        if k:
            backlog = backlog - wait(k)  # B_{k-1} = human_end_{k-1} - robot_start_k
        g = d * u + robot(k) - backlog
        # exact on used positions; relaxed (and zeroed) on unused ones, which come last
        add(m.p5[k] - m.q5[k] - g <= big_m * (1 - u))
        add(m.p5[k] - m.q5[k] - g >= -big_m * (1 - u))
        add(m.p5[k] + m.q5[k] <= big_m * u)
        add(m.p5[k] <= big_m * m.s5[k])
        add(m.q5[k] <= big_m * (1 - m.s5[k]))
        backlog = m.q5[k] + human(k)  # = max(0, B_{k-1} - R_k - d) + H_k (before the tray)
        add(m.p6[k] - m.q6[k] == d * u + robot(k + 1) - human(k))
        add(m.p6[k] <= big_m * m.s6[k])
        add(m.q6[k] <= big_m * (1 - m.s6[k]))
    w2, w3, w4, w5 = (weights[k] for k in ("W2", "W3", "W4", "W5"))
    sign = -1.0 if signed else 1.0
    m.obj = pyo.Objective(
        expr=sum((-w2 * len(cols[c].tasks) - w5 * cols[c].fitness) * m.z[c, k] for c, k in keys)
        + sum(w3 * (m.p5[k] + sign * m.q5[k]) + w4 * (m.p6[k] + sign * m.q6[k]) for k in range(K)),
        sense=pyo.minimize,
    )
    return m, keys


def _tray_waits(m: Any, instance: Instance, K: int, used: Any, robot: Any) -> Any:
    """``w(k)``: how long the robot waits for a tray before kit k (module docstring), exact
    on used positions; 0 with unlimited trays."""
    import pyomo.environ as pyo

    T = instance.tray_limit
    o_h, d = instance.kit_overhead_human, instance.delivery_time
    if T is None:
        return lambda k: 0.0
    if T == 1:  # the human has started kit k - 1 when it arrived: w_k = q5_{k-1} + o_H
        return lambda k: m.q5[k - 1] + o_h * used(k)
    ids = [t.id for t in instance.tasks]
    horizon = sum(instance.robot_time(t) + instance.human_time(t) for t in ids) + len(ids) * (
        instance.kit_overhead_robot + o_h + d
    )  # every time of the timeline lies in [0, horizon]
    m.w = pyo.Var(range(T, K), bounds=(0.0, horizon))
    m.v = pyo.Var(range(T, K), bounds=(0.0, horizon))
    m.sw = pyo.Var(range(T, K), domain=pyo.Binary)
    add = m.cons.add
    for k in range(T, K):
        u = used(k)
        # y_k = human start of kit k - T + o_H - arrival of kit k - 1
        y = m.q5[k - T] + o_h * u
        for j in range(k - T + 1, k):
            y = y - (m.w[j] if j >= T else 0.0) - robot(j) - d * used(j)
        add(m.w[k] - m.v[k] - y <= 2 * horizon * (1 - u))
        add(m.w[k] - m.v[k] - y >= -2 * horizon * (1 - u))
        add(m.w[k] <= horizon * u)
        add(m.w[k] <= horizon * m.sw[k])
        add(m.v[k] <= horizon * (1 - m.sw[k]))
    return lambda k: m.w[k] if k >= T else 0.0


@dataclass(frozen=True)
class BilevelMilpOptions:
    """Options of the registered method ``bilevel-milp`` (the Python :func:`solve` also takes
    a warm-start plan, CE parameters, shared kit values and solver options)."""

    solver: str = field(
        default="highs",
        metadata={"help": "highs (HiGHS in a child process) or any Pyomo solver name"},
    )
    lower: Literal["ce", "best"] = field(
        default="best",
        metadata={"help": "kit values from CE and the oracle, or also CP-SAT's fitness layout"},
    )
    pack_time_limit: float = field(
        default=0.5,
        metadata={"help": "seconds per multiset for the CP-SAT fitness layout", "min": 0.0},
    )
    max_tasks: int = field(
        default=MAX_TASKS, metadata={"help": "largest instance accepted (tasks)", "min": 1}
    )
    max_columns: int = field(
        default=MAX_COLUMNS,
        metadata={"help": "largest number of candidate kits accepted", "min": 1},
    )
    signed: bool = field(
        default=False, metadata={"help": "the printed signed terms 5 and 6 (docs/errata.md)"}
    )
    log: bool = field(default=False, metadata={"help": "print the MILP solver's log"})


def solve(
    instance: Instance,
    *,
    seed: int = 0,
    time_limit: float | None = 60.0,
    solver: str = "highs",
    lower: str = "best",
    pack_time_limit: float = 0.5,
    max_tasks: int = MAX_TASKS,
    max_columns: int = MAX_COLUMNS,
    signed: bool = False,
    warm_plan: Plan | str | None = "greedy",
    ce_params: Any = None,
    values: LowerLevel | None = None,
    log: bool = False,
    solver_options: Mapping[str, Any] | None = None,
) -> MethodOutput:
    """The Python entry: :func:`run` with the options as keywords (validated like the
    method's) and the Python-only arguments of :func:`run`."""
    params = {
        "solver": solver,
        "lower": lower,
        "pack_time_limit": pack_time_limit,
        "max_tasks": max_tasks,
        "max_columns": max_columns,
        "signed": signed,
        "log": log,
    }
    options = parse_options(BilevelMilpOptions, params, "bilevel-milp")
    return run(
        instance,
        options,
        seed=seed,
        time_limit=time_limit,
        warm_plan=warm_plan,
        ce_params=ce_params,
        values=values,
        solver_options=solver_options,
    )


def run(
    instance: Instance,
    options: BilevelMilpOptions,
    *,
    seed: int = 0,
    time_limit: float | None = None,
    warm_plan: Plan | str | None = "greedy",
    ce_params: Any = None,
    values: LowerLevel | None = None,
    solver_options: Mapping[str, Any] | None = None,
) -> MethodOutput:
    """Minimise the paper's whole-plan objective J exactly over enumerated kits (the result:
    module docstring; each kit of the plan has its best known layout); with its defaults, the
    registered method ``bilevel-milp`` (no time limit: the budget's default, 60 s).

    ``warm_plan``: a plan, or ``"greedy"`` (greedy-ce with this seed and these CE parameters),
    improved by :func:`local_search`, is the MIP start; ``ce_params`` (a
    :class:`~bilevel_kit.heuristics.cross_entropy.CEParams`) must match greedy-ce's for J to
    compare kit by kit; ``values``: a :class:`LowerLevel` to use (and fill), so that the caller
    scores other plans with the same kit values; ``solver_options`` go to the MILP solver.
    """
    budget = Budget(time_limit)
    n = instance.n_tasks
    if n > options.max_tasks:
        raise UsageError(
            f"bilevel-milp: {instance.name!r} has {n} tasks; the exact column model accepts at "
            f"most {options.max_tasks} (parameter max_tasks)"
        )
    ensure_ortools()
    opt = make_solver(options.solver)
    weights = dict(instance.weights)
    kits = enumerate_kits(instance, options.max_columns)
    lower_level = values or LowerLevel(
        instance,
        seed=seed,
        lower=options.lower,
        pack_time_limit=options.pack_time_limit,
        ce_params=ce_params,
    )
    closed = best_bound(instance)
    extra: dict[str, Any] = {
        "solver": options.solver,
        "lower": options.lower,
        "candidates": len(kits),
    }

    def finish(plan: Plan | None, status: Status) -> MethodOutput:
        extra["wall_time_s"] = budget.elapsed()
        return MethodOutput(plan, status, closed, extra, status_objective="J")

    cols = build_columns(instance, kits, lower_level, budget.cut(MARGIN))
    extra.update(multisets=lower_level.n_values, lower_level_s=lower_level.time_s)
    extra["lower_level_cut"] = lower_level.n_cut  # updated below: the plan's values may cut too
    if cols is None:
        extra["reason"] = "time limit reached while computing the kits' lower-level values"
        return finish(None, Status.UNKNOWN)
    extra["columns"] = len(cols)
    covered = set().union(*(c.tasks for c in cols)) if cols else set()
    if len(covered) < n:
        extra["reason"] = "some task fits in no kit"
        return finish(None, Status.INFEASIBLE)

    start = None
    if warm_plan is not None:
        start, start_j, ls_j, ls_converged = _warm_start(
            instance,
            warm_plan,
            lower_level,
            ce_params=ce_params,
            budget=budget,
            signed=options.signed,
            seed=seed,
        )
        extra.update(
            start_objective=start_j,
            local_search_objective=ls_j,
            local_search_converged=ls_converged,
        )
    t_milp = time.perf_counter()
    m, keys = _model(instance, cols, options.signed, weights)
    extra["binaries"] = len(keys)
    if start is not None:
        _warm(m, instance, cols, keys, start)
    info = run_solver(
        m,
        opt,
        options.solver,
        budget=budget.cut(MARGIN),
        seed=seed,
        log=options.log,
        objective=m.obj,
        options=solver_options,
        warmstart=start is not None,
    )
    extra.update(milp_s=time.perf_counter() - t_milp, termination=info.termination)
    if info.has_solution:
        plan = _solution_plan(instance, m, keys, cols, lower_level)
        extra["incumbent"] = "milp"
    elif (
        start is not None and not info.infeasible and math.isfinite(extra["local_search_objective"])
    ):
        # the solver stopped without returning a solution (e.g. killed past the time limit):
        # the MIP start it was given is still a plan whose every kit fits
        plan = _with_layouts(instance, [k.tasks for k in start.kits], lower_level)
        extra["incumbent"] = "warm start"
    else:
        return finish(None, Status.INFEASIBLE if info.infeasible else Status.UNKNOWN)
    value = paper_objective(instance, plan, lower_level, signed=options.signed)
    bound = info.bound
    if bound is not None and bound > value:
        bound = value  # solver tolerance
    extra.update(
        plan_objective_J=value,
        plan_objective_J_milp=info.objective,
        plan_objective_J_bound=bound,
        plan_objective_J_gap=None if bound is None else abs(value - bound) / max(1.0, abs(value)),
        makespan=evaluate(instance, plan).makespan,
        lower_level_cut=lower_level.n_cut,
    )
    return finish(plan, Status.OPTIMAL if info.optimal else Status.FEASIBLE)


#: The registered method ``bilevel-milp``: :func:`run` warm-started from greedy-ce's plan.
bilevel_milp = run


def _solution_plan(
    instance: Instance,
    m: Any,
    keys: Sequence[tuple[int, int]],
    cols: Sequence[Column],
    lower_level: LowerLevel,
) -> Plan:
    """The MILP's chosen columns in kit order, each with its best known layout."""
    chosen = sorted(
        ((k, c) for c, k in keys if m.z[c, k].value is not None and m.z[c, k].value > 0.5)
    )
    return _with_layouts(instance, [cols[c].tasks for _, c in chosen], lower_level)


def _with_layouts(
    instance: Instance, kits: Sequence[Collection[str]], lower_level: LowerLevel
) -> Plan:
    """``kits`` in delivery order, each in human order with its best known layout."""
    plan_kits = []
    for kit in kits:
        tasks = human_order(instance, kit)
        plan_kits.append(Kit(tasks, lower_level.value(instance.kit_parts(tasks)).layout))
    return Plan(tuple(plan_kits))


def _warm_start(
    instance: Instance,
    warm_plan: Plan | str,
    lower_level: LowerLevel,
    *,
    ce_params: Any,
    budget: Budget,
    signed: bool,
    seed: int,
) -> tuple[Plan, float, float, bool]:
    """The MIP start: ``warm_plan`` (``"greedy"``: greedy-ce's plan) improved by
    :func:`local_search` in a tenth of the time left; with J before and after, and whether the
    local search converged."""
    if isinstance(warm_plan, str):
        if warm_plan != "greedy":
            raise UsageError(f"warm_plan must be a Plan, 'greedy' or None, not {warm_plan!r}")
        from ..heuristics.cross_entropy import CEParams
        from ..heuristics.greedy_ce import GreedyParams
        from ..heuristics.greedy_ce import plan as greedy_plan

        gp = GreedyParams(ce=ce_params or CEParams())
        warm_plan = greedy_plan(instance, gp, seed)
    ls_until = budget.share(0.1)
    kits_ls, j_ls, converged = local_search(
        instance, [k.tasks for k in warm_plan.kits], lower_level, ls_until, signed=signed
    )
    start_j = paper_objective(instance, warm_plan, lower_level, signed=signed)
    return Plan(tuple(Kit(tuple(k)) for k in kits_ls)), start_j, j_ls, converged


def _warm(
    m: Any, instance: Instance, cols: Sequence[Column], keys: Sequence[Any], plan: Plan
) -> None:
    """Load a plan as a MIP start (only its z; HiGHS completes the rest)."""
    pos = {c.tasks: j for j, c in enumerate(cols)}
    where = {}
    kits = canonical_kits(instance, [list(k.tasks) for k in plan.kits])  # symmetry-consistent
    for k, kit in enumerate(kits):
        c = pos.get(frozenset(kit))
        if c is None:
            return  # not a column (e.g. not convex): no start
        where[(c, k)] = 1.0
    for key in keys:
        m.z[key].set_value(where.get(key, 0.0), skip_validation=True)
