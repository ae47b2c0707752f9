"""One run's time budget, shared by the exact solvers and their sub-steps.

A method's ``time_limit`` covers everything it does (packing, model building, every solve), so
each sub-step asks the budget how long it may take instead of doing its own deadline
arithmetic. All times are :func:`time.perf_counter` values.
"""

from __future__ import annotations

import time

#: Seconds a method runs when the caller gives no time limit.
DEFAULT_TIME_LIMIT = 60.0


class Budget:
    """``time_limit`` seconds from ``start``; the ``deadline`` keeps ``keep_back`` x the limit
    in reserve (CP-SAT stops a little after its own limit on large models)."""

    def __init__(
        self,
        time_limit: float | None = None,
        *,
        keep_back: float = 0.0,
        start: float | None = None,
        deadline: float | None = None,
    ) -> None:
        self.start = time.perf_counter() if start is None else start
        self.time_limit = DEFAULT_TIME_LIMIT if time_limit is None else float(time_limit)
        if deadline is None:
            deadline = self.start + self.time_limit - keep_back * self.time_limit
        self.deadline = deadline

    def __repr__(self) -> str:
        return f"Budget(time_limit={self.time_limit!r}, remaining={self.remaining():.3f})"

    def remaining(self, margin: float = 0.0) -> float:
        """Seconds left before the deadline less ``margin`` (negative once it has passed)."""
        return self.deadline - time.perf_counter() - margin

    def expired(self, margin: float = 0.0) -> bool:
        """Has the deadline (less ``margin``) passed?"""
        return time.perf_counter() > self.deadline - margin

    def elapsed(self) -> float:
        """Seconds since the budget started."""
        return time.perf_counter() - self.start

    def share(self, fraction: float, margin: float = 0.0) -> float:
        """The deadline of a sub-step that may use ``fraction`` of what is left (less
        ``margin``); never in the past."""
        return time.perf_counter() + max(0.0, fraction * self.remaining(margin))

    def cut(self, margin: float) -> Budget:
        """The same budget ending ``margin`` seconds earlier (time kept back for the end)."""
        return Budget(self.time_limit, start=self.start, deadline=self.deadline - margin)

    def head(self, fraction: float) -> Budget:
        """The first ``fraction`` of the time limit (a quick first step), within the deadline."""
        end = min(self.deadline, self.start + fraction * self.time_limit)
        return Budget(self.time_limit, start=self.start, deadline=end)
