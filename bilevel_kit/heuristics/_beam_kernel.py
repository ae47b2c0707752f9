"""greedy-ce's beam over prefix sets, scored compiled (numba).

Once a level of closed prefix sets would pass ``max_prefix_sets``,
:func:`bilevel_kit.heuristics.prefix.levels.build_levels` keeps the ``beam_width`` children of
least optimistic score (:class:`..prefix.bounds.OptimisticScore`). On sparse wide graphs
(hundreds of available tasks) the second level alone has ~300,000 children at every decision,
and building them, their sums and part counts and their scores with numpy took 35 % of
greedy-ce's time on 1,000 sparse tasks (docs/scaling.md). :func:`beam_scores` makes the same
children in the same order (``levels._children``: parent-major, increasing) and their
optimistic scores in one pass, operation by operation as numpy forms them (Eqs. 4-7): robot
and human sums, the rest-sum bounds when every sum of robot times is exact (the first ``m``
window tasks of least, or greatest, robot time outside the row), the fitness bound read from
a table of the bound of every (parent's count row, task's count row), computed by the same
numpy code. It keeps the rows ``frontier.smallest`` keeps (a heap of the best so far), and
the caller builds only them.

numba is imported on first use; without it (or with ``BILEVEL_KIT_NO_NUMBA=1``,
:mod:`bilevel_kit.heuristics._kernels`) :func:`kernel` returns None and the caller scores
with numpy.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from . import _kernels

#: The layout of ``consts`` of :func:`beam_scores`: -W2 i, W3, W4, W5, d, d + o_R, o_R, o_H,
#: H_rem, signed, the default rest-sum bounds (rows outside the window's extreme tasks).
CONSTS = ("c0", "w3", "w4", "w5", "d", "d_or", "o_r", "o_h", "h_rem", "signed", "lo0", "hi0")


def _rest_sum(ids: np.ndarray, m: int, r: np.ndarray, mask: int) -> float:
    """The robot sum of the first ``m`` of ``ids`` whose bit is not set in ``mask``."""
    total = 0.0
    taken = 0
    for q in range(len(ids)):
        if taken == m:
            break
        if not (mask >> q) & 1:
            total += r[ids[q]]
            taken += 1
    return total


def _bits(ids: np.ndarray, pos: np.ndarray, tasks: np.ndarray) -> int:
    """The bit mask of the positions in ``ids`` of ``tasks`` (``pos``: position or -1)."""
    mask = 0
    for t in tasks:
        if pos[t] >= 0:
            mask |= 1 << pos[t]
    return mask


def _above(opt: np.ndarray, rows: np.ndarray, a: int, b: int) -> bool:
    """Slot ``a`` after slot ``b`` in the order (score, row)."""
    return opt[a] > opt[b] or (opt[a] == opt[b] and rows[a] > rows[b])


def _sift_down(heap: np.ndarray, kept: int, opt: np.ndarray, rows: np.ndarray) -> None:
    """Restore the max-heap ``heap`` (slots) after its top changed."""
    q = 0
    while True:
        a, b, big = 2 * q + 1, 2 * q + 2, q
        if a < kept and _above(opt, rows, heap[a], heap[big]):
            big = a
        if b < kept and _above(opt, rows, heap[b], heap[big]):
            big = b
        if big == q:
            return
        heap[q], heap[big] = heap[big], heap[q]
        q = big


def _offer(
    heap: np.ndarray,
    kept: int,
    slots: tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray],
    score: float,
    row: int,
    p: int,
    c: int,
) -> int:
    """Keep the first entries in the order (score, row) seen so far, as many as the slots
    (``frontier.smallest``: the first of a stable sort; rows come in increasing order, so an
    entry tied with the largest kept one is not kept). ``slots``: (score, row, parent, child)
    of each kept entry; ``heap``: the slots as a max-heap. Returns how many are kept."""
    opt, rows, par, child = slots
    if kept < len(opt):
        opt[kept], rows[kept], par[kept], child[kept] = score, row, p, c
        heap[kept] = kept
        q = kept
        while q > 0:  # sift up
            up = (q - 1) // 2
            if not _above(opt, rows, heap[q], heap[up]):
                break
            heap[q], heap[up] = heap[up], heap[q]
            q = up
        return kept + 1
    top = heap[0]
    if score < opt[top]:
        opt[top], rows[top], par[top], child[top] = score, row, p, c
        _sift_down(heap, kept, opt, rows)
    return kept


def _starts(
    avail: np.ndarray, p_tasks: np.ndarray, p_unl: np.ndarray, n: int
) -> tuple[np.ndarray, int]:
    """Per parent the position in ``avail`` of its first child there (above its largest
    task), and the children of all parents (those plus the unlocked ones)."""
    starts = np.empty(len(p_tasks), dtype=np.int64)
    count = 0
    for p in range(len(p_tasks)):
        last = -1
        for t in p_tasks[p]:
            last = max(last, t)
        starts[p] = np.searchsorted(avail, last, side="right")
        count += len(avail) - starts[p]
        for t in p_unl[p]:
            if t < n:
                count += 1
    return starts, count


def beam_scores(
    avail: np.ndarray,
    p_tasks: np.ndarray,
    p_unl: np.ndarray,
    p_robot: np.ndarray,
    p_human: np.ndarray,
    robot: np.ndarray,
    human: np.ndarray,
    keys: tuple[np.ndarray, np.ndarray, np.ndarray],
    low: np.ndarray,
    high: np.ndarray,
    m: int,
    consts: np.ndarray,
    width: int,
) -> tuple[np.ndarray, np.ndarray, np.ndarray, bool]:
    """The ``width`` children of least optimistic score, ties to the first (the beam of
    ``build_levels``), as (parent row, task, score) in the level's order, and False if a
    score is NaN (then nothing: the caller's numpy order applies). The children are those of
    every parent row (``p_tasks``; ``p_unl``: its unlocked children padded with the number
    of tasks). ``keys``: the key of each parent's count row, of each task's, and the fitness
    bound of every (parent key, task key); ``low``/``high``: the window tasks of least/greatest
    robot time (``length`` of each); ``m``: the rest's size (0: no rest); ``consts``:
    :data:`CONSTS`."""
    p_key, c_key, table = keys
    n = len(robot)
    n_par = len(p_tasks)
    starts, count = _starts(avail, p_tasks, p_unl, n)
    keep = min(count, width)
    slots = (
        np.empty(keep),
        np.empty(keep, dtype=np.int64),
        np.empty(keep, dtype=np.int64),
        np.empty(keep, dtype=np.int64),
    )
    heap = np.empty(keep, dtype=np.int64)
    kept = 0
    pos_lo = np.full(n, -1, dtype=np.int64)
    pos_hi = np.full(n, -1, dtype=np.int64)
    for q in range(len(low)):
        pos_lo[low[q]] = q
        pos_hi[high[q]] = q
    c0, w3, w4, w5 = consts[0], consts[1], consts[2], consts[3]
    d, d_or, o_r, o_h, h_rem = consts[4], consts[5], consts[6], consts[7], consts[8]
    signed = consts[9] != 0.0
    lo0, hi0 = consts[10], consts[11]
    row = 0
    for p in range(n_par):
        lo_mask = _bits(low, pos_lo, p_tasks[p])
        hi_mask = _bits(high, pos_hi, p_tasks[p])
        a, b = starts[p], 0
        while a < len(avail) or (b < p_unl.shape[1] and p_unl[p, b] < n):
            if (
                b == p_unl.shape[1]
                or p_unl[p, b] >= n
                or (a < len(avail) and avail[a] < p_unl[p, b])
            ):
                c = avail[a]
                a += 1
            else:
                c = p_unl[p, b]
                b += 1
            diff5 = d_or + (p_robot[p] + robot[c]) - h_rem
            h_kit = o_h + (p_human[p] + human[c])
            if m == 0:
                diff6 = d + 0.0 - h_kit
                if not signed:
                    diff6 = abs(diff6)
            else:
                lm, hm = lo_mask, hi_mask
                if pos_lo[c] >= 0:
                    lm |= 1 << pos_lo[c]
                if pos_hi[c] >= 0:
                    hm |= 1 << pos_hi[c]
                lo = lo0 if lm == 0 else _rest_sum(low, m, robot, lm)
                hi = hi0 if hm == 0 else _rest_sum(high, m, robot, hm)
                diff6 = d + (o_r + lo) - h_kit
                if not signed:
                    other = -(d + (o_r + hi) - h_kit)
                    if other > diff6:
                        diff6 = other
                    if diff6 < 0.0:
                        diff6 = 0.0
            if not signed:
                diff5 = abs(diff5)
            fb = table[p_key[p], c_key[c]]
            score = c0 + w3 * diff5 + w4 * diff6 - w5 * fb
            if score != score:  # NaN: numpy's order, not this heap's
                return slots[2][:0], slots[3][:0], slots[0][:0], False
            kept = _offer(heap, kept, slots, score, row, p, c)
            row += 1
    order = np.argsort(slots[1])  # by row: the order of the level
    return slots[2][order], slots[3][order], slots[0][order], True


#: The compiled :func:`beam_scores` once built.
_JITTED: Callable[..., tuple[np.ndarray, np.ndarray, np.ndarray, bool]] | None = None

#: The helpers :func:`kernel` compiles before :func:`beam_scores` (it calls them).
_HELPERS = ("_rest_sum", "_bits", "_above", "_sift_down", "_offer", "_starts")


def kernel() -> Callable[..., tuple[np.ndarray, np.ndarray, np.ndarray, bool]] | None:
    """The compiled :func:`beam_scores`, or None when numba is disabled or missing."""
    return _kernels.compiled_once(globals(), _HELPERS, "beam_scores")
