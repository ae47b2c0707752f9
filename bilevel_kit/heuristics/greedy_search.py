r"""greedy-ce's decision without enumerating permutations (paper Section IV-A, Eqs. 3-7).

The enumeration scores every precedence-feasible sequence :math:`K` of
:math:`L = \min(N, \text{remaining})` tasks and every split :math:`i`. With precedence hard,
:math:`F(K, i)` (:mod:`bilevel_kit.heuristics.upper_level`) depends on the order of :math:`K`
only through

* the prefix *set* :math:`P = K_{1:i}`: its robot and human sums (terms 5 and 6), its part
  multiset (term 7, the kit fitness, and the W7 term) and its size (term 4);
* the robot-time sum of the rest :math:`Q = K_{i+1:L}`, a set of :math:`L - i` further
  tasks with :math:`P \cup Q` precedence-closed given the tasks already done (term 6).

So this module minimises over the precedence-closed prefix sets :math:`P` (|P| = 1..L), each
with its best rest :math:`Q`, and calls the lower level (a CE run, memoised per multiset) only
for prefixes whose optimistic score can still reach the incumbent. The optimistic score of
:math:`P` is :math:`F` with term (6) at its least over :math:`R(Q) \in [lo, hi]` and with
:math:`W_5 f` replaced by :math:`W_5 \bar f(P)` until the multiset's fitness is known (then
the fitness itself). :math:`lo`/:math:`hi` are the sums of the :math:`L - i` smallest/largest
robot times of the *window* tasks outside :math:`P`: the tasks with at most :math:`L - 1`
undone ancestors, the only ones a closed window of :math:`L` tasks can hold.
:func:`fitness_upper_bounds` gives :math:`\bar f \ge f` for any valid layout (a geometric
bound; CE is a heuristic, so no bound from other multisets' CE fitness holds, and none is
used). Prefixes are taken in increasing optimistic score; the search stops at the first one
whose optimistic score exceeds the incumbent by more than the tie tolerance.

The best rest of a prefix (its least F) is found by decomposition when the robot times take
few distinct values (:class:`_Rests`: a rest is a *core* of tasks not available at the epoch
with their undone ancestors, plus free available tasks whose best sum is read from a sorted
table of value multisets), else by a depth-first search over closed extensions in
lexicographic order (also used for the tie rule below).

Ties (the enumeration's rule, reproduced): the enumeration returns the first pair within
``TIE_TOL`` of the minimum in its order (sequences lexicographic in task file positions,
then increasing ``i``). Any sequence with a minimising split ``i`` realises a pair
:math:`(P, Q)`, and the lexicographically smallest sequence realising :math:`(P, Q)` is
``topo(P) + topo(Q)``, each part in its smallest topological order (always the smallest
available task next). So among the pairs within ``TIE_TOL`` of the minimum this module
picks the smallest ``(topo(P) + topo(Q), i)``; both searches enumerate canonical orders in
lexicographic order, so the first rest found under a threshold is the smallest.

Bounds on work (never silent, counted in :class:`SearchStats`):

* ``max_prefix_sets``: if the closed prefix sets of a level would take the total beyond this
  cap, that level and the deeper ones keep only the ``beam_width`` sets of best optimistic
  score (a beam over prefix sets; the epoch counts in ``beam_epochs``);
* ``max_rest_nodes``: the rest search stops after this many search nodes (or cores, in the
  decomposition) with the best rest found so far (counted in ``rest_capped``).

Within both caps the decision is exact: the same minimum F as the enumeration and the same
chosen kit (property-tested against the enumeration in tests/heuristics/test_greedy_search.py).
The bounds assume ``W4, W5, W6 >= 0``; otherwise every prefix is evaluated.
"""

from __future__ import annotations

import bisect
import heapq
import itertools
import math
from collections import OrderedDict
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any, TypeVar

import numpy as np

from .. import geometry
from ..instance import Instance
from . import _rest_kernel, upper_level

FloatOrArray = TypeVar("FloatOrArray", float, np.ndarray)

#: Score tolerance of the tie rule (the enumeration's).
TIE_TOL = 1e-9

#: Fitness of a part multiset (count vector over the sorted part types): (fitness, fits).
FitnessFn = Callable[[np.ndarray], tuple[float, bool]]


@dataclass(frozen=True)
class SearchLimits:
    """Caps of one decision (module docstring)."""

    max_prefix_sets: int = 5000
    beam_width: int = 64
    max_rest_nodes: int = 2000


@dataclass
class SearchStats:
    """Counters summed over decisions."""

    prefix_sets: int = 0
    evaluated: int = 0
    beam_epochs: int = 0
    rest_capped: int = 0


@dataclass(frozen=True)
class Choice:
    """The chosen pair: ``prefix`` (the next kit, in its smallest topological order),
    ``rest`` (the window's rest) and its score F."""

    prefix: tuple[int, ...]
    rest: tuple[int, ...]
    score: float


def fitness_upper_bounds(
    instance: Instance, types: Sequence[str], counts: np.ndarray
) -> np.ndarray:
    r"""An upper bound of the kit fitness :math:`f = D_{diff} - D_{same} - W_6 Z` of any valid
    layout of each multiset (``counts``: shape (K, T) over ``types``), for ``W6 >= 0``.

    * :math:`Z \ge 0`.
    * :math:`D_{diff}`: a part's centre keeps a half-extent from each tray side, and a rotated
      ``w x h`` box has half-extents of at least ``min(w, h) / 2`` (``w/2``, ``h/2`` if fixed),
      so a pair (t, u) is at most :math:`\delta_{tu}` apart (the diagonal of the region both
      centres can reach), giving :math:`\sum_{t<u} c_t c_u \delta_{tu}`. Also, with
      :math:`|p - q| \le |dx| + |dy|`, the cross-type distances along x sum to the integral
      over cut lines of the cross pairs they separate, at most :math:`\min(N^2/4, \text{pairs})`
      per line over a length :math:`\ell_x = W - 2 e_x^{min}`; the smaller bound is used.
    * :math:`D_{same}`: two valid parts penetrate by at most ``geometry.TOL``, and each holds a
      disc of diameter ``min(w, h)`` about its centre, so two parts of type t are at least
      ``min(w, h) - 2 TOL`` apart.
    """
    return _FitnessBound(instance, types)(counts)


