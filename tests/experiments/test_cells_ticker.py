"""A sweep's progress bar redraws during a long cell (its clock ticks), and stops with it."""

from __future__ import annotations

import threading

from bilevel_kit.experiments.cells import _Ticker


class Bar:
    def __init__(self, disable: bool) -> None:
        self.disable = disable
        self.redraws = 0
        self.drawn = threading.Event()

    def refresh(self) -> None:
        self.redraws += 1
        if self.redraws >= 2:
            self.drawn.set()


def test_the_ticker_redraws_a_shown_bar_until_stopped():
    bar = Bar(disable=False)
    ticker = _Ticker(bar, every=0.01)
    assert bar.drawn.wait(30)  # the mechanism, not its speed: two redraws happen
    ticker.stop()
    after = bar.redraws
    assert not ticker._thread.is_alive()
    assert bar.redraws == after


def test_a_hidden_bar_gets_no_thread():
    bar = Bar(disable=True)
    ticker = _Ticker(bar, every=0.01)
    assert ticker._thread is None
    ticker.stop()
    assert bar.redraws == 0
