r"""What the CP-SAT schedule model (:mod:`.model`) adds with several assembly stations
(docs/timeline.md#several-stations; docs/formulations.md, "Several stations"). With one
station none of it is built: the model is the one-station model, variable for variable.

The assignment ``x``, the used kits ``u`` (used kits first, ``sum_k u_k >= m_min``), the
interchangeable chains' lexicographic order (chains of one station only: the station is part
of a task's signature), the kit positions ``p_i <= n - |descendants(i)|`` and the tray
(area relaxation, embedded rectangles or Benders counts) are the one-station model's. Added,
on the scaled integer times of :mod:`.scaling`:

* ``z[s,k]`` = kit k is for station s: ``sum_s z[s,k] = u_k``, ``x[i,k] => z[s(i),k]`` (a kit
  never mixes stations), ``sum_k z[s,k] >= m_min(s)`` (the station's own area bound);
* the shared robot and each station's human, with running values per station, ``F[s,k]``
  (end of s's last kit up to position k) and, for one tray, ``G[s,k]`` (when s's tray is
  back)::

      R_k = o_R u_k + sum_i r_i x[i,k]     D_k = sum_s d_s z[s,k]
      H_k = sum_s o_H,s z[s,k] + sum_i h_i x[i,k]
      S_k >= A_{k-1},  A_k = S_k + R_k + D_k,  E_k >= A_k + H_k
      F[s,k] >= F[s,k-1];  z[s,k] => F[s,k] >= E_k,  E_k >= F[s,k-1] + H_k
      T_s = 1:  G[s,k] >= G[s,k-1];  z[s,k] => G[s,k] >= E_k - H_k + o_H,s,  S_k >= G[s,k-1]
      T_s >= 2: z[s,j], z[s,k], (at least T_s kits of s in j..k-1) => S_k >= E_j - H_j + o_H,s
      C >= F[s,K-1]

  Every constraint is monotone, so for fixed kits the least solution is the timeline
  (:func:`.scaling.stations_timeline`) and ``F[s,K-1]`` station s's completion;
* redundant bounds (they help the search): the closed-form makespan bound of
  :func:`bilevel_kit.bounds.best_bound` on an exact grid, the robot across stations with the
  model's own kits (``C >= sum_i r_i + sum_k (R_k - sum_i r_i x[i,k] + D_k) + min_s (o_H,s +
  min_{sinks of s} h_i)``: the last kit arrives after all the robot's work and holds a sink)
  and each station's human (``F[s,K-1] >= o_R + min_{sources of s} r_i + d_s + sum_{i at s}
  h_i + o_H,s sum_k z[s,k]``).

The objective is the registry's expression on C, the completions ``sum_s F[s,K-1]`` and the
overheads ``sum_s o_H,s sum_k z[s,k]``. Not here (one station only): release times, the
Johnson lines, the one-tray robot bound and the kit-count LP of :mod:`bilevel_kit.models.relax`.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

from ...bounds import best_bound, end_tasks, min_kits
from ...instance import Instance
from ...instance.model import station_instance
from ...objectives import ModelTerms
from ...objectives import get as get_objective
from .context import Model
from .scaling import Scaled, stations_timeline


def build_stations(
    m: Any,
    instance: Instance,
    sc: Scaled,
    x: list[dict[int, Any]],
    used: list[Any],
    upper: int | None,
    objective: str,
) -> Model:
    """The station variables, timeline, bounds and objective (module docstring) on the
    one-station model's assignment ``x`` and used kits ``used``."""
    K, n, S = len(used), len(x), len(sc.st_d)
    hz = sum(sc.r) + sum(sc.h) + K * (sc.o_r + max(sc.st_d) + max(sc.st_oh))
    if upper is not None:
        hz = min(hz, upper)
    z = [[m.new_bool_var(f"z{s}_{k}") for k in range(K)] for s in range(S)]
    for k in range(K):
        m.add(sum(z[s][k] for s in range(S)) == used[k])
        for i in range(n):
            if k in x[i]:
                m.add_implication(x[i][k], z[sc.station[i]][k])
    for s, sid in enumerate(instance.station_ids):
        sub = station_instance(instance, sid)
        if sub.tasks:
            m.add(sum(z[s]) >= min(K, min_kits(sub)))
    mdl = Model(m, K, x, used, [], [], None, z=z)
    _timeline(mdl, sc, hz)
    _bounds(mdl, instance, sc)
    obj = get_objective(objective)
    terms = ModelTerms(mdl.C, lambda: sum(f[-1] for f in mdl.last), lambda: _overhead(sc, z))
    m.minimize(obj.expression(terms))
    mdl.obj_const = -obj.dropped(sc.h)
    return mdl


