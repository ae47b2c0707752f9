"""The live progress pieces: the line's text, the tracker's monotone forwarding, the sink."""

from __future__ import annotations

import io

from bilevel_kit import progress
from bilevel_kit.progress import LiveLine, Tracker, Update, format_line


def test_format_line_on_given_numbers():
    u = Update("makespan", 450.78, 425.25, 12.34, "CP-SAT Benders, 2 cuts")
    assert format_line(u) == (
        "  12.3 s  CP-SAT Benders, 2 cuts  makespan 450.78 s  bound 425.25 s  gap 5.66%"
    )
    assert format_line(Update("human_idle", None, None, 0.0)) == (
        "   0.0 s  human idle -  bound -  gap -"
    )
    assert format_line(Update("J", 2.5, 2.0, 1.0, "HiGHS", unit="")) == (
        "   1.0 s  HiGHS  J 2.5  bound 2  gap 20.00%"
    )


def test_gap_is_relative_to_the_incumbent():
    assert Update("makespan", 200.0, 150.0, 0.0).gap == 0.25
    assert Update("makespan", 200.0, None, 0.0).gap is None
    assert Update("makespan", 100.0, 100.0, 0.0).gap == 0.0


def test_tracker_forwards_only_improvements_and_clamps_the_bound():
    seen: list[Update] = []
    t = Tracker(seen.append, "makespan", start=0.0)
    t.report(incumbent=500.0, bound=400.0)
    t.report(incumbent=510.0)  # worse: ignored
    t.report(bound=390.0)  # worse: ignored
    t.report(incumbent=480.0, bound=420.0)
    t.report(bound=481.0)  # float noise above the incumbent: shown as the incumbent
    assert [(u.incumbent, u.bound) for u in seen] == [
        (500.0, 400.0),
        (480.0, 420.0),
        (480.0, 480.0),
    ]


def test_without_a_sink_nothing_is_tracked():
    t = progress.tracker("makespan")
    assert not t.active
    t.report(incumbent=1.0)
    assert t.incumbent is None


def test_one_tracker_per_objective_within_a_solve():
    seen: list[Update] = []
    with progress.reporting(seen.append):
        a = progress.tracker("makespan")
        assert progress.tracker("makespan") is a
        assert progress.tracker("human_idle") is not a
        a.report(incumbent=3.0)
    assert len(seen) == 1 and seen[0].incumbent == 3.0
    assert not progress.tracker("makespan").active  # gone after the solve


def test_live_line_is_silent_off_a_terminal_unless_forced():
    stream = io.StringIO()
    with LiveLine(stream) as line:
        line(Update("makespan", 1.0, 0.5, 0.1))
    assert not line.enabled and stream.getvalue() == ""


def test_quiet_live_line_draws_nothing_even_when_forced():
    stream = io.StringIO()
    with LiveLine(stream, force=True, quiet=True) as line:
        line(Update("makespan", 1.0, 0.5, 0.1))
    assert stream.getvalue() == ""


def test_forced_live_line_rewrites_one_line_and_ends_it():
    stream = io.StringIO()
    with LiveLine(stream, force=True, interval=3600.0) as line:
        line(Update("makespan", 200.0, 100.0, 1.0, "CP-SAT"))
        line(Update("makespan", 150.0, 100.0, 2.0, "CP-SAT"))  # within the interval: not drawn
    text = stream.getvalue()
    assert text.startswith("\r") and text.endswith("\n") and text.count("\n") == 1
    draws = text[:-1].split("\r")[1:]
    assert len(draws) == 2  # the first update, then the last one when the line ends
    assert "makespan 200.00 s  bound 100.00 s  gap 50.00%" in draws[0]
    assert "makespan 150.00 s  bound 100.00 s  gap 33.33%" in draws[1]
