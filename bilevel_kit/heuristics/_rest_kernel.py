"""The core enumeration of greedy-ce's window rests, compiled (numba).

:class:`bilevel_kit.heuristics.prefix.rests.RestDecomposition` finds the best rest of a prefix
by enumerating *cores* (unions of the need sets of deep tasks, at most ``m`` tasks) in the
order of a depth-first search, and scoring each with the best free multiset of robot times from
a sorted table. :func:`best_cores` is that loop, operation by operation: the same candidates in
the same order (:func:`_candidates`), the same search (a stack, the distinct cores in the order
they are popped, at most ``max_cores`` of them: :func:`_enumerate`), the same table look-up
(binary search, then a scan up and down past multisets that use more tasks of a value than are
left: :func:`_score`) and the same floating-point sums, which are exact here (the caller uses
it only when every sum of robot times is exact, so a core's sum does not depend on the order of
its tasks). It returns each core's rest sum R(Q); :func:`best_rest` scores them all with F
(:func:`._dfs_kernel._leaf_score`) and takes the first of least F, the result of the loop that
keeps the first strict improvement.

The search does not depend on the scores, so the cores are enumerated first and scored in a
second pass: the same work as one loop, with no call per core (a core's work is small, and a
compiled helper called per core with its arrays made the kernel 5-20 % slower).

numba is imported on first use; without it (or with ``BILEVEL_KIT_NO_NUMBA=1``,
:mod:`bilevel_kit.heuristics._kernels`) :func:`kernel` returns None and the caller runs its own
Python loop, the one it also runs when sums of robot times are inexact.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from . import _dfs_kernel, _kernels


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


def _candidates(
    prefix: np.ndarray,
    m: int,
    deep: np.ndarray,
    deep_size: np.ndarray,
    anc_ptr: np.ndarray,
    anc_idx: np.ndarray,
    desc_ptr: np.ndarray,
    desc_idx: np.ndarray,
    mark: np.ndarray,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The need sets after ``prefix`` (a deep task with its undone ancestors outside the
    prefix) of at most ``m`` tasks, for the deep tasks (increasing) with a need set of at most
    ``m`` tasks or below the prefix: (task of each local id, the need sets as CSR (pointers,
    local ids, increasing within a set)). Local ids number the tasks in order of first sight;
    ``mark`` (zeros, one per task) is restored."""
    for x in prefix:  # the prefix: marked 1
        mark[x] = 1
    below = np.zeros(len(deep), dtype=np.bool_)
    for x in prefix:
        for q in range(desc_ptr[x], desc_ptr[x + 1]):
            below[desc_idx[q]] = True
    glob_list: list[int] = []
    cand_ptr_list = [0]
    cand_list: list[int] = []
    for p in range(len(deep)):
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
    cand_ptr = np.array(cand_ptr_list, dtype=np.int64)
    cands = np.array(cand_list, dtype=np.int64)
    for a in range(len(cand_ptr) - 1):  # each need set in increasing local ids (for the merge)
        cands[cand_ptr[a] : cand_ptr[a + 1]] = np.sort(cands[cand_ptr[a] : cand_ptr[a + 1]])
    return glob, cand_ptr, cands


