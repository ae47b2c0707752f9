"""greedy-ce's depth-first search of a window rest, written once: compiled (numba), or run
as plain Python when numba is disabled or missing.

:meth:`bilevel_kit.heuristics.prefix.rests.RestSearch.depth_first` looks for the rest of ``m``
tasks after a prefix in lexicographic order of canonical sequences (the tie rule of
docs/scaling.md#greedy-ce-without-a-time-limit, and the best rest when the robot times take
many values). On sparse wide graphs (hundreds of available tasks) it visits its whole node
cap at almost every decision, and each node's work grows with the window: 40 % of greedy-ce's
time on 1,000 sparse tasks (docs/scaling.md#sparse-wide-graphs), hence compiled.
:func:`depth_first` visits the nodes in that order (so the cap counts the same nodes), with
the children of :func:`_unlocked` (the rule of :meth:`..prefix.levels.Precedence.unlocked_after`),
a pruning bound (:func:`_lower`) and F of Eqs. 4-7 with term (6) a function of the rest's
robot sum (:func:`_score`).

numba is imported on first use; without it (or with ``BILEVEL_KIT_NO_NUMBA=1``,
:mod:`bilevel_kit.heuristics._kernels`) :func:`kernel` returns None and :func:`search` the
same source as Python (tests/heuristics/test_sparse_kernels.py compares both).
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from . import _kernels

#: The layout of the ``terms`` array of :func:`depth_first` (F of one prefix, by rest sum):
#: -W2 i, W3 |diff5|, W4, W5 f, whether W7 counts, W7 u, d, o_R, o_H + H(P), signed.
TERMS = ("c0", "a3", "w4", "w5f", "has_u", "w7u", "d", "o_r", "human", "signed")


def _score(terms: np.ndarray, diff6: float) -> float:
    """F given term (6)'s difference, in the order of :func:`.upper_level.objective` (the
    one F of a pair: greedy-ce's Python rest loop calls it too)."""
    f = terms[0]
    f = f + terms[1] + terms[2] * diff6 - terms[3]
    if terms[4] != 0.0:
        f = f + terms[5]
    return f


def _leaf_score(terms: np.ndarray, rest: float) -> float:
    """F of a rest of robot sum ``rest`` (the caller's ``score``)."""
    diff6 = terms[6] + (terms[7] + rest) - terms[8]
    if terms[9] == 0.0:
        diff6 = abs(diff6)
    return _score(terms, diff6)


def _lower(terms: np.ndarray, lo: float, hi: float) -> float:
    """A lower bound of F given bounds of the rest's sum (the caller's ``bound``; Python's
    ``max(a, b, c)`` keeps the first of equal maxima)."""
    diff6 = terms[6] + (terms[7] + lo) - terms[8]
    if terms[9] == 0.0:
        other = -(terms[6] + (terms[7] + hi) - terms[8])
        if other > diff6:
            diff6 = other
        if diff6 < 0.0:
            diff6 = 0.0
    return _score(terms, diff6)


def _unlocked(
    unl: np.ndarray,
    src: int,
    n_src: int,
    y: int,
    rel: np.ndarray,
    succ_ptr: np.ndarray,
    succ_idx: np.ndarray,
    pred_ptr: np.ndarray,
    pred_idx: np.ndarray,
    inseq: np.ndarray,
) -> int:
    """Row ``src + 1`` of ``unl``: the children of the sequence grown by ``y`` that ``done``
    and the prefix alone do not make available, from row ``src`` (``n_src`` of them): the
    kept ones above ``y``, and the successors of ``y`` whose undone predecessors outside the
    prefix (``rel``) are all in the sequence (``inseq``), increasing. Returns their count."""
    out = src + 1
    count = 0
    for q in range(n_src):
        if unl[src, q] > y:
            unl[out, count] = unl[src, q]
            count += 1
    for q in range(succ_ptr[y], succ_ptr[y + 1]):
        z = succ_idx[q]
        need = rel[z]
        ok = need == 1
        if need > 1:
            hit = 0
            for p in range(pred_ptr[z], pred_ptr[z + 1]):
                if inseq[pred_idx[p]]:
                    hit += 1
            ok = hit == need
        if ok:  # insert in order (the lists are short)
            pos = count
            while pos > 0 and unl[out, pos - 1] > z:
                unl[out, pos] = unl[out, pos - 1]
                pos -= 1
            unl[out, pos] = z
            count += 1
    return count


def _children(
    kid: np.ndarray,
    k: int,
    ordered: np.ndarray,
    top: int,
    unl: np.ndarray,
    n_unl: int,
) -> int:
    """Row ``k`` of ``kid``: the available tasks above ``top`` merged with the unlocked
    children (both increasing, disjoint); returns their count."""
    lo, hi = 0, len(ordered)
    while lo < hi:  # bisect_right(ordered, top)
        mid = (lo + hi) // 2
        if ordered[mid] <= top:
            lo = mid + 1
        else:
            hi = mid
    a, b, c = lo, 0, 0
    while a < len(ordered) or b < n_unl:
        if b == n_unl or (a < len(ordered) and ordered[a] < unl[k, b]):
            kid[k, c] = ordered[a]
            a += 1
        else:
            kid[k, c] = unl[k, b]
            b += 1
        c += 1
    return c


