r"""When one end state of a window of kits is no better than another: what the exact windows of
:mod:`.stations` compare before timing a whole plan.

The timeline (docs/timeline.md#several-stations) after a run of kits depends on them only
through its *end state*, the :class:`~..cpsat.scaling.Clock` the integer timelines step: the
last arrival, each station's human end and, for a station with ``T`` trays, the human starts
of its last ``T`` kits. Every later time is a maximum of sums of these and of durations
(max-plus), so it is non-decreasing in each of them: a rearrangement of a window whose end
state is at least the incumbent's everywhere cannot lower the makespan or the sum of
completions; for the human idle, which subtracts the human's kit overheads, it cannot when it
also has no more kits at any station.
"""

from __future__ import annotations

from collections.abc import Sequence

from ..cpsat.scaling import Clock, Scaled


def end_key(sc: Scaled, clock: Clock, idle: bool) -> tuple[int, ...]:
    """The end state as a vector in which larger is never better (``idle``: the kit counts
    too, negated)."""
    out = [clock.arrive, *clock.done]
    for s, mine in enumerate(clock.starts):
        trays = sc.st_trays[s] if sc.station else sc.trays
        if trays is not None:
            out += [-1] * (trays - len(mine)) + mine[-trays:]  # -1: a tray never used
    if idle:
        out += [-k for k in clock.kits]
    return tuple(out)


def dominated(key: Sequence[int], by: Sequence[int]) -> bool:
    """``key`` is at least ``by`` everywhere: no better plan follows from it."""
    return all(a >= b for a, b in zip(key, by, strict=True))
