"""Reading the toolkit's JSON files strictly: one place for every input file (instances,
solutions, pack files).

``read_json`` refuses what :func:`json.loads` lets through silently: a duplicate key (the last
one would win) and NaN/Infinity (not JSON). ``validate_document`` checks a document against a
JSON Schema; valid documents take a fast path (the subset of JSON Schema our schemas use,
checked directly), and only an invalid one goes through :mod:`jsonschema`, whose best-matching
error names the JSON path. Both keep large files linear and cheap (docs/formats.md).
"""

from __future__ import annotations

import functools
import json
import math
import os
import re
import stat
from collections.abc import Callable, Iterable, Mapping
from pathlib import Path
from typing import Any

#: What an error type looks like: ``error(source, json_path, message)``.
ErrorType = Callable[[str, str, str], Exception]


#: The most digits an integer of these files may have: no field takes a number near 10^30,
#: and a longer one would only be slow to convert (Python refuses 4,300 digits) or overflow a
#: float later.
MAX_INT_DIGITS = 30
#: A ``\\u`` escape of a UTF-16 surrogate in JSON text: a lone one is not Unicode.
_SURROGATE_ESCAPE = re.compile(r"\\u[dD][89a-fA-F]")
_SURROGATE = re.compile("[\ud800-\udfff]")


class _TooLong(str):
    """An integer literal of more than :data:`MAX_INT_DIGITS` digits, kept as its text."""


class _Duplicated(dict):  # type: ignore[type-arg]
    """A JSON object in which ``duplicate`` appeared more than once."""

    duplicate: str = ""


def _pairs(pairs: list[tuple[str, Any]]) -> dict[str, Any]:
    obj = dict(pairs)
    if len(obj) == len(pairs):
        return obj
    seen: set[str] = set()
    out = _Duplicated(pairs)
    for key, _ in pairs:
        if key in seen:
            out.duplicate = key
            break
        seen.add(key)
    return out


def json_path(parts: Iterable[Any]) -> str:
    """``$.tasks[3].id`` from ``("tasks", 3, "id")``."""
    out = "$"
    for p in parts:
        out += f"[{p}]" if isinstance(p, int) else f".{p}"
    return out


def _first_problem(doc: Any) -> tuple[tuple[Any, ...], str] | None:
    """The path and message of the first duplicate key, non-finite number, integer of too
    many digits or string with a lone surrogate, in file order."""
    stack: list[tuple[Any, tuple[Any, ...]]] = [(doc, ())]
    while stack:
        obj, path = stack.pop()
        if isinstance(obj, float):
            if not math.isfinite(obj):
                return path, "must be a finite number (NaN/Infinity not allowed)"
        elif isinstance(obj, _TooLong):
            return path, f"an integer of {len(obj.lstrip('-'))} digits is out of range"
        elif isinstance(obj, str):
            if _SURROGATE.search(obj):
                return path, "not valid Unicode (a lone UTF-16 surrogate escape)"
        elif isinstance(obj, dict):
            if isinstance(obj, _Duplicated):
                return path, f"duplicate key {obj.duplicate!r} (JSON objects need unique keys)"
            for k in obj:
                if _SURROGATE.search(k):
                    return path, f"key {k!r} is not valid Unicode (a lone UTF-16 surrogate escape)"
            stack.extend((v, (*path, k)) for k, v in reversed(obj.items()))
        elif isinstance(obj, list):
            stack.extend((v, (*path, i)) for i, v in reversed(list(enumerate(obj))))
    return None


def read_json(path: str | Path, error: ErrorType, *, long_ints: bool = False) -> Any:
    """Parse a JSON file; a missing file, malformed JSON, a duplicate key, a non-finite
    number, a lone surrogate or an integer of more than :data:`MAX_INT_DIGITS` digits raises
    ``error(file, json_path, message)``. ``long_ints``: integers up to Python's own limit of
    4,300 digits are read as they are (the checker names them as violations itself)."""
    src = str(path)
    try:  # a FIFO would block until a writer comes (forever), a device never ends
        if not stat.S_ISREG(os.stat(path).st_mode):
            raise error(src, "$", "cannot read file (not a regular file: a folder, pipe or device)")
        text = Path(path).read_text(encoding="utf-8")
    except FileNotFoundError:
        raise error(src, "$", "file not found") from None
    except (OSError, UnicodeDecodeError) as exc:
        raise error(src, "$", f"cannot read file ({exc.__class__.__name__}: {exc})") from None
    return parse_json(text, src, error, long_ints=long_ints)


