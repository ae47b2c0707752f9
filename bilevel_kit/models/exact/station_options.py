"""Which options of ``cpsat`` and ``milp`` hold with several assembly stations
(docs/timeline.md#several-stations; docs/formulations.md, "Options with several stations").

Each backend declares every field of its options class, next to the class, as
:class:`Honoured` (its station model uses the option) or :class:`Refused` (it does not: a
value other than the default, or than the values in ``also`` that it does honour, is a
:class:`~bilevel_kit.errors.UsageError`, exit 2 at the CLI). :func:`declare` refuses a
declaration that misses a field, so a new option cannot be ignored silently.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import MISSING, dataclass, fields
from typing import Any

from ...errors import UsageError
from ...instance import Instance


@dataclass(frozen=True)
class Honoured:
    """An option the station model uses as the one-station model does."""


@dataclass(frozen=True)
class Refused:
    """An option the station model does not use: ``why`` says what it does instead; the
    default and the values ``also`` (which it does honour) are accepted, any other refused."""

    why: str
    also: tuple[Any, ...] = ()


StationRule = Honoured | Refused
HONOURED = Honoured()


def declare(cls: type, rules: Mapping[str, StationRule]) -> dict[str, StationRule]:
    """``rules`` for the options dataclass ``cls``: a TypeError unless every field of ``cls``
    is declared, and nothing else."""
    names = {f.name for f in fields(cls)}
    missing, extra = sorted(names - set(rules)), sorted(set(rules) - names)
    if missing or extra:
        raise TypeError(
            f"{cls.__name__}: options not declared for several stations: {missing}; "
            f"declared but not options: {extra} (bilevel_kit.models.exact.station_options)"
        )
    return dict(rules)


def default_of(cls: type, name: str) -> Any:
    """The default value of the field ``name`` of the dataclass ``cls``."""
    for f in fields(cls):
        if f.name == name:
            if f.default is not MISSING:
                return f.default
            if f.default_factory is not MISSING:
                return f.default_factory()
    raise KeyError(name)


def refusal(
    instance: Instance, method: str, options: Any, rules: Mapping[str, StationRule]
) -> str | None:
    """Why ``options`` cannot run on ``instance`` (one line), None when they can: every option
    is honoured with several stations or at a value the station model honours."""
    if not instance.stations:
        return None
    cls = type(options)
    for f in fields(cls):
        rule = rules[f.name]
        if isinstance(rule, Honoured):
            continue
        value, default = getattr(options, f.name), default_of(cls, f.name)
        if value == default or value in rule.also:
            continue
        keep = [f"{f.name}={v}" for v in (default, *rule.also)]
        return (
            f"{instance.source}: {method} does not use option '{f.name}={value}' with several "
            f"assembly stations ({rule.why}); drop it or use {' or '.join(keep)} "
            "(docs/timeline.md#several-stations)"
        )
    return None


def check_station_options(
    instance: Instance, method: str, options: Any, rules: Mapping[str, StationRule]
) -> None:
    """A UsageError (exit 2) with :func:`refusal`'s line, if any."""
    why = refusal(instance, method, options, rules)
    if why is not None:
        raise UsageError(why)
