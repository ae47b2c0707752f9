r"""Cheap closed-form lower bounds on the makespan, and Johnson's rule for F2||Cmax.

Notation (docs/timeline.md): tasks i with robot time r_i and human time h_i, kit overheads
o_R (robot) and o_H (human), delivery time d, m kits. Every bound below holds for every plan
whose kits fit the tray, so ``best_bound`` can be printed next to any result.

* (c) **area**: a kit's parts must fit the tray without overlap, so their total footprint area
  is at most the tray area and

  .. math:: m \ge m_{\min} = \max\bigl(1, \lceil \textstyle\sum_p w_p h_p / (W H) \rceil\bigr).

* (a) **human**: kit 1 holds a task without predecessors (every task of kit 1 has its
  ancestors in kit 1), so it cannot arrive before :math:`\min_{i \in \mathrm{src}} r_i + o_R + d`;
  after that the human still has all of her work, at least :math:`\sum_i h_i + m_{\min} o_H`:

  .. math:: C \ge \min_{i \in \mathrm{src}} r_i + o_R + d + \sum_i h_i + m_{\min}\, o_H.

* (b) **robot**: the robot never idles between kits (it starts kit k+1 when kit k arrives), so
  the last kit arrives at :math:`\sum_i r_i + m (o_R + d)`; it holds a task without successors,
  whose human time plus o_H is still to be done:

  .. math:: C \ge \sum_i r_i + m_{\min} (o_R + d) + o_H + \min_{i \in \mathrm{snk}} h_i.

**Trays.** With T trays in circulation (the instance's ``trays``) the tray rule
``robot_start_k >= human_start_{k-T} + o_H`` only adds constraints to the timeline, and the
makespan is non-decreasing in every start time, so (a)-(c) hold for every T. With **one tray**
(T = 1) (b) tightens by the robot's wait for the tray: the robot cannot start kit k + 1 before
the human has taken kit k's parts, and the human cannot start kit k before it arrives, so

.. math:: S_{k+1} \ge \mathrm{hs}_k + o_H \ge A_k + o_H = S_k + R_k + d + o_H,

hence :math:`S_m \ge \sum_{k<m} (R_k + d + o_H)` and :math:`C \ge S_m + R_m + d + H_m`, with
:math:`H_m \ge o_H + \min_{snk} h_i` (the last kit holds a sink) and
:math:`\sum_k R_k = \sum_i r_i + m\, o_R`:

.. math:: C \ge \sum_i r_i + m_{\min} (o_R + d) + (m_{\min} - 1)\, o_H + o_H
          + \min_{i \in \mathrm{snk}} h_i

(the one-tray robot bound, F2|block|Cmax's robot-side bound plus the overheads; every term is
non-decreasing in m, so m_min may replace m). :func:`tray_wait` is the per-kit wait it adds.

* (d) **flow shop** (:func:`flow_bound`, tight on flow-shop-like instances). With unlimited
  trays a plan of m kits is a two-machine flow shop on its kits (docs/timeline.md): kit k
  occupies the robot for :math:`a_k = o_R + d + \sum_{i \in k} r_i` (the robot is busy while
  delivering) and then the human for :math:`b_k = o_H + \sum_{i \in k} h_i`, starting no
  earlier than its arrival. Split every kit into m "jobs": one **overhead job**
  :math:`(o_R + d,\ o_H)` and one job :math:`(r_i, h_i)` per task. Inside kit k's robot
  interval :math:`[S_k, A_k]` give each job a robot sub-interval of its length, inside the
  human interval :math:`[\mathrm{hs}_k, E_k]` (:math:`\mathrm{hs}_k \ge A_k`) a human
  sub-interval; every job then ends on the robot before it starts on the human, and no two
  jobs overlap on a machine: a feasible F2||Cmax schedule of the n + m jobs with makespan C.
  So :math:`C \ge J(m)`, the optimal F2||Cmax makespan of the tasks and m overhead jobs,
  which Johnson's rule computes. Adding a job never lowers J (drop it from an optimal
  schedule), so :math:`C \ge J(m_{\min})`. Precedence, the tray's geometry and the tray rule
  (with T trays it only delays starts, and C is non-decreasing in every start) are relaxed,
  so (d) holds for every plan and every T. With d = 0 and no overheads, J is Johnson's
  makespan of the tasks, which the plan of single-task kits in Johnson's order attains when
  there is no precedence: the bound is then exact. (a) and (b) are relaxations of F2 too,
  but keep their source/sink and one-tray terms, so :func:`best_bound` takes the max.
  :func:`johnson_lines` writes J(m) as the max of two lines in m, so the exact models add
  (d) with their own kit count (``C >= c + s * sum_k u_k``).

  The one-task-per-job Gilmore-Gomory makespan (F2|block) is **not** claimed as a bound with
  one tray: a kit's tasks are all picked before the human starts any of them, which a
  blocking flow shop of single tasks does not model.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import TYPE_CHECKING, Any, TypeVar

from .instance import Instance
from .instance.model import station_instance
from .objectives import get as get_objective
from .objectives import human_times

if TYPE_CHECKING:
    from .plan import Plan

#: Relative slack when rounding an area ratio up, so that float noise (e.g. 4 * 2500 / 10000
#: = 1.0000000000000002) does not add a kit.
_AREA_EPS = 1e-9


def instance_times(instance: Instance) -> list[float]:
    """Every time the timeline adds (docs/timeline.md): each task's robot and human time, the
    robot's kit overhead, each station's delivery time and human overhead."""
    ids = [t.id for t in instance.tasks]
    params = [instance.params_of(s) for s in instance.station_ids]  # (Instance.params_of)
    return (
        [instance.robot_time(i) for i in ids]
        + [instance.human_time(i) for i in ids]
        + [instance.kit_overhead_robot]
        + [v for p in params for v in (p.delivery_time, p.kit_overhead_human)]
    )


def makespan_grid(instance: Instance) -> float | None:
    """The coarsest grid every makespan lies on (docs/formulations.md#what-optimal-means): the
    greatest common divisor of :func:`instance_times` (the timeline only adds them and takes
    maxima, so every start, end and makespan is a sum of them), e.g. 1 s when all are whole
    seconds; None when a time is no fraction of denominator up to 10^6."""
    from .geometry import exact_step

    return exact_step([v for v in instance_times(instance) if v > 0])


def on_grid(value: float, grid: float | None) -> float:
    """``value`` (a lower bound on a makespan) rounded up to the makespan's grid (every
    makespan lies on it, :func:`makespan_grid`), or as is (no grid, or not finite)."""
    if grid is None or not math.isfinite(value):
        return value
    return round(math.ceil(value / grid - 1e-9) * grid, 9)


def min_kits(instance: Instance) -> int:
    """(c): the area-based minimum number of kits, ``ceil(total part area / tray area)``."""
    total = sum(instance.part_types[p].area * n for t in instance.tasks for p, n in t.parts)
    return max(1, math.ceil(total / instance.tray.area - _AREA_EPS))


def tray_wait(instance: Instance) -> float:
    """The robot's least wait per kit after the first for the tray: o_H with one tray (the
    one-tray robot bound of the module docstring), else 0 (one station: :meth:`params_of`)."""
    params = instance.params_of()
    return params.kit_overhead_human if params.tray_limit == 1 else 0.0


def end_tasks(instance: Instance) -> tuple[list[int], list[int]]:
    """The task indices (task order) of the sources and the sinks of the precedence graph:
    the first kit holds a source, the last a sink (bounds (a) and (b))."""
    idx = instance.index
    has_pred = {idx[b] for _, b in instance.precedence}
    has_succ = {idx[a] for a, _ in instance.precedence}
    every = range(instance.n_tasks)
    return [i for i in every if i not in has_pred], [i for i in every if i not in has_succ]


#: Seconds (float) or the exact models' integer time grid (int).
Num = TypeVar("Num", int, float)


def human_robot(
    times: tuple[Sequence[Num], Sequence[Num]],
    kit: tuple[Num, Num, Num, Num],
    ends: tuple[list[int], list[int]],
    m: int,
) -> tuple[Num, Num]:
    """(a) human and (b) robot bounds of the module docstring with ``m`` kits, from the
    tasks' ``times`` (r, h), the ``kit`` overheads and wait ``(o_R, d, o_H, w)`` (w:
    :func:`tray_wait`) and the :func:`end_tasks`; in seconds or on a model's integer grid
    (the one derivation :func:`lower_bounds` and the CP-SAT model share)."""
    (r, h), (o_r, d, o_h, w), (sources, sinks) = times, kit, ends
    human = min(r[i] for i in sources) + o_r + d + sum(h) + m * o_h
    robot = sum(r) + m * (o_r + d) + (m - 1) * w + o_h + min(h[i] for i in sinks)
    return human, robot


def kit_slacks(
    upper: Num,
    times: tuple[Sequence[Num], Sequence[Num]],
    kit: tuple[Num, Num, Num, Num],
    ends: tuple[list[int], list[int]],
) -> list[tuple[Num, Num]]:
    """(b) and (a) with the plan's own kit count m solved for m: every plan of makespan at
    most ``upper`` has ``m * per_kit <= slack`` for each ``(slack, per_kit)`` (no limit where
    ``per_kit`` is 0); arguments as :func:`human_robot`. The exact models' kit caps."""
    (r, h), (o_r, d, o_h, w), (sources, sinks) = times, kit, ends
    return [
        (upper - sum(r) - o_h + w - min(h[i] for i in sinks), o_r + d + w),
        (upper - min(r[i] for i in sources) - o_r - d - sum(h), o_h),
    ]