def parse_json(text: str, src: str, error: ErrorType, *, long_ints: bool = False) -> Any:
    """Parse the JSON text of the file ``src`` as strictly as :func:`read_json` (a cell on a
    worker parses the document it carries, not a file: docs/cluster.md)."""
    suspect = [False]  # a duplicate key or a NaN/Infinity literal was seen

    def pairs(items: list[tuple[str, Any]]) -> dict[str, Any]:
        obj = _pairs(items)
        suspect[0] = suspect[0] or isinstance(obj, _Duplicated)
        return obj

    def constant(name: str) -> float:
        suspect[0] = True
        return float(name)

    def number(literal: str) -> float:
        value = float(literal)  # 1e999 overflows to inf without being a constant
        if not math.isfinite(value):
            suspect[0] = True
        return value

    def integer(literal: str) -> int | str:
        if len(literal) > MAX_INT_DIGITS and not (long_ints and len(literal) <= 4300):
            suspect[0] = True
            return _TooLong(literal)
        return int(literal)

    suspect[0] = bool(_SURROGATE_ESCAPE.search(text))
    try:
        doc = json.loads(
            text,
            object_pairs_hook=pairs,
            parse_constant=constant,
            parse_float=number,
            parse_int=integer,
        )
    except json.JSONDecodeError as exc:
        raise error(
            src, "$", f"malformed JSON at line {exc.lineno} column {exc.colno}: {exc.msg}"
        ) from None
    except RecursionError:
        raise error(src, "$", "JSON nested too deeply") from None
    problem = _first_problem(doc) if suspect[0] else None  # the walk finds its path
    if problem is not None:
        raise error(src, json_path(problem[0]), problem[1])
    return doc


# ---------------------------------------------------------------------------------------------
# Schema validation
# ---------------------------------------------------------------------------------------------

_ANNOTATIONS = frozenset({"$schema", "$id", "title", "description", "default", "examples"})


class _Unsupported(Exception):
    """The fast path met a keyword it does not implement: use jsonschema."""


Check = Callable[[Any], bool]

#: JSON Schema's types as :mod:`jsonschema` defines them: bool is not a number, an integral
#: float is an integer.
_TYPES: dict[str, Check] = {
    "object": lambda v: isinstance(v, dict),
    "array": lambda v: isinstance(v, list),
    "string": lambda v: isinstance(v, str),
    "boolean": lambda v: isinstance(v, bool),
    "null": lambda v: v is None,
    "number": lambda v: type(v) in (int, float),
    "integer": lambda v: type(v) is int or (type(v) is float and v.is_integer()),
}
_KNOWN = _ANNOTATIONS | {
    "type",
    "const",
    "enum",
    "minimum",
    "maximum",
    "exclusiveMinimum",
    "exclusiveMaximum",
    "minLength",
    "pattern",
    "minItems",
    "maxItems",
    "items",
    "prefixItems",
    "required",
    "properties",
    "additionalProperties",
    "oneOf",
}


def _all_of(tests: list[Check]) -> Check:
    if len(tests) == 1:
        return tests[0]

    def check(v: Any) -> bool:
        return all(t(v) for t in tests)

    return check


def _one_of(allowed: list[Any], v: Any) -> bool:
    """``const``/``enum``: equal and of the same JSON type (``True`` is not ``1``)."""
    return any(v == w and type(v) is type(w) for w in allowed)


def _compile(schema: Mapping[str, Any]) -> Check:
    """One predicate for ``schema`` (raises :class:`_Unsupported` for unknown keywords)."""
    unknown = set(schema) - _KNOWN
    if unknown:
        raise _Unsupported(sorted(unknown)[0])
    tests: list[Check] = []
    if "type" in schema:
        names = [schema["type"]] if isinstance(schema["type"], str) else schema["type"]
        if any(n not in _TYPES for n in names):
            raise _Unsupported("type")
        preds = [_TYPES[n] for n in names]
        tests.append(preds[0] if len(preds) == 1 else lambda v: any(p(v) for p in preds))
    for key in ("const", "enum"):
        if key in schema:
            allowed = [schema[key]] if key == "const" else list(schema[key])
            tests.append(functools.partial(_one_of, allowed))
    tests += _number_tests(schema) + _string_tests(schema)
    if {"items", "prefixItems", "minItems", "maxItems"} & set(schema):
        tests.append(_array_test(schema))
    if {"properties", "required", "additionalProperties"} & set(schema):
        tests.append(_object_test(schema))
    if "oneOf" in schema:  # exactly one branch holds (the solution's ``trays``)
        branches = [_compile(s) for s in schema["oneOf"]]
        tests.append(lambda v: sum(b(v) for b in branches) == 1)
    return _all_of(tests) if tests else lambda v: True