class _FitnessBound:
    """:func:`fitness_upper_bounds` with its geometry (independent of the counts) computed
    once per instance."""

    def __init__(self, instance: Instance, types: Sequence[str]) -> None:
        pts = [instance.part_types[t] for t in types]
        short = np.array([min(p.width, p.height) for p in pts])
        ex = np.array([short[k] / 2 if p.rotatable else p.width / 2 for k, p in enumerate(pts)])
        ey = np.array([short[k] / 2 if p.rotatable else p.height / 2 for k, p in enumerate(pts)])
        tray = instance.tray
        slack = 1e-6
        dx = np.maximum(tray.width - ex[:, None] - ex[None, :], 0.0) + slack
        dy = np.maximum(tray.height - ey[:, None] - ey[None, :], 0.0) + slack
        self.delta = np.hypot(dx, dy)
        np.fill_diagonal(self.delta, 0.0)
        lx = max(tray.width - 2 * float(ex.min()), 0.0) + slack if len(pts) else 0.0
        ly = max(tray.height - 2 * float(ey.min()), 0.0) + slack if len(pts) else 0.0
        self.cut_length = lx + ly
        self.same_gap = np.maximum(short - 2 * geometry.TOL - slack, 0.0)

    def __call__(self, counts: np.ndarray) -> np.ndarray:
        counts = np.asarray(counts)
        if counts.shape[1] == 1 and counts.dtype.kind in "iu" and len(counts) > 64:
            # one part type: every sum and product in the bound has one term, so the value
            # of a row does not depend on the batch: compute it once per count
            table = self._bounds(np.arange(int(counts.max()) + 1)[:, None])
            return np.asarray(table[counts[:, 0]])
        return self._bounds(counts)

    def _bounds(self, counts: np.ndarray) -> np.ndarray:
        counts = np.asarray(counts, dtype=np.float64)
        pair_bound = 0.5 * np.einsum("kt,tu,ku->k", counts, self.delta, counts)
        n = counts.sum(axis=1)
        same_pairs = (counts * (counts - 1) / 2).sum(axis=1)
        diff_pairs = n * (n - 1) / 2 - same_pairs
        cut_bound = self.cut_length * np.minimum(np.floor(n * n / 4), diff_pairs)
        d_same_lb = (counts * (counts - 1) / 2) @ self.same_gap
        return np.asarray(np.minimum(pair_bound, cut_bound) - d_same_lb)


@dataclass
class _Level:
    """The prefix sets of one size: canonical sequences and their sums."""

    seqs: list[tuple[int, ...]]
    tasks: np.ndarray
    robot: np.ndarray
    human: np.ndarray
    counts: np.ndarray