def lower_bounds(instance: Instance) -> dict[str, float]:
    """All closed-form bounds (seconds), keyed ``human``, ``robot``, ``min_kits`` (a count)."""
    ids = [t.id for t in instance.tasks]
    m = min_kits(instance)
    params = instance.params_of()  # one station (best_bound: several, per station)
    o_r, o_h, d = instance.kit_overhead_robot, params.kit_overhead_human, params.delivery_time
    times = ([instance.robot_time(i) for i in ids], [instance.human_time(i) for i in ids])
    kit = (o_r, d, o_h, tray_wait(instance))
    human, robot = human_robot(times, kit, end_tasks(instance), m)
    return {"human": human, "robot": robot, "flow": flow_bound(instance, m), "min_kits": float(m)}


def best_bound(instance: Instance) -> float:
    """The largest of the closed-form makespan bounds (seconds); with several stations, the
    largest over the stations of their own (:func:`bilevel_kit.stations.station_instance`)."""
    instance = instance.as_one_station()  # one declared station: the S = 1 bounds
    if instance.stations:
        return stations_bound(instance)
    lb = lower_bounds(instance)
    return max(lb["human"], lb["robot"], lb["flow"])


def stations_bound(instance: Instance) -> float:
    """With several stations (docs/timeline.md#several-stations): the largest of each
    station's own bounds (:func:`bilevel_kit.stations.station_instance`: its completion is at
    least its tasks' makespan with the robot to itself), and the **robot across stations**: a
    kit holds one station's tasks, so station s needs at least ``m_s`` (its area bound) kits,
    the robot is busy ``sum_i r_i + sum_s m_s (o_R + d_s)`` before the last kit arrives, and
    that kit's human then needs at least ``o_H,s`` plus a task without successors at s."""
    subs = station_bounds(instance)
    robot = sum(instance.robot_time(t.id) for t in instance.tasks)
    last = math.inf
    for sub, _ in subs:
        params = sub.params_of()  # the station's own (station_instance)
        robot += min_kits(sub) * (instance.kit_overhead_robot + params.delivery_time)
        has_succ = {a for a, _ in sub.precedence}
        sink = min(sub.human_time(t.id) for t in sub.tasks if t.id not in has_succ)
        last = min(last, params.kit_overhead_human + sink)
    return max(robot + last, *(lb for _, lb in subs))


