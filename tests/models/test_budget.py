"""The one time budget of the exact solvers."""

from __future__ import annotations

import time

import pytest

from bilevel_kit.models.budget import DEFAULT_TIME_LIMIT, Budget


def test_deadline_keeps_back_a_share_of_the_limit():
    b = Budget(10.0, keep_back=0.01, start=100.0)
    assert b.deadline == pytest.approx(100.0 + 10.0 - 0.1)
    assert Budget(None, start=0.0).time_limit == DEFAULT_TIME_LIMIT
    assert Budget(None, start=0.0).deadline == DEFAULT_TIME_LIMIT


def test_remaining_expired_share_and_sub_budgets():
    b = Budget(5.0)
    assert 4.5 < b.remaining() <= 5.0
    assert b.remaining(0.5) == pytest.approx(b.remaining() - 0.5, abs=1e-3)
    assert not b.expired() and b.expired(margin=10.0)
    now = time.perf_counter()
    assert now < b.share(0.1) <= now + 0.5 + 1e-3
    cut = b.cut(0.2)
    assert cut.deadline == pytest.approx(b.deadline - 0.2) and cut.start == b.start
    head = b.head(0.1)
    assert head.deadline == pytest.approx(b.start + 0.5)
    assert Budget(1.0, start=0.0).head(2.0).deadline == 1.0  # never past the deadline
    assert b.elapsed() >= 0.0


def test_an_expired_budget_shares_nothing():
    b = Budget(1.0, start=time.perf_counter() - 2.0)
    assert b.expired() and b.remaining() < 0
    assert b.share(0.5) <= time.perf_counter()
