"""The first run after an install says that numba compiles (issue: ~15 s of silence)."""

from __future__ import annotations

import io

import pytest

from bilevel_kit.cli import solve as solve_cli
from bilevel_kit.heuristics import _kernels


class Terminal(io.StringIO):
    def isatty(self) -> bool:
        return True


def test_the_note_appears_on_a_terminal_only_when_the_cache_is_missing(monkeypatch):
    monkeypatch.setattr(_kernels, "cache_missing", lambda: True)
    out = Terminal()
    solve_cli.compile_notice(["greedy-ce"], out)
    assert out.getvalue() == solve_cli.COMPILE_NOTE + "\n"
    for needed, stream in ((["cpsat"], Terminal()), (["optimized"], io.StringIO())):
        solve_cli.compile_notice(needed, stream)  # no CE method / not a terminal: silent
        assert stream.getvalue() == ""
    monkeypatch.setattr(_kernels, "cache_missing", lambda: False)
    out = Terminal()
    solve_cli.compile_notice(["optimized-adaptive"], out)
    assert out.getvalue() == ""


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
