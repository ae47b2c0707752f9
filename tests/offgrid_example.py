"""The off-grid instance of issue 23 (docs/formulations.md#what-optimal-means), shared by the
exact models' grid tests (tests/models/test_grid_claims.py) and the command-line edge rows
(tests/edges/test_edges.py)."""

from __future__ import annotations

from typing import Any


def offgrid_doc(side: float = 50.25, tray: float = 100.5) -> dict[str, Any]:
    """Two tasks with one square part each; the two squares fill the tray's width exactly, so
    one kit holds both (on the exact 0.75 mm grid), but on the 1 mm grid each grows to 51 mm
    and the tray shrinks to 100 mm. With these overheads the one-kit plan (46 s) beats two
    kits (56 s)."""
    part = {"type": "a", "count": 1}
    return {
        "format": "bilevel-kit/1",
        "name": "offgrid",
        "tray": {"width": tray, "height": 60.0},
        "delivery_time": 10.0,
        "kit_overhead": {"robot": 10.0, "human": 0.0},
        "part_types": [{"id": "a", "width": side, "height": side, "pick_time": 3.0}],
        "tasks": [{"id": t, "parts": [part], "human_time": {"mean": 10.0}} for t in ("t1", "t2")],
        "precedence": [["t1", "t2"]],
    }
