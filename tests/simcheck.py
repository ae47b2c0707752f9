"""One comparison of a simulated run with the evaluator's timeline, shared by the simulation
tests: every kit's five times, the totals and each task's start and end, to 1e-9 s."""

from __future__ import annotations

import pytest

TIME_FIELDS = ("robot_start", "robot_end", "arrive", "human_start", "human_end")
TOTALS = ("makespan", "human_idle", "robot_idle", "human_work", "robot_work")


def assert_matches_evaluator(res, tl, *, tasks: bool = True) -> None:
    assert len(res.kit_times) == len(tl.kits)
    for got, want in zip(res.kit_times, tl.kits, strict=True):
        for name in TIME_FIELDS:
            assert getattr(got, name) == pytest.approx(getattr(want, name), abs=1e-9, rel=0)
    for name in TOTALS:
        assert getattr(res, name) == pytest.approx(getattr(tl, name), abs=1e-9, rel=0)
    if tasks:
        for t, start in tl.task_start.items():
            assert res.task_start[t] == pytest.approx(start, abs=1e-9, rel=0)
            assert res.task_end[t] == pytest.approx(tl.task_end[t], abs=1e-9, rel=0)
