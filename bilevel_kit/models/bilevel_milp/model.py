"""The set-partitioning + sequencing MILP over the columns (package docstring, "MILP" and
"Trays"), its MIP start and its chosen kits."""

from __future__ import annotations

import itertools
from collections.abc import Mapping, Sequence
from typing import Any

from ...instance import Instance
from ...plan import Plan
from ..common import chain_groups, reduced_edges
from ..milp.model import canonical_kits
from .columns import Column


def _order(m: Any, instance: Instance, K: int) -> None:
    """Precedence on the reduced graph and interchangeable chains in lexicographic order, on
    the task-position variables X (package docstring)."""
    add = m.cons.add
    idx = instance.index
    for a_id, b_id in reduced_edges(instance):
        a, b = idx[a_id], idx[b_id]
        for k in range(K - 1):
            add(sum(m.X[b, q] for q in range(k + 1)) <= sum(m.X[a, q] for q in range(k + 1)))
    for group in chain_groups(instance) if K > 1 else []:
        chains = sorted([idx[t] for t in c] for c in group)
        length = len(chains[0])
        while length > 1 and K ** (length - 1) > 1e6:
            length -= 1
        for c1, c2 in itertools.pairwise(chains):
            add(
                sum(
                    K ** (length - 1 - j) * k * (m.X[c1[j], k] - m.X[c2[j], k])
                    for j in range(length)
                    for k in range(1, K)
                )
                <= 0
            )


def build_model(
    instance: Instance, cols: Sequence[Column], signed: bool, weights: Mapping[str, float]
) -> tuple[Any, list[tuple[int, int]]]:
    """The set-partitioning + sequencing MILP of the package docstring (used kits first)."""
    import pyomo.environ as pyo

    ids = [t.id for t in instance.tasks]
    n = len(ids)
    K = n
    idx = instance.index
    one = instance.params_of()  # the paper's problem: one station
    d = one.delivery_time
    big_m = (
        d
        + instance.kit_overhead_robot
        + sum(instance.robot_time(t) for t in ids)
        + n * one.kit_overhead_human
        + sum(instance.human_time(t) for t in ids)
    )
    keys = [(c, k) for c, col in enumerate(cols) for k in range(col.lo, col.hi + 1)]
    m = pyo.ConcreteModel(name="kit_columns")
    m.z = pyo.Var(keys, domain=pyo.Binary)
    m.X = pyo.Var(range(n), range(K), bounds=(0.0, 1.0))
    m.p5 = pyo.Var(range(K), bounds=(0.0, big_m))
    m.q5 = pyo.Var(range(K), bounds=(0.0, big_m))
    m.s5 = pyo.Var(range(K), domain=pyo.Binary)
    m.p6 = pyo.Var(range(K), bounds=(0.0, big_m))
    m.q6 = pyo.Var(range(K), bounds=(0.0, big_m))
    m.s6 = pyo.Var(range(K), domain=pyo.Binary)
    m.cons = pyo.ConstraintList()
    add = m.cons.add
    at_k: list[list[int]] = [[] for _ in range(K)]
    holding: dict[tuple[int, int], list[int]] = {}
    for c, k in keys:
        at_k[k].append(c)
        for t in cols[c].tasks:
            holding.setdefault((idx[t], k), []).append(c)
    for i in range(n):
        for k in range(K):
            zs = holding.get((i, k), [])
            if zs:
                add(m.X[i, k] == sum(m.z[c, k] for c in zs))
            else:
                m.X[i, k].fix(0.0)
        add(sum(m.X[i, k] for k in range(K)) == 1)

    def used(k: int) -> Any:
        return sum(m.z[c, k] for c in at_k[k]) if k < K and at_k[k] else 0.0

    for k in range(K):
        if at_k[k]:
            add(used(k) <= 1)
            if k:
                add(used(k) <= used(k - 1))  # used kits first
    _order(m, instance, K)

    def robot(k: int) -> Any:
        return sum(cols[c].robot * m.z[c, k] for c in at_k[k]) if k < K and at_k[k] else 0.0

    def human(k: int) -> Any:
        return sum(cols[c].human * m.z[c, k] for c in at_k[k]) if at_k[k] else 0.0

    wait = _tray_waits(m, instance, K, used, robot)
    backlog: Any = 0.0
    for k in range(K):
        u = used(k)
        if k:
            backlog = backlog - wait(k)  # B_{k-1} = human_end_{k-1} - robot_start_k
        g = d * u + robot(k) - backlog
        # exact on used positions; relaxed (and zeroed) on unused ones, which come last
        add(m.p5[k] - m.q5[k] - g <= big_m * (1 - u))
        add(m.p5[k] - m.q5[k] - g >= -big_m * (1 - u))
        add(m.p5[k] + m.q5[k] <= big_m * u)
        add(m.p5[k] <= big_m * m.s5[k])
        add(m.q5[k] <= big_m * (1 - m.s5[k]))
        backlog = m.q5[k] + human(k)  # = max(0, B_{k-1} - R_k - d) + H_k (before the tray)
        add(m.p6[k] - m.q6[k] == d * u + robot(k + 1) - human(k))
        add(m.p6[k] <= big_m * m.s6[k])
        add(m.q6[k] <= big_m * (1 - m.s6[k]))
    w2, w3, w4, w5 = (weights[k] for k in ("W2", "W3", "W4", "W5"))
    sign = -1.0 if signed else 1.0
    m.obj = pyo.Objective(
        expr=sum((-w2 * len(cols[c].tasks) - w5 * cols[c].fitness) * m.z[c, k] for c, k in keys)
        + sum(w3 * (m.p5[k] + sign * m.q5[k]) + w4 * (m.p6[k] + sign * m.q6[k]) for k in range(K)),
        sense=pyo.minimize,
    )
    return m, keys


