"""Live progress of a long solve: the best plan's objective, the proven bound, the gap.

A caller passes a *sink* (any callable taking an :class:`Update`) to
:func:`bilevel_kit.methods.solve` (``progress=``), or installs one with :func:`reporting`. A
method that can report asks :func:`tracker` for a :class:`Tracker` and tells it what it knows:
the objective of its best *valid* plan (``incumbent``) and a *proven* lower bound on it
(``bound``), both in the instance's time unit (seconds). The tracker keeps the best of each,
so the sink sees incumbents that never increase and bounds that never decrease, and forwards
only changes. Without a sink (the default) :func:`tracker` returns a tracker that does
nothing, so results never depend on whether progress is shown.

:class:`LiveLine` is the terminal sink of ``bilevel-kit solve``: one line on stderr rewritten
in place (``\\r``) at most twice a second, with a final newline, and silent unless the stream is
a terminal (or ``force=True``). Only the standard library is imported here.
"""

from __future__ import annotations

import contextlib
import contextvars
import sys
import threading
import time
from collections.abc import Callable, Iterator
from dataclasses import dataclass, replace
from types import TracebackType
from typing import IO

from .objectives import relative_gap


@dataclass(frozen=True)
class Update:
    """What a solve knows at ``elapsed`` seconds after it started.

    ``incumbent``: objective of the best valid plan found (None: none yet); ``bound``: a proven
    lower bound on the optimum of ``objective`` (None: none); ``stage``: what runs now
    (``warm start``, ``CP-SAT``, ``HiGHS`` ...); ``unit``: the objective's unit.
    """

    objective: str
    incumbent: float | None
    bound: float | None
    elapsed: float
    stage: str = ""
    unit: str = "s"

    @property
    def gap(self) -> float | None:
        """(incumbent - bound) / incumbent: the one gap, :func:`~.objectives.relative_gap`."""
        return relative_gap(self.incumbent, self.bound)


#: A progress sink: called with every change of a solve's incumbent, bound or stage.
Sink = Callable[[Update], None]


@dataclass
class _Session:
    """The installed sink, when it was installed and its trackers (one per objective)."""

    sink: Sink
    start: float
    trackers: dict[tuple[str, str], Tracker]


_SESSION: contextvars.ContextVar[_Session | None] = contextvars.ContextVar(
    "bilevel_kit_progress", default=None
)


@contextlib.contextmanager
def reporting(sink: Sink | None) -> Iterator[None]:
    """Send the progress of the solve run inside to ``sink`` (None: silence); elapsed times
    count from entering."""
    session = None if sink is None else _Session(sink, time.perf_counter(), {})
    token = _SESSION.set(session)
    try:
        yield
    finally:
        _SESSION.reset(token)


class Tracker:
    """The best incumbent and bound of one solve, forwarded to the sink when they change.

    Thread-safe: CP-SAT calls back from its worker threads, the HiGHS pipe from a reader
    thread. A bound above the incumbent (solver float noise) is shown as the incumbent.
    """

    def __init__(
        self, sink: Sink | None, objective: str, start: float, unit: str = "s", stage: str = ""
    ) -> None:
        self.sink = sink
        self.objective = objective
        self.unit = unit
        self.start = start
        self.incumbent: float | None = None
        self.bound: float | None = None
        self.stage = stage
        self._lock = threading.Lock()

    @property
    def active(self) -> bool:
        """Does anyone listen (else callers may skip work done only to report)?"""
        return self.sink is not None

    def report(
        self, incumbent: float | None = None, bound: float | None = None, stage: str | None = None
    ) -> None:
        """Tell what is known now; values no better than the best so far are ignored."""
        if self.sink is None:
            return
        with self._lock:
            changed = False
            if incumbent is not None and (self.incumbent is None or incumbent < self.incumbent):
                self.incumbent, changed = incumbent, True
            if bound is not None and (self.bound is None or bound > self.bound):
                self.bound, changed = bound, True
            if stage is not None and stage != self.stage:
                self.stage, changed = stage, True
            if not changed:
                return
            shown = self.bound
            if shown is not None and self.incumbent is not None:
                shown = min(shown, self.incumbent)
            update = Update(
                self.objective,
                self.incumbent,
                shown,
                time.perf_counter() - self.start,
                self.stage,
                self.unit,
            )
            self.sink(update)


