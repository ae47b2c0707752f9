r"""The search space of :mod:`.search` with several assembly stations (docs/formulations.md,
"Branch, bound and remember", and docs/timeline.md#several-stations): one robot, a kit of one
station's tasks at a time.

**Tasks** are numbered station by station, each station's block in its own topological order
(:class:`.space.Space` on the station's instance, :func:`bilevel_kit.stations.
station_instance`): stations share no precedence, so the union of the blocks' ideals is an
ideal of the whole graph, and a kit (one station's tasks) in increasing number is a valid human
order.

**State** after the kits that complete ``J``: ``F``, the arrival of the last kit (the robot is
free then), and per station ``s`` with tasks its human's end ``E_s`` and, when its ``T_s`` trays
bind, the returns ``human_start + o_H,s`` of its last ``T_s`` kits, oldest first (0 while fewer
are out). A kit ``S`` of station ``s`` moves it by the timeline's rule: the robot starts at
``g = max(F, ret_s)`` (``ret_s`` the oldest return, absent without a binding limit),
``arrive = g + o_R + r(S) + d_s``, ``hs = max(arrive, E_s)``, ``E_s' = hs + o_H,s + h(S)``,
``F' = arrive``, and the tray of ``S`` returns at ``hs + o_H,s``. Every later time is a
max-plus expression of these components, non-decreasing in each, so the dominance of the one
station holds: same ideal, componentwise at most.

**Lower bound** on the makespan ``max_s C_s``, with ``U_s`` station ``s``'s tasks left:

.. math::

   LB = \max\Bigl(\max_s LB_s(g_s, E_s),\
        F + \sum_{s:\,U_s \ne \emptyset} \bigl(r(U_s) + k_0(U_s)\,(o_R + d_s)\bigr)
          + \min_{s:\,U_s \ne \emptyset} \bigl(o_{H,s} + \min_{i \in U_s\ \mathrm{sink}}
          h_i\bigr)\Bigr)

with ``LB_s`` the one-station bound of :mod:`.space` on ``U_s`` with the robot free at
``g_s = max(F, ret_s)`` and the human at ``E_s`` (``E_s`` itself when ``U_s`` is empty): the
other stations' kits only delay the robot, so it holds for ``C_s``. The second term is the
robot's: it builds every kit left one after another, at least ``k_0(U_s)`` for station ``s``,
and the last kit's human works at least its overhead and a task with no successor left after
it arrives. The one-station cut on a kit's robot time and area (:meth:`.space.Space.kit_cut`)
holds per station with ``(g_s, E_s)``.
"""

from __future__ import annotations

import math
from collections.abc import Iterator

from ...instance import Instance
from ...stations import station_instance
from .space import Space


class StationSpace:
    """Several stations' instance, indexed for the search (module docstring)."""

    def __init__(self, instance: Instance) -> None:
        self.instance = instance
        busy = {t.station for t in instance.tasks}
        #: one :class:`.space.Space` per station with tasks, in the file's order
        self.spaces = [
            Space(station_instance(instance, s)) for s in instance.station_ids if s in busy
        ]
        self.offsets: list[int] = []
        #: where each station's ``E_s`` is in the state (its returns follow)
        self.at: list[int] = []
        self.ids: list[str] = []
        width = 1
        for sp in self.spaces:
            self.offsets.append(len(self.ids))
            self.ids += sp.ids
            self.at.append(width)
            width += 1 + (sp.trays or 0)
        self.width = width
        self.n = len(self.ids)
        self.full = (1 << self.n) - 1
        self.o_r = instance.kit_overhead_robot

    def root(self) -> tuple[float, ...]:
        """The state before the first kit: robot and humans free at 0, every tray home."""
        return (0.0,) * self.width

    def _part(self, done: int, s: int) -> int:
        """Station ``s``'s ideal (in its own numbering) within ``done``."""
        return done >> self.offsets[s] & self.spaces[s].full

    def _robot_free(self, state: tuple[float, ...], s: int) -> float:
        """``g_s``: the earliest robot start of station ``s``'s next kit (module docstring)."""
        free = state[0]
        if self.spaces[s].trays is None:
            return free
        ret = state[self.at[s] + 1]
        return ret if ret > free else free

    def step(
        self, state: tuple[float, ...], r: float, h: float, station: int = 0
    ) -> tuple[float, ...]:
        """The state after one more kit of ``station`` with robot time ``r`` and human time
        ``h`` (tasks only; the overheads are added here): the timeline's rule."""
        sp, p = self.spaces[station], self.at[station]
        arrive = self._robot_free(state, station) + self.o_r + r + sp.d
        end = state[p]
        hs = arrive if arrive > end else end
        new_end = hs + sp.o_h + h
        if sp.trays is None:
            return (arrive, *state[1:p], new_end, *state[p + 1 :])
        q = p + 1 + sp.trays
        return (arrive, *state[1:p], new_end, *state[p + 2 : q], hs + sp.o_h, *state[q:])

    def makespan(self, state: tuple[float, ...]) -> float:
        """The latest human end, the makespan of a complete plan."""
        return max(state[p] for p in self.at)

    def lower_bound(self, done: int, state: tuple[float, ...]) -> float:
        """The state's lower bound on the makespan (module docstring); its makespan when
        ``done`` is every task."""
        if done == self.full:
            return self.makespan(state)
        free = state[0]
        best, robot, tail = -math.inf, 0.0, math.inf
        for s, sp in enumerate(self.spaces):
            part, end = self._part(done, s), state[self.at[s]]
            if part == sp.full:
                best = end if end > best else best
                continue
            own = sp.lower_bound(part, (end, self._robot_free(state, s)))
            best = own if own > best else best
            work, last = sp.robot_work(part)
            robot += work
            tail = last if last < tail else tail
        return max(best, free + robot + tail)

    def children(
        self, done: int, state: tuple[float, ...], below: float
    ) -> Iterator[tuple[int, float, float, int]]:
        """Every kit of one station from a node (:meth:`.space.Space.kits` of each station
        with tasks left) under that station's cut on its robot time and area for a plan
        below ``below`` (:meth:`.space.Space.kit_cut` with ``(g_s, E_s)``, module docstring):
        ``(mask, r(S), h(S), station)``."""
        for s, sp in enumerate(self.spaces):
            part = self._part(done, s)
            if part == sp.full:
                continue
            cut = sp.kit_cut(part, (state[self.at[s]], self._robot_free(state, s)), below)
            if cut.max_r == -math.inf:
                continue
            off = self.offsets[s]
            for mask, r, h, _ in sp.kits(part, *cut):
                yield mask << off, r, h, s

    def order(self, mask: int) -> list[str]:
        """A kit's task ids in the human's order (increasing number: topological)."""
        return [self.ids[i] for i in range(self.n) if mask >> i & 1]