def _overhead(sc: Scaled, z: list[list[Any]]) -> Any:
    return sum(sc.st_oh[s] * v for s, zs in enumerate(z) for v in zs)


def _timeline(mdl: Model, sc: Scaled, hz: int) -> None:
    """Robot start, arrival, human end, the running values F and G, and C (module
    docstring) into ``mdl``."""
    m, x, used, z, K = mdl.model, mdl.x, mdl.used, mdl.z, mdl.K
    n, S = len(x), len(z)
    trays = any(t is not None for t in sc.st_trays)
    mdl.last = [[m.new_int_var(0, hz, f"F{s}_{k}") for k in range(K)] for s in range(S)]
    F = mdl.last
    for k in range(K):
        R = sc.o_r * used[k] + sum(sc.r[i] * x[i][k] for i in range(n) if k in x[i])
        D = sum(sc.st_d[s] * z[s][k] for s in range(S))
        H = m.new_int_var(0, hz, f"H{k}")  # a variable: the enforced rules below stay short
        work = sum(sc.h[i] * x[i][k] for i in range(n) if k in x[i])
        m.add(sum(sc.st_oh[s] * z[s][k] for s in range(S)) + work == H)
        prev = mdl.arrive[-1] if k else 0
        a = m.new_int_var(0, hz, f"A{k}")
        e = m.new_int_var(0, hz, f"E{k}")
        s_k = None
        if trays:
            s_k = m.new_int_var(0, hz, f"S{k}")
            m.add(s_k >= prev)
            m.add(a == s_k + R + D)
        else:
            m.add(a == prev + R + D)
        m.add(e >= a + H)
        for s in range(S):
            if k:
                m.add(F[s][k] >= F[s][k - 1])
                m.add(e >= F[s][k - 1] + H).only_enforce_if(z[s][k])
            m.add(F[s][k] >= e).only_enforce_if(z[s][k])
        mdl.start.append(s_k)
        mdl.arrive.append(a)
        mdl.end.append(e)
        mdl.human.append(H)
    if trays:
        _tray_rules(mdl, sc, hz)
    mdl.C = m.new_int_var(0, hz, "C")
    for f in F:
        m.add(f[-1] <= mdl.C)


def _tray_rules(mdl: Model, sc: Scaled, hz: int) -> None:
    """Each station's trays (module docstring): the running ``G`` with one tray, pairs of
    positions with ``T_s >= 2``."""
    m, z, K = mdl.model, mdl.z, mdl.K
    S, E, H = mdl.start, mdl.end, mdl.human
    for s, trays in enumerate(sc.st_trays):
        zs, oh = z[s], sc.st_oh[s]
        if trays is None:
            continue
        if trays == 1:
            G = [m.new_int_var(0, hz + oh, f"G{s}_{k}") for k in range(K)]
            mdl.back[s] = G
            for k in range(K):
                if k:
                    m.add(G[k] >= G[k - 1])
                    m.add(S[k] >= G[k - 1]).only_enforce_if(zs[k])
                m.add(G[k] >= E[k] - H[k] + oh).only_enforce_if(zs[k])
            continue
        count = [m.new_int_var(0, k, f"n{s}_{k}") for k in range(K + 1)]  # kits of s before k
        for k in range(K + 1):
            m.add(count[k] == sum(zs[:k]))
        for k in range(1, K):
            for j in range(k):
                far = m.new_bool_var("")
                m.add(count[k] - count[j] <= trays - 1).only_enforce_if(far.Not())
                m.add(S[k] >= E[j] - H[j] + oh).only_enforce_if([zs[j], zs[k], far])