class PrefixSearch:
    """The decision over closed prefix sets for one instance (static data built once)."""

    def __init__(
        self,
        instance: Instance,
        robot: np.ndarray,
        human: np.ndarray,
        pred: Sequence[frozenset[int]],
        part_matrix: np.ndarray,
        types: Sequence[str],
        limits: SearchLimits,
    ) -> None:
        self.instance = instance
        self.r = robot
        self._h = human
        #: what a decision computes from ``done`` alone (:class:`_EpochData`), by (done, N,
        #: signed), least recently used first; emptied when the human times change
        self._epochs: OrderedDict[tuple[bytes, int, bool], _EpochData] = OrderedDict()
        self._epoch_rows = 0
        #: the rest search's packed sum tables by available tasks per value (capped at the
        #: largest k), shared by the epochs (:meth:`_Rests._packed_tables`)
        self._packed: dict[bytes, tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]] = {}
        self.pred = [tuple(sorted(p)) for p in pred]
        succ: list[list[int]] = [[] for _ in pred]
        for j, ps in enumerate(self.pred):
            for p in ps:
                succ[p].append(j)
        self.succ = [tuple(s) for s in succ]
        self.pred_set = [frozenset(p) for p in self.pred]
        #: the precedence arcs (predecessor, task), for the epoch's available tasks at once
        self._arc_pred = np.array([p for ps in self.pred for p in ps], dtype=np.int64)
        self._arc_task = np.array([j for j, ps in enumerate(self.pred) for _ in ps], dtype=np.int64)
        #: the arcs as sorted keys ``pred * n + task`` (membership of many arcs at once)
        self._arc_keys = np.sort(self._arc_pred * len(self.pred) + self._arc_task)
        #: the successors of every task, flat (CSR: task x's are ``_succ_flat[start:start+deg]``)
        self._succ_deg = np.array([len(s) for s in self.succ], dtype=np.int64)
        self._succ_start = np.cumsum(self._succ_deg) - self._succ_deg
        self._succ_flat = np.array([z for s in self.succ for z in s], dtype=np.int64)
        self.part_matrix = part_matrix
        self.types = list(types)
        self.limits = limits
        self.stats = SearchStats()
        w = instance.weights
        self._prune = w["W4"] >= 0 and w["W5"] >= 0 and w["W6"] >= 0
        self._r_range = (0.0, 0.0)
        self._fitness_bound = _FitnessBound(instance, types)
        self._r_list: list[float] = robot.tolist()
        #: undone predecessors of each task at the epoch (-1: done)
        self._undone: list[int] = []
        self._sums = _SumTable.build(robot, instance.horizon - 1)
        #: every sum of robot times is exact (multiples of 1/64 far below 2**53), so equal in
        #: any summation order: the rest search may then memoise sums by set
        self._exact_sums = bool(
            np.all(robot * 64 == np.round(robot * 64)) and np.abs(robot).sum() * 64 < 2.0**52
        )

    @property
    def h(self) -> np.ndarray:
        """Human time of each task (terms (5)-(6)); setting it forgets the cached epochs."""
        return self._h

    @h.setter
    def h(self, human: np.ndarray) -> None:
        self._h = human
        self._epochs.clear()
        self._epoch_rows = 0

    # -- prefix sets ---------------------------------------------------------------------------
    def _unlocked_after(
        self, unlocked: tuple[int, ...], seq: tuple[int, ...], y: int, undone: list[int]
    ) -> tuple[int, ...]:
        """The *unlocked children* of ``seq``, from those of its parent ``seq[:-1]``.

        The children of a canonical sequence ``s`` (the smallest topological order of its
        set) are the tasks ``z`` such that ``s + (z,)`` is canonical again: ``z`` available
        given done and ``s``, and above every task of ``s`` after the last predecessor of
        ``z`` in ``s``. Those available given done alone are the available tasks above
        ``max(s)``; the others, the unlocked ones (increasing), are built here. With
        ``seq = s + (y,)``: a child of ``s`` stays one iff it is above ``y``, and the
        successors of ``y`` whose undone predecessors (``undone``: their count, < 0 for a task
        done) all lie in ``seq`` are new children (``y`` comes last)."""
        kept = [u for u in unlocked if u > y] if unlocked else []
        new = [
            z
            for z in self.succ[y]
            if undone[z] == 1
            or (undone[z] > 1 and len(self.pred_set[z].intersection(seq)) == undone[z])
        ]
        if not new:
            return tuple(kept)
        return tuple(sorted([*kept, *new]))

    def _unlocked_rows(
        self,
        p_unl: np.ndarray,
        par: np.ndarray,
        child: np.ndarray,
        tasks: np.ndarray,
        undone: np.ndarray,
    ) -> np.ndarray:
        """:meth:`_unlocked_after` for every row of a level at once.

        ``p_unl``: the parents' unlocked children, one row per parent, increasing and padded
        with ``n`` (the number of tasks, above every task); row k of the level is parent
        ``par[k]`` followed by ``child[k]`` (its tasks: ``tasks[k]``). Returns the rows'
        unlocked children in the same padded form: the parent's above ``child[k]``, and the
        successors z of ``child[k]`` whose undone predecessors (``undone[z]``) all lie in
        ``tasks[k]``."""
        n = len(self.r)
        k_rows = len(child)
        kept = p_unl[par]
        kr, kc = np.nonzero((kept < n) & (kept > child[:, None]))
        rows_out = [kr]
        vals_out = [kept[kr, kc]]
        deg = self._succ_deg[child]
        rows = np.repeat(np.arange(k_rows), deg)
        if rows.size:
            offset = _ragged_positions(deg)
            z = self._succ_flat[np.repeat(self._succ_start[child], deg) + offset]
            need = undone[z]
            ok = need == 1
            multi = np.flatnonzero(need > 1)
            if multi.size:  # count the arcs (task of the row) -> z
                keys = tasks[rows[multi]] * n + z[multi, None]
                arcs = self._arc_keys
                pos = np.minimum(np.searchsorted(arcs, keys), len(arcs) - 1)
                ok[multi] = (arcs[pos] == keys).sum(axis=1) == need[multi]
            rows_out.append(rows[ok])
            vals_out.append(z[ok])
        all_rows = np.concatenate(rows_out)
        all_vals = np.concatenate(vals_out)
        if all_rows.size == 0:
            return np.full((k_rows, 0), n, dtype=np.int64)
        order = np.lexsort((all_vals, all_rows))
        all_rows, all_vals = all_rows[order], all_vals[order]
        count = np.bincount(all_rows, minlength=k_rows)
        col = _ragged_positions(count)
        out = np.full((k_rows, int(count.max())), n, dtype=np.int64)
        out[all_rows, col] = all_vals
        return out

    def _rest_sum_bounds(
        self, tasks: np.ndarray | _Children, m: int, ctx: _Epoch
    ) -> tuple[np.ndarray, np.ndarray]:
        """Bounds (lo, hi) of the rest's robot sum R(Q) (tasks only) of each prefix (rows of
        ``tasks``) for rests of ``m`` tasks: the ``m`` smallest and largest robot times of the
        window tasks (:meth:`_window`) outside the prefix. Every task of a rest is such a task,
        so these bound every rest's sum."""
        rows = tasks if isinstance(tasks, _Children) else _Children(tasks)
        n = len(rows)
        if m == 0:
            return np.zeros(n), np.zeros(n)
        out = []
        for ids in (ctx.low_ids, ctx.high_ids):
            pos = np.full(len(self.r), -1, dtype=np.int64)
            pos[ids] = np.arange(len(ids))
            if not self._exact_sums:
                out.append(self._first_outside(rows.take(), pos, ids, m))
                continue
            # sums exact in any order: rows without a task among ``ids`` take the first m
            sums = np.full(n, self.r[ids[:m]].sum())
            hit = np.flatnonzero(rows.touches(pos >= 0))
            if hit.size:
                sums[hit] = self._first_outside(rows.take(hit), pos, ids, m)
            out.append(sums)
        return out[0], out[1]

    def _first_outside(
        self, tasks: np.ndarray, pos: np.ndarray, ids: np.ndarray, m: int
    ) -> np.ndarray:
        """The robot sum of the first ``m`` of ``ids`` outside each row of ``tasks`` (``pos``:
        the position of each task in ``ids``, -1 if none)."""
        n = len(tasks)
        rows = np.arange(n)
        keep = np.ones((n, len(ids) + 1), dtype=bool)  # the last column catches misses
        for c in range(tasks.shape[1]):
            keep[rows, pos[tasks[:, c]]] = False
        keep = keep[:, :-1]
        chosen = keep & (np.cumsum(keep, axis=1) <= m)
        return np.asarray(chosen @ self.r[ids])

    def _optimistic(
        self,
        i: int,
        length: int,
        tasks: np.ndarray | _Children,
        robot: np.ndarray,
        human: np.ndarray,
        counts: np.ndarray,
        ctx: _Epoch,
        fitness: np.ndarray | None = None,
        parts: _BoundParts | None = None,
    ) -> np.ndarray:
        r"""Lower bounds of F over the rests of prefixes of size ``i`` (module docstring):
        term (6) at its least over :math:`R(Q) \in [lo, hi]` (:meth:`_rest_sum_bounds`), the
        fitness at its bound :func:`fitness_upper_bounds` where ``fitness`` is NaN or None.
        ``parts``: :meth:`_bound_parts` of the same rows, if already computed."""
        if not self._prune:
            return np.full(len(robot), -math.inf)
        lo, hi, bound = parts or self._bound_parts(i, length, tasks, counts, ctx)
        inst = self.instance
        d, o_r, o_h = inst.delivery_time, inst.kit_overhead_robot, inst.kit_overhead_human
        diff5 = d + o_r + robot - ctx.human_remaining
        h_kit = o_h + human
        if lo is None or hi is None:  # i == length: no rest
            diff6 = d + 0.0 - h_kit
            if not ctx.signed:
                diff6 = np.abs(diff6)
        else:
            diff6 = d + (o_r + lo) - h_kit
            if not ctx.signed:
                diff6 = np.maximum(np.maximum(diff6, -(d + (o_r + hi) - h_kit)), 0.0)
        if not ctx.signed:
            diff5 = np.abs(diff5)
        if fitness is not None:
            bound = np.where(np.isnan(fitness), bound, fitness)
        return upper_level.objective(
            inst.weights,
            n_tasks=float(i),
            diff5=diff5,
            diff6=diff6,
            fitness=bound,
            unavailable=ctx.unavailable(counts),
        )

    def _bound_parts(
        self, i: int, length: int, tasks: np.ndarray | _Children, counts: np.ndarray, ctx: _Epoch
    ) -> _BoundParts:
        """What :meth:`_optimistic` needs besides H_rem, the parts at hand and known
        fitnesses: the bounds (lo, hi) of the rest's robot sum (None if ``i == length``) and
        the fitness bound of each row."""
        lo = hi = None
        if i < length:
            lo, hi = self._rest_sum_bounds(tasks, length - i, ctx)
        return lo, hi, self._fitness_bound(counts)

    def _epoch(self, done: np.ndarray, length: int, signed: bool) -> _EpochData:
        """The data of a decision that depends on ``done`` alone (not on H_rem, the parts at
        hand or the fitnesses known), from the cache if the same epoch was seen before (the
        simulator meets the same ``done`` in run after run). Epochs whose levels became a
        beam (chosen with H_rem) are not kept."""
        key = (done.tobytes(), length, signed)
        hit = self._epochs.get(key)
        if hit is not None:
            self._epochs.move_to_end(key)
            return hit
        undone = np.bincount(self._arc_task[~done[self._arc_pred]], minlength=len(self.r))
        avail: list[int] = np.flatnonzero((undone == 0) & ~done).tolist()
        anc = self._window(done, avail, length)
        window = np.array(sorted(anc), dtype=np.int64)
        order = np.lexsort((window, self.r[window]))
        low = window[order[:length]]
        high = window[order[::-1][:length]]
        r_range = (float(self.r[low[0]]), float(self.r[high[0]]))
        undone_list: list[int] = np.where(done, -1, undone).tolist()
        return _EpochData(avail, anc, low, high, r_range, undone_list)

    def _keep_epoch(self, key: tuple[bytes, int, bool], data: _EpochData) -> None:
        """Cache an epoch, forgetting the least recently used beyond :data:`EPOCH_CACHE_ROWS`
        rows in all (an epoch's prefix sets plus one per task, for its per-task arrays)."""
        self._epochs[key] = data
        self._epoch_rows += data.rows
        while self._epoch_rows > EPOCH_CACHE_ROWS and len(self._epochs) > 1:
            _, old = self._epochs.popitem(last=False)
            self._epoch_rows -= old.rows

    def _window(self, done: np.ndarray, avail: list[int], length: int) -> dict[int, frozenset[int]]:
        """The tasks with at most ``length - 1`` undone ancestors (sorted): only they can be in
        a window of ``length`` tasks, since a closed window holds every undone ancestor of its
        tasks."""
        anc: dict[int, frozenset[int]] = {y: frozenset() for y in avail}
        queue = list(avail)
        for x in queue:
            for y in self.succ[x]:
                if y in anc or done[y]:
                    continue
                ps = [p for p in self.pred[y] if not done[p]]
                if not all(p in anc for p in ps):
                    continue
                a = frozenset().union(*(anc[p] for p in ps)) | frozenset(ps)
                if len(a) <= length - 1:
                    anc[y] = a
                    queue.append(y)
        return anc

    def _levels(
        self, undone: list[int], length: int, ctx: _Epoch, avail: list[int]
    ) -> tuple[list[_Level], bool]:
        """The closed prefix sets of sizes 1..``length`` (``undone``: undone predecessors per
        task, -1 if done), and whether a level became a beam."""
        lim = self.limits
        avail_arr = np.array(avail, dtype=np.int64)
        parents: list[tuple[int, ...]] = [()]
        p_tasks = np.zeros((1, 0), dtype=np.int64)
        p_robot = np.zeros(1)
        p_human = np.zeros(1)
        p_counts = np.zeros((1, len(self.types)), dtype=np.int64)
        #: per parent, its children that ``done`` alone does not make available (increasing,
        #: padded with n: :meth:`_unlocked_rows`)
        p_unl = np.zeros((1, 0), dtype=np.int64)
        undone_arr = np.array(undone, dtype=np.int64)
        levels: list[_Level] = []
        total = 0
        beam = False
        for i in range(1, length + 1):
            # children (module docstring: canonical sequences): the available tasks above the
            # parent's largest, at once, plus the tasks the parent unlocks (per parent)
            last = p_tasks.max(axis=1) if i > 1 else np.full(1, -1)
            # per parent the available tasks from its first above ``last``, parent-major
            starts = np.searchsorted(avail_arr, last, side="right")
            n_per = len(avail_arr) - starts
            par = np.repeat(np.arange(len(last)), n_per)
            offset = _ragged_positions(n_per)
            child = avail_arr[np.repeat(starts, n_per) + offset]
            extra_par, extra_col = np.nonzero(p_unl < len(self.r))
            if extra_par.size:
                par = np.concatenate([par, extra_par])
                child = np.concatenate([child, p_unl[extra_par, extra_col]])
                order = np.lexsort((child, par))
                par, child = par[order], child[order]
            n_kids = len(child)
            if n_kids == 0:
                break
            robot = p_robot[par] + self.r[child]
            human = p_human[par] + self.h[child]
            counts = p_counts[par] + self.part_matrix[child]
            if beam or total + n_kids > lim.max_prefix_sets:
                beam = True
                kids = _Children(p_tasks, par, child)
                opt = self._optimistic(i, length, kids, robot, human, counts, ctx)
                keep = _smallest(opt, lim.beam_width)
                par, child = par[keep], child[keep]
                robot, human, counts = robot[keep], human[keep], counts[keep]
            seqs = [(*parents[a], y) for a, y in zip(par.tolist(), child.tolist(), strict=True)]
            tasks = np.concatenate([p_tasks[par], child[:, None]], axis=1)
            levels.append(_Level(seqs, tasks, robot, human, counts))
            total += len(seqs)
            if i < length:
                p_unl = self._unlocked_rows(p_unl, par, child, tasks, undone_arr)
            parents, p_tasks, p_robot, p_human, p_counts = seqs, tasks, robot, human, counts
        return levels, beam

    # -- the rest of the window ------------------------------------------------------------------
    def _rest(
        self,
        prefix: tuple[int, ...],
        done: np.ndarray,
        avail: list[int],
        m: int,
        score: Callable[[Any], Any],
        bound: Callable[[float, float], float],
        threshold: float | None,
        cutoff: float = math.inf,
    ) -> tuple[float, tuple[int, ...], bool]:
        """The rest of ``m`` tasks after ``prefix`` of least F: (F, rest in its smallest
        topological order, capped). ``score`` maps R(Q) (task times only) to F, ``bound`` maps
        bounds (lo, hi) of R(Q) to a lower bound of F (a partial sum plus the smallest, or the
        largest, times left bounds R(Q) from below, or above). With ``threshold``, the first
        rest (lexicographic) whose F is at most the threshold. Rests whose F exceeds ``cutoff``
        are not looked for (the result is then ``(inf, ())``)."""
        base = set(prefix)
        base_avail = {y for y in avail if y not in base}
        # undone predecessors of each task given done and the prefix (< 0: done or in it)
        rel = list(self._undone)
        for x in prefix:
            rel[x] = -1
        for x in prefix:
            for y in self.succ[x]:
                rel[y] -= 1
                if rel[y] == 0:
                    base_avail.add(y)
        ordered = sorted(base_avail)
        rl = self._r_list
        rmin, rmax = self._r_range  # over the tasks not done (a superset of those left)
        best_f = math.inf
        best_q: tuple[int, ...] = ()
        nodes = 0
        cap = self.limits.max_rest_nodes
        capped = False
        seq: list[int] = []

        def rec(total: float, top: int, unlocked: tuple[int, ...]) -> bool:
            """Depth-first in lexicographic order of canonical sequences; True stops.
            ``top``: the largest task of ``seq``; ``unlocked``: its children outside
            ``ordered`` (:meth:`_unlocked_after`, given done and the prefix)."""
            nonlocal best_f, best_q, nodes, capped
            k = len(seq)
            nodes += 1
            if nodes > cap:
                capped = True
                return True
            if self._prune and k:
                lower = bound(total + (m - k) * rmin, total + (m - k) * rmax)
                if (lower > threshold) if threshold is not None else (lower >= best_f):
                    return False
                if lower > cutoff:
                    return False
            kids = ordered[bisect.bisect_right(ordered, top) :]
            if unlocked:
                kids = sorted([*kids, *unlocked])
            if not kids:
                return False
            if k == m - 1:  # the leaves at once (numpy gives the same floats, in index order)
                s = tuple(seq)
                vals = score(total + self.r[kids])
                if threshold is not None:
                    hit = np.flatnonzero(vals <= threshold)
                    if hit.size:
                        best_f, best_q = float(vals[hit[0]]), (*s, kids[int(hit[0])])
                        return True
                    return False
                a = int(np.argmin(vals))
                if vals[a] < best_f and vals[a] <= cutoff:
                    best_f, best_q = float(vals[a]), (*s, kids[a])
                return False
            for y in kids:
                seq.append(y)
                grown = self._unlocked_after(unlocked, tuple(seq), y, rel)
                stop = rec(total + rl[y], max(top, y), grown)
                seq.pop()
                if stop:
                    return True
            return False

        rec(0.0, -1, ())
        return best_f, best_q, capped

    # -- the decision ----------------------------------------------------------------------------
    def _score(
        self, i: int, diff5: float, diff6: FloatOrArray, fit: float, unav: float | None
    ) -> FloatOrArray:
        """F of one pair in the same floating-point order as :func:`upper_level.objective`."""
        w = self.instance.weights
        f: Any = -w["W2"] * float(i)
        f = f + w["W3"] * diff5 + w["W4"] * diff6 - w["W5"] * fit
        if unav is not None:
            f = f + w["W7"] * unav
        return f

    def decide(
        self,
        done: np.ndarray,
        length: int,
        human_remaining: float,
        available: np.ndarray | None,
        fitness: FitnessFn,
        signed: bool,
        cached: Callable[[np.ndarray], tuple[float, bool] | None] | None = None,
    ) -> Choice | None:
        """The minimising (P, Q) of F (module docstring); None if no prefix fits the tray.
        ``cached``: the fitness of a multiset if already known (else None), without a CE run;
        known fitnesses give exact stage-1 bounds from the start."""
        inst = self.instance
        d, o_r, o_h = inst.delivery_time, inst.kit_overhead_robot, inst.kit_overhead_human
        ep = self._epoch(done, length, signed)
        avail, anc = ep.avail, ep.anc
        self._r_range = ep.r_range
        self._undone = ep.undone
        ctx = _Epoch(human_remaining, available, signed, ep.low, ep.high)
        if ep.levels is None:  # a new epoch: its prefix sets, row keys and bounds
            levels, beam = self._levels(self._undone, length, ctx, avail)
            ep.levels, ep.beam = levels, beam
            ep.unique = [_unique_rows(lv.counts) for lv in levels]
            ep.parts = [
                self._bound_parts(li + 1, length, lv.tasks, lv.counts, ctx)
                for li, lv in enumerate(levels)
            ]
            if self._sums is not None and length > 1:
                ep.rests = _Rests(self, done, avail, anc, signed)
            if not beam:
                ep.rows = sum(len(lv.seqs) for lv in levels) + len(self.r)
                self._keep_epoch((done.tobytes(), length, signed), ep)
        levels = ep.levels
        self.stats.beam_epochs += ep.beam
        # Best-first: (bound, stage, level, row); stage 0 holds the optimistic score (fitness
        # bounded), stage 1 the bound with the prefix's own fitness (only the rest unknown).
        fits_of: list[np.ndarray] = []  # per level: the fitness of each row (NaN: unknown)
        parts: list[tuple[np.ndarray, ...]] = []
        for li, lv in enumerate(levels):
            self.stats.prefix_sets += len(lv.seqs)
            keys, inverse = ep.unique[li]
            key_fit = np.full(len(keys), np.nan)
            key_fits = np.ones(len(keys), dtype=bool)
            for u, row in enumerate(keys):
                hit = cached(row) if cached is not None else None
                if hit is not None:
                    key_fit[u], key_fits[u] = hit
            level_fit, level_fits = key_fit[inverse], key_fits[inverse]
            opt = self._optimistic(
                li + 1,
                length,
                lv.tasks,
                lv.robot,
                lv.human,
                lv.counts,
                ctx,
                level_fit,
                ep.parts[li],
            )
            known = ~np.isnan(level_fit)
            self.stats.evaluated += int((known & level_fits).sum())
            fits_of.append(level_fit)
            rows = np.flatnonzero(level_fits)
            parts.append((opt[rows], known[rows].astype(np.int64), np.full(len(rows), li), rows))
        queue = _Frontier(*(np.concatenate([p[c] for p in parts]) for c in range(4)))

        def scorer(
            li: int, k: int, fit: float
        ) -> tuple[Callable[[Any], Any], Callable[[float, float], float]]:
            """F of prefix (li, k) as a function of the rest's robot sums (vectorised), and a
            lower bound of F given a lower bound of the sum (term 6 is |x| or x, x growing with
            the sum)."""
            lv, i = levels[li], li + 1
            diff5 = d + o_r + float(lv.robot[k]) - human_remaining
            diff5 = diff5 if signed else abs(diff5)
            unav = ctx.unavailable(lv.counts[k][None, :])
            u = None if unav is None else float(unav[0])
            human = o_h + float(lv.human[k])

            def f(rest: Any) -> Any:  # R(Q): a float or an array of candidate sums
                diff6 = d + (o_r + rest) - human if i < length else d + 0.0 - human
                return self._score(i, diff5, diff6 if signed else np.abs(diff6), fit, u)

            def lower(lo: float, hi: float = math.inf) -> float:
                diff6 = d + (o_r + lo) - human
                if not signed:
                    diff6 = max(diff6, -(d + (o_r + hi) - human), 0.0)
                return float(self._score(i, diff5, diff6, fit, u))

            return f, lower

        rests = ep.rests
        found: list[tuple[float, int, int, tuple[int, ...], float]] = []
        incumbent = math.inf
        while queue and queue.peek()[0] <= incumbent + TIE_TOL:
            _, stage, li, k = queue.pop()
            i = li + 1
            lv = levels[li]
            if stage == 0:
                fit0, fits = fitness(lv.counts[k])
                if not fits:
                    continue
                self.stats.evaluated += 1
                fits_of[li][k] = fit0
                bound = self._optimistic(
                    i,
                    length,
                    lv.tasks[k : k + 1],
                    lv.robot[k : k + 1],
                    lv.human[k : k + 1],
                    lv.counts[k : k + 1],
                    ctx,
                    np.array([fit0]),
                )
                queue.push((float(bound[0]), 1, li, k))
                continue
            fit = float(fits_of[li][k])
            f, lower = scorer(li, k, fit)
            if i == length:
                score = float(f(0.0))
                found.append((score, li, k, (), fit))
                incumbent = min(incumbent, score)
                continue
            if rests is not None:
                target = -math.inf if signed else o_h + float(lv.human[k]) - d - o_r
                floor = lower(-math.inf, math.inf) if self._prune and not signed else -math.inf
                score, rest, capped = rests.best(
                    lv.seqs[k], length - i, f, incumbent + TIE_TOL, target, floor
                )
            else:
                score, rest, capped = self._rest(
                    lv.seqs[k], done, avail, length - i, f, lower, None, incumbent + TIE_TOL
                )
            self.stats.rest_capped += capped
            if rest:
                found.append((score, li, k, rest, fit))
                incumbent = min(incumbent, score)
        if not found:
            return None
        fmin = min(x[0] for x in found)
        resolved: dict[int, tuple[tuple[int, ...], float]] = {}

        def prefix_of(c: int) -> tuple[int, ...]:
            return levels[found[c][1]].seqs[found[c][2]]

        def resolve(c: int) -> tuple[tuple[int, ...], float]:
            """The smallest rest of candidate ``c`` still within the tolerance of the minimum
            (with its F); the rest found above if that search stops at its cap."""
            if c not in resolved:
                score, li, k, rest, fit = found[c]
                i = li + 1
                if i < length:
                    f2, first, _ = self._rest(
                        levels[li].seqs[k],
                        done,
                        avail,
                        length - i,
                        *scorer(li, k, fit),
                        fmin + TIE_TOL,
                    )
                    if first:
                        rest, score = first, f2
                resolved[c] = (rest, score)
            return resolved[c]

        def smaller(a: int, b: int) -> bool:
            """Key (prefix + rest, i) of ``a`` below that of ``b``; the rests are looked for
            only when one prefix starts the other (else the prefixes decide)."""
            pa, pb = prefix_of(a), prefix_of(b)
            for x, y in zip(pa, pb, strict=False):
                if x != y:
                    return x < y
            return (pa + resolve(a)[0], len(pa)) < (pb + resolve(b)[0], len(pb))

        best = -1
        for c, entry in enumerate(found):
            if entry[0] <= fmin + TIE_TOL and (best < 0 or smaller(c, best)):
                best = c
        rest, score = resolve(best)
        return Choice(prefix_of(best), rest, score)