def _tray_waits(m: Any, instance: Instance, K: int, used: Any, robot: Any) -> Any:
    """``w(k)``: how long the robot waits for a tray before kit k (package docstring), exact
    on used positions; 0 with unlimited trays."""
    import pyomo.environ as pyo

    one = instance.params_of()  # the paper's problem: one station
    T, o_h, d = one.tray_limit, one.kit_overhead_human, one.delivery_time
    if T is None:
        return lambda k: 0.0
    if T == 1:  # the human has started kit k - 1 when it arrived: w_k = q5_{k-1} + o_H
        return lambda k: m.q5[k - 1] + o_h * used(k)
    ids = [t.id for t in instance.tasks]
    horizon = sum(instance.robot_time(t) + instance.human_time(t) for t in ids) + len(ids) * (
        instance.kit_overhead_robot + o_h + d
    )  # every time of the timeline lies in [0, horizon]
    m.w = pyo.Var(range(T, K), bounds=(0.0, horizon))
    m.v = pyo.Var(range(T, K), bounds=(0.0, horizon))
    m.sw = pyo.Var(range(T, K), domain=pyo.Binary)
    add = m.cons.add
    for k in range(T, K):
        u = used(k)
        # y_k = human start of kit k - T + o_H - arrival of kit k - 1
        y = m.q5[k - T] + o_h * u
        for j in range(k - T + 1, k):
            y = y - (m.w[j] if j >= T else 0.0) - robot(j) - d * used(j)
        add(m.w[k] - m.v[k] - y <= 2 * horizon * (1 - u))
        add(m.w[k] - m.v[k] - y >= -2 * horizon * (1 - u))
        add(m.w[k] <= horizon * u)
        add(m.w[k] <= horizon * m.sw[k])
        add(m.v[k] <= horizon * (1 - m.sw[k]))
    return lambda k: m.w[k] if k >= T else 0.0


def set_start(
    m: Any, instance: Instance, cols: Sequence[Column], keys: Sequence[Any], plan: Plan
) -> None:
    """Load a plan as a MIP start (only its z; HiGHS completes the rest)."""
    pos = {c.tasks: j for j, c in enumerate(cols)}
    where = {}
    kits = canonical_kits(instance, [list(k.tasks) for k in plan.kits])  # symmetry-consistent
    for k, kit in enumerate(kits):
        c = pos.get(frozenset(kit))
        if c is None:
            return  # not a column (e.g. not convex): no start
        where[(c, k)] = 1.0
    for key in keys:
        m.z[key].set_value(where.get(key, 0.0), skip_validation=True)


def chosen_kits(
    m: Any, keys: Sequence[tuple[int, int]], cols: Sequence[Column]
) -> list[frozenset[str]]:
    """The MILP's chosen columns, in kit order."""
    chosen = sorted(
        ((k, c) for c, k in keys if m.z[c, k].value is not None and m.z[c, k].value > 0.5)
    )
    return [cols[c].tasks for _, c in chosen]
