r"""The optimistic score of a prefix (:mod:`..greedy_search`): a lower bound of F over every
rest, from bounds of the rest's robot sum and an upper bound of the kit fitness (Eqs. 3-7
with term (6) at its least and :math:`W_5 f` at its most), so that the decision calls the
lower level only for prefixes that can still reach the incumbent.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from ... import geometry
from ...instance import Instance
from .. import upper_level
from .levels import Children, unique_rows

#: Types of a multiset up to which :meth:`FitnessBound.tight` enumerates their corners
#: (4 ** (k - 1) assignments).
CORNER_TYPES = 7

#: (lo, hi, fitness bound) of prefix rows (:meth:`OptimisticScore.parts`).
BoundParts = tuple[np.ndarray | None, np.ndarray | None, np.ndarray]


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
    return FitnessBound(instance, types)(counts)


class FitnessBound:
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
        # the corners of each type's box of centres (x then y from the box's lower left,
        # counter-clockwise), widened by the checker's tolerance
        lo_x, lo_y = ex - geometry.TOL, ey - geometry.TOL
        hi_x = np.maximum(tray.width - lo_x, lo_x)
        hi_y = np.maximum(tray.height - lo_y, lo_y)
        cx = np.stack([lo_x, hi_x, hi_x, lo_x], axis=1)
        cy = np.stack([lo_y, lo_y, hi_y, hi_y], axis=1)
        #: corner_dist[t, a, u, b]: distance from corner a of type t's box to corner b of u's
        self.corner_dist = (
            np.hypot(
                cx[:, :, None, None] - cx[None, None, :, :],
                cy[:, :, None, None] - cy[None, None, :, :],
            )
            + slack
        )
        self._tight: dict[bytes, float] = {}
        self._patterns: dict[int, tuple[np.ndarray, list[tuple[int, int]], np.ndarray]] = {}

    def __call__(self, counts: np.ndarray) -> np.ndarray:
        counts = np.asarray(counts)
        if counts.shape[1] == 1 and counts.dtype.kind in "iu" and len(counts) > 64:
            # one part type: every sum and product in the bound has one term, so the value
            # of a row does not depend on the batch: compute it once per count
            table = self._bounds(np.arange(int(counts.max()) + 1)[:, None])
            return np.asarray(table[counts[:, 0]])
        if counts.dtype.kind in "iu" and len(counts) > 64:
            # many rows repeat (a beam scores every child of a level): once per distinct
            # row, each row's value computed as in the batch (tested bit for bit)
            keys, inverse = unique_rows(counts)
            if 2 * len(keys) < len(counts):
                return np.asarray(self._bounds(keys)[inverse])
        return self._bounds(counts)

    def tight(self, counts: np.ndarray) -> np.ndarray:
        r"""A bound at most :meth:`__call__`'s: also :math:`\max D_{diff} - D_{same}^{lb}`
        with :math:`\max D_{diff}` exact over the centres' boxes (:meth:`_corner_max`).
        Only the best-first queue uses it: the beam ranks by :meth:`__call__` (its choice of
        prefix sets is part of the decision)."""
        counts = np.asarray(counts, dtype=np.int64)
        keys, inverse = unique_rows(counts)
        values = np.empty(len(keys))
        todo = []
        for k, row in enumerate(keys):
            hit = self._tight.get(row.tobytes())
            if hit is None:
                todo.append(k)
            else:
                values[k] = hit
        if todo:
            rows = keys[todo]
            fresh = np.minimum(self._bounds(rows), self._corner_max(rows) - self._same(rows))
            values[todo] = fresh
            for row, v in zip(rows, fresh.tolist(), strict=True):
                self._tight[row.tobytes()] = v
        return values[inverse]

    def _same(self, counts: np.ndarray) -> np.ndarray:
        c = np.asarray(counts, dtype=np.float64)
        return np.asarray((c * (c - 1) / 2) @ self.same_gap)

    def _corner_max(self, counts: np.ndarray) -> np.ndarray:
        r"""The largest :math:`D_{diff}` of any centres in the boxes, each type's parts
        gathered at one corner of its box (inf for more than :data:`CORNER_TYPES` types).

        Exact: with the other parts fixed, a type's parts add :math:`\sum_{i \in t}
        \phi_t(p_i)`, :math:`\phi_t(q) = \sum_{j \notin t} |q - p_j|` the same function for
        all of them, so moving them all to a maximiser of :math:`\phi_t` (convex: a corner
        of the box) never lowers :math:`D_{diff}`; type after type, every type ends on a
        corner. The first type's corner is fixed (the tray's symmetries map corners of every
        box alike)."""
        out = np.full(len(counts), np.inf)
        present = counts > 0
        codes = present @ (1 << np.arange(counts.shape[1], dtype=np.int64))
        for code in np.unique(codes).tolist():
            rows = np.flatnonzero(codes == code)
            idx, pairs, dist = self._pattern(int(code))
            if len(idx) <= 1:
                out[rows] = 0.0
            elif len(idx) <= CORNER_TYPES:
                c = counts[rows][:, idx].astype(np.float64)
                weight = np.stack([c[:, x] * c[:, y] for x, y in pairs], axis=1)
                out[rows] = (weight @ dist).max(axis=1)
        return out

    def _pattern(self, code: int) -> tuple[np.ndarray, list[tuple[int, int]], np.ndarray]:
        """The types of a support pattern, their pairs and each pair's corner distance under
        every assignment of types to corners (pairs x assignments), memoised."""
        hit = self._patterns.get(code)
        if hit is None:
            idx = np.array([t for t in range(self.delta.shape[0]) if code >> t & 1], dtype=np.int64)
            k = len(idx)
            pairs = [(x, y) for x in range(k) for y in range(x + 1, k)]
            dist = np.zeros((len(pairs), 1))
            if 1 < k <= CORNER_TYPES:
                assign = np.array(list(itertools.product(range(4), repeat=k - 1)), dtype=np.int64)
                assign = np.concatenate([np.zeros((len(assign), 1), dtype=np.int64), assign], 1)
                dist = np.stack(
                    [self.corner_dist[idx[x], assign[:, x], idx[y], assign[:, y]] for x, y in pairs]
                )
            hit = self._patterns[code] = (idx, pairs, dist)
        return hit

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
class DecisionContext:
    """What one decision knows: H_rem, the parts at hand, the signed flag, the window tasks
    that bound the rest's robot sums (:class:`.levels.Window`: ``low``, ``high``), and whether
    every sum of robot times is exact (then equal in any summation order)."""

    human_remaining: float
    available: np.ndarray | None
    signed: bool
    low_ids: np.ndarray
    high_ids: np.ndarray
    exact_sums: bool

    def unavailable(self, counts: np.ndarray) -> np.ndarray | None:
        if self.available is None:
            return None
        return upper_level.unavailable_parts(counts, self.available)


class OptimisticScore:
    """Lower bounds of F over the rests of prefix rows (module docstring), for one instance;
    with ``prune`` False (a negative W4, W5 or W6) no bound holds and every row scores -inf."""

    def __init__(
        self, instance: Instance, robot: np.ndarray, types: Sequence[str], prune: bool
    ) -> None:
        self.instance = instance
        self.station = instance.params_of()  # one station's d and o_H (GreedyCEPolicy)
        self.r = robot
        self.prune = prune
        self.fitness_bound = FitnessBound(instance, types)

    def __call__(
        self,
        i: int,
        length: int,
        tasks: np.ndarray | Children,
        robot: np.ndarray,
        human: np.ndarray,
        counts: np.ndarray,
        ctx: DecisionContext,
        fitness: np.ndarray | None = None,
        parts: BoundParts | None = None,
    ) -> np.ndarray:
        r"""Lower bounds of F over the rests of prefixes of size ``i``: term (6) at its least
        over :math:`R(Q) \in [lo, hi]` (:meth:`_rest_sum_bounds`), the fitness at its bound
        :func:`fitness_upper_bounds` where ``fitness`` is NaN or None. ``parts``:
        :meth:`parts` of the same rows, if already computed."""
        if not self.prune:
            return np.full(len(robot), -math.inf)
        lo, hi, bound = parts or self.parts(i, length, tasks, counts, ctx)
        d, o_r = self.station.delivery_time, self.instance.kit_overhead_robot
        o_h = self.station.kit_overhead_human
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
            self.instance.weights,
            n_tasks=float(i),
            diff5=diff5,
            diff6=diff6,
            fitness=bound,
            unavailable=ctx.unavailable(counts),
        )

    def parts(
        self,
        i: int,
        length: int,
        tasks: np.ndarray | Children,
        counts: np.ndarray,
        ctx: DecisionContext,
        tight: bool = False,
    ) -> BoundParts:
        """What the score needs besides H_rem, the parts at hand and known fitnesses: the
        bounds (lo, hi) of the rest's robot sum (None if ``i == length``) and the fitness
        bound of each row (``tight``: :meth:`FitnessBound.tight`, for the best-first queue)."""
        lo = hi = None
        if i < length:
            lo, hi = self._rest_sum_bounds(tasks, length - i, ctx)
        fb = self.fitness_bound
        return lo, hi, fb.tight(counts) if tight else fb(counts)

    def _rest_sum_bounds(
        self, tasks: np.ndarray | Children, m: int, ctx: DecisionContext
    ) -> tuple[np.ndarray, np.ndarray]:
        """Bounds (lo, hi) of the rest's robot sum R(Q) (tasks only) of each prefix (rows of
        ``tasks``) for rests of ``m`` tasks: the ``m`` smallest and largest robot times of the
        window tasks outside the prefix. Every task of a rest is such a task, so these bound
        every rest's sum."""
        rows = tasks if isinstance(tasks, Children) else Children(tasks)
        n = len(rows)
        if m == 0:
            return np.zeros(n), np.zeros(n)
        out = []
        for ids in (ctx.low_ids, ctx.high_ids):
            pos = np.full(len(self.r), -1, dtype=np.int64)
            pos[ids] = np.arange(len(ids))
            if not ctx.exact_sums:
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
