r"""The LP relaxation with a fixed kit count m (docs/formulations.md, "Stronger lower bounds").

For a plan of exactly m kits, let :math:`Y_{ik} = [\text{kit of } i \le k]` (the order
encoding of the exact models) and relax it to :math:`0 \le Y_{ik} \le 1`, non-decreasing in k,
:math:`Y_{i,m-1} = 1`; the share of task i in kit k is :math:`f_{ik} = Y_{ik} - Y_{i,k-1}`.
The constraints hold for every plan of m kits whose kits fit the tray:

* the timeline of docs/timeline.md with T trays, linear in f (robot start :math:`S_k`, human
  end :math:`E_k`; the kit's times :math:`R_k = o_R + \sum_i r_i f_{ik}`,
  :math:`H_k = o_H + \sum_i h_i f_{ik}`)::

      S_0 = 0,  S_k >= A_{k-1} (= for k < T),  S_k >= E_{k-T} - H_{k-T} + o_H  (k >= T)
      A_k = S_k + R_k + d,  E_k >= A_k + H_k,  E_k >= E_{k-1} + H_k,  C = E_{m-1}

* precedence :math:`Y_{bk} \le Y_{ak}` for every edge a -> b of the transitive reduction;
* the tray's area :math:`\sum_i a_i f_{ik} \le W H`;
* every kit holds a task, :math:`\sum_i f_{ik} \ge 1`; the first kit holds a task without
  predecessors, :math:`\sum_{src} f_{i0} \ge 1`; the last one a task without successors,
  :math:`\sum_{snk} f_{i,m-1} \ge 1`;
* task i is in one of the kits ``m - n + |anc(i)| .. n - 1 - |desc(i)|`` (every kit before
  it holds a task that is not a descendant, every kit after it one that is not an ancestor).

So its optimum :math:`L(m)` is at most the makespan of every such plan. The closed-form
bounds of :mod:`bilevel_kit.bounds` with m kits, :math:`B(m)`, do not decrease in m, so for any
:math:`M`, :math:`\min(\min_{m_{min} \le m < M} L(m), B(M))` is a lower bound on the makespan
of every plan: the *kit-count LP bound*. The integer plans have integral Y; the relaxation
keeps the batching (a kit's tasks all arrive together), precedence, the overheads, the
delivery time and the tray rule, which the closed forms lose: on the paper's table with one
tray it gives 430.4 s where they give 415.8 s (optimum 435.085 s).

Each LP is solved by HiGHS (``highspy``, one thread); an LP that does not finish in
time ends the scan (its m and the larger ones fall back to :math:`B`). The value is lowered by
HiGHS's tolerance before use (:data:`LP_TOL`).
"""

from __future__ import annotations

import math
import os
import sys
import time
from dataclasses import dataclass
from typing import Any

import numpy as np

from ...instance import Instance
from ..common import reduced_edges

#: Seconds per task x kit variable an LP may need: HiGHS does not stop at its time limit
#: inside presolve (an LP of 50,000 took 1.0-5.9 s with a 0.5 s limit on a loaded machine), so
#: an LP larger than the time left allows is not started.
LP_S_PER_CELL = 1e-4
#: Relative safety margin taken off an LP optimum (HiGHS's feasibility tolerances are 1e-7).
LP_TOL = 1e-6


