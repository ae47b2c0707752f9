"""The worked example of docs/timeline.md#several-stations, shared by the tests that check it
by hand (the evaluator's times, the checker, the per-station Gantt chart), and the instance of
issue 35's false "optimal" of ``milp`` on the station objectives."""

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


def first_tray_doc() -> dict[str, Any]:
    """Two one-tray stations with a long human overhead (A: a1, a2, a3, ``o_H = 3``; B: b1,
    b2, ``o_H = 6``), d = 0, ``o_R = 0.5``, every robot time 0.5 s, and a 100 x 50 mm tray that
    takes any two of the parts (40 x 40 and 45 x 35 mm, never turned)."""
    parts = [
        {"id": p, "width": w, "height": h, "pick_time": 1, "rotatable": False}
        for p, w, h in (("a", 40, 40), ("b", 45, 35))
    ]
    tasks = [
        {
            "id": tid,
            "parts": [{"type": part, "count": 1}],
            "human_time": {"mean": h},
            "robot_time": 0.5,
            "station": tid[0].upper(),
        }
        for tid, part, h in (
            ("a1", "b", 9),
            ("a2", "a", 4),
            ("a3", "b", 11),
            ("b1", "a", 15),
            ("b2", "a", 7.5),
        )
    ]
    stations = [
        {"id": "A", "trays": 1, "kit_overhead_human": 3},
        {"id": "B", "trays": 1, "kit_overhead_human": 6},
    ]
    return document(
        "first_tray",
        parts,
        tasks,
        tray=(100, 50),
        delivery_time=0,
        overhead=(0.5, 0.5),
        stations=stations,
    )
