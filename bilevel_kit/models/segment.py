r"""The best cut of a fixed task order into kits, exactly, under one tray.

With **one tray** (docs/timeline.md, "Trays in circulation") the timeline of consecutive kits
telescopes. Write :math:`x_k = o_R + d + \sum_{i \in k} r_i` (the robot's block for kit k,
delivery included) and :math:`y_k = \sum_{i \in k} h_i` (the human's work on it, without the
overhead). The human starts kit 1 when it arrives, :math:`\mathrm{hs}_1 = x_1`; the robot
starts kit k + 1 when the tray is back, :math:`\mathrm{hs}_k + o_H` (the tray has arrived
before the human starts, so that is the later of the two), and the human starts kit k + 1 at
the later of its arrival and the end of kit k:

.. math:: \mathrm{hs}_{k+1} = \mathrm{hs}_k + o_H + \max(x_{k+1},\ y_k),
          \qquad C = \mathrm{hs}_m + o_H + y_m,

so a plan of m kits has the makespan

.. math:: C = x_1 + m\, o_H + \sum_{k=1}^{m-1} \max(x_{k+1},\ y_k) + y_m,

a sum of terms over consecutive kit pairs. For a fixed order of the tasks (topological, so
every contiguous segment is a kit whose tasks the human can do in that order), the best cut
into contiguous kits that fit the tray is a shortest path over "last kit = [a, b)" states
(docs/formulations.md, "Segmenting a fixed order"):

.. math:: f(0, b) = x_{[0,b)} + o_H, \qquad
          f(b, c) = \min_a\ f(a, b) + o_H + \max(x_{[b,c)},\ y_{[a,b)}), \qquad
          C^* = \min_a\ f(a, n) + y_{[a,n)}.

Fitting is monotone (a segment that does not fit stays unfit when it grows), so the longest
fitting segment from each start is found with O(n) packing calls (two pointers; past a
deadline the segments stop growing, so the cut stays valid but may be coarser), and the
recursion costs O(n L^2) for segments of at most L tasks, vectorised over one of the L's.
"Fits" is the caller's predicate: the exact models pass the packing oracle's "a layout is
known", so a segment the oracle cannot decide in time counts as unfit. The cut is then exact
among the segments known to fit: a valid plan and an upper bound (the models' first
incumbent), never a claim of optimality (docs/formulations.md#what-optimal-means).
With T != 1 trays the recursion is not the timeline: its cut is then only a candidate that the
caller scores with :func:`bilevel_kit.plan.evaluate` like any other.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Sequence

import numpy as np

from ..instance import Instance


def fit_extents(
    n: int, fits: Callable[[int, int], bool], until: float | None = None
) -> list[int] | None:
    """``ext[b]``: the largest c such that the segment [b, c) fits (``fits(b, c)``), for
    every start b; two pointers over a monotone predicate ([b, c) fits when [b - 1, c) does,
    so it is not asked again). Past ``until`` (a ``time.perf_counter`` deadline) no segment
    grows any more: every listed segment still fits, but may be shorter than the longest.
    None if a single task does not fit."""
    ext: list[int] = []
    c = 0
    for b in range(n):
        if c <= b:
            c = b + 1
            if not fits(b, c):
                return None
        while c < n and (until is None or time.perf_counter() <= until) and fits(b, c + 1):
            c += 1
        ext.append(c)
    return ext


def one_tray_cut(
    instance: Instance,
    order: Sequence[str],
    ext: Sequence[int],
) -> tuple[float, list[list[str]]]:
    """The one-tray makespan and the kits of the best cut of ``order`` (module docstring),
    where the segment [b, c) may be a kit iff ``c <= ext[b]``. Ties go to the first minimiser
    in (a, c) order, so the cut is deterministic."""
    n = len(order)
    one = instance.params_of()  # one station (the exact cut: one tray)
    o_r, o_h, d = instance.kit_overhead_robot, one.kit_overhead_human, one.delivery_time
    pr = np.concatenate(([0.0], np.cumsum([instance.robot_time(t) for t in order])))
    ph = np.concatenate(([0.0], np.cumsum([instance.human_time(t) for t in order])))
    span = max(c - b for b, c in enumerate(ext))
    # f[c, c - b]: the best value with last kit [b, c); back[c, c - b] its previous kit's start.
    f = np.full((n + 1, span + 1), np.inf)
    back = np.full((n + 1, span + 1), -1, dtype=np.int64)
    for c in range(1, ext[0] + 1):
        f[c, c] = o_r + d + pr[c] + o_h
    lens = np.arange(1, span + 1)
    for b in range(1, n):
        starts = b - lens  # previous kit [a, b) with a = b - length
        ok = (starts >= 0) & np.isfinite(f[b, 1:])
        if not ok.any():
            continue
        a = starts[ok]
        fa = f[b, 1:][ok]
        y_prev = ph[b] - ph[a]
        cs = np.arange(b + 1, ext[b] + 1)
        x_next = o_r + d + pr[cs] - pr[b]
        vals = fa[:, None] + o_h + np.maximum(x_next[None, :], y_prev[:, None])
        # first minimiser in increasing a: reverse the rows (lengths run from short to long)
        rows = vals[::-1]
        arg = rows.argmin(axis=0)
        # the state (last kit [b, c)) is reached from start b only: set once, here
        f[cs, cs - b] = rows[arg, np.arange(len(cs))]
        back[cs, cs - b] = a[::-1][arg]
    a = n - lens
    ok = (a >= 0) & np.isfinite(f[n, 1:])
    totals = np.where(ok, f[n, 1:] + ph[n] - ph[np.maximum(a, 0)], np.inf)
    last = totals[::-1].argmin()
    value = float(totals[::-1][last])
    start = int(a[::-1][last])
    kits: list[list[str]] = []
    end = n
    while end > 0:
        kits.append(list(order[start:end]))
        start, end = int(back[end, end - start]), start
    kits.reverse()
    return value, kits
