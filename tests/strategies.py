"""Small random instances for tests: hypothesis building blocks (the greedy tests'
strategies) and seeded instance documents with a binding tray (the exact solvers' tests)."""

from __future__ import annotations

import itertools
import random
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
    if not any(t["parts"] for t in tasks):  # part-less tasks ride in a kit with parts, so
        tasks[0]["parts"] = [{"type": "p0", "count": 1}]  # one is needed (docs/timeline.md)
    return types, tasks


def binding_types() -> list[dict[str, Any]]:
    """A fresh list of the three part types whose 50 x 40 part and 70 x 15 bar share a
    100 x 60 tray only one way (fresh, so a test may edit its copy)."""
    return [
        {"id": "big", "width": 50.0, "height": 40.0, "pick_time": 3.0, "rotatable": True},
        {"id": "bar", "width": 70.0, "height": 15.0, "pick_time": 2.0, "rotatable": False},
        {"id": "sq", "width": 30.0, "height": 30.0, "pick_time": 1.5, "rotatable": True},
    ]


def binding_parts(draw: st.DrawFn) -> list[tuple[str, int]]:
    """One task's parts among :func:`binding_types`: 1-2 distinct types, 1-2 squares, one of
    any other type, as (type, count)."""
    kinds = draw(
        st.lists(st.sampled_from(["big", "bar", "sq"]), min_size=1, max_size=2, unique=True)
    )
    return [(k, draw(st.integers(1, 2)) if k == "sq" else 1) for k in kinds]


def random_doc(
    seed: int,
    n: int | None = None,
    *,
    robot_share: float = 0.4,
    robot_halves: tuple[int, int] = (1, 30),
) -> dict[str, Any]:
    """A small random instance: precedence DAG, d > 0, overheads, a tray that binds
    geometrically (a 50 x 40 part and a 70 x 15 bar share a 100 x 60 tray only one way).
    A share ``robot_share`` of the tasks get a robot time of ``robot_halves`` half-seconds."""
    rng = random.Random(seed)
    n = n or rng.randint(4, 6)
    types = binding_types()
    tasks = []
    for i in range(n):
        kinds = rng.sample(["big", "bar", "sq"], rng.randint(1, 2))
        task: dict[str, Any] = {
            "id": f"t{i}",
            "parts": [{"type": k, "count": rng.randint(1, 2) if k == "sq" else 1} for k in kinds],
            "human_time": {"mean": rng.randint(2, 40) / 2},
        }
        if rng.random() < robot_share:
            task["robot_time"] = rng.randint(*robot_halves) / 2
        tasks.append(task)
    prec = [[f"t{i}", f"t{j}"] for i in range(n) for j in range(i + 1, n) if rng.random() < 0.3]
    return {
        "format": "bilevel-kit/1",
        "name": f"rand{seed}",
        "tray": {"width": 100.0, "height": 60.0},
        "delivery_time": rng.randint(1, 16) / 2,
        "kit_overhead": {"robot": rng.randint(1, 6) / 2, "human": rng.randint(1, 6) / 2},
        "part_types": types,
        "tasks": tasks,
        "precedence": prec,
    }


def stations_doc(seed: int, n_stations: int, n: int | None = None) -> dict[str, Any]:
    """:func:`random_doc` on ``n_stations`` assembly stations (docs/timeline.md): each task on
    a random station (every station gets one), the edges between stations dropped, each
    station with its own delivery time, trays (1, 2 or the instance's unlimited) and, on
    some, its own human overhead."""
    doc = random_doc(seed, n)
    rng = random.Random(seed + 7919)
    ids = [f"S{k}" for k in range(n_stations)]
    where = ids + [rng.choice(ids) for _ in range(len(doc["tasks"]) - n_stations)]
    rng.shuffle(where)
    for task, s in zip(doc["tasks"], where, strict=True):
        task["station"] = s
    on = {t["id"]: t["station"] for t in doc["tasks"]}
    doc["precedence"] = [e for e in doc["precedence"] if on[e[0]] == on[e[1]]]
    stations = []
    for s in ids:
        st: dict[str, Any] = {"id": s, "delivery_time": rng.randint(0, 16) / 2}
        trays = rng.choice([1, 2, None])
        if trays is not None:
            st["trays"] = trays
        if rng.random() < 0.5:
            st["kit_overhead_human"] = rng.randint(0, 6) / 2
        stations.append(st)
    doc["stations"] = stations
    return doc


