"""One run's time budget, shared by the exact solvers and their sub-steps.

A method's ``time_limit`` covers everything it does (packing, model building, every solve), so
each sub-step asks the budget how long it may take instead of doing its own deadline
arithmetic. All times are :func:`time.perf_counter` values.

The exact models also check their size here before building (:func:`check_model_memory`,
:func:`too_slow_to_build`): a model over the memory limit is a usage error (exit 2, never a
kernel kill), one that cannot be built in time leaves the run with its incumbent.
"""

from __future__ import annotations

import contextlib
import time
from collections.abc import Iterator

#: Seconds a method runs when the caller gives no time limit.
DEFAULT_TIME_LIMIT = 60.0


class Budget:
    """``time_limit`` seconds from ``start``; the ``deadline`` keeps ``keep_back`` x the limit
    in reserve (CP-SAT stops a little after its own limit on large models).

    ``stretch`` (> 1 for a reproducible run, :attr:`deterministic`,
    docs/simulation.md#determinism): every sub-step's share (:meth:`share`, :meth:`next`,
    :meth:`head`) is the whole budget, so the steps are limited by work or deterministic time
    alone and the budget's deadline is their one wall-clock safety net, far above what they
    need; when a step sees it (or a wall-clock safety net of its own fires) it says so with
    :meth:`net_fired`, which a run reports (:attr:`net`, shared with every sub-budget)."""

    def __init__(
        self,
        time_limit: float | None = None,
        *,
        keep_back: float = 0.0,
        start: float | None = None,
        deadline: float | None = None,
        stretch: float = 1.0,
        record: list[bool] | None = None,
    ) -> None:
        self.start = time.perf_counter() if start is None else start
        self.time_limit = DEFAULT_TIME_LIMIT if time_limit is None else float(time_limit)
        if deadline is None:
            deadline = self.start + self.time_limit - keep_back * self.time_limit
        self.deadline = deadline
        self.stretch = stretch
        self._record = record if record is not None else []

    @property
    def deterministic(self) -> bool:
        """A reproducible run's budget: its clock is a safety net only (class docstring)."""
        return self.stretch != 1.0

    @property
    def net(self) -> bool:
        """Has a wall-clock safety net of this reproducible run fired (:meth:`net_fired`)?"""
        return bool(self._record)

    def net_fired(self) -> None:
        """Record that a wall-clock safety net cut a step of this run short."""
        if not self._record:
            self._record.append(True)

    def _part(self, fraction: float) -> float:
        return 1.0 if self.deterministic else min(1.0, fraction * self.stretch)

    def __repr__(self) -> str:
        return f"Budget(time_limit={self.time_limit!r}, remaining={self.remaining():.3f})"

    def remaining(self, margin: float = 0.0) -> float:
        """Seconds left before the deadline less ``margin`` (negative once it has passed)."""
        return self.deadline - time.perf_counter() - margin

    def expired(self, margin: float = 0.0) -> bool:
        """Has the deadline (less ``margin``) passed? (In a reproducible run: its safety net
        fired, recorded.)"""
        out = time.perf_counter() > self.deadline - margin
        if out and self.deterministic:
            self.net_fired()
        return out

    def elapsed(self) -> float:
        """Seconds since the budget started."""
        return time.perf_counter() - self.start

    def share(self, fraction: float, margin: float = 0.0) -> float:
        """The deadline of a sub-step that may use ``fraction`` of what is left (less
        ``margin``); never in the past."""
        return time.perf_counter() + max(0.0, self._part(fraction) * self.remaining(margin))

    def cut(self, margin: float) -> Budget:
        """The same budget ending ``margin`` seconds earlier (time kept back for the end)."""
        return self._sub(self.deadline - margin)

    def next(self, fraction: float) -> Budget:
        """The next ``fraction`` of what is left (a quick step after slow set-up work, which
        :meth:`head` would have eaten into)."""
        return self._sub(self.share(fraction))

    def head(self, fraction: float) -> Budget:
        """The first ``fraction`` of the time limit (a quick first step), within the deadline."""
        return self._sub(min(self.deadline, self.start + self._part(fraction) * self.time_limit))

    @contextlib.contextmanager
    def capped(self, deadline: float) -> Iterator[None]:
        """This budget ending at ``deadline`` at the latest while the block runs (the sub-budgets
        made in it keep that end), its own deadline restored after it: a step that must leave
        time for a later one (the exact models' LNS after the model, docs/formulations.md)."""
        saved = self.deadline
        self.deadline = min(saved, deadline)
        try:
            yield
        finally:
            self.deadline = saved

    def _sub(self, deadline: float) -> Budget:
        return Budget(
            self.time_limit,
            start=self.start,
            deadline=deadline,
            stretch=self.stretch,
            record=self._record,
        )


