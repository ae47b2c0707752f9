r"""The search space of :mod:`.search`: ideals of the precedence graph as bit masks, kits as
down-set extensions, the timeline as a transition on a small state vector, and the state's
lower bound (docs/formulations.md, "Branch, bound and remember").

**Tasks** are renumbered in a topological order, so a kit's tasks in increasing number are a
valid human order and a set ``S`` of tasks outside the ideal ``J`` is a kit exactly when every
predecessor of a task of ``S`` lies in ``J`` or ``S`` (then ``J | S`` is an ideal again).

**State.** After the kits that complete ``J`` (docs/timeline.md), the future depends only on

* ``E``, the human's end of the last kit, and
* ``nxt = max(arrive_k, ret_{k+1-T})``, the earliest robot start of the next kit (the last
  arrival, or the return of the tray it needs, ``human_start_j + o_H``), and
* with ``T >= 2`` trays, the returns of the last ``T - 1`` kits after it (oldest first).

A kit ``S`` moves the state by the timeline's rule: ``arrive = nxt + o_R + r(S) + d``,
``hs = max(arrive, E)``, ``E' = hs + o_H + h(S)``, and the tray of this kit returns at
``hs + o_H``. Every later time is a max-plus expression, non-decreasing in each component, so a
state whose vector is componentwise at most another's with the same ``J`` dominates it.

**Lower bound** of a state with ``U`` the tasks left and ``k0`` the area bound on their kits
(:func:`bilevel_kit.bounds.min_kits` on ``U``), ``a = nxt``, ``b = E``:

.. math::

   LB = \max\Bigl(b + B_U,\ a + P_U,\
        \min\bigl(\max(b,\ a + o_R + d + \rho_U) + B_U,\
                  \max(b,\ a + o_R + d + \min_{i\ \mathrm{ready}} r_i) + B_U + o_H\bigr),\
        [T = 1]\ a + r(U) + k_0 (o_R + d + o_H) + \min_{i \in U\ \mathrm{sink}} h_i\Bigr)

with :math:`B_U = h(U) + k_0 o_H` and :math:`P_U = \max_j (\sum_{i \le j} a_i +
\sum_{i \ge j} b_i)` over Johnson's order of the jobs :math:`(r_i, h_i)_{i \in U}` and
``k0`` overhead jobs :math:`(o_R + d, o_H)`: the two-machine flow-shop bound (d) of
:mod:`bilevel_kit.bounds` with machines free at ``a`` and ``b`` (Johnson's order minimises
the second term, the first does not depend on the order), the first kit's arrival (it holds a
ready task, and when the rest takes exactly ``k0`` kits the area the other ``k0 - 1`` cannot:
``rho_U`` is the larger of the least ready ``r_i`` and :func:`_least_robot_time` of
``area(U) - (k0 - 1)`` tray areas; with more kits the human has one more ``o_H``) and the
one-tray robot bound (b) of the same module from ``a``. Every term depends
on the state only through ``a`` and ``b`` plus a per-``U`` constant, cached per ideal.
"""

from __future__ import annotations

import math
from collections.abc import Iterator
from dataclasses import dataclass, field
from typing import NamedTuple

from ...bounds import flow_shop_makespan, johnson_order
from ...instance import Instance
from ...instance.model import topological_order

#: Relative slack of the area bound (as :data:`bilevel_kit.bounds._AREA_EPS`).
_AREA_EPS = 1e-9


@dataclass(frozen=True)
class Constants:
    """The per-ideal constants of the lower bound (module docstring)."""

    human: float  # B_U
    flow: float  # P_U
    robot_one: float  # r(U) + k0 (o_R + d + o_H) + min sink h (one tray), else -inf
    first: float  # o_R + d + min ready r
    exact: float  # o_R + d + the least robot time of a first kit of k0 kits (>= first)
    robot: float  # r(U) + k0 (o_R + d): the robot's least work on U
    sink: float  # min sink h
    area: float  # area(U)
    kits: int  # k0(U), at least 1


class Cut(NamedTuple):
    """The cut on a node's kits from the human's bound (:meth:`Space.kit_cut`): a kit ``S``
    may lead below the incumbent only if ``r(S) <= max_r``, and, when ``r(S) > same_r``,
    ``area(S) >= min_area`` (it leaves one kit fewer to the rest)."""

    max_r: float
    same_r: float
    min_area: float


