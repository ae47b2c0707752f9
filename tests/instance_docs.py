"""A factory for small instance documents (format bilevel-kit/1, docs/formats.md): the fields
every test document repeats get their usual values, the test names what it varies."""

from __future__ import annotations

from typing import Any


def instance_doc(
    name: str,
    part_types: list[dict[str, Any]],
    tasks: list[dict[str, Any]],
    *,
    tray: tuple[float, float] = (100.0, 100.0),
    delivery_time: float = 1.0,
    overhead: tuple[float, float] = (1.0, 1.0),
    precedence: list[list[str]] | None = None,
    **fields: Any,
) -> dict[str, Any]:
    """An instance document; ``overhead`` is (robot, human) in seconds; ``fields``: any other
    top-level field (``trays``, ``units`` ...), after the usual ones."""
    return {
        "format": "bilevel-kit/1",
        "name": name,
        "tray": {"width": tray[0], "height": tray[1]},
        "delivery_time": delivery_time,
        "kit_overhead": {"robot": overhead[0], "human": overhead[1]},
        "part_types": part_types,
        "tasks": tasks,
        "precedence": [] if precedence is None else precedence,
        **fields,
    }