@dataclass(frozen=True)
class _Data:
    """The instance in the arrays the LP reads (file order of the tasks)."""

    n: int
    r: np.ndarray
    h: np.ndarray
    area: np.ndarray
    n_anc: np.ndarray
    n_desc: np.ndarray
    src: np.ndarray
    snk: np.ndarray
    edges: np.ndarray  # (E, 2) task indices of the transitive reduction
    o_r: float
    o_h: float
    d: float
    trays: int | None
    tray_area: float

    @classmethod
    def of(cls, instance: Instance) -> _Data:
        ids = [t.id for t in instance.tasks]
        idx = instance.index
        n_anc = np.array([len(instance.ancestors[i]) for i in ids], dtype=np.int64)
        n_desc = np.zeros(len(ids), dtype=np.int64)
        for i in ids:
            for a in instance.ancestors[i]:
                n_desc[idx[a]] += 1
        edges = np.array([(idx[a], idx[b]) for a, b in reduced_edges(instance)], dtype=np.int64)
        has_pred = set(edges[:, 1].tolist()) if len(edges) else set()
        has_succ = set(edges[:, 0].tolist()) if len(edges) else set()
        one = instance.params_of()  # one station's bound (several: each station's own)
        return cls(
            n=len(ids),
            r=np.array([instance.robot_time(i) for i in ids], dtype=np.float64),
            h=np.array([instance.human_time(i) for i in ids], dtype=np.float64),
            area=np.array(
                [sum(instance.part_types[p].area * c for p, c in t.parts) for t in instance.tasks]
            ),
            n_anc=n_anc,
            n_desc=n_desc,
            src=np.array([i for i in range(len(ids)) if i not in has_pred], dtype=np.int64),
            snk=np.array([i for i in range(len(ids)) if i not in has_succ], dtype=np.int64),
            edges=edges.reshape(-1, 2),
            o_r=instance.kit_overhead_robot,
            o_h=one.kit_overhead_human,
            d=one.delivery_time,
            trays=one.tray_limit,
            tray_area=instance.tray.area,
        )