class _Children:
    """Prefix rows (task indices) as parent rows plus one task each, built only where needed
    (a beam level scores many children and keeps few)."""

    def __init__(
        self, parents: np.ndarray, par: np.ndarray | None = None, child: np.ndarray | None = None
    ) -> None:
        self.parents = parents
        self.par = par
        self.child = child

    def __len__(self) -> int:
        return len(self.parents) if self.par is None else len(self.par)

    def take(self, rows: np.ndarray | None = None) -> np.ndarray:
        """The task matrix of ``rows`` (all if None)."""
        if self.par is None or self.child is None:
            return self.parents if rows is None else self.parents[rows]
        par, child = (self.par, self.child) if rows is None else (self.par[rows], self.child[rows])
        return np.concatenate([self.parents[par], child[:, None]], axis=1)

    def touches(self, marked: np.ndarray) -> np.ndarray:
        """Whether each row holds a task with ``marked`` set."""
        hit = marked[self.parents].any(axis=1)
        if self.par is None or self.child is None:
            return np.asarray(hit)
        return np.asarray(hit[self.par] | marked[self.child])


def _ragged_positions(sizes: np.ndarray) -> np.ndarray:
    """For groups of ``sizes`` laid out one after another, each element's position in its
    group: ``[0, 1, .., sizes[0] - 1, 0, 1, .., sizes[1] - 1, ...]``."""
    return np.arange(int(sizes.sum())) - np.repeat(np.cumsum(sizes) - sizes, sizes)