def flow_bound(instance: Instance, m: int | None = None) -> float:
    """(d): Johnson's makespan of the tasks plus ``m`` (default m_min) overhead jobs
    (o_R + d, o_H); a lower bound on the makespan of every plan of at least m kits."""
    ids = [t.id for t in instance.tasks]
    a = [instance.robot_time(i) for i in ids]
    b = [instance.human_time(i) for i in ids]
    params = instance.params_of()
    a0 = instance.kit_overhead_robot + params.delivery_time
    b0 = params.kit_overhead_human
    return lines_value(johnson_lines(a, b, a0, b0), min_kits(instance) if m is None else m)


Line = tuple[float, float]


def lines_value(lines: Sequence[Line], m: int) -> float:
    """max over the lines (c, s) of c + s m."""
    return max(c + s * m for c, s in lines)


def johnson_lines(
    a: Sequence[float], b: Sequence[float], a0: float, b0: float
) -> list[tuple[float, float]]:
    """Lines (c, s) with J(m) = max_l (c_l + s_l m) for every m >= 1, J(m) the optimal
    F2||Cmax makespan of the jobs (a_j, b_j) plus m identical jobs (a0, b0).

    Johnson's rule puts the m identical jobs in one block at a slot q of the tasks' Johnson
    order (ties by index). A permutation's makespan is the max over split jobs j of
    (robot time up to and including j) + (human time from j on). A task before the block:
    the block's m b0 is in its human suffix (slope b0); a task after it: m a0 is in its robot
    prefix (slope a0); the t-th block job gives P + t a0 + (m - t + 1) b0 + S (P, S: robot time
    before, human time after the block), linear in t, so t = 1 (slope b0) or t = m (slope a0).
    Exact integers in, exact integers out."""
    n = len(a)
    order = johnson_order([*a, a0], [*b, b0])
    q = order.index(n)
    tasks = [j for j in order if j != n]
    pre_a = a0 - a0  # zero of the inputs' type: ints stay ints
    pre = []
    for j in tasks:
        pre_a += a[j]
        pre.append(pre_a)
    suf_b = b0 - b0
    suf = [suf_b] * n
    for pos in range(n - 1, -1, -1):
        suf_b += b[tasks[pos]]
        suf[pos] = suf_b
    split = [pre[pos] + suf[pos] for pos in range(n)]
    big_p = pre[q - 1] if q else a0 - a0
    big_s = suf[q] if q < n else b0 - b0
    c_b = max([big_p + big_s + a0, *split[:q]])
    c_a = max([big_p + big_s + b0, *split[q:]])
    return [(c_b, b0), (c_a, a0)]


