"""Hypothesis building blocks for small random instances (the greedy tests' strategies)."""

from __future__ import annotations

from typing import Any

from hypothesis import strategies as st


def part_types_and_tasks(
    draw: st.DrawFn, max_side: int, max_tasks: int
) -> tuple[list[dict[str, Any]], list[dict[str, Any]]]:
    """1-3 part types of sides 5..``max_side`` mm and 1..``max_tasks`` tasks, each with 1-2 of
    a random subset of the types and an integer human time of 1-30 s (no robot times)."""
    n_types = draw(st.integers(1, 3))
    types = [
        {
            "id": f"p{k}",
            "width": draw(st.integers(5, max_side)) * 1.0,
            "height": draw(st.integers(5, max_side)) * 1.0,
            "pick_time": draw(st.integers(0, 9)) * 1.0,
            "rotatable": draw(st.booleans()),
        }
        for k in range(n_types)
    ]
    n = draw(st.integers(1, max_tasks))
    tasks = []
    for j in range(n):
        parts = [
            {"type": f"p{k}", "count": draw(st.integers(1, 2))}
            for k in range(n_types)
            if draw(st.booleans())
        ]
        tasks.append(
            {"id": f"t{j}", "parts": parts, "human_time": {"mean": draw(st.integers(1, 30)) * 1.0}}
        )
    return types, tasks