def tracker(objective: str = "makespan", unit: str = "s") -> Tracker:
    """The tracker of ``objective`` in the current solve: the same one for every step that asks
    (a warm start, then the model), one that does nothing when no sink is installed."""
    session = _SESSION.get()
    if session is None:
        return Tracker(None, objective, time.perf_counter(), unit)
    key = (objective, unit)
    if key not in session.trackers:
        session.trackers[key] = Tracker(session.sink, objective, session.start, unit)
    return session.trackers[key]


def _number(value: float | None, unit: str) -> str:
    if value is None:
        return "-"
    return f"{value:.2f} {unit}" if unit else f"{value:.4g}"


def format_line(update: Update) -> str:
    """The live line: elapsed time, stage, incumbent, bound and gap (as the summary line)."""
    gap = update.gap
    name = update.objective.replace("_", " ")
    parts = [f"{update.elapsed:6.1f} s"]
    if update.stage:
        parts.append(update.stage)
    parts += [
        f"{name} {_number(update.incumbent, update.unit)}",
        f"bound {_number(update.bound, update.unit)}",
        f"gap {'-' if gap is None else f'{100 * gap:.2f}%'}",
    ]
    return "  ".join(parts)


def is_terminal(stream: IO[str]) -> bool:
    try:
        return stream.isatty()
    except (AttributeError, ValueError):  # no isatty, or a closed stream
        return False


class LiveLine:
    """A sink drawing :func:`format_line` on one terminal line (module docstring).

    Use as a context manager: inside, a ticker redraws the line every ``interval`` seconds
    (the elapsed time advances between updates); leaving ends the line with a newline. Updates
    between two draws replace each other: at most one draw per ``interval``.
    """

    def __init__(
        self,
        stream: IO[str] | None = None,
        *,
        force: bool = False,
        quiet: bool = False,
        interval: float = 0.5,
    ) -> None:
        self.stream = sys.stderr if stream is None else stream
        #: Drawing at all: not ``quiet``, and on a terminal unless ``force``.
        self.enabled = not quiet and (force or is_terminal(self.stream))
        self.interval = interval
        self._last: Update | None = None
        self._received = 0.0
        self._drawn_at: float | None = None
        self._width = 0
        self._lock = threading.Lock()
        self._stop = threading.Event()
        self._ticker: threading.Thread | None = None

    def __call__(self, update: Update) -> None:
        if not self.enabled:
            return
        with self._lock:
            self._last, self._received = update, time.perf_counter()
            if self._drawn_at is None or self._received - self._drawn_at >= self.interval:
                self._draw()

    def _draw(self) -> None:
        """Write the last update, its elapsed time advanced to now (lock held)."""
        if self._last is None:
            return
        now = time.perf_counter()
        text = format_line(replace(self._last, elapsed=self._last.elapsed + now - self._received))
        self.stream.write("\r" + text.ljust(self._width))
        self.stream.flush()
        self._width, self._drawn_at = len(text), now

    def _tick(self) -> None:
        while not self._stop.wait(self.interval):
            with self._lock:
                self._draw()

    def __enter__(self) -> LiveLine:
        if self.enabled:
            self._ticker = threading.Thread(target=self._tick, name="live-line", daemon=True)
            self._ticker.start()
        return self

    def __exit__(
        self,
        exc_type: type[BaseException] | None,
        exc: BaseException | None,
        tb: TracebackType | None,
    ) -> None:
        self._stop.set()
        if self._ticker is not None:
            self._ticker.join()
        with self._lock:
            if self._last is not None:
                self._draw()
                self.stream.write("\n")
                self.stream.flush()
