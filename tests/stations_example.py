"""The worked example of docs/timeline.md#several-stations, shared by the tests that check it
by hand (the evaluator's times, the checker, the per-station Gantt chart)."""

from __future__ import annotations

from typing import Any

from bilevel_kit.instance import document


def worked_example_doc(**fields: Any) -> dict[str, Any]:
    """Station A (one tray) with a1, a2 and station B (d = 2, no pickup) with b1; ``fields``
    override the document's top-level keys (e.g. ``stations``)."""
    parts = [{"id": "p", "width": 10, "height": 10, "pick_time": 1}]
    tasks = [
        {"id": "a1", "parts": [], "human_time": {"mean": 10}, "robot_time": 2, "station": "A"},
        {"id": "b1", "parts": [], "human_time": {"mean": 6}, "robot_time": 3, "station": "B"},
        {"id": "a2", "parts": [], "human_time": {"mean": 4}, "robot_time": 5, "station": "A"},
    ]
    stations = [{"id": "A", "trays": 1}, {"id": "B", "delivery_time": 2, "kit_overhead_human": 0}]
    base = {"stations": stations, **fields}
    return document("two", parts, tasks, delivery_time=1, overhead=(1, 0.5), **base)
