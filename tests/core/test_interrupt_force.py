"""The watchdog's forced exit adds no second line once the command printed its own (a busy
machine's slow exit after an interrupt printed "interrupted" twice)."""

from __future__ import annotations

import io
import signal
import threading
import time

import pytest

from bilevel_kit import interrupt


class Exited(Exception):
    pass


@pytest.fixture
def forced(monkeypatch):
    """The guard's forced exit, recording what it writes instead of ending the process."""
    written: list[bytes] = []
    monkeypatch.setattr(interrupt.os, "write", lambda fd, data: written.append(data))

    def exit_(code):
        raise Exited(code)

    monkeypatch.setattr(interrupt.os, "_exit", exit_)
    monkeypatch.setattr(interrupt, "_REPORTED", interrupt.threading.Event())
    guard = interrupt._Guard(grace=1.0)
    yield guard, written
    guard.reader.close()
    guard.writer.close()


def test_a_forced_exit_says_so_when_nothing_was_printed(forced):
    guard, written = forced
    with pytest.raises(Exited, match="130"):
        guard._force(signal.SIGTERM)
    assert written == [b"bilevel-kit: interrupted (SIGTERM) (forced)\n"]


def test_a_forced_exit_after_the_commands_line_is_silent(forced):
    guard, written = forced
    out = io.StringIO()
    interrupt.report(interrupt.Terminated(), out)
    assert out.getvalue() == "bilevel-kit: interrupted (SIGTERM)\n"
    with pytest.raises(Exited, match="130"):
        guard._force(signal.SIGTERM)
    assert written == []


def test_a_forced_exit_while_the_commands_line_is_written_waits_for_it(forced):
    """The race a busy machine hit once: the watchdog fires between the command's line and
    its record of it. It waits for the line and then stays silent (one line, never two)."""
    guard, written = forced
    out = io.StringIO()
    fired: list[BaseException] = []

    class SlowStream(io.StringIO):
        def flush(self) -> None:  # the watchdog fires while the line is being written
            thread = threading.Thread(target=lambda: _force_into(guard, fired))
            thread.start()
            thread.join(timeout=0.2)  # it is held at the lock, not finished
            assert thread.is_alive()
            out.write(self.getvalue())
            self._thread = thread

    stream = SlowStream()
    interrupt.report(interrupt.Terminated(), stream)
    stream._thread.join(timeout=5.0)
    assert out.getvalue() == "bilevel-kit: interrupted (SIGTERM)\n"
    assert written == [] and [str(e) for e in fired] == ["130"]


def test_a_forced_exit_during_a_summary_line_writes_its_own_after_that_lines_end(forced):
    """The race a busy machine hit once: a sweep's summary ("compare: 1 done ...
    (interrupted)") and the watchdog's line on one line. ``say`` writes the line with its
    newline in one write under the watchdog's lock, so the forced line comes after it."""
    guard, written = forced
    order: list[str] = []
    fired: list[BaseException] = []

    class SlowStream(io.StringIO):
        def write(self, text: str) -> int:
            thread = threading.Thread(target=lambda: _force_into(guard, fired))
            thread.start()
            thread.join(timeout=0.2)  # held at the lock while the line is written
            assert thread.is_alive()
            order.append(text)
            self._thread = thread
            return len(text)

    stream = SlowStream()
    interrupt.say("compare: 1 done, 0 skipped, 0 failed of 2 cells in 3.0 s (interrupted)", stream)
    assert order == ["compare: 1 done, 0 skipped, 0 failed of 2 cells in 3.0 s (interrupted)\n"]
    stream._thread.join(timeout=5.0)
    # not a command's interrupt line: the watchdog still writes its own, on a line of its own
    assert written == [b"bilevel-kit: interrupted (SIGTERM) (forced)\n"]
    assert [str(e) for e in fired] == ["130"]


def _force_into(guard, fired: list[BaseException]) -> None:
    try:
        guard._force(signal.SIGTERM)
    except Exited as exc:
        fired.append(exc)


def _swallowed_signal(sig: int) -> None:
    """A signal whose exception some code swallowed (as OR-Tools' import turning it into an
    ImportError that a fallback catches, issue 35 item 6)."""
    import os

    try:
        os.kill(os.getpid(), sig)
        for _ in range(1000):  # the handler runs at the next bytecode boundary
            pass
    except KeyboardInterrupt:
        pass


@pytest.mark.parametrize("sig", [signal.SIGINT, signal.SIGTERM])
def test_no_result_is_committed_after_a_swallowed_signal(tmp_path, sig):
    from bilevel_kit.atomic import write_text

    target = tmp_path / "result.json"
    expected = interrupt.Terminated if sig == signal.SIGTERM else KeyboardInterrupt
    with pytest.raises(expected), interrupt.signal_guard():
        _swallowed_signal(sig)
        assert interrupt.signalled() == sig
        write_text(target, "{}")
    assert not target.exists() and list(tmp_path.iterdir()) == []
    assert interrupt.signalled() is None  # the next guard's command starts afresh
    write_text(target, "{}")  # outside the guard, writes go on
    assert target.read_text() == "{}"


def test_the_command_line_exits_130_after_a_swallowed_signal(monkeypatch, capsys):
    """The command turned the interrupt into an ImportError (exit 1 with a traceback before),
    or swallowed it and returned 0 (then exit -2 with no message): both are exit 130."""
    from bilevel_kit import cli

    def broken(argv):
        _swallowed_signal(signal.SIGTERM)
        raise ImportError("initialization failed")

    monkeypatch.setattr(cli, "_parse_and_run", broken)
    assert cli.main(["methods"]) == interrupt.EXIT_INTERRUPTED
    assert capsys.readouterr().err == "bilevel-kit: interrupted (SIGTERM)\n"

    def carries_on(argv):
        _swallowed_signal(signal.SIGINT)
        return 0

    monkeypatch.setattr(cli, "_parse_and_run", carries_on)
    assert cli.main(["methods"]) == interrupt.EXIT_INTERRUPTED
    assert capsys.readouterr().err == "bilevel-kit: interrupted\n"


def test_an_interrupt_swallowed_as_unraisable_is_raised_again_and_prints_nothing(capsys):
    """Raised in importlib's weakref callback, the interrupt was printed as "Exception ignored
    ... Traceback" before the interrupt's line (1 run in 30 of cpsat in bench/signals.py), and
    once that text was dropped the command went on computing until the guard ended it 2 s
    after the signal (caught at a numba cache load in greedy-ce's prepare step). It is raised
    again in the main thread, outside the callback."""

    class Dropped:
        def __del__(self):
            raise KeyboardInterrupt

    class HalfBuilt:  # cut short by the interrupt before its attribute was set (llvmlite)
        def __del__(self):
            del self.handle

    import sys

    before = sys.unraisablehook
    went_on = []
    with pytest.raises(KeyboardInterrupt), interrupt.signal_guard(grace=30):
        dropped = sys.unraisablehook
        _swallowed_signal(signal.SIGINT)
        half = HalfBuilt()
        del half  # AttributeError, printed as "Exception ignored ..." before
        obj = Dropped()
        del obj
        t0 = time.monotonic()
        while time.monotonic() - t0 < 1.0:  # the command goes on: the interrupt comes back
            time.sleep(0.005)
        went_on.append(time.monotonic() - t0)
    assert not went_on
    assert capsys.readouterr().err == ""
    assert dropped is not before and sys.unraisablehook is before  # given back