def _bounds(mdl: Model, instance: Instance, sc: Scaled) -> None:
    """The redundant bounds of the module docstring."""
    m, x, z, used = mdl.model, mdl.x, mdl.z, mdl.used
    n = len(x)
    if sc.exact:  # the closed forms hold for the scaled times only when these are exact
        m.add(math.ceil(best_bound(instance) / sc.res - 1e-6) <= mdl.C)
    sources, sinks = end_tasks(instance)
    last = min(sc.st_oh[sc.station[i]] + sc.h[i] for i in sinks)
    robot = sum(sc.r) + sc.o_r * sum(used)
    robot += sum(sc.st_d[s] * v for s, zs in enumerate(z) for v in zs)
    m.add(robot + last <= mdl.C)
    for s, zs in enumerate(z):
        mine = [i for i in range(n) if sc.station[i] == s]
        if not mine:
            continue
        first = min(sc.r[i] for i in sources if sc.station[i] == s)
        work = sum(sc.h[i] for i in mine) + sc.st_oh[s] * sum(zs)
        m.add(mdl.last[s][-1] >= sc.o_r + first + sc.st_d[s] + work)


def hint_stations(mdl: Model, sc: Scaled, padded: Sequence[Sequence[int]]) -> None:
    """Hint the station variables of the kits ``padded`` (K positions, unused ones empty):
    ``z``, the timeline, ``F``, ``G`` and C (:func:`.scaling.stations_timeline`)."""
    m = mdl.model
    timeline, done = stations_timeline(sc, padded)
    ends: dict[int, int] = {}
    backs: dict[int, int] = {}
    for k, (start, arrive, end) in enumerate(timeline):
        s = sc.station[padded[k][0]] if padded[k] else None
        m.add_hint(mdl.used[k], s is not None)
        for t, zs in enumerate(mdl.z):
            m.add_hint(zs[k], t == s)
        if s is not None:
            ends[s] = end
            backs[s] = end - sum(sc.h[i] for i in padded[k])  # human start + o_H,s
        m.add_hint(
            mdl.human[k], sc.st_oh[s] + sum(sc.h[i] for i in padded[k]) if s is not None else 0
        )
        if mdl.start[k] is not None:
            m.add_hint(mdl.start[k], start)
        m.add_hint(mdl.arrive[k], arrive)
        m.add_hint(mdl.end[k], end)
        for t, f in enumerate(mdl.last):
            m.add_hint(f[k], ends.get(t, 0))
        for t, g in mdl.back.items():
            m.add_hint(g[k], backs.get(t, 0))
    m.add_hint(mdl.C, max(done.values(), default=0))
    where = {i: k for k, kit in enumerate(padded) for i in kit}
    p, y = mdl.order
    for i, pi in enumerate(p):
        m.add_hint(pi, where[i])
        for k, v in enumerate(y[i]):
            m.add_hint(v, where[i] <= k)
    _hint_counts(mdl, sc, padded)


def _hint_counts(mdl: Model, sc: Scaled, padded: Sequence[Sequence[int]]) -> None:
    """Hint the part counts of the Benders mode (``c_{t,k}``, :mod:`.tray`)."""
    for (t, k), var in mdl.counts.items():
        mdl.model.add_hint(var, sum(c for i in padded[k] for q, c in mdl.parts[i] if q == t))
