r"""The incumbent's end state after each of its kits, with several stations: what lets the
search of :mod:`.stations` reject candidates without timing the whole plan
(docs/stations.md#lns-with-several-stations).

A candidate differs from the incumbent in a run of kits and shares the rest: the same kits
before (the incumbent's state there is the candidate's too) and the same kits after. Stepped
(:class:`..cpsat.scaling.Clock`) over its own run, then along the shared kits after it, the
candidate's state is compared with the incumbent's at the same place of those shared kits:
once it is at least the incumbent's everywhere (:func:`.clock.dominated`), the rest of the
timeline cannot make the candidate's objective lower than the incumbent's (the timeline is
max-plus, the argument of :mod:`.clock`), so it is *hopeless*. A full timing steps every kit
of the plan; a hopeless candidate often shows it within a few kits after its run.
"""

from __future__ import annotations

from ..cpsat.scaling import Clock, Scaled
from .clock import dominated, end_key
from .enumerate import Kits


class Trail:
    """The incumbent ``kits`` and its state before each kit and after the last (``keys``:
    their vectors of :func:`.clock.end_key`; ``idle``: the kit counts are part of them)."""

    def __init__(self, sc: Scaled, kits: Kits, idle: bool, since: Trail | None = None) -> None:
        """``since``: an earlier incumbent's trail, whose states before the first kit that
        differs are kept (an improvement changes a few kits; the prefix is most of the plan)."""
        self.sc, self.kits, self.idle = sc, kits, idle
        self.clocks: list[Clock]
        self.keys: list[tuple[int, ...]]
        lo = 0
        if since is not None:
            old = since.kits
            while lo < min(len(kits), len(old)) and kits[lo] == old[lo]:
                lo += 1
            self.clocks, self.keys = since.clocks[: lo + 1], since.keys[: lo + 1]
        else:
            self.clocks, self.keys = [Clock.start(sc)], [end_key(sc, Clock.start(sc), idle)]
        clock = self.clocks[-1].copy()
        for kit in kits[lo:]:
            clock.step(sc, kit)
            self.clocks.append(clock.copy())
            self.keys.append(end_key(sc, clock, idle))

    def hopeless(self, kits: Kits) -> bool:
        """Whether ``kits``' objective is at least the incumbent's: its state is dominated by
        the incumbent's somewhere along their common kits after its change (module docstring).
        Kits are compared by identity (a move shares the incumbent's unchanged kit lists), so
        a kit equal but rebuilt only makes the changed run longer."""
        inc, n, m = self.kits, len(kits), len(self.kits)
        lo = 0
        while lo < min(n, m) and kits[lo] is inc[lo]:
            lo += 1
        tail = 0  # kits shared at the end, after the changed run
        while tail < min(n, m) - lo and kits[n - 1 - tail] is inc[m - 1 - tail]:
            tail += 1
        clock = self.clocks[lo].copy()
        for kit in kits[lo : n - tail]:
            clock.step(self.sc, kit)
        for j in range(m - tail, m + 1):  # the incumbent's place of the same shared kits
            if dominated(end_key(self.sc, clock, self.idle), self.keys[j]):
                return True
            if j < m:
                clock.step(self.sc, inc[j])
        return False
