"""numba's compile happens before any clock starts and is announced (issue: ~15-60 s of
silence on a first run, charged to --time-limit; docs/scaling.md#first-run)."""

from __future__ import annotations

import io

import pytest

from bilevel_kit.cli import solve as solve_cli
from bilevel_kit.heuristics import _kernels, warmup

needs_numba = pytest.mark.skipif(_kernels.njit() is None, reason="numba disabled or missing")


@needs_numba
def test_a_cold_compile_is_announced_on_any_stream_with_its_time(monkeypatch):
    monkeypatch.setattr(warmup, "_state", {})
    monkeypatch.setattr(_kernels, "cache_missing", lambda: True)
    out = io.StringIO()  # not a terminal: said all the same (a redirected job looked hung)
    solve_cli.prepare(["single-task", "greedy-ce", "cpsat"], out)
    lines = out.getvalue().splitlines()
    assert len(lines) == 2, lines  # one compile for every method that needs it
    assert lines[0].startswith("note: compiling the cross-entropy kernels")
    assert "not charged to any time limit" in lines[0]
    assert lines[1].startswith("note: compiled the cross-entropy kernels in ")
    assert lines[1].endswith(" s")
    assert warmup.ready()
    again = io.StringIO()
    solve_cli.prepare(["greedy-ce"], again)  # compiled in this process: nothing to do
    assert again.getvalue() == ""


@needs_numba
def test_a_cached_load_or_a_method_without_kernels_says_nothing(monkeypatch):
    monkeypatch.setattr(warmup, "_state", {})
    monkeypatch.setattr(_kernels, "cache_missing", lambda: False)
    out = io.StringIO()
    solve_cli.prepare(["optimized-adaptive"], out)  # loaded from the cache: silent
    assert out.getvalue() == ""
    monkeypatch.setattr(warmup, "_state", {})
    monkeypatch.setattr(_kernels, "cache_missing", lambda: True)
    solve_cli.prepare(["single-task", "whole-assembly", "cpsat-rolling"], out)
    assert out.getvalue() == ""
    assert not warmup._state  # nothing compiled for methods that never run a kernel


#: When the slow prepare step below ended (perf_counter).
_ENDED: list[float] = []


def slow_prepare(notify=None) -> float:
    """A prepare step that takes 0.3 s, like a (short) compile."""
    import time

    time.sleep(0.3)
    _ENDED.append(time.perf_counter())
    return 0.3


def test_solve_runs_the_prepare_step_outside_the_clock(table, monkeypatch):
    """The step's seconds are reported beside the method's wall time, not in it."""
    import dataclasses
    import time

    from bilevel_kit import methods

    spec = dataclasses.replace(methods.REGISTRY["greedy-ce"], prepare=f"{__name__}:slow_prepare")
    monkeypatch.setitem(methods.REGISTRY, "greedy-ce", spec)
    res = methods.solve(table, "greedy-ce", time_limit=60)
    after = time.perf_counter()
    assert res.extra["prepare_s"] == 0.3
    assert res.wall_time_s <= after - _ENDED[-1]  # the clock started after the step
    assert res.extra["time_limit_hit"] is False
    res = methods.solve(table, "single-task", time_limit=60)
    assert "prepare_s" not in res.extra  # no prepare step declared
    assert res.extra["time_limit_hit"] is False


def test_cache_missing_follows_numbas_index_of_the_ce_block(tmp_path, monkeypatch):
    """numba names the index by the kernel's first source line: a stale index of an older
    line does not count, the current one does; every entry kernel's index must be there."""
    if _kernels.njit() is None:
        pytest.skip("numba is disabled or missing")
    monkeypatch.setattr(_kernels, "__file__", str(tmp_path / "_kernels.py"))
    monkeypatch.delenv("NUMBA_CACHE_DIR", raising=False)
    assert _kernels.cache_missing()
    cache = tmp_path / "__pycache__"
    cache.mkdir()
    (cache / "_kernels._ce_block-1.py311.nbi").write_text("")
    assert _kernels.cache_missing()
    func = getattr(_kernels._ce_block, "py_func", _kernels._ce_block)
    (cache / f"_kernels._ce_block-{func.__code__.co_firstlineno}.py311.nbi").write_text("")
    others = _kernels.cache_indexes()[1:]  # greedy-ce's decision kernels: each one counts
    for pattern in others:
        assert _kernels.cache_missing()
        (cache / pattern.replace("py*", "py311")).write_text("")
    assert len(others) == 3
    assert not _kernels.cache_missing()


def test_a_cache_folder_of_the_users_own_is_the_only_one_numba_reads(tmp_path, monkeypatch):
    """With ``NUMBA_CACHE_DIR`` set numba reads and writes that folder alone: an empty one
    means a compile, whatever lies beside the sources (a first run there was silent)."""
    if _kernels.njit() is None:
        pytest.skip("numba is disabled or missing")
    beside = tmp_path / "src" / "__pycache__"
    beside.mkdir(parents=True)
    for pattern in _kernels.cache_indexes():
        (beside / pattern.replace("py*", "py311")).write_text("")
    monkeypatch.setattr(_kernels, "__file__", str(tmp_path / "src" / "_kernels.py"))
    monkeypatch.delenv("NUMBA_CACHE_DIR", raising=False)
    assert not _kernels.cache_missing()
    monkeypatch.setenv("NUMBA_CACHE_DIR", str(tmp_path / "mine"))
    assert _kernels.cache_missing()
    (tmp_path / "mine").mkdir()
    for pattern in _kernels.cache_indexes():
        (tmp_path / "mine" / pattern.replace("py*", "py311")).write_text("")
    assert not _kernels.cache_missing()