def one_task_doc(
    name: str,
    width: float,
    height: float,
    types: list[tuple[str, float, float, bool]],
    parts: dict[str, int],
    task: str = "t",
) -> dict[str, Any]:
    """One task ``task`` needing ``parts`` of the ``(id, width, height, rotatable)`` types
    (pick time 1 s each) on a ``width`` x ``height`` tray: the kit-level tests' instance."""
    return {
        "format": "bilevel-kit/1",
        "name": name,
        "tray": {"width": width, "height": height},
        "part_types": [
            {"id": t, "width": w, "height": h, "pick_time": 1.0, "rotatable": r}
            for t, w, h, r in types
        ],
        "tasks": [
            {
                "id": task,
                "parts": [{"type": t, "count": n} for t, n in parts.items()],
                "human_time": {"mean": 1.0},
            }
        ],
    }


@st.composite
def timeline_cases(
    draw: st.DrawFn, max_tasks: int = 8, max_stations: int = 3, grid: bool = False
) -> tuple[dict[str, Any], list[list[str]]]:
    """An instance document on 1-``max_stations`` stations (none declared, or declared, for
    one; ``max_stations=0``: none declared) with fractional times (``grid``: multiples of
    1/8 s only), trays 1, 2 or unlimited on the instance and on each station, and a plan on
    it: a random order of its tasks cut into kits of one station each (the evaluator does not
    check plans, so any such cut is a plan to time; docs/timeline.md)."""
    n = draw(st.integers(1, max_tasks))
    n_stations = draw(st.integers(1, max(1, max_stations)))
    declared = max_stations > 0 and (n_stations > 1 or draw(st.booleans()))
    sids = [f"S{k}" for k in range(n_stations)]
    time = st.integers(0, 400).map(lambda v: v / 8)
    if not grid:
        time = time | st.floats(0, 60, allow_nan=False)
    tasks: list[dict[str, Any]] = []
    for j in range(n):
        task: dict[str, Any] = {
            "id": f"t{j}",
            "parts": [{"type": "p", "count": draw(st.integers(1, 3))}],
            "human_time": {"mean": draw(time)},
        }
        if draw(st.booleans()):
            task["robot_time"] = draw(time)
        if declared:
            task["station"] = sids[j] if j < n_stations else draw(st.sampled_from(sids))
        tasks.append(task)
    trays = st.sampled_from([1, 2, None])
    doc: dict[str, Any] = {
        "format": "bilevel-kit/1",
        "name": "timeline-case",
        "tray": {"width": 100.0, "height": 100.0},
        "delivery_time": draw(time),
        "kit_overhead": {"robot": draw(time), "human": draw(time)},
        "part_types": [
            {"id": "p", "width": 5.0, "height": 5.0, "pick_time": draw(time), "rotatable": True}
        ],
        "tasks": tasks,
        "precedence": [],
    }
    if (limit := draw(trays)) is not None:
        doc["trays"] = limit
    if declared:
        doc["stations"] = []
        for s in sids[: min(n_stations, n)]:
            entry: dict[str, Any] = {"id": s}
            for key, values in (
                ("delivery_time", time),
                ("kit_overhead_human", time),
                ("trays", trays),
            ):
                if draw(st.booleans()) and (v := draw(values)) is not None:
                    entry[key] = v
            doc["stations"].append(entry)
    order = draw(st.permutations([t["id"] for t in tasks]))
    where = {t["id"]: t.get("station", "") for t in tasks}
    kits: list[list[str]] = [[order[0]]]
    for prev, t in itertools.pairwise(order):
        if where[prev] != where[t] or draw(st.booleans()):
            kits.append([])
        kits[-1].append(t)
    return doc, kits
