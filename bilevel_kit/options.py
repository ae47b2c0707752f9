"""Typed options for methods and simulation policies, validated in one place.

Every registered method (and every simulation policy) declares its options as a frozen
dataclass. :func:`parse_options` turns the loose ``key=value`` pairs a user gives (``-p`` on
the command line, keyword arguments in Python) into an instance of that dataclass, or raises a
:class:`~bilevel_kit.errors.UsageError` naming the owner and the key. So an unknown key, a
value of the wrong type or out of range is always a clear exit 2, never a ``TypeError`` deep in
a solver.

A field's ``metadata`` may hold ``help`` (one line for ``bilevel-kit methods NAME``), ``min``
and ``max`` (inclusive bounds for numbers), and ``choices`` (allowed strings, when the type is
a plain ``str``: a collection, or a function returning one, called when a value is parsed, so
that a list a plugin adds to, the objectives' registry say, is read when it is complete).
``typing.Literal`` types give their choices themselves.
"""

from __future__ import annotations

import dataclasses
import importlib
import math
import types
import typing
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any, ClassVar, Literal, TypeVar, Union, get_args, get_origin

from .errors import UsageError

T = TypeVar("T")

_TRUE = ("true", "yes", "on", "1")
_FALSE = ("false", "no", "off", "0")
_NONE = ("none", "null")


@dataclass(frozen=True)
class NoOptions:
    """The options of a method that takes none."""


#: The one value of :class:`NoOptions` (a default argument).
NO_OPTIONS = NoOptions()


@dataclass(frozen=True)
class OptionInfo:
    """One option as ``bilevel-kit methods NAME`` lists it."""

    name: str
    type: str
    default: Any
    help: str


def _type_name(tp: Any) -> str:
    origin = get_origin(tp)
    if origin is Literal:
        return " | ".join(repr(a) for a in get_args(tp))
    if origin in (Union, types.UnionType):
        return " | ".join(_type_name(a) for a in get_args(tp))
    if tp is type(None):
        return "none"
    return getattr(tp, "__name__", str(tp))


def _hints(cls: type) -> dict[str, Any]:
    return typing.get_type_hints(cls)


def describe(cls: type) -> list[OptionInfo]:
    """The options of ``cls`` with type, default and one-line meaning."""
    hints = _hints(cls)
    out = []
    for f in dataclasses.fields(cls):
        if f.default is not dataclasses.MISSING:
            default = f.default
        elif f.default_factory is not dataclasses.MISSING:
            default = f.default_factory()
        else:
            default = None
        allowed = allowed_choices(f.metadata)
        kind = _type_name(hints[f.name]) if allowed is None else " | ".join(map(repr, allowed))
        out.append(OptionInfo(f.name, kind, default, f.metadata.get("help", "")))
    return out


def allowed_choices(meta: Mapping[str, Any]) -> tuple[str, ...] | None:
    """A field's ``choices`` (None: any string), a function's called now."""
    allowed = meta.get("choices")
    if allowed is None:
        return None
    return tuple(allowed() if callable(allowed) else allowed)


def _coerce(value: Any, tp: Any, meta: Mapping[str, Any], where: str) -> Any:
    """``value`` as type ``tp`` or a :class:`UsageError` saying what was expected."""
    origin = get_origin(tp)
    if origin in (Union, types.UnionType):
        args = get_args(tp)
        if type(None) in args and (
            value is None or (isinstance(value, str) and value.lower() in _NONE)
        ):
            return None
        errors = []
        for arg in args:
            if arg is type(None):
                continue
            try:
                return _coerce(value, arg, meta, where)
            except UsageError as exc:
                errors.append(exc)
        ranged = [e for e in errors if "must be" in str(e)]
        if ranged:  # the right type, out of range: say so rather than "expected ..."
            raise ranged[0]
        raise UsageError(f"{where}: expected {_type_name(tp)}, got {value!r}")
    if origin is Literal:
        choices = get_args(tp)
        if value in choices:
            return value
        raise UsageError(
            f"{where}: must be one of {', '.join(repr(c) for c in choices)}, got {value!r}"
        )
    if tp is bool:
        if isinstance(value, bool):
            return value
        if isinstance(value, str) and value.lower() in _TRUE + _FALSE:
            return value.lower() in _TRUE
        if isinstance(value, int) and value in (0, 1):
            return bool(value)
        raise UsageError(f"{where}: expected true or false, got {value!r}")
    if tp is int:
        if isinstance(value, bool):
            raise UsageError(f"{where}: expected an integer, got {value!r}")
        if isinstance(value, float) and value.is_integer():
            value = int(value)
        if isinstance(value, str):
            try:
                value = int(value)
            except ValueError:
                raise UsageError(f"{where}: expected an integer, got {value!r}") from None
        if not isinstance(value, int):
            raise UsageError(f"{where}: expected an integer, got {value!r}")
        _check_range(value, meta, where)
        return value
    if tp is float:
        if isinstance(value, bool):
            raise UsageError(f"{where}: expected a number, got {value!r}")
        if isinstance(value, str):
            try:
                value = float(value)
            except ValueError:
                raise UsageError(f"{where}: expected a number, got {value!r}") from None
        if not isinstance(value, int | float):
            raise UsageError(f"{where}: expected a number, got {value!r}")
        value = float(value)
        if not math.isfinite(value):
            raise UsageError(f"{where}: expected a finite number, got {value!r}")
        _check_range(value, meta, where)
        return value
    if tp is str:
        if not isinstance(value, str):
            value = str(value)
        allowed = allowed_choices(meta)
        if allowed is not None and value not in allowed:
            raise UsageError(
                f"{where}: must be one of {', '.join(map(repr, allowed))}, got {value!r}"
            )
        return value
    return value  # structured values (Python API only) are passed as given


