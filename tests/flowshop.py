"""Two-machine flow-shop references from the literature, independent of every model here.

The robot is machine 1 (time ``a_i``), the human machine 2 (time ``b_i``); one task per kit,
``d = 0`` and no kit overheads.

* Unlimited trays: F2||Cmax, solved by Johnson's rule (Johnson 1954): jobs with ``a_i <= b_i``
  first in increasing ``a_i``, then the others in decreasing ``b_i``.
* One tray: the robot may start job k+1 only once the human has started job k (the tray comes
  back when its parts are taken), which is the two-machine flow shop with blocking,
  F2|block|Cmax. Its makespan for a sequence ``p`` is

      C(p) = a_{p1} + sum_{k<n} max(b_{pk}, a_{p(k+1)}) + b_{pn}
           = sum_i b_i + sum over the tour 0 -> p1 -> ... -> pn -> 0 of max(0, a_next - b_prev)

  with a dummy job 0 (``a_0 = b_0 = 0``): a travelling-salesman problem whose distance
  ``max(0, a_k - b_j)`` is of the Gilmore-Gomory type (f = 1 above, g = 0 below), solved
  exactly by the Gilmore-Gomory algorithm (Gilmore & Gomory 1964; Pinedo, *Scheduling*,
  Section 6.2): sort the entering values ``a`` and the leaving values ``b``, match them in
  order (the optimal assignment, possibly several subtours), join the subtours by a minimum
  spanning tree of adjacent interchanges whose cost is the length of
  ``[a_(j), a_(j+1)] cap [b_(j), b_(j+1)]``, then apply those interchanges (the jobs entering
  at ranks j and j+1 swap predecessors), the ones with ``b_(j) >= a_(j)`` in decreasing j
  first, then the others in increasing j.

The module's own tests check both against enumeration of every sequence.
"""

from __future__ import annotations

import itertools
from collections.abc import Sequence


def jobs_doc(
    name: str,
    a: Sequence[float],
    b: Sequence[float],
    *,
    part: tuple[str, float] = ("p", 10.0),
    tray: float = 100.0,
    prefix: str = "j",
    trays: int | None = None,
) -> dict:
    """An instance of these jobs: task ``prefix + i`` has robot time ``a_i``, human time
    ``b_i`` and one square part ``part`` (id, side) on a square tray of side ``tray``; d = 0,
    no overheads, no precedence, ``trays`` kit trays (unlimited when None)."""
    pid, side = part
    doc: dict = {
        "format": "bilevel-kit/1",
        "name": name,
        "tray": {"width": tray, "height": tray},
        "delivery_time": 0.0,
        "kit_overhead": {"robot": 0.0, "human": 0.0},
        "part_types": [{"id": pid, "width": side, "height": side, "pick_time": 1.0}],
        "tasks": [
            {
                "id": f"{prefix}{i}",
                "parts": [{"type": pid, "count": 1}],
                "robot_time": a[i],
                "human_time": {"mean": b[i]},
            }
            for i in range(len(a))
        ],
    }
    if trays is not None:
        doc["trays"] = trays
    return doc


def johnson_order(a: Sequence[float], b: Sequence[float]) -> list[int]:
    """Johnson's rule: an optimal F2||Cmax sequence (indices)."""
    first = sorted((i for i in range(len(a)) if a[i] <= b[i]), key=lambda i: (a[i], i))
    last = sorted((i for i in range(len(a)) if a[i] > b[i]), key=lambda i: (-b[i], i))
    return first + last


def flow_makespan(a: Sequence[float], b: Sequence[float], order: Sequence[int]) -> float:
    """F2||Cmax makespan of ``order`` (machine 2 waits for machine 1, no blocking)."""
    t1 = t2 = 0.0
    for i in order:
        t1 += a[i]
        t2 = max(t2, t1) + b[i]
    return t2


def blocking_makespan(a: Sequence[float], b: Sequence[float], order: Sequence[int]) -> float:
    """F2|block|Cmax makespan of ``order``: machine 1 starts job k+1 when job k leaves it,
    i.e. when machine 2 starts job k."""
    m1_free = 0.0  # when machine 1 may start the next job
    m2_free = 0.0
    for i in order:
        end1 = m1_free + a[i]
        start2 = max(end1, m2_free)
        m1_free = start2  # blocked until the job moves on to machine 2
        m2_free = start2 + b[i]
    return m2_free


def gilmore_gomory_order(a: Sequence[float], b: Sequence[float]) -> list[int]:
    """An optimal F2|block|Cmax sequence (indices) by the Gilmore-Gomory algorithm."""
    n = len(a)
    # cities 0..n, city 0 the dummy job; entering value A (machine 1), leaving value B
    A = [0.0, *map(float, a)]
    B = [0.0, *map(float, b)]
    cities = range(n + 1)
    by_a = sorted(cities, key=lambda c: (A[c], c))  # entering order
    by_b = sorted(cities, key=lambda c: (B[c], c))  # leaving order
    succ = {by_b[j]: by_a[j] for j in cities}  # the optimal assignment
    # subtours of the assignment
    comp = {}
    for start in cities:
        if start in comp:
            continue
        c = start
        while c not in comp:
            comp[c] = start
            c = succ[c]
    parent = {c: c for c in set(comp.values())}

    def find(x: int) -> int:
        while parent[x] != x:
            parent[x] = parent[parent[x]]
            x = parent[x]
        return x

    cost = [
        max(0.0, min(A[by_a[j + 1]], B[by_b[j + 1]]) - max(A[by_a[j]], B[by_b[j]]))
        for j in range(n)
    ]
    chosen = []
    for j in sorted(range(n), key=lambda j: (cost[j], j)):
        u, v = find(comp[by_a[j]]), find(comp[by_a[j + 1]])
        if u != v:
            parent[u] = v
            chosen.append(j)
    group1 = sorted((j for j in chosen if B[by_b[j]] >= A[by_a[j]]), reverse=True)
    group2 = sorted(j for j in chosen if B[by_b[j]] < A[by_a[j]])
    for j in group1 + group2:
        # interchange: the cities entering at ranks j and j+1 swap their predecessors
        pred = {nxt: c for c, nxt in succ.items()}
        u, v = pred[by_a[j]], pred[by_a[j + 1]]
        succ[u], succ[v] = succ[v], succ[u]
    order, c = [], succ[0]
    while c != 0:
        order.append(c - 1)
        c = succ[c]
    assert len(order) == n, "the interchanges must join every subtour"
    return order


def best_by_enumeration(a: Sequence[float], b: Sequence[float], makespan) -> float:
    """The least ``makespan(a, b, order)`` over every order (n <= 8)."""
    return min(makespan(a, b, p) for p in itertools.permutations(range(len(a))))
