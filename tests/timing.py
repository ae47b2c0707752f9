"""Wall-clock limits in tests, load-aware: a time limit is promised as ``T + max(2 s, 5 %)``
on a machine that runs nothing else (docs/scaling.md); on a busy machine the work after the
deadline (evaluating, checking, closing a solver) takes longer in wall time although the code
stops at the same point, so the slack grows with the load average per core. The strict bound
is measured in ``bench/`` on a quiet machine; tests check the mechanism (the solve stops)."""

from __future__ import annotations

import os


def load_factor() -> float:
    """The 1-minute load average per core, at least 1 (1 on a machine without it)."""
    try:
        load = os.getloadavg()[0]
    except OSError:
        return 1.0
    return max(1.0, load / (os.cpu_count() or 1))


def allowed(limit: float, slack: float | None = None) -> float:
    """The wall time a call with time limit ``limit`` may take here: ``limit`` plus the
    slack (default ``max(2 s, 5 %)``) times :func:`load_factor`."""
    base = max(2.0, 0.05 * limit) if slack is None else slack
    return limit + base * load_factor()