def _smallest(values: np.ndarray, k: int) -> np.ndarray:
    """The indices (increasing) of the ``k`` smallest values, ties to the smaller index: the
    first ``k`` of a stable sort, without sorting everything."""
    n = len(values)
    if n <= k:
        return np.arange(n)
    kth = values[np.argpartition(values, k - 1)[k - 1]]
    if np.isnan(kth):  # NaNs sort last; keep the plain rule
        return np.sort(np.lexsort((np.arange(n), values))[:k])
    below = np.flatnonzero(values < kth)
    ties = np.flatnonzero(values == kth)[: k - len(below)]
    return np.sort(np.concatenate([below, ties]))


def _unique_rows(counts: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The distinct rows of a non-negative integer matrix and the index of each row's, as
    ``np.unique(axis=0)`` (rows packed into one integer each when they fit 52 bits)."""
    if len(counts) == 0 or counts.shape[1] == 0:
        keys, inverse = np.unique(counts, axis=0, return_inverse=True)
        return keys, inverse.reshape(-1)
    base = counts.max(axis=0).astype(np.float64) + 1.0
    if float(np.prod(base)) >= 2.0**52:  # the radix below exact in floating point
        keys, inverse = np.unique(counts, axis=0, return_inverse=True)
        return keys, inverse.reshape(-1)
    radix = np.cumprod(np.concatenate([[1.0], base[:0:-1]]))[::-1].astype(np.int64)
    _, first, inverse = np.unique(counts @ radix, return_index=True, return_inverse=True)
    return counts[first], inverse.reshape(-1)


class _Frontier:
    """The best-first queue of :meth:`PrefixSearch.decide`: entries (bound, stage, level, row)
    popped in increasing order, the initial ones sorted at once (numpy) and merged with a heap
    of the later pushes; the same order as one heap of all (entries are distinct)."""

    def __init__(self, bound: np.ndarray, stage: np.ndarray, level: np.ndarray, row: np.ndarray):
        order = np.lexsort((row, level, stage, bound))
        self._cols = [c[order] for c in (bound, stage, level, row)]
        self._pos = 0
        self._buf: list[tuple[float, int, int, int]] = []
        self._next = 0
        self._heap: list[tuple[float, int, int, int]] = []

    def _static(self) -> tuple[float, int, int, int] | None:
        if self._next == len(self._buf):  # convert the next block of sorted entries
            a, b = self._pos, min(self._pos + 256, len(self._cols[0]))
            if a == b:
                return None
            cols = [c[a:b].tolist() for c in self._cols]
            self._buf, self._next, self._pos = list(zip(*cols, strict=True)), 0, b
        return self._buf[self._next]

    def __bool__(self) -> bool:
        return bool(self._heap) or self._static() is not None

    def peek(self) -> tuple[float, int, int, int]:
        s = self._static()
        if s is None or (self._heap and self._heap[0] < s):
            return self._heap[0]
        return s

    def pop(self) -> tuple[float, int, int, int]:
        s = self._static()
        if s is None or (self._heap and self._heap[0] < s):
            return heapq.heappop(self._heap)
        self._next += 1
        return s

    def push(self, item: tuple[float, int, int, int]) -> None:
        heapq.heappush(self._heap, item)


@dataclass(frozen=True)
class _SumTable:
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
    def build(cls, robot: np.ndarray, kmax: int) -> _SumTable | None:
        vals, vidx = np.unique(robot, return_inverse=True)
        n_vals = len(vals)
        if kmax < 1 or sum(math.comb(n_vals + k - 1, k) for k in range(1, kmax + 1)) > (
            MAX_SUM_COMBOS
        ):
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


#: Deep tasks from which an epoch's rest search runs compiled (both loops give the same).
MIN_DEEP_COMPILED = 1

#: Largest sum table (multisets over all k) :class:`_SumTable` builds.
MAX_SUM_COMBOS = 300_000


class _Rests:
    r"""The best rest of each prefix at one epoch, by decomposition instead of a search over
    sequences. Let :math:`A` be the tasks available at the epoch (every predecessor done).
    A rest :math:`Q` (closed given done and :math:`P`) splits uniquely into its *core*
    :math:`C`: its tasks outside :math:`A` with their undone ancestors outside :math:`P`
    (all in :math:`Q`, by closedness), and the *free* tasks :math:`Q \setminus C \subseteq A
    \setminus (P \cup C)`, any of which may be added since their predecessors are done.
    So the best rest is the best over cores (few: unions of the needed sets of window tasks
    outside :math:`A`, of total size at most :math:`m`) of :math:`R(C)` plus the sum of
    :math:`m - |C|` free tasks closest to the target (or least, in the signed form), read
    from the sorted multiset sums of :class:`_SumTable` (skipping multisets that use more
    tasks of a value than are left). Exact: every rest is some (core, free multiset).
    When every sum of robot times is exact, the loop over cores runs compiled
    (:mod:`bilevel_kit.heuristics._rest_kernel`, the same cores, order and sums)."""

    def __init__(
        self,
        search: PrefixSearch,
        done: np.ndarray,
        avail: list[int],
        anc: dict[int, frozenset[int]],
        signed: bool,
    ) -> None:
        tab = search._sums
        assert tab is not None
        self.search = search
        self.done = done
        self.r = search.r
        self.vidx = tab.vidx
        self.signed = signed
        self.pool = frozenset(avail)
        self.vlist: list[int] = tab.vidx.tolist()
        #: R(core) by core when every sum of robot times is exact (then in any order)
        self._core_sums: dict[frozenset[int], float] | None = {} if search._exact_sums else None
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
        self.max_cores = search.limits.max_rest_nodes
        #: the compiled loop of :meth:`best` (sums exact in any order only) and its arrays;
        #: without deep tasks the only core is the empty one: the Python loop is quicker
        self._kernel = None
        if search._exact_sums and len(self.deep) >= MIN_DEEP_COMPILED:
            self._kernel = _rest_kernel.kernel()
        self._window_size = len(anc)
        self._epoch: tuple[np.ndarray, ...] = ()
        self._packed: tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray] | None = None
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

    def _packed_tables(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """The tables of :meth:`_table` for every k as one array each (offsets by k, combos
        and ranks padded to the largest k, sums), for the compiled loop. They depend on the
        available tasks per value only up to the largest k (a rank is below it), so epochs
        share them (:attr:`PrefixSearch._packed`)."""
        if self._packed is None:
            kmax = max(self._tab.tables)
            shared = self.search._packed
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
        score: Callable[[Any], Any],
        cutoff: float,
        target: float,
        floor: float = -math.inf,
    ) -> tuple[float, tuple[int, ...], bool]:
        """(F, a rest of least F in its smallest topological order, capped) over the rests of
        ``m`` tasks after ``prefix`` with F at most ``cutoff`` ((inf, (), capped) if none).
        ``target``: the rest sum R(Q) that makes term (6) zero (-inf in the signed form);
        ``floor``: F with term (6) zero, below every rest's F (-inf: unknown). Every core is
        still enumerated, so the cap counts as without the floor."""
        if self._kernel is not None and (self._window_size + 1) ** m < 2**62:
            return self._best_compiled(prefix, m, score, cutoff, target)
        pset = set(prefix)
        cands: list[tuple[int, frozenset[int]]] = []
        some = set(self.small[min(m, len(self.small) - 1)])
        for x in prefix:
            some.update(self.desc.get(x, ()))
        for y in sorted(some):
            if y in pset:
                continue
            need = (self.anc[y] - pset) | {y}
            if len(need) <= m:
                cands.append((y, frozenset(need)))
        sets = [c[1] for c in cands]
        sizes = [len(c) for c in sets]
        base: dict[int, int] = {}  # the prefix's available tasks by value
        for t in pset & self.pool:
            base[self.vlist[t]] = base.get(self.vlist[t], 0) + 1
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
                removed = base
                if core:
                    removed = dict(base)
                    for t in core & self.pool:
                        removed[self.vlist[t]] = removed.get(self.vlist[t], 0) + 1
                r_core = self._core_sum(core) if core else 0.0
                free = self._free(m - len(core), target - r_core, removed)
                if free is not None:
                    val = float(score(r_core + free[0]))
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

    def _best_compiled(
        self,
        prefix: tuple[int, ...],
        m: int,
        score: Callable[[Any], Any],
        cutoff: float,
        target: float,
    ) -> tuple[float, tuple[int, ...], bool]:
        """:meth:`best` by :func:`_rest_kernel.best_cores` (the same cores in the same order,
        the same sums): every core's F at once, the first of least F at most ``cutoff``."""
        assert self._kernel is not None
        tables = self._packed_tables()
        prefix_arr = np.array(prefix, dtype=np.int64)
        _, capped, sums, rows, members = self._kernel(
            prefix_arr, m, self.max_cores, float(target), self._epoch, tables
        )
        val = np.asarray(score(sums), dtype=np.float64)
        ok = np.flatnonzero(val <= cutoff)  # NaN (no free multiset) never is
        if not ok.size:
            return math.inf, (), bool(capped)
        best = int(ok[np.argmin(val[ok])])  # the first of least F, as the loop keeps it
        tasks = [t for t in members[best].tolist() if t >= 0]
        k = m - len(tasks)
        free = tuple(tables[1][rows[best], :k].tolist()) if k else ()
        return float(val[best]), self._order(set(prefix), frozenset(tasks), free), bool(capped)

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
        seen = _DoneView(self.done, pset)
        out: list[int] = []
        left = set(tasks)
        while left:
            y = min(t for t in left if all(seen[p] or p in out for p in self.search.pred[t]))
            out.append(y)
            left.discard(y)
        return tuple(out)


class _DoneView:
    """``done`` plus the prefix, as seen by the rest search (indexable like ``done``)."""

    __slots__ = ("base", "done")

    def __init__(self, done: np.ndarray, base: set[int]) -> None:
        self.done = done
        self.base = base

    def __getitem__(self, j: int) -> bool:
        return bool(self.done[j]) or j in self.base


#: (lo, hi, fitness bound) of prefix rows (:meth:`PrefixSearch._bound_parts`).
_BoundParts = tuple[np.ndarray | None, np.ndarray | None, np.ndarray]

#: Size of the decision's epoch cache: prefix sets plus tasks (per epoch), in all its epochs.
EPOCH_CACHE_ROWS = 50_000


@dataclass
class _EpochData:
    """What a decision computes from ``done`` alone (:meth:`PrefixSearch._epoch`): the
    available tasks, the window (undone ancestors of each window task), the window tasks of
    least and greatest robot times and their range, undone predecessors per task; then the
    levels of prefix sets with their distinct count rows and bounds, and the rest search."""

    avail: list[int]
    anc: dict[int, frozenset[int]]
    low: np.ndarray
    high: np.ndarray
    r_range: tuple[float, float]
    undone: list[int]
    levels: list[_Level] | None = None
    beam: bool = False
    unique: list[tuple[np.ndarray, np.ndarray]] = field(default_factory=list)
    parts: list[_BoundParts] = field(default_factory=list)
    rests: _Rests | None = None
    #: its size in the cache (:meth:`PrefixSearch._keep_epoch`)
    rows: int = 0


@dataclass
class _Epoch:
    """What one decision knows: H_rem, the parts at hand, the signed flag and the window tasks
    that bound the rest's robot sums."""

    human_remaining: float
    available: np.ndarray | None
    signed: bool
    #: the window tasks (:meth:`PrefixSearch._window`) of least and greatest robot times,
    #: ``length`` of each, in increasing and decreasing order
    low_ids: np.ndarray
    high_ids: np.ndarray

    def unavailable(self, counts: np.ndarray) -> np.ndarray | None:
        if self.available is None:
            return None
        return upper_level.unavailable_parts(counts, self.available)


def available_vector(
    available: Mapping[str, int] | None, types: Sequence[str]
) -> np.ndarray | None:
    """The parts at hand as a count vector over ``types`` (None: everything available)."""
    if available is None:
        return None
    return np.array([available.get(t, 0) for t in types])