def _check_range(value: float, meta: Mapping[str, Any], where: str) -> None:
    lo, hi = meta.get("min"), meta.get("max")
    if lo is not None and value < lo:
        raise UsageError(f"{where}: must be >= {lo}, got {value!r}")
    if hi is not None and value > hi:
        raise UsageError(f"{where}: must be <= {hi}, got {value!r}")
    below = meta.get("below")  # an open upper end, e.g. a CVaR level alpha in [0, 1)
    if below is not None and not value < below:
        raise UsageError(f"{where}: must be < {below}, got {value!r}")


def finger_room_field() -> bool:
    """The ``finger_room`` option (off by default) of every method that has it (greedy-ce,
    cpsat): one declaration, so its default, meaning and check are the same for each."""
    return dataclasses.field(
        default=False,
        metadata={
            "help": "pack every part with room for the station gripper's open fingers "
            "(docs/execution.md#finger-room): its grasp footprint is packed, not its outline"
        },
    )


def field_names(cls: type) -> list[str]:
    return [f.name for f in dataclasses.fields(cls)]


def keyword_options(cls: type[T], values: Mapping[str, Any], owner: str) -> T:
    """The options dataclass ``cls`` from a Python entry's keywords (``values``: its
    ``locals()``, the entry's other arguments left out), validated like ``-p`` options."""
    return parse_options(cls, {name: values[name] for name in field_names(cls)}, owner)


def parse_options(cls: type[T], params: Mapping[str, Any], owner: str) -> T:
    """Validate ``params`` against the options dataclass ``cls`` of ``owner``.

    Keys match field names exactly, or case-insensitively when that is unambiguous (so ``w5``
    and ``W5`` both name the weight ``W5``); dashes count as underscores.
    """
    if isinstance(params, cls):
        return params
    fields = {f.name: f for f in dataclasses.fields(cls)}  # type: ignore[arg-type]
    lower = {name.lower(): name for name in fields}
    hints = _hints(cls)
    values: dict[str, Any] = {}
    for raw_key, value in params.items():
        key = str(raw_key).replace("-", "_")
        name = key if key in fields else lower.get(key.lower())
        if name is None:
            listing = ", ".join(fields) if fields else "none"
            raise UsageError(f"{owner}: unknown option {raw_key!r}; its options are {listing}")
        f = fields[name]
        values[name] = _coerce(value, hints[name], f.metadata, f"{owner}: option {name!r}")
    try:
        return cls(**values)
    except (TypeError, ValueError) as exc:
        raise UsageError(f"{owner}: {exc}") from None


def as_params(options: Any) -> dict[str, Any]:
    """The options that differ from their defaults, as a plain dict (for result files)."""
    out = {}
    for info, f in zip(describe(type(options)), dataclasses.fields(options), strict=True):
        value = getattr(options, f.name)
        if value != info.default:
            out[f.name] = value
    return out


def import_target(target: str) -> Any:
    """The object a ``"module:name"`` import path names, imported now."""
    module, name = target.split(":")
    return getattr(importlib.import_module(module), name)


@dataclass(frozen=True)
class Registered:
    """A registered method or policy: ``target`` and ``options`` are ``"module:name"`` import
    paths, so registering imports nothing heavy; ``kind`` names the owner in errors."""

    kind: ClassVar[str] = "method"

    name: str
    target: str
    summary: str
    options: str | None = None  # None: it takes no options

    def options_class(self) -> type:
        return import_target(self.options) if self.options else NoOptions

    def describe_options(self) -> list[OptionInfo]:
        """Type, default and meaning of every option (``bilevel-kit methods NAME``)."""
        return describe(self.options_class())

    def parse(self, params: Mapping[str, Any]) -> Any:
        """The options dataclass from loose ``key=value`` pairs, validated."""
        return parse_options(self.options_class(), params, f"{self.kind} {self.name!r}")
