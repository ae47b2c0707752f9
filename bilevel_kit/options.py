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
``typing.Literal`` types give their choices themselves. :func:`option` declares such a field in
one call.

``needs`` maps another option's name to the values under which this one is read (a collection,
or a function returning one), e.g. ``{"objective": ("expected_makespan", "cvar_makespan")}``
for the scenario options of ``lns`` (docs/robust.md#options-of-the-scenario-objectives):
setting the option while the other one has a value outside them is a :class:`UsageError`
rather than an option silently ignored. "Setting" is giving its key (``-p`` or a Python
keyword of :func:`bilevel_kit.methods.solve`), whatever the value, the default included; an
options dataclass built directly, or a Python entry's keywords (:func:`keyword_options`),
cannot tell a default passed from one left out, so there a value other than the default
counts as set.
"""

from __future__ import annotations

import dataclasses
import importlib
import math
import types
import typing
from collections.abc import Callable, Collection, Mapping
from dataclasses import dataclass
from typing import Any, ClassVar, Literal, TypeVar, Union, get_args, get_origin

from .errors import UsageError

T = TypeVar("T")
R = TypeVar("R")

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
        text = f.metadata.get("help", "")
        for other, values in _needs(f.metadata).items():  # say when it is refused
            text += f" (only with {other} {_either(values)}: refused with another {other})"
        out.append(OptionInfo(f.name, kind, default, text))
    return out


def _needs(meta: Mapping[str, Any]) -> dict[str, tuple[Any, ...]]:
    """A field's ``needs`` (module docstring), each function called now."""
    return {
        other: tuple(values() if callable(values) else values)
        for other, values in meta.get("needs", {}).items()
    }


def _either(values: tuple[Any, ...]) -> str:
    return " or ".join(map(repr, values))


def _default_of(f: dataclasses.Field[Any]) -> Any:
    if f.default is not dataclasses.MISSING:
        return f.default
    if f.default_factory is not dataclasses.MISSING:
        return f.default_factory()
    return dataclasses.MISSING


def check_needs(options: Any, owner: str, given: Collection[str] | None = None) -> None:
    """Refuse an option set while the option its ``needs`` names has a value that does not
    read it (module docstring): ``given`` the names the user gave, None to count every value
    other than the default as given."""
    for f in dataclasses.fields(options):
        needs = _needs(f.metadata)
        if not needs:
            continue
        if given is None and getattr(options, f.name) == _default_of(f):
            continue
        if given is not None and f.name not in given:
            continue
        for other, values in needs.items():
            chosen = getattr(options, other)
            if chosen not in values:
                raise UsageError(
                    f"{owner}: option {f.name!r} is read only with {other} {_either(values)}, "
                    f"and {other} is {chosen!r}: set {other}={values[0]} or leave "
                    f"{f.name!r} out"
                )


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


def option(default: Any, help: str, **checks: Any) -> Any:
    """One field of an options dataclass: its default, its one-line ``help`` and its checks
    (``min``, ``max``, ``below``, ``choices``, ``needs``: module docstring) as keywords, so
    that each declaration is one call rather than a ``field()`` with a metadata dict."""
    return dataclasses.field(default=default, metadata={"help": help, **checks})


def finger_room_field() -> bool:
    """The ``finger_room`` option (off by default) of every method that has it (greedy-ce,
    cpsat): one declaration, so its default, meaning and check are the same for each."""
    return option(
        False,
        "pack every part with room for the station gripper's open fingers "
        "(docs/execution.md#finger-room): its grasp footprint is packed, not its outline",
    )


def field_names(cls: type) -> list[str]:
    return [f.name for f in dataclasses.fields(cls)]


def keyword_options(cls: type[T], values: Mapping[str, Any], owner: str) -> T:
    """The options dataclass ``cls`` from a Python entry's keywords (``values``: its
    ``locals()``, the entry's other arguments left out), validated like ``-p`` options."""
    given = {name: values[name] for name in field_names(cls)}
    return parse_options(cls, given, owner, explicit=False)


def keyword_run(run: Callable[..., R], cls: type[T], values: Mapping[str, Any], owner: str) -> R:
    """A Python entry's call of its method's ``run(instance, options, **rest)``: ``values`` (the
    entry's ``locals()``) split into the options dataclass ``cls`` (:func:`keyword_options`)
    and the entry's other arguments, passed on by name, so an entry never forwards them by
    hand."""
    options = keyword_options(cls, values, owner)
    fields = set(field_names(cls))
    rest = {k: v for k, v in values.items() if k not in fields and k != "instance"}
    return run(values["instance"], options, **rest)


def parse_options(
    cls: type[T], params: Mapping[str, Any], owner: str, *, explicit: bool = True
) -> T:
    """Validate ``params`` against the options dataclass ``cls`` of ``owner``.

    Keys match field names exactly, or case-insensitively when that is unambiguous (so ``w5``
    and ``W5`` both name the weight ``W5``); dashes count as underscores. ``explicit``: the
    keys are the ones the user gave (``needs``, module docstring); False: every option is
    there, so only a value other than the default counts as set.
    """
    if isinstance(params, cls):
        check_needs(params, owner)
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
        options = cls(**values)
    except (TypeError, ValueError) as exc:
        raise UsageError(f"{owner}: {exc}") from None
    check_needs(options, owner, set(values) if explicit else None)
    return options


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