@dataclass
class Space:
    """One station's instance, indexed for the search (module docstring)."""

    instance: Instance
    ids: list[str] = field(init=False)
    pred: list[int] = field(init=False)
    r: list[float] = field(init=False)
    h: list[float] = field(init=False)
    area: list[float] = field(init=False)
    #: trays in circulation that bind (None: unlimited, or at least as many as tasks)
    trays: int | None = field(init=False)
    _consts: dict[int, Constants] = field(init=False, default_factory=dict)

    def __post_init__(self) -> None:
        inst = self.instance
        self.ids = topological_order(inst)
        pos = {t: i for i, t in enumerate(self.ids)}
        self.n = len(self.ids)
        self.full = (1 << self.n) - 1
        self.pred = [0] * self.n
        self.succ = [0] * self.n
        for a, b in inst.precedence:
            self.pred[pos[b]] |= 1 << pos[a]
            self.succ[pos[a]] |= 1 << pos[b]
        self.r = [inst.robot_time(t) for t in self.ids]
        self.h = [inst.human_time(t) for t in self.ids]
        types = inst.part_types
        self.parts = [tuple(inst.task_by_id[t].parts) for t in self.ids]
        self.area = [sum(types[p].area * n for p, n in ps) for ps in self.parts]
        # part-less tasks ride in a neighbouring kit (docs/timeline.md#part-less-tasks)
        self.needs = [inst.needs_kit(t) for t in self.ids]
        self.twin = self._twins()
        self.tray_area = inst.tray.area
        params = inst.params_of()
        self.o_r, self.o_h, self.d = (
            inst.kit_overhead_robot,
            params.kit_overhead_human,
            params.delivery_time,
        )
        limit = params.tray_limit
        self.trays = limit if limit is not None and limit < self.n else None
        # Johnson's order of the task jobs (r_i, h_i) and where the overhead jobs
        # (o_R + d, o_H) go in it: Johnson's own rule on the tasks plus one overhead job
        order = johnson_order([*self.r, self.o_r + self.d], [*self.h, self.o_h])
        self.overhead_at = order.index(self.n)
        self.johnson = [i for i in order if i != self.n]
        self.rank = [0] * self.n
        for j, i in enumerate(self.johnson):
            self.rank[i] = j
        #: the tasks with parts, most area per robot second first (:func:`_least_robot_time`,
        #: :meth:`kits`)
        self.dense = sorted(
            (i for i in range(self.n) if self.area[i] > 0),
            key=lambda i: -math.inf if self.r[i] <= 0 else -self.area[i] / self.r[i],
        )

    def _twins(self) -> list[int]:
        """For each task, the task of next lower number it is interchangeable with (the same
        parts, times, predecessors and successors), or -1: a plan that does such twins out
        of number order is the same plan with two of them swapped, so kits add a twin only
        after the twin before it (symmetry breaking; the repeated parts of a product unit,
        e.g. a table's four feet)."""
        last: dict[tuple[object, ...], int] = {}
        out = [-1] * self.n
        for i in range(self.n):
            key = (
                tuple(sorted(self.parts[i])),
                self.r[i],
                self.h[i],
                self.needs[i],
                self.pred[i],
                self.succ[i],
            )
            out[i] = last.get(key, -1)
            last[key] = i
        return out

    # -- the timeline --------------------------------------------------------------------
    def root(self) -> tuple[float, ...]:
        """The state before the first kit: human and robot free at 0, every tray home."""
        return (0.0, 0.0) + (0.0,) * max(0, (self.trays or 1) - 1)

    def step(
        self, state: tuple[float, ...], r: float, h: float, station: int = 0
    ) -> tuple[float, ...]:
        """The state after one more kit of robot time ``r`` and human time ``h`` (tasks only;
        the overheads are added here): the timeline's rule (module docstring). ``station``:
        the kit's (one here; :class:`.stations.StationSpace` takes several)."""
        end, nxt = state[0], state[1]
        arrive = nxt + self.o_r + r + self.d
        hs = arrive if arrive > end else end
        new_end = hs + self.o_h + h
        if self.trays is None:
            return (new_end, arrive)
        rets = (*state[2:], hs + self.o_h)  # the last T kits' returns, oldest first
        return (new_end, max(arrive, rets[0]), *rets[1:])

    # -- kits ------------------------------------------------------------------------------
    def children(
        self, done: int, state: tuple[float, ...], below: float
    ) -> Iterator[tuple[int, float, float, int]]:
        """The kits from a node that may lead below ``below``: :meth:`kits` under
        :meth:`kit_cut` (the search's branching, :mod:`.search`)."""
        return self.kits(done, *self.kit_cut(done, state, below))

    def kits(
        self,
        done: int,
        max_r: float = math.inf,
        same_r: float = math.inf,
        min_area: float = -math.inf,
    ) -> Iterator[tuple[int, float, float, int]]:
        """Every kit from the ideal ``done`` whose parts' area fits the tray and that holds a
        task needing a kit: ``(mask, r(S), h(S), station)`` (station 0, the one), each set
        once (tasks added in increasing number), under the cut :class:`Cut` ``(max_r, same_r,
        min_area)`` (:meth:`kit_cut`): a kit's robot time above ``max_r`` cuts that kit and
        every larger one; a kit whose robot time is above ``same_r`` is left out when its
        area is below ``min_area``, and with every larger one when even the most area the
        tasks after it could add within the robot time left to ``max_r`` (a fractional
        knapsack by area per robot second, precedence ignored) stays below ``min_area``."""
        n, pred, cap = self.n, self.pred, self.tray_area * (1 + 1e-12)
        r, h, area, needs, twin = self.r, self.h, self.area, self.needs, self.twin
        free = [i for i in range(n) if not done >> i & 1]
        # the free tasks' positions in the knapsack's order (:attr:`dense`; a task without
        # area adds none, so leaving it out changes no answer)
        at = {i: j for j, i in enumerate(free)}
        dense = [at[i] for i in self.dense if not done >> i & 1]

        def reach(after: int, budget: float, want: float) -> bool:
            """Whether tasks at positions after ``after`` within ``budget`` robot seconds may
            add ``want`` area (the fractional knapsack's upper bound)."""
            got = 0.0
            for j in dense:
                if j <= after:
                    continue
                i = free[j]
                if r[i] <= budget:
                    got += area[i]
                    budget -= r[i]
                else:
                    got += area[i] * budget / r[i]
                    return got >= want
                if got >= want:
                    return True
            return got >= want

        stack: list[tuple[int, int, float, float, float, bool]] = [(0, 0, 0.0, 0.0, 0.0, False)]
        while stack:
            start, mask, rs, hs, ar, real = stack.pop()
            have = done | mask
            for j in range(start, len(free)):
                i = free[j]
                if pred[i] & ~have or (twin[i] >= 0 and not have >> twin[i] & 1):
                    continue
                a2, r2 = ar + area[i], rs + r[i]
                if a2 > cap or r2 > max_r:
                    continue
                m2, real2 = mask | 1 << i, real or needs[i]
                if r2 > same_r and a2 < min_area:  # needs more area: only a larger kit may
                    if reach(j, max_r - r2, min_area - a2):
                        stack.append((j + 1, m2, r2, hs + h[i], a2, real2))
                    continue
                if real2:  # a kit of part-less tasks alone is never needed
                    yield m2, r2, hs + h[i], 0
                stack.append((j + 1, m2, r2, hs + h[i], a2, real2))

    def kit_cut(self, done: int, state: tuple[float, ...], below: float) -> Cut:
        r"""The cut on the kits from this node for a plan below ``below`` (:class:`Cut`,
        :meth:`kits`), from the first term of the child's bound: after a kit ``S`` the human
        ends at least at ``max(nxt + o_R + d + r(S), E) + o_H + h(S)`` and then still needs
        ``h(U \ S)`` and ``o_H`` for each of ``k0(U \ S)`` kits, so

        .. math:: \max(nxt + o_R + d + r(S), E) + h(U) + (1 + k_0(U \setminus S))\, o_H < below

        is needed. A kit takes at most a tray's area, so ``k0(U \ S)`` is ``k0(U) - 1`` or
        ``k0(U)``: ``max_r`` (:meth:`robot_cap`) is the cap with one kit fewer, ``same_r``
        (one ``o_H`` less, plus a margin of ``1e-9 below`` over the float sums' error) the cap
        for a kit that leaves ``k0(U)`` kits, i.e. whose area is below ``min_area = area(U) -
        (k0(U) - 1)`` tray areas (slightly less, a relative margin of 1e-9): a kit these cut
        would fail the search's bound test (:mod:`.search`) anyway, so the children pushed
        are the same, only not generated. ``-inf``: no such kit."""
        c = self.constants(done)
        max_r = self.robot_cap(done, state, below)
        margin = 1e-9 * max(1.0, abs(below))
        slack = below - c.human - self.o_h + margin
        same_r = -math.inf if state[0] >= slack else slack - state[1] - self.o_r - self.d
        if same_r >= max_r:
            return Cut(max_r, math.inf, -math.inf)
        min_area = c.area * (1 - 1e-9) - (c.kits - 1 + _AREA_EPS) * self.tray_area * (1 + 1e-9)
        return Cut(max_r, same_r, min_area)

    def robot_cap(self, done: int, state: tuple[float, ...], below: float) -> float:
        r"""The most robot time a kit from this node may have for a plan below ``below``: after
        a kit ``S`` the human ends at least at ``max(nxt + o_R + d + r(S), E) + o_H + h(S)``
        and then still needs ``h(U \ S)`` and ``o_H`` for each of at least ``k0(U) - 1``
        kits (the kit takes at most a tray's area), so

        .. math:: \max(nxt + o_R + d + r(S), E) + h(U) + \max(1, k_0(U))\, o_H < below

        is needed; it binds only ``r(S)`` and grows with it, so a kit above the cap and every
        larger one are cut (inf: no cap from this bound)."""
        c = self.constants(done)
        slack = below - c.human  # c.human = h(U) + k0(U) o_H
        if state[0] >= slack:
            return -math.inf
        return slack - state[1] - self.o_r - self.d

    def order(self, mask: int) -> list[str]:
        """A kit's task ids in the human's order (increasing number: topological)."""
        return [self.ids[i] for i in range(self.n) if mask >> i & 1]

    # -- the bound -----------------------------------------------------------------------
    def constants(self, done: int) -> Constants:
        """The per-ideal constants of the lower bound (cached)."""
        hit = self._consts.get(done)
        if hit is not None:
            return hit
        left = [i for i in self.johnson if not done >> i & 1]
        r_u = sum(self.r[i] for i in left)
        h_u = sum(self.h[i] for i in left)
        area_u = sum(self.area[i] for i in left)
        k0 = max(1, math.ceil(area_u / self.tray_area - _AREA_EPS))
        a0, b0 = self.o_r + self.d, self.o_h
        human = h_u + k0 * b0
        flow = _johnson_value(
            [(self.r[i], self.h[i]) for i in left], (a0, b0), k0, self._overhead_pos(left)
        )
        robot = r_u + k0 * a0
        sink = min(self.h[i] for i in left if not self.succ[i] & ~done)
        robot_one = r_u + k0 * (a0 + b0) + sink if self.trays == 1 else -math.inf
        ready = min(self.r[i] for i in left if not self.pred[i] & ~done)
        # exactly k0 kits: the next leaves at most (k0 - 1) trays' area to the rest
        need = area_u * (1 - 1e-9) - (k0 - 1) * self.tray_area * (1 + 1e-9)
        least = _least_robot_time(self.dense, self.r, self.area, done, need)
        exact = a0 + (least if least > ready else ready)
        out = Constants(human, flow, robot_one, a0 + ready, exact, robot, sink, area_u, k0)
        self._consts[done] = out
        return out

    def robot_work(self, done: int) -> tuple[float, float]:
        """``(r(U) + k0 (o_R + d), o_H + min sink h)`` of the tasks ``U`` left (the cached
        :meth:`constants`): the robot's least work on them and the least human work after
        their last kit arrives, for the robot term of the several-station bound
        (:class:`.stations.StationSpace`)."""
        c = self.constants(done)
        return c.robot, self.o_h + c.sink

    def _overhead_pos(self, left: list[int]) -> int:
        """Where the overhead jobs go among ``left`` (Johnson's order)."""
        return sum(1 for i in left if self.rank[i] < self.overhead_at)

    def lower_bound(self, done: int, state: tuple[float, ...]) -> float:
        """The state's lower bound on the makespan (module docstring); its makespan when
        ``done`` is every task."""
        if done == self.full:
            return state[0]
        c = self.constants(done)
        b, a = state[0], state[1]
        first, exact = a + c.first, a + c.exact
        # the next kit holds a ready task; with exactly k0 kits left it holds the area the
        # others cannot, with more the human has one more overhead (>= the first's alone)
        fewest = (exact if exact > b else b) + c.human
        more = (first if first > b else b) + c.human + self.o_h
        return max(
            b + c.human,
            a + c.flow,
            fewest if fewest < more else more,
            a + c.robot_one,
        )


def _least_robot_time(
    dense: list[int], r: list[float], area: list[float], done: int, need: float
) -> float:
    """A lower bound on the robot time of a set of the tasks outside ``done`` whose area is at
    least ``need``: the fractional knapsack over ``dense`` (most area per robot second first;
    precedence ignored). 0 when ``need <= 0``, inf when even every task falls short."""
    got = spent = 0.0
    if need <= 0:
        return 0.0
    for i in dense:
        if done >> i & 1:
            continue
        if got + area[i] >= need:
            return spent + r[i] * (need - got) / area[i]
        got += area[i]
        spent += r[i]
    return math.inf


def _johnson_value(
    jobs: list[tuple[float, float]], overhead: tuple[float, float], k: int, at: int
) -> float:
    """The flow-shop makespan with both machines free at 0 (the module docstring's P_U,
    :func:`bilevel_kit.bounds.flow_shop_makespan`) of ``jobs`` in order with ``k`` copies of
    ``overhead`` inserted before position ``at``."""
    seq = jobs[:at] + [overhead] * k + jobs[at:]
    a, b = [x for x, _ in seq], [y for _, y in seq]
    return flow_shop_makespan(range(len(seq)), a, b)
