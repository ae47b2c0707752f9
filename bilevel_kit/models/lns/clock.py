r"""The state of the timeline after a window of kits, with several stations: what the exact
windows of :mod:`.stations` compare before timing a whole plan.

The timeline (docs/timeline.md#several-stations) after a run of kits depends on them only
through its *end state*: the last arrival, each station's human end and, for a station with
``T`` trays, the human starts of its last ``T`` kits. Every later time is a maximum of sums of
these and of durations (max-plus), so it is non-decreasing in each of them: a rearrangement of
a window whose end state is at least the incumbent's everywhere cannot lower the makespan or
the sum of completions; for the human idle, which subtracts the human's kit overheads, it
cannot when it also has no more kits at any station. The rule is that of
:func:`..cpsat.scaling.stations_timeline` on the same integer times, stepped from a state
instead of from the start; tests/models/test_lns_stations.py holds the two together.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

from ..cpsat.scaling import Scaled, pick_end


@dataclass
class Clock:
    """The end state (module docstring): ``arrive``; per station index ``done`` (its human
    end) and ``starts`` (its human starts, oldest first); ``kits`` per station."""

    arrive: int
    done: list[int]
    starts: list[list[int]]
    kits: list[int]

    @classmethod
    def start(cls, sc: Scaled) -> Clock:
        n = max(1, len(sc.st_d))
        return cls(0, [0] * n, [[] for _ in range(n)], [0] * n)

    def copy(self) -> Clock:
        return Clock(self.arrive, list(self.done), [list(s) for s in self.starts], list(self.kits))

    def step(self, sc: Scaled, kit: Sequence[int]) -> None:
        """Deliver ``kit`` (a used kit of task indices) after the kits so far."""
        if sc.station:
            s = sc.station[kit[0]]
            d, o_h, trays = sc.st_d[s], sc.st_oh[s], sc.st_trays[s]
        else:  # one station: the instance's own
            s, d, o_h, trays = 0, sc.d, sc.o_h, sc.trays
        mine = self.starts[s]
        start = self.arrive
        if trays is not None and len(mine) >= trays:  # its T_s-th previous kit's tray is back
            start = max(start, mine[-trays] + o_h)
        self.arrive = pick_end(sc, start, kit) + d
        human_start = max(self.arrive, self.done[s])
        mine.append(human_start)
        if trays is not None and len(mine) > trays:
            del mine[0]  # only the last T_s starts matter from here on
        self.done[s] = human_start + o_h + sum(sc.h[i] for i in kit)
        self.kits[s] += 1

    def key(self, sc: Scaled, idle: bool) -> tuple[int, ...]:
        """The end state as a vector in which larger is never better (``idle``: the kit
        counts too, negated)."""
        out = [self.arrive, *self.done]
        for s, mine in enumerate(self.starts):
            trays = sc.st_trays[s] if sc.station else sc.trays
            if trays is not None:
                out += [-1] * (trays - len(mine)) + mine[-trays:]  # -1: a tray never used
        if idle:
            out += [-k for k in self.kits]
        return tuple(out)


def dominated(key: Sequence[int], by: Sequence[int]) -> bool:
    """``key`` is at least ``by`` everywhere: no better plan follows from it."""
    return all(a >= b for a, b in zip(key, by, strict=True))