def johnson_order(a: Sequence[float], b: Sequence[float]) -> list[int]:
    """Johnson's rule for F2||Cmax: jobs with a_j <= b_j by increasing a_j, then the others by
    decreasing b_j (ties by index). Optimal for two machines in series without precedence."""
    first = sorted((j for j in range(len(a)) if a[j] <= b[j]), key=lambda j: (a[j], j))
    last = sorted((j for j in range(len(a)) if a[j] > b[j]), key=lambda j: (-b[j], j))
    return first + last


def flow_shop_makespan(order: Sequence[int], a: Sequence[float], b: Sequence[float]) -> float:
    r"""Makespan of a permutation schedule on two machines:
    :math:`F_1 \mathrel{+}= a_j,\ F_2 = \max(F_2, F_1) + b_j`."""
    f1 = f2 = 0.0
    for j in order:
        f1 += a[j]
        f2 = max(f2, f1) + b[j]
    return f2


def johnson_makespan(a: Sequence[float], b: Sequence[float]) -> float:
    """Optimal F2||Cmax makespan (Johnson's rule)."""
    return flow_shop_makespan(johnson_order(a, b), a, b)


def station_bounds(instance: Instance) -> list[tuple[Instance, float]]:
    """Each station with tasks as an instance of its own
    (:func:`bilevel_kit.stations.station_instance`) and its makespan bound
    (:func:`best_bound`), which holds for that station's completion: what the objectives'
    closed-form bounds over the stations add up (:meth:`bilevel_kit.objectives.Objective.bound`)."""
    subs = (station_instance(instance, s) for s in instance.station_ids)
    return [(one, best_bound(one)) for one in subs if one.tasks]


def objective_bound(instance: Instance, objective: str) -> float:
    """A closed-form lower bound on ``objective`` over every plan (s): the registry's
    (:meth:`bilevel_kit.objectives.Objective.bound`)."""
    return get_objective(objective).bound(instance, best_bound, station_bounds)


def objective_extra(
    instance: Instance,
    plan: Plan,
    objective: str,
    lower: tuple[float | None, float | None],
    optimal: tuple[bool, bool],
    *,
    model_scale: bool = False,
) -> dict[str, Any]:
    """An exact model's ``extra`` for ``objective`` besides the makespan: ``objective_value``,
    ``objective_bound``, ``objective_gap`` (s; the objective's gap: the keys every method states
    its minimised objective under, :data:`bilevel_kit.methods.OBJECTIVE_KEYS`) and
    ``objective_bound_axis_aligned``. Each bound is
    :func:`objective_bound` or the model's ``lower``, valid for every plan and for
    0/90-degree plans (None: none), in s or (``model_scale``) on the model's scale, with the
    constant :meth:`~bilevel_kit.objectives.Objective.dropped`; the value when ``optimal`` in
    the same two scopes (docs/formulations.md#what-optimal-means)."""
    from .plan import evaluate

    obj = get_objective(objective)
    value = obj.value(evaluate(instance, plan))
    if value is None:
        raise ValueError(f"{objective!r} is not a function of the timeline")
    closed = obj.bound(instance, best_bound, station_bounds)
    bounds = []
    for low, opt in zip(lower, optimal, strict=True):
        if low is not None and model_scale:
            low -= obj.dropped(human_times(instance))
        bound = closed if low is None else max(closed, low)
        bounds.append(value if opt else min(bound, value))
    out: dict[str, Any] = {
        "objective_value": value,
        "objective_bound": bounds[0],
        "objective_gap": obj.gap(value, bounds[0]),
        "objective_bound_axis_aligned": bounds[1],
    }
    return out