class _Rows:
    """Constraint rows ``lower <= a x <= upper`` built from index arrays (row-wise CSR)."""

    def __init__(self) -> None:
        self.r: list[np.ndarray] = []
        self.c: list[np.ndarray] = []
        self.v: list[np.ndarray] = []
        self.lower: list[float] = []
        self.upper: list[float] = []

    def add(self, cols: np.ndarray, vals: np.ndarray, upper: float, equal: bool = False) -> None:
        """One row ``a x <= upper`` (``= upper`` when ``equal``)."""
        self.add_many(np.zeros(len(cols), dtype=np.int64), cols, vals, [upper], equal)

    def add_many(
        self,
        rows: np.ndarray,
        cols: np.ndarray,
        vals: np.ndarray,
        upper: list[float],
        equal: bool = False,
    ) -> None:
        """Rows given as (local row, column, value) triples, local rows 0..len(upper)-1."""
        self.r.append(np.asarray(rows, dtype=np.int64) + len(self.upper))
        self.c.append(np.asarray(cols, dtype=np.int64))
        self.v.append(np.asarray(vals, dtype=np.float64))
        self.upper.extend(upper)
        self.lower.extend(upper if equal else [-math.inf] * len(upper))

    def csr(self, n_cols: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(start, index, value) of the rows in order, repeated entries of a row summed."""
        keys, inverse = np.unique(
            np.concatenate(self.r) * n_cols + np.concatenate(self.c), return_inverse=True
        )
        value = np.bincount(inverse.ravel(), weights=np.concatenate(self.v))
        rows = keys // n_cols
        start = np.searchsorted(rows, np.arange(len(self.upper) + 1))
        return start, keys % n_cols, value


#: Set once this process made its first HiGHS object (whose banner went to the null device).
_QUIET: list[bool] = []


def _highs() -> Any:
    """A new HiGHS instance without output, one per LP. Not one per process: HiGHS (before
    2.0) measures ``time_limit`` against the run time an instance accumulated over all its
    runs, so a reused instance reports every LP as timed out once the process has spent the
    limit in earlier LPs, earlier experiment cells included (docs/simulation.md#determinism).
    HiGHS prints a banner on the process's standard output (the file descriptor, past Python)
    when the first one is made: it goes to the null device."""
    import highspy

    if _QUIET:
        h = highspy.Highs()
    else:
        sys.stdout.flush()
        saved = os.dup(1)
        try:
            with open(os.devnull, "w") as null:
                os.dup2(null.fileno(), 1)
                h = highspy.Highs()
        finally:
            os.dup2(saved, 1)
            os.close(saved)
        _QUIET.append(True)
    h.setOptionValue("output_flag", False)
    h.setOptionValue("threads", 1)
    return h


def _solve(
    cost: np.ndarray, lo: np.ndarray, hi: np.ndarray, rows: _Rows, time_limit: float
) -> float | None:
    """min cost x over the rows and column bounds: its value, inf when infeasible, None when
    not solved to optimality in ``time_limit`` s."""
    import highspy

    h = _highs()
    lp = highspy.HighsLp()
    lp.num_col_ = len(cost)
    lp.num_row_ = len(rows.upper)
    lp.col_cost_ = cost
    lp.col_lower_ = lo
    lp.col_upper_ = hi
    lp.row_lower_ = np.array(rows.lower)
    lp.row_upper_ = np.array(rows.upper)
    start, index, value = rows.csr(len(cost))
    lp.a_matrix_.format_ = highspy.MatrixFormat.kRowwise
    lp.a_matrix_.start_ = start
    lp.a_matrix_.index_ = index
    lp.a_matrix_.value_ = value
    h.passModel(lp)
    h.setOptionValue("time_limit", max(0.01, time_limit))
    h.run()
    status = h.getModelStatus()
    if status == highspy.HighsModelStatus.kInfeasible:
        return math.inf
    if status != highspy.HighsModelStatus.kOptimal:
        return None
    return float(h.getInfo().objective_function_value)


def kit_lp(data: _Data, m: int, time_limit: float) -> float | None:
    """:math:`L(m)` (module docstring), or None when HiGHS does not solve it in
    ``time_limit`` s; inf when no plan of m kits exists (the LP is infeasible)."""
    n = data.n
    ny = n * m  # Y[i, k] at i * m + k
    i_s, i_e = ny, ny + m  # S_k, E_k
    n_var = ny + 2 * m
    lo = np.zeros(n_var)
    hi = np.full(n_var, math.inf)
    hi[:ny] = 1.0
    first = np.maximum(0, m - n + data.n_anc)  # first kit task i may be in
    last = np.minimum(m - 1, n - 1 - data.n_desc)  # last kit
    if np.any(first > last):
        return math.inf
    kk = np.tile(np.arange(m), n)
    ii = np.repeat(np.arange(n), m)
    hi[:ny][kk < first[ii]] = 0.0
    lo[:ny][kk >= last[ii]] = 1.0
    hi[i_s] = 0.0  # S_0 = 0
    rows = _Rows()
    _share_rows(data, m, rows)
    _timeline_rows(data, m, rows)
    if len(data.edges) and m > 1:  # Y_bk <= Y_ak for every edge a -> b
        a, b = data.edges[:, 0], data.edges[:, 1]
        ks = np.arange(m - 1)
        local = np.arange(len(a) * (m - 1))
        rows.add_many(
            np.concatenate([local, local]),
            np.concatenate([(b[:, None] * m + ks).ravel(), (a[:, None] * m + ks).ravel()]),
            np.concatenate([np.ones(len(local)), -np.ones(len(local))]),
            [0.0] * len(local),
        )
    cost = np.zeros(n_var)
    cost[i_e + m - 1] = 1.0
    return _solve(cost, lo, hi, rows, time_limit)


def _share_terms(m: int, n: int, k: int, weights: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Columns and coefficients of :math:`\\sum_i w_i f_{ik}` with f = Y_k - Y_{k-1}."""
    cols = np.arange(n) * m + k
    if k == 0:
        return cols, weights
    return np.concatenate([cols, cols - 1]), np.concatenate([weights, -weights])


def _share_rows(data: _Data, m: int, ub: _Rows) -> None:
    """Monotone Y, the area of each kit, every kit used, a source first and a sink last."""
    n = data.n
    for k in range(m):
        if k:  # Y_{i,k-1} <= Y_{ik}
            ub.add_many(
                np.concatenate([np.arange(n)] * 2),
                np.concatenate([np.arange(n) * m + k - 1, np.arange(n) * m + k]),
                np.concatenate([np.ones(n), -np.ones(n)]),
                [0.0] * n,
            )
        cols, vals = _share_terms(m, n, k, data.area)
        ub.add(cols, vals, data.tray_area)
        cols, vals = _share_terms(m, n, k, np.ones(n))
        ub.add(cols, -vals, -1.0)
    ub.add(data.src * m, -np.ones(len(data.src)), -1.0)  # sum_src Y_i0 >= 1
    if m > 1:  # sum_snk (1 - Y_{i,m-2}) >= 1
        ub.add(data.snk * m + m - 2, np.ones(len(data.snk)), len(data.snk) - 1.0)


def _timeline_rows(data: _Data, m: int, ub: _Rows) -> None:
    """The timeline of the module docstring; A_k and H_k are expressions in S_k and Y."""
    n, ny = data.n, data.n * m
    i_s, i_e = ny, ny + m
    rob = data.o_r + data.d

    def arrive(k: int, sign: float) -> tuple[np.ndarray, np.ndarray, float]:
        cols, vals = _share_terms(m, n, k, data.r)
        return np.append(cols, i_s + k), np.append(sign * vals, sign), sign * rob

    def human(k: int, sign: float) -> tuple[np.ndarray, np.ndarray, float]:
        cols, vals = _share_terms(m, n, k, data.h)
        return cols, sign * vals, sign * data.o_h

    for k in range(m):
        ca, va, ka = arrive(k, 1.0)
        ch, vh, kh = human(k, 1.0)
        # E_k >= A_k + H_k
        ub.add(np.concatenate([ca, ch, [i_e + k]]), np.concatenate([va, vh, [-1.0]]), -ka - kh)
        if k:
            # E_k >= E_{k-1} + H_k
            ub.add(np.append(ch, [i_e + k - 1, i_e + k]), np.append(vh, [1.0, -1.0]), -kh)
            cp, vp, kp = arrive(k - 1, 1.0)
            if data.trays is None or k < data.trays:  # S_k = A_{k-1}
                ub.add(np.append(cp, i_s + k), np.append(vp, -1.0), -kp, equal=True)
            else:
                ub.add(np.append(cp, i_s + k), np.append(vp, -1.0), -kp)  # S_k >= A_{k-1}
                # S_k >= E_{k-T} - H_{k-T} + o_H
                t = k - data.trays
                cq, vq, kq = human(t, -1.0)
                ub.add(
                    np.append(cq, [i_e + t, i_s + k]), np.append(vq, [1.0, -1.0]), -kq - data.o_h
                )


@dataclass(frozen=True)
class KitCountBound:
    """The kit-count LP bound: ``value`` (s, lowered by :data:`LP_TOL`), the LP optimum of
    every kit count scanned (``per_kits``: m -> L(m), inf when no plan of m kits exists) and
    the first count not scanned, ``stop`` (its closed-form bound and the larger counts' are
    at least ``value``). ``safety_net``: a scan limited by work (``work``) was cut by its
    wall-clock safety net instead, so it is not reproducible."""

    value: float
    per_kits: dict[int, float]
    stop: int
    complete: bool
    safety_net: bool = False


def kit_count_bound(
    instance: Instance,
    closed_at: object,
    *,
    m_min: int,
    deadline: float,
    upper: float | None = None,
    max_cells: int = 60_000,
    work: int | None = None,
) -> KitCountBound:
    """Scan m = m_min, m_min + 1, ... while the closed-form bound with m kits
    (``closed_at(m)``) is below the best LP value so far (and below ``upper``, a known plan's
    makespan, if given), until ``deadline`` (``time.perf_counter``), a model of more than
    ``max_cells`` task x kit variables or one that would not fit the time left
    (:data:`LP_S_PER_CELL`); see :class:`KitCountBound`.

    ``work`` (a reproducible scan, docs/simulation.md#determinism): the scan stops instead
    before its LPs' task x kit variables would add up to more than ``work``, whatever the
    clock says; ``deadline`` is then a wall-clock safety net only (its firing is recorded)."""
    data = _Data.of(instance)
    best = math.inf
    per: dict[int, float] = {}
    m = m_min
    complete = net = False
    spent = 0
    while True:
        cap = closed_at(m)  # type: ignore[operator]
        if cap >= best or (upper is not None and cap > upper) or m > data.n:
            complete = True
            break
        cells = data.n * m
        left = deadline - time.perf_counter()
        if cells > max_cells or (work is not None and spent + cells > work):
            break
        if left <= 0.02 or (work is None and cells * LP_S_PER_CELL > left):
            net = work is not None
            break
        value = kit_lp(data, m, left)
        spent += cells
        if value is None:
            net = work is not None and time.perf_counter() >= deadline - 0.02
            break
        value = value - LP_TOL * max(1.0, abs(value)) if math.isfinite(value) else value
        per[m] = value
        best = min(best, value)
        m += 1
    final = min(best, closed_at(m))  # type: ignore[operator]
    return KitCountBound(final, per, m, complete, net)