def _grown(
    st_start: np.ndarray, st_len: np.ndarray, st_items: np.ndarray, sp: int
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The search stack (start, size and tasks of each entry), full at ``sp`` entries, with
    twice the room."""
    cap = 2 * sp
    st_start = np.concatenate((st_start, np.empty(cap - sp, dtype=np.int64)))
    st_len = np.concatenate((st_len, np.empty(cap - sp, dtype=np.int64)))
    grown = np.empty((cap, st_items.shape[1]), dtype=np.int64)
    grown[:sp] = st_items[:sp]
    return st_start, st_len, grown


def _enumerate(
    m: int, max_cores: int, glob: np.ndarray, cand_ptr: np.ndarray, cands: np.ndarray
) -> tuple[int, bool, np.ndarray]:
    """The cores: the distinct unions of need sets (:func:`_candidates`) of at most ``m``
    tasks, from the empty one, in the order a depth-first search pops them (a stack of
    (start, core as increasing local ids)), at most ``max_cores`` of them. Returns (cores,
    capped, the tasks of each core (rows padded with -1))."""
    base_key = len(glob) + 1
    st_start = np.zeros(64, dtype=np.int64)
    st_len = np.zeros(64, dtype=np.int64)
    st_items = np.empty((64, max(m, 1)), dtype=np.int64)
    sp = 1
    seen = {np.int64(-1)}
    members = np.full((max_cores, max(m, 1)), -1, dtype=np.int64)
    in_core = np.zeros(len(glob), dtype=np.bool_)
    count = 0
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
            return count, True, members[:count]
        for q in range(n_core):
            members[count, q] = glob[core[q]]
        count += 1
        room = m - n_core
        if room <= 0:  # every need set holds a task, so nothing grows the core
            continue
        for q in range(n_core):
            in_core[core[q]] = True
        for a in range(start, len(cand_ptr) - 1):
            a0, a1 = cand_ptr[a], cand_ptr[a + 1]
            new = 0
            for q in range(a0, a1):
                if not in_core[cands[q]]:
                    new += 1
            if a1 - a0 > room and new == a1 - a0:  # too big and disjoint from the core
                continue
            if new == 0 or n_core + new > m:  # nothing new, or too big
                continue
            if sp == len(st_start):
                st_start, st_len, st_items = _grown(st_start, st_len, st_items, sp)
            x, z, w = 0, a0, 0  # the union, in increasing local ids (both parts are)
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
    return count, False, members[:count]


def _score(
    prefix: np.ndarray,
    m: int,
    target: float,
    value: np.ndarray,
    r: np.ndarray,
    mult: np.ndarray,
    tables: tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray],
    members: np.ndarray,
) -> tuple[np.ndarray, np.ndarray]:
    """The rest sum R(Q) of each core (rows of ``members``): R(core) plus the free multiset
    of ``m - |core|`` values closest to the target (NaN if none), and that multiset's row in
    the tables (-1: none or empty). The free values exclude the prefix's and the core's."""
    tab_ptr, tab_combos, tab_ranks, tab_sums = tables
    base = np.zeros(len(mult), dtype=np.int64)  # the prefix's available tasks by value
    for x in prefix:
        if value[x] >= 0:
            base[value[x]] += 1
    left = np.empty(len(mult), dtype=np.int64)
    rest_sum = np.empty(len(members), dtype=np.float64)
    rows = np.full(len(members), -1, dtype=np.int64)
    for c in range(len(members)):
        r_core = 0.0
        for q in range(len(mult)):
            left[q] = mult[q] - base[q]
        n_core = 0
        while n_core < members.shape[1] and members[c, n_core] >= 0:
            t = members[c, n_core]
            r_core += r[t]
            if value[t] >= 0:
                left[value[t]] -= 1
            n_core += 1
        k = m - n_core
        if k == 0:
            rest_sum[c] = r_core + 0.0
            continue
        # binary search, then up and down past multisets that use more tasks than are left
        lo, hi, goal = tab_ptr[k], tab_ptr[k + 1], target - r_core
        j = lo if goal == -np.inf else _lower_bound(tab_sums, lo, hi, goal)
        up = j
        while up < hi and not _fits(tab_combos, tab_ranks, up, k, left):
            up += 1
        down = j - 1
        if goal != -np.inf:
            while down >= lo and not _fits(tab_combos, tab_ranks, down, k, left):
                down -= 1
        row = up if up < hi else -1
        if down >= lo and (row < 0 or goal - tab_sums[down] < tab_sums[row] - goal):
            row = down
        rows[c] = row
        rest_sum[c] = r_core + tab_sums[row] if row >= 0 else np.nan
    return rest_sum, rows


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
    glob, cand_ptr, cands = _candidates(
        prefix, m, deep, deep_size, anc_ptr, anc_idx, desc_ptr, desc_idx, mark
    )
    count, capped, members = _enumerate(m, max_cores, glob, cand_ptr, cands)
    rest_sum, rows = _score(prefix, m, target, value, r, mult, tables, members)
    return count, capped, rest_sum, rows, members


def best_rest(
    prefix: np.ndarray,
    m: int,
    max_cores: int,
    target: float,
    epoch: tuple[np.ndarray, ...],
    tables: tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray],
    terms: np.ndarray,
    cutoff: float,
) -> tuple[float, int, bool, np.ndarray, np.ndarray]:
    """:func:`best_cores` with each core's F (``terms``: F by rest sum,
    :data:`._dfs_kernel.TERMS`, the floats of the caller's ``score``) and the first core of
    least F at most ``cutoff``: (its F, its index (-1: none), capped, rows, members)."""
    count, capped, rest_sum, rows, members = best_cores(prefix, m, max_cores, target, epoch, tables)
    best, best_f = -1, np.inf
    for c in range(count):
        if rest_sum[c] != rest_sum[c]:  # NaN: no free multiset
            continue
        v = _dfs_kernel._leaf_score(terms, rest_sum[c])
        if v <= cutoff and (best < 0 or v < best_f):
            best, best_f = c, v
    return best_f, best, capped, rows, members


#: The compiled :func:`best_cores` once built.
_JITTED: Callable[..., tuple[int, bool, np.ndarray, np.ndarray, np.ndarray]] | None = None

#: The helpers :func:`kernel` compiles before :func:`best_cores` (they call each other).
_HELPERS = ("_lower_bound", "_fits", "_candidates", "_grown", "_enumerate", "_score")


def kernel() -> Callable[..., tuple[int, bool, np.ndarray, np.ndarray, np.ndarray]] | None:
    """The compiled :func:`best_cores`, or None when numba is disabled or missing. The
    module's helpers are replaced by their compiled versions first, so that the compiled
    kernel calls compiled code."""
    return _kernels.compiled_once(globals(), _HELPERS, "best_cores")


#: The compiled :func:`best_rest` once built.
_JITTED_REST: Callable[..., tuple[float, int, bool, np.ndarray, np.ndarray]] | None = None


def rest_kernel() -> Callable[..., tuple[float, int, bool, np.ndarray, np.ndarray]] | None:
    """The compiled :func:`best_rest` (after :func:`kernel` and the compiled F of
    :mod:`._dfs_kernel`), or None when numba is disabled or missing."""
    global _JITTED_REST
    if _JITTED_REST is None:
        compiled = kernel()
        jit = _kernels.njit()
        if compiled is None or jit is None or _dfs_kernel.kernel() is None:
            return None
        globals()["best_cores"] = compiled  # the compiled best_rest calls compiled code
        _JITTED_REST = jit(best_rest)
    return _JITTED_REST