def depth_first(
    ordered: np.ndarray,
    rel: np.ndarray,
    graph: tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray],
    r: np.ndarray,
    m: int,
    cap: int,
    prune: bool,
    r_range: tuple[float, float],
    terms: np.ndarray,
    use_threshold: bool,
    threshold: float,
    cutoff: float,
) -> tuple[float, np.ndarray, bool]:
    """The search of ``RestSearch.depth_first`` (module docstring): ``ordered`` the available
    tasks after the prefix (increasing), ``rel`` their undone predecessors outside it (< 0:
    done or in it), ``graph`` (successor pointers and tasks, predecessor pointers and tasks),
    ``terms`` F as :data:`TERMS`. Returns (F, the rest (empty if none), capped)."""
    succ_ptr, succ_idx, pred_ptr, pred_idx = graph
    rmin, rmax = r_range
    n = len(r)
    width = len(ordered) + n
    kid = np.empty((m, width), dtype=np.int64)
    n_kid = np.zeros(m, dtype=np.int64)
    pos = np.zeros(m, dtype=np.int64)
    unl = np.empty((m + 1, n), dtype=np.int64)
    n_unl = np.zeros(m + 1, dtype=np.int64)
    total = np.zeros(m + 1)
    top = np.full(m + 1, -1, dtype=np.int64)
    seq = np.empty(m, dtype=np.int64)
    inseq = np.zeros(n, dtype=np.bool_)
    best_f = np.inf
    best_q = np.empty(0, dtype=np.int64)
    nodes = 0
    k = 0  # the depth of the node being entered
    while True:
        # enter the node of depth k (the sequence seq[:k]): 0 no children, 1 stop, 2 expand
        nodes += 1
        action = 2
        if nodes > cap:
            return best_f, best_q, True
        if prune and k > 0:
            lower = _lower(terms, total[k] + (m - k) * rmin, total[k] + (m - k) * rmax)
            if ((lower > threshold) if use_threshold else (lower >= best_f)) or lower > cutoff:
                action = 0
        if action == 2:
            n_kid[k] = _children(kid, k, ordered, top[k], unl, n_unl[k])
            if n_kid[k] == 0:
                action = 0
            elif k == m - 1:  # the leaves at once
                action = 0
                a = -1
                a_val = np.inf
                for q in range(n_kid[k]):
                    v = _leaf_score(terms, total[k] + r[kid[k, q]])
                    if use_threshold:
                        if v <= threshold:
                            a, a_val = q, v
                            break
                    elif a < 0 or v < a_val:
                        a, a_val = q, v
                if a >= 0 and (use_threshold or (a_val < best_f and a_val <= cutoff)):
                    best_f = a_val
                    best_q = np.empty(m, dtype=np.int64)
                    best_q[:k] = seq[:k]
                    best_q[k] = kid[k, a]
                    if use_threshold:
                        return best_f, best_q, False
            else:
                pos[k] = 0
        if action == 0:
            # back up: to the next child of the deepest node with one left
            if k == 0:
                return best_f, best_q, False
            k -= 1
            inseq[seq[k]] = False
            while pos[k] == n_kid[k]:
                if k == 0:
                    return best_f, best_q, False
                k -= 1
                inseq[seq[k]] = False
        # descend into the next child of depth k
        y = kid[k, pos[k]]
        pos[k] += 1
        seq[k] = y
        inseq[y] = True
        n_unl[k + 1] = _unlocked(
            unl, k, n_unl[k], y, rel, succ_ptr, succ_idx, pred_ptr, pred_idx, inseq
        )
        total[k + 1] = total[k] + r[y]
        top[k + 1] = max(top[k], y)
        k += 1


#: The compiled :func:`depth_first` once built.
_JITTED: Callable[..., tuple[float, np.ndarray, bool]] | None = None

#: The helpers :func:`kernel` compiles before :func:`depth_first` (it calls them).
_HELPERS = ("_score", "_leaf_score", "_lower", "_unlocked", "_children")


def kernel() -> Callable[..., tuple[float, np.ndarray, bool]] | None:
    """The compiled :func:`depth_first`, or None when numba is disabled or missing."""
    return _kernels.compiled_once(globals(), _HELPERS, "depth_first")


def search() -> Callable[..., tuple[float, np.ndarray, bool]]:
    """The compiled :func:`depth_first`, or its source run as Python when numba is disabled
    or missing (the same nodes, floats and result, slower)."""
    return kernel() or depth_first