# ---------------------------------------------------------------------------------------------
# Model size: memory limit and build time
# ---------------------------------------------------------------------------------------------

#: Peak resident memory (bytes) a method may need; a larger model is refused before it is built.
MEMORY_LIMIT = 2 * 1024**3
#: Memory (bytes) a run needs besides its model: Python, OR-Tools, the instance, caches.
BASE_MEMORY = 450 * 1024**2
#: A model is not built when its estimated build time exceeds this share of the time left.
BUILD_SHARE = 0.5


def check_model_memory(owner: str, cells: int, bytes_per_cell: float, what: str) -> float:
    """Refuse (``UsageError``, exit 2) a model whose estimated peak memory
    ``BASE_MEMORY + cells * bytes_per_cell`` exceeds :data:`MEMORY_LIMIT`; else the estimate
    in bytes. ``bytes_per_cell`` is measured per solver (bench/results/scale.md)."""
    from ..errors import UsageError

    refusal = memory_refusal(owner, cells, bytes_per_cell, what)
    if refusal is not None:
        raise UsageError(f"{refusal}; use greedy-ce, or fewer tasks (--units, --horizon)")
    return BASE_MEMORY + cells * bytes_per_cell


def memory_refusal(owner: str, cells: int, bytes_per_cell: float, what: str) -> str | None:
    """Why a model of ``cells`` task x kit variables is too large for :data:`MEMORY_LIMIT`
    (None: it is not). An exact method holding a plan returns that plan instead of failing."""
    need = BASE_MEMORY + cells * bytes_per_cell
    if need <= MEMORY_LIMIT:
        return None
    return (
        f"{owner}: the model would have {cells:,} {what}, about {need / 2**30:.1f} GB, above "
        f"the {MEMORY_LIMIT / 2**30:g} GB memory limit"
    )


def no_model_reason(
    owner: str,
    cells: int,
    costs: tuple[float, float],
    what: str,
    budget: Budget,
    margin: float,
    has_plan: bool,
) -> tuple[str, str] | None:
    """Why an exact method builds no model of ``cells`` task x kit variables, given its
    measured ``costs`` (bytes and build seconds per variable): ``("too_large", reason)`` over
    the memory limit while it holds a plan (a ``UsageError`` without one), ``("not_built",
    reason)`` when it would not be built within the time left; None: build it. The caller
    names the outcome in its own ``extra`` keys (docs/formulations.md, "Model too large")."""
    bytes_per_cell, build_s_per_cell = costs
    refusal = memory_refusal(owner, cells, bytes_per_cell, what)
    if refusal is not None and has_plan:
        return "too_large", refusal
    check_model_memory(owner, cells, bytes_per_cell, what)
    estimate = cells * build_s_per_cell
    if too_slow_to_build(budget, estimate, margin):
        why = f"a model of {cells:,} task x kit variables would not be built and solved"
        left = budget.remaining(margin)
        return (
            "not_built",
            f"{why} within the time limit (about {estimate:.1f} s to build, {left:.1f} s left)",
        )
    return None


def too_slow_to_build(budget: Budget, estimate_s: float, margin: float = 0.0) -> bool:
    """Would building a model (``estimate_s`` seconds) take more than :data:`BUILD_SHARE` of
    the time left? Then the run keeps its incumbent instead of overrunning its limit (in a
    reproducible run that is its safety net firing, recorded)."""
    out = estimate_s > BUILD_SHARE * budget.remaining(margin)
    if out and budget.deterministic:
        budget.net_fired()
    return out
