"""Reading the toolkit's JSON files strictly: one place for every input file (instances,
solutions, pack files).

``read_json`` refuses what :func:`json.loads` lets through silently: a duplicate key (the last
one would win) and NaN/Infinity (not JSON). ``validate_document`` checks a document against a
JSON Schema; valid documents take a fast path (the subset of JSON Schema our schemas use,
checked directly), and only an invalid one goes through :mod:`jsonschema`, whose best-matching
error names the JSON path. Both keep large files linear and cheap (docs/formats.md).
"""

from __future__ import annotations

import json
import math
import re
from collections.abc import Callable, Iterable, Mapping
from pathlib import Path
from typing import Any

#: What an error type looks like: ``error(source, json_path, message)``.
ErrorType = Callable[[str, str, str], Exception]


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
    """The path and message of the first duplicate key or non-finite number, in file order."""
    stack: list[tuple[Any, tuple[Any, ...]]] = [(doc, ())]
    while stack:
        obj, path = stack.pop()
        if isinstance(obj, float):
            if not math.isfinite(obj):
                return path, "must be a finite number (NaN/Infinity not allowed)"
        elif isinstance(obj, dict):
            if isinstance(obj, _Duplicated):
                return path, f"duplicate key {obj.duplicate!r} (JSON objects need unique keys)"
            stack.extend((v, (*path, k)) for k, v in reversed(obj.items()))
        elif isinstance(obj, list):
            stack.extend((v, (*path, i)) for i, v in reversed(list(enumerate(obj))))
    return None


def read_json(path: str | Path, error: ErrorType) -> Any:
    """Parse a JSON file; a missing file, malformed JSON, a duplicate key or a non-finite
    number raises ``error(file, json_path, message)``."""
    src = str(path)
    try:
        text = Path(path).read_text(encoding="utf-8")
    except FileNotFoundError:
        raise error(src, "$", "file not found") from None
    except (OSError, UnicodeDecodeError) as exc:
        raise error(src, "$", f"cannot read file ({exc.__class__.__name__}: {exc})") from None
    try:
        doc = json.loads(text, object_pairs_hook=_pairs)
    except json.JSONDecodeError as exc:
        raise error(
            src, "$", f"malformed JSON at line {exc.lineno} column {exc.colno}: {exc.msg}"
        ) from None
    except RecursionError:
        raise error(src, "$", "JSON nested too deeply") from None
    problem = _first_problem(doc)
    if problem is not None:
        raise error(src, json_path(problem[0]), problem[1])
    return doc


# ---------------------------------------------------------------------------------------------
# Schema validation
# ---------------------------------------------------------------------------------------------

_ANNOTATIONS = frozenset({"$schema", "$id", "title", "description", "default", "examples"})


class _Unsupported(Exception):
    """The fast path met a keyword it does not implement: use jsonschema."""


def _is_type(value: Any, name: str) -> bool:
    """JSON Schema's types, as :mod:`jsonschema` defines them (bool is not a number; an
    integral float is an integer)."""
    if name == "object":
        return isinstance(value, dict)
    if name == "array":
        return isinstance(value, list)
    if name == "string":
        return isinstance(value, str)
    if name == "boolean":
        return isinstance(value, bool)
    if name == "null":
        return value is None
    if isinstance(value, bool):
        return False
    if name == "number":
        return isinstance(value, int | float)
    if name == "integer":
        return isinstance(value, int) or (isinstance(value, float) and value.is_integer())
    raise _Unsupported(name)


def _valid(doc: Any, schema: Mapping[str, Any]) -> bool:
    """Whether ``doc`` satisfies ``schema`` (raises :class:`_Unsupported` when unsure)."""
    for key, want in schema.items():
        if key in _ANNOTATIONS:
            continue
        if key == "type":
            names = [want] if isinstance(want, str) else want
            if not any(_is_type(doc, n) for n in names):
                return False
        elif key == "const":
            if not (doc == want and type(doc) is type(want)):
                return False
        elif key == "enum":
            if not any(doc == w and type(doc) is type(w) for w in want):
                return False
        elif key in ("minimum", "maximum", "exclusiveMinimum", "exclusiveMaximum"):
            if _is_type(doc, "number") and not _in_range(key, doc, want):
                return False
        elif key in ("minLength", "pattern"):
            if isinstance(doc, str) and not _string_ok(key, doc, want):
                return False
        elif key in ("minItems", "maxItems", "items", "prefixItems"):
            if isinstance(doc, list) and not _array_ok(key, doc, want):
                return False
        elif key in ("required", "properties", "additionalProperties"):
            if isinstance(doc, dict) and not _object_ok(key, doc, want, schema):
                return False
        else:
            raise _Unsupported(key)
    return True


def _in_range(key: str, v: float, bound: float) -> bool:
    if key == "minimum":
        return v >= bound
    if key == "maximum":
        return v <= bound
    if key == "exclusiveMinimum":
        return v > bound
    return v < bound


def _string_ok(key: str, s: str, want: Any) -> bool:
    if key == "minLength":
        return len(s) >= want
    return re.search(want, s) is not None


def _array_ok(key: str, a: list[Any], want: Any) -> bool:
    if key == "minItems":
        return len(a) >= want
    if key == "maxItems":
        return len(a) <= want
    if key == "prefixItems":
        return all(_valid(v, s) for v, s in zip(a, want, strict=False))
    return all(_valid(v, want) for v in a)


def _object_ok(key: str, o: dict[str, Any], want: Any, schema: Mapping[str, Any]) -> bool:
    if key == "required":
        return all(k in o for k in want)
    if key == "properties":
        return all(_valid(o[k], s) for k, s in want.items() if k in o)
    known = schema.get("properties", {})
    if want is False:
        return all(k in known for k in o)
    if want is True:
        return True
    return all(_valid(v, want) for k, v in o.items() if k not in known)


def validate_document(
    doc: Any, source: str, doc_schema: Mapping[str, Any], error: ErrorType
) -> None:
    """Structural validation; the most relevant error raises ``error`` naming its JSON path."""
    try:
        if _valid(doc, doc_schema):
            return
    except _Unsupported:
        pass
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
        raise error(source, where, err.message.replace("Additional properties", "unknown field"))
    if err.validator == "const":
        raise error(source, where, f"expected {err.validator_value!r}, got {err.instance!r}")
    msg = err.message
    if len(msg) > 160:
        msg = msg[:157] + "..."
    raise error(source, where, msg)
