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
:func:`.prefix.bounds.fitness_upper_bounds` gives :math:`\bar f \ge f` for any valid layout
(a geometric bound; CE is a heuristic, so no bound from other multisets' CE fitness holds,
and none is used). Prefixes are taken in increasing optimistic score; the search stops at the
first one whose optimistic score exceeds the incumbent by more than the tie tolerance.

The best rest of a prefix (its least F) is found by decomposition when the robot times take
few distinct values (:class:`.prefix.rests.RestDecomposition`: a rest is a *core* of tasks
not available at the epoch with their undone ancestors, plus free available tasks whose best
sum is read from a sorted table of value multisets), else by a depth-first search over closed
extensions in lexicographic order (also used for the tie rule below).

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

The parts live in :mod:`.prefix` (the prefix sets, the optimistic score, the rest searches,
the best-first queue); this module holds the decision itself.
"""

from __future__ import annotations

import math
from collections import OrderedDict
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field

import numpy as np

from ..instance import Instance
from . import _beam_kernel, _dfs_kernel
from .prefix.bounds import BoundParts, DecisionContext, OptimisticScore
from .prefix.frontier import Frontier
from .prefix.levels import Children, Level, Precedence, Window, build_levels, unique_rows
from .prefix.rests import RestDecomposition, RestSearch

#: Score tolerance of the tie rule (the enumeration's).
TIE_TOL = 1e-9

#: Fitness of a part multiset (count vector over the sorted part types): (fitness, fits).
FitnessFn = Callable[[np.ndarray], tuple[float, bool]]

#: Parent count rows whose fitness bounds (one per task count row) the beam keeps.
BOUND_ROWS = 20_000

#: Size of the decision's epoch cache: prefix sets plus tasks (per epoch), in all its epochs.
EPOCH_CACHE_ROWS = 50_000


class OutOfTime(Exception):
    """The time limit passed before a decision had the layouts it needs (:func:`timed`)."""


def timed(
    fitness: FitnessFn,
    cached: Callable[[np.ndarray], tuple[float, bool] | None],
    past_deadline: Callable[[], bool],
) -> FitnessFn:
    """``fitness`` that raises :class:`OutOfTime` for a multiset not yet laid out once
    ``past_deadline()``: the best-first loop calls the lower level once per promising prefix,
    and hundreds of CE runs carried a 5 s limit to 43 s (docs/cli.md#time-limits)."""

    def call(row: np.ndarray) -> tuple[float, bool]:
        if past_deadline() and cached(row) is None:
            raise OutOfTime
        return fitness(row)

    return call


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


@dataclass
class _EpochData:
    """What a decision computes from ``done`` alone (:meth:`PrefixSearch._epoch`): the window,
    then the levels of prefix sets with their distinct count rows and bounds, and the rest
    search by decomposition (None: the depth-first one)."""

    window: Window
    levels: list[Level] | None = None
    beam: bool = False
    unique: list[tuple[np.ndarray, np.ndarray]] = field(default_factory=list)
    parts: list[BoundParts] = field(default_factory=list)
    rests: RestDecomposition | None = None
    #: its size in the cache (:meth:`PrefixSearch._keep_epoch`)
    rows: int = 0


@dataclass
class _Decision:
    """One call of :meth:`PrefixSearch.decide`: its epoch (levels built), what it knows, the
    window length, the lower level, and per level the fitness of each row (NaN: unknown)."""

    ep: _EpochData
    ctx: DecisionContext
    length: int
    fitness: FitnessFn
    fits_of: list[np.ndarray] = field(default_factory=list)

    @property
    def levels(self) -> list[Level]:
        assert self.ep.levels is not None
        return self.ep.levels


#: A pair found by the best-first search: (F, level, row, rest, the prefix's fitness).
_Found = tuple[float, int, int, tuple[int, ...], float]


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
        self.station = instance.params_of()  # one station's d and o_H (GreedyCEPolicy)
        self.r = robot
        self._h = human
        #: what a decision computes from ``done`` alone (:class:`_EpochData`), by (done, N,
        #: signed), least recently used first; emptied when the human times change
        self._epochs: OrderedDict[tuple[bytes, int, bool], _EpochData] = OrderedDict()
        self._epoch_rows = 0
        self.graph = Precedence(pred)
        self.part_matrix = part_matrix
        self.types = list(types)
        self.limits = limits
        self.stats = SearchStats()
        w = instance.weights
        self._prune = w["W4"] >= 0 and w["W5"] >= 0 and w["W6"] >= 0
        self._optimistic = OptimisticScore(instance, robot, types, self._prune)
        #: the compiled beam (:mod:`._beam_kernel`) and each task's count row's key
        self._beam_kernel = _beam_kernel.kernel()
        keys, inverse = unique_rows(np.asarray(part_matrix, dtype=np.int64))
        self._task_keys = (keys, inverse.astype(np.int64))
        #: fitness bounds of a parent count row plus each task's (:meth:`_bound_table`)
        self._bound_rows: dict[bytes, np.ndarray] = {}
        self._rests = RestSearch(
            self.graph, robot, instance.horizon, self._prune, limits.max_rest_nodes
        )
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

    # -- the decision ----------------------------------------------------------------------------
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
        ep = self._epoch(done, length, signed)
        win = ep.window
        ctx = DecisionContext(
            human_remaining, available, signed, win.low, win.high, self._exact_sums
        )
        if ep.levels is None:
            self._build_epoch(ep, done, length, ctx)
        self.stats.beam_epochs += ep.beam
        dc = _Decision(ep, ctx, length, fitness)
        queue = self._frontier(dc, cached)
        found = self._best_first(dc, queue)
        if not found:
            return None
        return self._tie_break(dc, found)

    def _build_epoch(
        self, ep: _EpochData, done: np.ndarray, length: int, ctx: DecisionContext
    ) -> None:
        """A new epoch's prefix sets, row keys, bounds and rest search; cached unless its
        levels became a beam (chosen with H_rem)."""
        lim = self.limits

        def beam_score(
            i: int, kids: Children, robot: np.ndarray, human: np.ndarray, counts: np.ndarray
        ) -> np.ndarray:
            return self._optimistic(i, length, kids, robot, human, counts, ctx)

        def fast_beam(
            i: int,
            p_tasks: np.ndarray,
            p_unl: np.ndarray,
            p_robot: np.ndarray,
            p_human: np.ndarray,
            p_counts: np.ndarray,
        ) -> tuple[np.ndarray, np.ndarray, np.ndarray] | None:
            parents = (p_tasks, p_unl, p_robot, p_human, p_counts)
            return self._fast_beam(i, length, ep.window, ctx, parents)

        levels, beam = build_levels(
            self.graph,
            ep.window,
            length,
            robot=self.r,
            human=self.h,
            part_matrix=self.part_matrix,
            max_sets=lim.max_prefix_sets,
            beam_width=lim.beam_width,
            beam_score=beam_score,
            fast_beam=fast_beam if self._beam_kernel is not None else None,
        )
        ep.levels, ep.beam = levels, beam
        ep.unique = [unique_rows(lv.counts) for lv in levels]
        # the queue's bounds may be tighter than the beam's: the beam's choice of prefix sets
        # is part of the decision, the queue's order is not (the tie rule decides)
        ep.parts = [
            self._optimistic.parts(li + 1, length, lv.tasks, lv.counts, ctx, tight=True)
            for li, lv in enumerate(levels)
        ]
        if self._rests.sums is not None and length > 1:
            ep.rests = RestDecomposition(self._rests, done, ep.window, self._exact_sums)
        if not beam:
            ep.rows = sum(len(lv.seqs) for lv in levels) + len(self.r)
            self._keep_epoch((done.tobytes(), length, ctx.signed), ep)

    def _fast_beam(
        self,
        i: int,
        length: int,
        window: Window,
        ctx: DecisionContext,
        parents: tuple[np.ndarray, ...],
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray] | None:
        """The rows a beam level keeps and their optimistic scores, compiled
        (:mod:`._beam_kernel`: the rows and floats of ``beam_score`` and ``smallest``); None
        where the kernel does not apply (bounds off, inexact sums, parts at hand, windows
        beyond 62 tasks, a NaN score)."""
        kern = self._beam_kernel
        if kern is None or not self._prune or not ctx.exact_sums or ctx.available is not None:
            return None
        if len(ctx.low_ids) > 62 or len(ctx.high_ids) > 62:
            return None
        p_tasks, p_unl, p_robot, p_human, p_counts = parents
        inst, w, m = self.instance, self.instance.weights, length - i
        d, o_r = self.station.delivery_time, inst.kit_overhead_robot
        p_keys, p_key = unique_rows(p_counts)
        c_key = self._task_keys[1]
        table = self._bound_table(p_keys)
        low, high = ctx.low_ids, ctx.high_ids
        consts = np.array(
            [
                -w["W2"] * float(i),
                w["W3"],
                w["W4"],
                w["W5"],
                d,
                d + o_r,
                o_r,
                self.station.kit_overhead_human,
                ctx.human_remaining,
                float(ctx.signed),
                self.r[low[:m]].sum() if m else 0.0,
                self.r[high[:m]].sum() if m else 0.0,
            ],
            dtype=np.float64,
        )
        avail = np.array(window.avail, dtype=np.int64)
        keys = (p_key.astype(np.int64), c_key, np.ascontiguousarray(table, dtype=np.float64))
        par, child, opt, ok = kern(
            avail,
            p_tasks,
            p_unl,
            p_robot,
            p_human,
            self.r,
            self.h,
            keys,
            low,
            high,
            m,
            consts,
            self.limits.beam_width,
        )
        return (par, child, opt) if ok else None

    def _bound_table(self, p_keys: np.ndarray) -> np.ndarray:
        """The fitness bound of each parent count row (``p_keys``) plus each task's count row
        (:attr:`_task_keys`), for the compiled beam; rows memoised by parent row (the bound
        of a row does not depend on the batch it is computed in)."""
        c_keys = self._task_keys[0]
        memo = self._bound_rows
        names = [row.tobytes() for row in p_keys]
        todo = [u for u, name in enumerate(names) if name not in memo]
        if todo:
            rows = p_keys[todo][:, None, :] + c_keys[None, :, :]
            fresh = self._optimistic.fitness_bound(rows.reshape(-1, p_keys.shape[1]))
            if len(memo) + len(todo) > BOUND_ROWS:
                memo.clear()
            for u, values in zip(todo, fresh.reshape(len(todo), len(c_keys)), strict=True):
                memo[names[u]] = values
        return np.array([memo[name] for name in names], dtype=np.float64).reshape(
            len(p_keys), len(c_keys)
        )

    def _frontier(
        self, dc: _Decision, cached: Callable[[np.ndarray], tuple[float, bool] | None] | None
    ) -> Frontier:
        """The best-first queue of every prefix not known to overfill the tray: (bound, stage,
        level, row); stage 0 holds the optimistic score (fitness bounded), stage 1 the bound
        with the prefix's own fitness (only the rest unknown). Fills ``dc.fits_of``."""
        parts: list[tuple[np.ndarray, ...]] = []
        for li, lv in enumerate(dc.levels):
            self.stats.prefix_sets += len(lv.seqs)
            keys, inverse = dc.ep.unique[li]
            key_fit = np.full(len(keys), np.nan)
            key_fits = np.ones(len(keys), dtype=bool)
            for u, row in enumerate(keys):
                hit = cached(row) if cached is not None else None
                if hit is not None:
                    key_fit[u], key_fits[u] = hit
            level_fit, level_fits = key_fit[inverse], key_fits[inverse]
            opt = self._optimistic(
                li + 1,
                dc.length,
                lv.tasks,
                lv.robot,
                lv.human,
                lv.counts,
                dc.ctx,
                level_fit,
                dc.ep.parts[li],
            )
            known = ~np.isnan(level_fit)
            self.stats.evaluated += int((known & level_fits).sum())
            dc.fits_of.append(level_fit)
            rows = np.flatnonzero(level_fits)
            parts.append((opt[rows], known[rows].astype(np.int64), np.full(len(rows), li), rows))
        return Frontier(*(np.concatenate([p[c] for p in parts]) for c in range(4)))

    def _best_first(self, dc: _Decision, queue: Frontier) -> list[_Found]:
        """Prefixes in increasing bound while the bound is within the tie tolerance of the
        incumbent: a stage-0 prefix gets its fitness (a lower-level call) and goes back with
        its stage-1 bound, a stage-1 prefix its best rest. Returns the pairs found."""
        found: list[_Found] = []
        incumbent = math.inf
        while queue and queue.peek()[0] <= incumbent + TIE_TOL:
            _, stage, li, k = queue.pop()
            if stage == 0:
                self._fit_prefix(dc, queue, li, k)
                continue
            pair = self._best_pair(dc, li, k, incumbent)
            if pair is not None:
                found.append(pair)
                incumbent = min(incumbent, pair[0])
        return found

    def _fit_prefix(self, dc: _Decision, queue: Frontier, li: int, k: int) -> None:
        """Stage 0 of prefix (level ``li``, row ``k``): its fitness, and its stage-1 entry with
        that fitness in the bound (none if the multiset does not fit the tray)."""
        lv = dc.levels[li]
        fit0, fits = dc.fitness(lv.counts[k])
        if not fits:
            return
        self.stats.evaluated += 1
        dc.fits_of[li][k] = fit0
        parts = None
        if dc.ctx.exact_sums:  # the level's rest-sum bounds are this row's (exact in any order)
            lo, hi, fb = dc.ep.parts[li]
            row = slice(k, k + 1)
            parts = (None if lo is None else lo[row], None if hi is None else hi[row], fb[row])
        bound = self._optimistic(
            li + 1,
            dc.length,
            lv.tasks[k : k + 1],
            lv.robot[k : k + 1],
            lv.human[k : k + 1],
            lv.counts[k : k + 1],
            dc.ctx,
            np.array([fit0]),
            parts,
        )
        queue.push((float(bound[0]), 1, li, k))

    def _best_pair(self, dc: _Decision, li: int, k: int, incumbent: float) -> _Found | None:
        """Stage 1 of prefix (level ``li``, row ``k``): the pair with its best rest, if that
        rest's F is within the tie tolerance of ``incumbent`` (else None). F is the rest
        searches' own (:data:`._dfs_kernel.TERMS`, compiled or run as Python)."""
        lv, i, length = dc.levels[li], li + 1, dc.length
        fit = float(dc.fits_of[li][k])
        terms = self._pair_terms(dc, li, k, fit)
        signed = dc.ctx.signed
        if i == length:  # no rest: term (6) is d - (o_H + H(P))
            diff6 = terms[6] + 0.0 - terms[8]
            return float(_dfs_kernel._score(terms, diff6 if signed else abs(diff6))), li, k, (), fit
        rests = dc.ep.rests
        if rests is not None:
            d, o_r = self.station.delivery_time, self.instance.kit_overhead_robot
            o_h = self.station.kit_overhead_human
            target = -math.inf if signed else o_h + float(lv.human[k]) - d - o_r
            floor = -math.inf
            if self._prune and not signed:  # F with term (6) zero
                floor = float(_dfs_kernel._lower(terms, -math.inf, math.inf))
            score, rest, capped = rests.best(
                lv.seqs[k], length - i, terms, incumbent + TIE_TOL, target, floor
            )
        else:
            score, rest, capped = self._rests.depth_first(
                dc.ep.window, lv.seqs[k], length - i, terms, None, incumbent + TIE_TOL
            )
        self.stats.rest_capped += capped
        return (score, li, k, rest, fit) if rest else None

    def _pair_terms(self, dc: _Decision, li: int, k: int, fit: float) -> np.ndarray:
        """F of prefix (level ``li``, row ``k``) as a function of the rest's robot sum: the
        numbers the rest searches read (:data:`._dfs_kernel.TERMS`), each product formed as
        :func:`.upper_level.objective` forms it."""
        inst, ctx, w = self.instance, dc.ctx, self.instance.weights
        lv, i = dc.levels[li], li + 1
        diff5 = self.station.delivery_time + inst.kit_overhead_robot + float(lv.robot[k])
        diff5 = diff5 - ctx.human_remaining
        diff5 = diff5 if ctx.signed else abs(diff5)
        unav = ctx.unavailable(lv.counts[k][None, :])
        u = 0.0 if unav is None else float(unav[0])
        human = self.station.kit_overhead_human + float(lv.human[k])
        return np.array(
            [
                -w["W2"] * float(i),
                w["W3"] * diff5,
                w["W4"],
                w["W5"] * fit,
                float(unav is not None),
                w["W7"] * u,
                self.station.delivery_time,
                inst.kit_overhead_robot,
                human,
                float(ctx.signed),
            ],
            dtype=np.float64,
        )

    def _tie_break(self, dc: _Decision, found: list[_Found]) -> Choice:
        """The enumeration's tie rule (module docstring): among the pairs found within the
        tolerance of the least F, the smallest (prefix + rest, i), each rest the smallest
        within that tolerance."""
        levels, length = dc.levels, dc.length
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
                    f2, first, _ = self._rests.depth_first(
                        dc.ep.window,
                        levels[li].seqs[k],
                        length - i,
                        self._pair_terms(dc, li, k, fit),
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

    # -- the epoch cache -------------------------------------------------------------------------
    def _epoch(self, done: np.ndarray, length: int, signed: bool) -> _EpochData:
        """The data of a decision that depends on ``done`` alone (not on H_rem, the parts at
        hand or the fitnesses known), from the cache if the same epoch was seen before (the
        simulator meets the same ``done`` in run after run); a new one holds the window only
        (:meth:`_build_epoch` adds the rest)."""
        key = (done.tobytes(), length, signed)
        hit = self._epochs.get(key)
        if hit is not None:
            self._epochs.move_to_end(key)
            return hit
        return _EpochData(self.graph.window(done, length, self.r))

    def _keep_epoch(self, key: tuple[bytes, int, bool], data: _EpochData) -> None:
        """Cache an epoch, forgetting the least recently used beyond :data:`EPOCH_CACHE_ROWS`
        rows in all (an epoch's prefix sets plus one per task, for its per-task arrays)."""
        self._epochs[key] = data
        self._epoch_rows += data.rows
        while self._epoch_rows > EPOCH_CACHE_ROWS and len(self._epochs) > 1:
            _, old = self._epochs.popitem(last=False)
            self._epoch_rows -= old.rows


def available_vector(
    available: Mapping[str, int] | None, types: Sequence[str]
) -> np.ndarray | None:
    """The parts at hand as a count vector over ``types`` (None: everything available)."""
    if available is None:
        return None
    return np.array([available.get(t, 0) for t in types])