def _number_tests(schema: Mapping[str, Any]) -> list[Check]:
    out: list[Check] = []
    lo, hi = schema.get("minimum"), schema.get("maximum")
    xlo, xhi = schema.get("exclusiveMinimum"), schema.get("exclusiveMaximum")
    if lo is not None or hi is not None or xlo is not None or xhi is not None:

        def in_range(v: Any) -> bool:
            if type(v) not in (int, float):
                return True
            return not (
                (lo is not None and v < lo)
                or (hi is not None and v > hi)
                or (xlo is not None and v <= xlo)
                or (xhi is not None and v >= xhi)
            )

        out.append(in_range)
    return out


def _string_tests(schema: Mapping[str, Any]) -> list[Check]:
    out: list[Check] = []
    if "minLength" in schema:
        n = schema["minLength"]
        out.append(lambda v: not isinstance(v, str) or len(v) >= n)
    if "pattern" in schema:
        rx = re.compile(schema["pattern"])
        out.append(lambda v: not isinstance(v, str) or rx.search(v) is not None)
    return out


def _array_test(schema: Mapping[str, Any]) -> Check:
    item = _compile(schema["items"]) if "items" in schema else None
    prefix = [_compile(s) for s in schema.get("prefixItems", [])]
    lo, hi = schema.get("minItems", 0), schema.get("maxItems")

    def check(v: Any) -> bool:
        if not isinstance(v, list):
            return True
        if len(v) < lo or (hi is not None and len(v) > hi):
            return False
        if not all(p(x) for p, x in zip(prefix, v, strict=False)):
            return False
        return item is None or all(item(x) for x in v[len(prefix) :])

    return check


def _object_test(schema: Mapping[str, Any]) -> Check:
    props = {k: _compile(s) for k, s in schema.get("properties", {}).items()}
    required = list(schema.get("required", []))
    extra = schema.get("additionalProperties", True)
    extra_test = _compile(extra) if isinstance(extra, dict) else None

    def check(v: Any) -> bool:
        if not isinstance(v, dict):
            return True
        if any(k not in v for k in required):
            return False
        for k, x in v.items():
            test = props.get(k)
            if test is not None:
                if not test(x):
                    return False
            elif extra is False or (extra_test is not None and not extra_test(x)):
                return False
        return True

    return check


@functools.lru_cache(maxsize=32)
def _compiled(schema_text: str) -> Check | None:
    try:
        return _compile(json.loads(schema_text))
    except _Unsupported:
        return None


def validate_document(
    doc: Any, source: str, doc_schema: Mapping[str, Any], error: ErrorType
) -> None:
    """Structural validation; the most relevant error raises ``error`` naming its JSON path."""
    fast = _compiled(json.dumps(doc_schema, sort_keys=True))
    if fast is not None and fast(doc):
        return
    import jsonschema

    validator = jsonschema.Draft202012Validator(doc_schema)
    err = jsonschema.exceptions.best_match(validator.iter_errors(doc))
    if err is None:
        return
    where = json_path(err.absolute_path)
    if err.validator == "required":
        missing = [r for r in err.validator_value if r not in err.instance]
        raise error(source, where, f"missing required field {missing[0]!r}")
    if err.validator == "additionalProperties":
        allowed = set(err.schema.get("properties", {}))
        extra = sorted(k for k in err.instance if k not in allowed)
        names = ", ".join(repr(k) for k in extra)
        raise error(source, where, f"unknown field{'s' if len(extra) > 1 else ''} {names}")
    if err.validator == "const":
        raise error(source, where, f"expected {err.validator_value!r}, got {err.instance!r}")
    msg = err.message
    if len(msg) > 160:
        msg = msg[:157] + "..."
    raise error(source, where, msg)
