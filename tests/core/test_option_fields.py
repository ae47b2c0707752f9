"""``option()`` declares a field of an options dataclass in one call: its default, its help
and its checks reach ``parse_options`` and ``bilevel-kit methods NAME`` as a ``field()`` with
a metadata dict would (bilevel_kit/options.py, module docstring)."""

from __future__ import annotations

from dataclasses import dataclass, fields

import pytest

from bilevel_kit.errors import UsageError
from bilevel_kit.options import describe, option, parse_options


@dataclass(frozen=True)
class _Toy:
    depth: int = option(3, "search depth", min=1, max=9)
    mode: str = option("a", "search mode", choices=("a", "b"))


def test_option_holds_the_default_the_help_and_the_checks():
    depth, mode = fields(_Toy)
    assert depth.default == 3 and dict(depth.metadata) == {
        "help": "search depth",
        "min": 1,
        "max": 9,
    }
    assert mode.default == "a" and dict(mode.metadata) == {
        "help": "search mode",
        "choices": ("a", "b"),
    }
    assert [(i.name, i.type, i.default, i.help) for i in describe(_Toy)] == [
        ("depth", "int", 3, "search depth"),
        ("mode", "'a' | 'b'", "a", "search mode"),
    ]


def test_option_checks_are_applied_when_parsed():
    assert parse_options(_Toy, {"depth": "9", "mode": "b"}, "toy") == _Toy(9, "b")
    with pytest.raises(UsageError) as exc:
        parse_options(_Toy, {"depth": "10"}, "toy")
    assert str(exc.value) == "toy: option 'depth': must be <= 9, got 10"
    with pytest.raises(UsageError) as exc:
        parse_options(_Toy, {"mode": "c"}, "toy")
    assert str(exc.value) == "toy: option 'mode': must be one of 'a', 'b', got 'c'"
