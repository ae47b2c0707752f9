"""The core enumeration of greedy-ce's window rests, compiled (numba).

:class:`bilevel_kit.heuristics.prefix.rests.RestDecomposition` finds the best rest of a prefix
by enumerating *cores* (unions of the need sets of deep tasks, at most ``m`` tasks) in the
order of a depth-first search, and scoring each with the best free multiset of robot times from
a sorted table. :func:`best_cores` is that loop, operation by operation: the same candidates in
the same order, the same search (a stack, the distinct cores in the order they are popped, at
most ``max_cores`` of them), the same table look-up (binary search, then a scan up and down
past multisets that use more tasks of a value than are left) and the same floating-point sums,
which are exact here (the caller uses it only when every sum of robot times is exact, so a
core's sum does not depend on the order of its tasks). It returns each core's rest sum R(Q);
the caller scores them all with F at once and takes the first of least F, the result of the
loop that keeps the first strict improvement.

numba is imported on first use; without it (or with ``BILEVEL_KIT_NO_NUMBA=1``,
:mod:`bilevel_kit.heuristics._kernels`) :func:`kernel` returns None and the caller runs its own
Python loop.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from . import _kernels


def _lower_bound(sums: np.ndarray, lo: int, hi: int, x: float) -> int:
    """The first index in ``[lo, hi)`` with ``sums[index] >= x`` (``hi`` if none): numpy's
    ``searchsorted(x)`` (side left) on the slice, offset by ``lo``."""
    while lo < hi:
        mid = (lo + hi) // 2
        if sums[mid] < x:
            lo = mid + 1
        else:
            hi = mid
    return lo


def _fits(combos: np.ndarray, ranks: np.ndarray, row: int, k: int, left: np.ndarray) -> bool:
    """Whether multiset ``row`` takes, of each value, no more tasks than ``left``."""
    for q in range(k):  # noqa: SIM110 (a loop numba compiles)
        if ranks[row, q] >= left[combos[row, q]]:
            return False
    return True


def best_cores(
    prefix: np.ndarray,
    m: int,
    max_cores: int,
    target: float,
    epoch: tuple[np.ndarray, ...],
    tables: tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray],
) -> tuple[int, bool, np.ndarray, np.ndarray, np.ndarray]:
    """The cores after ``prefix`` (rests of ``m`` tasks) and the rest sum of each.

    ``epoch``: (deep tasks (sorted), their need-set sizes, their undone ancestors as CSR
    (pointers, tasks), the deep descendants of every task as CSR of positions in the deep
    tasks, the value index of every task (-1 if not available at the epoch), robot times,
    tasks of each value available, a scratch array of zeros (one per task), restored).
    ``tables``: the sum tables of 1..K free values as one array each (offsets by k, combos
    and ranks padded to K columns, sums). Returns (cores, capped, R(Q) of each core (NaN: no
    free multiset), the free multiset's row in the tables (-1: none or empty), the core's
    tasks (rows padded with -1))."""
    deep, deep_size, anc_ptr, anc_idx, desc_ptr, desc_idx, value, r, mult, mark = epoch
    tab_ptr, tab_combos, tab_ranks, tab_sums = tables
    n_vals = len(mult)
    # the prefix: marked 1 in ``mark``, and its available tasks by value
    base = np.zeros(n_vals, dtype=np.int64)
    for x in prefix:
        mark[x] = 1
        if value[x] >= 0:
            base[value[x]] += 1
    # candidates: deep tasks with a need set of at most m tasks, or below the prefix
    n_deep = len(deep)
    below = np.zeros(n_deep, dtype=np.bool_)
    for x in prefix:
        for q in range(desc_ptr[x], desc_ptr[x + 1]):
            below[desc_idx[q]] = True
    glob_list: list[int] = []
    cand_ptr_list = [0]
    cand_list: list[int] = []
    for p in range(n_deep):
        y = deep[p]
        if not (deep_size[p] <= m or below[p]) or mark[y] == 1:
            continue
        size = 1
        for q in range(anc_ptr[p], anc_ptr[p + 1]):
            if mark[anc_idx[q]] != 1:
                size += 1
        if size > m:
            continue
        for q in range(anc_ptr[p], anc_ptr[p + 1] + 1):
            t = y if q == anc_ptr[p + 1] else anc_idx[q]
            if mark[t] == 1:
                continue
            if mark[t] < 2:  # first sight: a local id (mark = 2 + id)
                mark[t] = 2 + len(glob_list)
                glob_list.append(t)
            cand_list.append(mark[t] - 2)
        cand_ptr_list.append(len(cand_list))
    glob = np.array(glob_list, dtype=np.int64)  # local id -> task
    for x in prefix:
        mark[x] = 0
    for t in glob:
        mark[t] = 0
    n_cand = len(cand_ptr_list) - 1
    cand_ptr = np.array(cand_ptr_list, dtype=np.int64)
    cands = np.array(cand_list, dtype=np.int64)
    for a in range(n_cand):  # each need set in increasing local ids (for the merge below)
        cands[cand_ptr[a] : cand_ptr[a + 1]] = np.sort(cands[cand_ptr[a] : cand_ptr[a + 1]])
    base_key = len(glob) + 1
    # the depth-first search: a stack of (start, core as increasing local ids)
    cap = 64
    st_start = np.empty(cap, dtype=np.int64)
    st_len = np.empty(cap, dtype=np.int64)
    st_items = np.empty((cap, max(m, 1)), dtype=np.int64)
    st_start[0], st_len[0] = 0, 0
    sp = 1
    seen = {np.int64(-1)}
    rest_sum = np.empty(max_cores, dtype=np.float64)
    rows = np.empty(max_cores, dtype=np.int64)
    members = np.full((max_cores, max(m, 1)), -1, dtype=np.int64)
    in_core = np.zeros(len(glob), dtype=np.bool_)
    left = np.empty(n_vals, dtype=np.int64)
    count = 0
    capped = False
    while sp > 0:
        sp -= 1
        start, n_core = st_start[sp], st_len[sp]
        core = st_items[sp, :n_core].copy()
        key = np.int64(0)
        for q in range(n_core):
            key = key * base_key + core[q] + 1
        if key in seen:
            continue
        seen.add(key)
        if count == max_cores:
            capped = True
            break
        # score the core: R(core) plus the free multiset closest to the target
        r_core = 0.0
        for q in range(n_vals):
            left[q] = mult[q] - base[q]
        for q in range(n_core):
            t = glob[core[q]]
            members[count, q] = t
            r_core += r[t]
            if value[t] >= 0:
                left[value[t]] -= 1
        k = m - n_core
        row = -1
        total = np.nan
        if k == 0:
            total = r_core + 0.0
        else:
            lo, hi = tab_ptr[k], tab_ptr[k + 1]
            goal = target - r_core
            j = lo if goal == -np.inf else _lower_bound(tab_sums, lo, hi, goal)
            up = j
            while up < hi and not _fits(tab_combos, tab_ranks, up, k, left):
                up += 1
            down = j - 1
            if goal != -np.inf:
                while down >= lo and not _fits(tab_combos, tab_ranks, down, k, left):
                    down -= 1
            if up < hi:
                row = up
            if down >= lo and (row < 0 or goal - tab_sums[down] < tab_sums[row] - goal):
                row = down
            if row >= 0:
                total = r_core + tab_sums[row]
        rest_sum[count] = total
        rows[count] = row
        count += 1
        room = m - n_core
        if room <= 0:  # every need set holds a task, so nothing grows the core
            continue
        for q in range(n_core):
            in_core[core[q]] = True
        for a in range(start, n_cand):
            a0, a1 = cand_ptr[a], cand_ptr[a + 1]
            new = 0
            for q in range(a0, a1):
                if not in_core[cands[q]]:
                    new += 1
            if a1 - a0 > room and new == a1 - a0:  # too big and disjoint from the core
                continue
            if new == 0 or n_core + new > m:  # nothing new, or too big
                continue
            if sp == cap:
                cap *= 2
                st_start = np.concatenate((st_start, np.empty(cap - sp, dtype=np.int64)))
                st_len = np.concatenate((st_len, np.empty(cap - sp, dtype=np.int64)))
                grown = np.empty((cap, st_items.shape[1]), dtype=np.int64)
                grown[:sp] = st_items[:sp]
                st_items = grown
            # the union, in increasing local ids (both parts are)
            x, z, w = 0, a0, 0
            while x < n_core or z < a1:
                if z < a1 and in_core[cands[z]]:
                    z += 1
                elif z == a1 or (x < n_core and core[x] < cands[z]):
                    st_items[sp, w] = core[x]
                    x += 1
                    w += 1
                else:
                    st_items[sp, w] = cands[z]
                    z += 1
                    w += 1
            st_start[sp], st_len[sp] = a + 1, w
            sp += 1
        for q in range(n_core):
            in_core[core[q]] = False
    return count, capped, rest_sum[:count], rows[:count], members[:count]


#: The compiled :func:`best_cores` once built.
_JITTED: Callable[..., tuple[int, bool, np.ndarray, np.ndarray, np.ndarray]] | None = None


def kernel() -> Callable[..., tuple[int, bool, np.ndarray, np.ndarray, np.ndarray]] | None:
    """The compiled :func:`best_cores`, or None when numba is disabled or missing."""
    global _JITTED, _lower_bound, _fits
    if _kernels.disabled():
        return None
    if _JITTED is None:
        jit = _kernels.njit()
        if jit is None:
            return None
        _lower_bound = jit(_lower_bound)
        _fits = jit(_fits)
        _JITTED = jit(best_cores)
    return _JITTED
