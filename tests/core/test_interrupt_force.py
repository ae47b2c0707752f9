"""The watchdog's forced exit adds no second line once the command printed its own (a busy
machine's slow exit after an interrupt printed "interrupted" twice)."""

from __future__ import annotations

import io
import signal

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
