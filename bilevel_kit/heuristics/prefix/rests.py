r"""The best rest of the window after a prefix (:mod:`..greedy_search`): the set :math:`Q` of
:math:`L - i` further tasks, closed given done and the prefix, of least F (term (6) depends
on :math:`Q` only through its robot sum :math:`R(Q)`).

Two searches give the same rests: :class:`RestDecomposition` when the robot times take few
distinct values (a core of tasks not available at the epoch plus free available tasks whose
best sum is read from a sorted table, :class:`SumTable`; its loop over cores is compiled,
:mod:`.._rest_kernel`), and :meth:`RestSearch.depth_first` over closed extensions in
lexicographic order otherwise, and for the tie rule (the first rest under a threshold).
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Set as AbstractSet
from dataclasses import dataclass

import numpy as np

from .. import _dfs_kernel, _rest_kernel
from .levels import Precedence, Window

#: Deep tasks from which an epoch's rest search runs compiled (both loops give the same).
MIN_DEEP_COMPILED = 1

#: Largest sum table (multisets over all k) :class:`SumTable` builds.
MAX_SUM_COMBOS = 300_000

#: The packed sum tables of every k (:meth:`RestDecomposition._packed_tables`).
PackedTables = tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]

#: A rest found: (F, the rest in its smallest topological order, whether the search capped).
RestResult = tuple[float, tuple[int, ...], bool]


@dataclass(frozen=True)
class SumTable:
    """Every multiset of ``k`` robot-time values (``k`` = 1..N-1) with its sum, sorted by sum:
    the sums a rest of ``k`` precedence-free tasks can take. Built once per instance, only
    when small (distinct robot times few, :data:`MAX_SUM_COMBOS`); else the rest search is
    the depth-first one."""

    vals: np.ndarray
    #: value index of each task
    vidx: np.ndarray
    #: k -> (combos (n, k) of value indices, non-decreasing; rank of each entry among equal
    #: values in its combo; sums), sorted by sum
    tables: dict[int, tuple[np.ndarray, np.ndarray, np.ndarray]]

    @classmethod
    def build(cls, robot: np.ndarray, kmax: int) -> SumTable | None:
        vals, vidx = np.unique(robot, return_inverse=True)
        n_vals = len(vals)
        # a rest holds at most every task but one: a horizon beyond the tasks changes nothing,
        # and the count stops at the cap (a horizon of 1e9 summed 1e9 binomials first)
        kmax = min(kmax, len(robot) - 1)
        if kmax < 1 or not _combos_within(n_vals, kmax, MAX_SUM_COMBOS):
            return None
        tables = {}
        for k in range(1, kmax + 1):
            combos = np.array(
                list(itertools.combinations_with_replacement(range(n_vals), k)), dtype=np.int64
            ).reshape(-1, k)
            rank = np.zeros_like(combos)
            for j in range(1, k):
                rank[:, j] = np.where(combos[:, j] == combos[:, j - 1], rank[:, j - 1] + 1, 0)
            sums = vals[combos].sum(axis=1)
            order = np.argsort(sums, kind="stable")
            tables[k] = (combos[order], rank[order], sums[order])
        return cls(vals, vidx.reshape(-1), tables)


def _combos_within(n_vals: int, kmax: int, cap: int) -> bool:
    """Do the multisets of 1..``kmax`` of ``n_vals`` values number at most ``cap``? Stops
    as soon as the count passes the cap, so a huge ``kmax`` costs a few steps."""
    total = 0
    for k in range(1, kmax + 1):
        total += math.comb(n_vals + k - 1, k)
        if total > cap:
            return False
    return True


class RestSearch:
    """What the rest searches of one instance share (built once): the precedence graph, the
    robot times, the sum table (None when too large), the packed tables by epoch
    (:meth:`RestDecomposition._packed_tables`) and the cap on search nodes; ``prune``: the
    bounds of F hold (W4, W5, W6 >= 0)."""

    def __init__(
        self, graph: Precedence, robot: np.ndarray, horizon: int, prune: bool, max_nodes: int
    ) -> None:
        self.graph = graph
        self.r = robot
        self.sums = SumTable.build(robot, horizon - 1)
        self.prune = prune
        self.max_nodes = max_nodes
        #: the decomposition's packed sum tables by available tasks per value (capped at the
        #: largest k), shared by the epochs
        self.packed: dict[bytes, PackedTables] = {}
        #: the depth-first search (:mod:`.._dfs_kernel`, compiled when numba runs) and the
        #: graph as its arrays
        self._dfs = _dfs_kernel.search()
        self._dfs_graph = (
            np.append(graph.succ_start, len(graph.succ_flat)).astype(np.int64),
            graph.succ_flat,
            np.cumsum([0, *(len(p) for p in graph.pred)]).astype(np.int64),
            graph.arc_pred,
        )

    def depth_first(
        self,
        window: Window,
        prefix: tuple[int, ...],
        m: int,
        terms: np.ndarray,
        threshold: float | None,
        cutoff: float = math.inf,
    ) -> RestResult:
        """The rest of ``m`` tasks after ``prefix`` of least F: (F, rest in its smallest
        topological order, capped), F given by ``terms`` as a function of R(Q) (task times
        only; :data:`.._dfs_kernel.TERMS`). With ``threshold``, the first rest (lexicographic)
        whose F is at most the threshold. Rests whose F exceeds ``cutoff`` are not looked for
        (the result is then ``(inf, ())``). The search is :func:`.._dfs_kernel.depth_first`,
        compiled or, without numba, the same source run as Python."""
        ordered, rel = self._after(window, prefix)
        f, rest, capped = self._dfs(
            np.array(ordered, dtype=np.int64),
            np.array(rel, dtype=np.int64),
            self._dfs_graph,
            self.r,
            m,
            self.max_nodes,
            self.prune,
            window.r_range,
            terms,
            threshold is not None,
            math.inf if threshold is None else threshold,
            cutoff,
        )
        return float(f), tuple(rest.tolist()), bool(capped)

    def _after(self, window: Window, prefix: tuple[int, ...]) -> tuple[list[int], list[int]]:
        """Given done and ``prefix``: the available tasks (sorted) and the undone predecessors
        of each task (< 0: done or in the prefix)."""
        base = set(prefix)
        base_avail = {y for y in window.avail if y not in base}
        rel = list(window.undone)
        for x in prefix:
            rel[x] = -1
        for x in prefix:
            for y in self.graph.succ[x]:
                rel[y] -= 1
                if rel[y] == 0:
                    base_avail.add(y)
        return sorted(base_avail), rel


class RestDecomposition:
    r"""The best rest of each prefix at one epoch, by decomposition instead of a search over
    sequences. Let :math:`A` be the tasks available at the epoch (every predecessor done).
    A rest :math:`Q` (closed given done and :math:`P`) splits uniquely into its *core*
    :math:`C`: its tasks outside :math:`A` with their undone ancestors outside :math:`P`
    (all in :math:`Q`, by closedness), and the *free* tasks :math:`Q \setminus C \subseteq A
    \setminus (P \cup C)`, any of which may be added since their predecessors are done.
    So the best rest is the best over cores (few: unions of the needed sets of window tasks
    outside :math:`A`, of total size at most :math:`m`) of :math:`R(C)` plus the sum of
    :math:`m - |C|` free tasks closest to the target (or least, in the signed form), read
    from the sorted multiset sums of :class:`SumTable` (skipping multisets that use more
    tasks of a value than are left). Exact: every rest is some (core, free multiset).
    When every sum of robot times is exact, the loop over cores runs compiled
    (:mod:`.._rest_kernel`, the same cores, order and sums)."""

    def __init__(
        self, search: RestSearch, done: np.ndarray, window: Window, exact_sums: bool
    ) -> None:
        tab = search.sums
        assert tab is not None
        avail, anc = window.avail, window.anc
        self.search = search
        self.done = done
        self.r = search.r
        self.vidx = tab.vidx
        self.pool = frozenset(avail)
        self.vlist: list[int] = tab.vidx.tolist()
        #: R(core) by core when every sum of robot times is exact (then in any order)
        self._core_sums: dict[frozenset[int], float] | None = {} if exact_sums else None
        self.anc = anc
        self.deep = sorted(y for y in anc if y not in self.pool)
        #: the deep tasks whose need set (itself and its undone ancestors) has at most k tasks
        #: (k = 0..len(avail)), and the deep descendants of each task: a deep task outside
        #: both is never a candidate of :meth:`best`, since its need set stays larger than m
        sizes = [len(anc[y]) + 1 for y in self.deep]
        self.small = [
            [y for y, z in zip(self.deep, sizes, strict=True) if z <= k]
            for k in range(max(sizes, default=0) + 1)
        ]
        self.desc: dict[int, list[int]] = {}
        for y in self.deep:
            for a in anc[y]:
                self.desc.setdefault(a, []).append(y)
        self.mult = np.bincount(tab.vidx[avail], minlength=len(tab.vals))
        self.by_value: dict[int, list[int]] = {}
        for t in avail:  # avail is sorted
            self.by_value.setdefault(int(tab.vidx[t]), []).append(t)
        self._tab = tab
        #: k -> (combos, ranks, sums) of the multisets the epoch's available tasks can give
        self.tables: dict[int, tuple[np.ndarray, np.ndarray, np.ndarray]] = {}
        self.max_cores = search.max_nodes
        #: the compiled loop of :meth:`best` (sums exact in any order only) and its arrays;
        #: without deep tasks the only core is the empty one: the Python loop is quicker
        self._kernel = None
        self._rest_kernel = None
        if exact_sums and len(self.deep) >= MIN_DEEP_COMPILED:
            self._kernel = _rest_kernel.kernel()
            self._rest_kernel = _rest_kernel.rest_kernel()
        self._window_size = len(anc)
        self._epoch: tuple[np.ndarray, ...] = ()
        self._packed: PackedTables | None = None
        if self._kernel is not None:
            self._epoch = self._epoch_arrays(sizes, avail)

    def _epoch_arrays(self, sizes: list[int], avail: list[int]) -> tuple[np.ndarray, ...]:
        """The epoch's data as arrays for :func:`_rest_kernel.best_cores`."""
        n = len(self.r)
        where = {y: p for p, y in enumerate(self.deep)}
        anc_ptr = np.cumsum([0, *(len(self.anc[y]) for y in self.deep)])
        anc_idx = [a for y in self.deep for a in self.anc[y]]
        desc_len = np.zeros(n + 1, dtype=np.int64)  # only the tasks with deep descendants
        for t, ys in self.desc.items():
            desc_len[t + 1] = len(ys)
        desc_ptr = np.cumsum(desc_len)
        desc_idx = [where[y] for t in sorted(self.desc) for y in self.desc[t]]
        value = np.full(n, -1, dtype=np.int64)
        value[avail] = self.vidx[avail]
        return (
            np.array(self.deep, dtype=np.int64),
            np.array(sizes, dtype=np.int64),
            anc_ptr.astype(np.int64),
            np.array(anc_idx, dtype=np.int64),
            desc_ptr.astype(np.int64),
            np.array(desc_idx, dtype=np.int64),
            value,
            np.asarray(self.r, dtype=np.float64),
            self.mult.astype(np.int64),
            np.zeros(n, dtype=np.int64),
        )

    def _packed_tables(self) -> PackedTables:
        """The tables of :meth:`_table` for every k as one array each (offsets by k, combos
        and ranks padded to the largest k, sums), for the compiled loop. They depend on the
        available tasks per value only up to the largest k (a rank is below it), so epochs
        share them (:attr:`RestSearch.packed`)."""
        if self._packed is None:
            kmax = max(self._tab.tables)
            shared = self.search.packed
            key = np.minimum(self.mult, kmax).tobytes()
            self._packed = shared.get(key)
            if self._packed is not None:
                return self._packed
            parts = [self._table(k) for k in range(1, kmax + 1)]
            ptr = np.cumsum([0, 0, *(len(p[2]) for p in parts)]).astype(np.int64)
            combos = np.zeros((int(ptr[-1]), kmax), dtype=np.int64)
            ranks = np.zeros((int(ptr[-1]), kmax), dtype=np.int64)
            for k, (c, q, _) in enumerate(parts, start=1):
                combos[ptr[k] : ptr[k + 1], :k] = c
                ranks[ptr[k] : ptr[k + 1], :k] = q
            sums = np.concatenate([p[2] for p in parts]).astype(np.float64)
            self._packed = (ptr, combos, ranks, sums)
            if len(shared) >= 64:
                shared.clear()
            shared[key] = self._packed
        return self._packed

    def _table(self, k: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(combos, ranks, sums) of the multisets of ``k`` values the epoch's available tasks
        can give (built on first use)."""
        if k not in self.tables:
            combos, rank, sums = self._tab.tables[k]
            keep = (rank < self.mult[combos]).all(axis=1)
            self.tables[k] = (combos[keep], rank[keep], sums[keep])
        return self.tables[k]

    def _free(
        self, k: int, target: float, removed: dict[int, int]
    ) -> tuple[float, tuple[int, ...]] | None:
        """The multiset of ``k`` free values with the sum closest to ``target`` (the least
        sum if ``target`` is -inf), none of them beyond what ``removed`` leaves."""
        if k == 0:
            return 0.0, ()
        combos, ranks, sums = self._table(k)
        mult = self.mult

        def ok(j: int) -> bool:
            if not removed:
                return True
            return all(
                v not in removed or q < mult[v] - removed[v]
                for v, q in zip(combos[j].tolist(), ranks[j].tolist(), strict=True)
            )

        n = len(sums)
        j = 0 if target == -math.inf else int(sums.searchsorted(target))
        up = j
        while up < n and not ok(up):
            up += 1
        down = j - 1
        if target != -math.inf:
            while down >= 0 and not ok(down):
                down -= 1
        best = None
        if up < n:
            best = up
        if down >= 0 and (best is None or target - sums[down] < sums[best] - target):
            best = down
        if best is None:
            return None
        return float(sums[best]), tuple(combos[best].tolist())

    def best(
        self,
        prefix: tuple[int, ...],
        m: int,
        terms: np.ndarray,
        cutoff: float,
        target: float,
        floor: float = -math.inf,
    ) -> RestResult:
        """(F, a rest of least F in its smallest topological order, capped) over the rests of
        ``m`` tasks after ``prefix`` with F at most ``cutoff`` ((inf, (), capped) if none).
        F by rest sum: ``terms`` (:data:`.._dfs_kernel.TERMS`); ``target``: the rest sum R(Q)
        that makes term (6) zero (-inf in the signed form); ``floor``: F with term (6) zero,
        below every rest's F (-inf: unknown). Every core is still enumerated, so the cap
        counts as without the floor."""
        if self.scores_compiled(m):
            return self._best_scored(prefix, m, terms, cutoff, target)
        pset = set(prefix)
        sets = self._need_sets(prefix, pset, m)
        sizes = [len(c) for c in sets]
        base = self._taken(pset, {})  # the prefix's available tasks by value
        best_f = math.inf
        best_set: frozenset[int] | None = None
        best_free: tuple[int, ...] = ()
        seen: set[frozenset[int]] = set()
        stack: list[tuple[int, frozenset[int]]] = [(0, frozenset())]
        cores = 0
        capped = False
        while stack:
            start, core = stack.pop()
            if core in seen:
                continue
            seen.add(core)
            cores += 1
            if cores > self.max_cores:
                capped = True
                break
            if best_f > floor:  # else no core can do strictly better: only count them
                removed = self._taken(core, base) if core else base
                r_core = self._core_sum(core) if core else 0.0
                free = self._free(m - len(core), target - r_core, removed)
                if free is not None:
                    val = float(_dfs_kernel._leaf_score(terms, r_core + free[0]))
                    if val < best_f and val <= cutoff:
                        best_f, best_set, best_free = val, core, free[1]
            room = m - len(core)
            if room <= 0:  # every need set holds a task, so nothing grows the core
                continue
            for a in range(start, len(sets)):
                if sizes[a] <= room or not sets[a].isdisjoint(core):
                    grown = core | sets[a]
                    if len(grown) <= m and grown != core:
                        stack.append((a + 1, grown))
        if best_set is None:
            return math.inf, (), capped
        return best_f, self._order(pset, best_set, best_free), capped

    def _need_sets(self, prefix: tuple[int, ...], pset: set[int], m: int) -> list[frozenset[int]]:
        """The need sets of at most ``m`` tasks after ``prefix`` (a deep task with its undone
        ancestors outside the prefix), by increasing deep task: cores are their unions."""
        some = set(self.small[min(m, len(self.small) - 1)])
        for x in prefix:
            some.update(self.desc.get(x, ()))
        sets = []
        for y in sorted(some):
            if y in pset:
                continue
            need = (self.anc[y] - pset) | {y}
            if len(need) <= m:
                sets.append(frozenset(need))
        return sets

    def _taken(self, tasks: AbstractSet[int], base: dict[int, int]) -> dict[int, int]:
        """``base`` plus the epoch's available tasks among ``tasks``, counted by value."""
        out = dict(base)
        for t in tasks & self.pool:
            out[self.vlist[t]] = out.get(self.vlist[t], 0) + 1
        return out

    def scores_compiled(self, m: int) -> bool:
        """Whether :meth:`best` scores the rests of ``m`` tasks compiled (else its Python
        loop runs, with the same F)."""
        return (
            self._kernel is not None
            and self._rest_kernel is not None
            and (self._window_size + 1) ** m < 2**62
        )

    def _best_scored(
        self, prefix: tuple[int, ...], m: int, terms: np.ndarray, cutoff: float, target: float
    ) -> RestResult:
        """:meth:`best` compiled (:func:`_rest_kernel.best_rest`: the same cores in the same
        order, the same sums, F from ``terms`` as :data:`.._dfs_kernel.TERMS`, the first core
        of least F at most ``cutoff``: the same floats and the same core)."""
        assert self._rest_kernel is not None
        tables = self._packed_tables()
        prefix_arr = np.array(prefix, dtype=np.int64)
        f, best, capped, rows, members = self._rest_kernel(
            prefix_arr, m, self.max_cores, float(target), self._epoch, tables, terms, cutoff
        )
        if best < 0:
            return math.inf, (), bool(capped)
        tasks = [t for t in members[best].tolist() if t >= 0]
        k = m - len(tasks)
        free = tuple(tables[1][rows[best], :k].tolist()) if k else ()
        return float(f), self._order(set(prefix), frozenset(tasks), free), bool(capped)

    def _core_sum(self, core: frozenset[int]) -> float:
        """R(core): memoised per epoch when sums are exact in any order, else summed as
        numpy sums the core's tasks in the set's iteration order (the same floats)."""
        if self._core_sums is None:
            return float(self.r[list(core)].sum())
        hit = self._core_sums.get(core)
        if hit is None:
            hit = self._core_sums[core] = float(self.r[list(core)].sum())
        return hit

    def _order(
        self, pset: set[int], core: frozenset[int], free: tuple[int, ...]
    ) -> tuple[int, ...]:
        """A rest realising (core, free values), in its smallest topological order."""
        tasks = set(core)
        taken: dict[int, int] = {}
        for v in free:
            pool = [t for t in self.by_value[v] if t not in pset and t not in core]
            tasks.add(pool[taken.get(v, 0)])
            taken[v] = taken.get(v, 0) + 1
        seen = DoneView(self.done, pset)
        out: list[int] = []
        left = set(tasks)
        while left:
            y = min(t for t in left if all(seen[p] or p in out for p in self.search.graph.pred[t]))
            out.append(y)
            left.discard(y)
        return tuple(out)


class DoneView:
    """``done`` plus the prefix, as seen by the rest search (indexable like ``done``)."""

    __slots__ = ("base", "done")

    def __init__(self, done: np.ndarray, base: set[int]) -> None:
        self.done = done
        self.base = base

    def __getitem__(self, j: int) -> bool:
        return bool(self.done[j]) or j in self.base
