"""A kit only CP-SAT can pack, an instance around it, and a clock that makes every wall-clock
packing limit expire at once (a machine far more loaded than any real one).

The kit is the CJCM instance E02F17 (bench/data/packing/README.md): 17 parts, no rotation, a
20 x 20 tray with 7 mm^2 to spare. The shelf heuristic finds no layout, CP-SAT finds one in
about 0.02 deterministic units (tens of milliseconds on an idle machine).
"""

from __future__ import annotations

from types import SimpleNamespace
from typing import Any

from bilevel_kit.instance import Instance, PartType, Tray, document, from_dict

SIZES = [
    (3, 7),
    (13, 4),
    (2, 14),
    (1, 6),
    (6, 7),
    (15, 2),
    (15, 2),
    (5, 2),
    (5, 8),
    (7, 3),
    (1, 20),
    (2, 3),
    (4, 14),
    (1, 9),
    (2, 5),
    (1, 3),
    (3, 3),
]
TRAY = Tray(20.0, 20.0)


def hard_items() -> list[tuple[str, PartType]]:
    """The kit's parts as (part id, part type) pairs."""
    return [
        (f"i{j}", PartType(id=f"p{j}", width=w, height=h, pick_time=1.0, rotatable=False))
        for j, (w, h) in enumerate(SIZES)
    ]


def hard_counts() -> dict[str, int]:
    return {f"p{j}": 1 for j in range(len(SIZES))}


def part_types() -> dict[str, PartType]:
    return {pt.id: pt for _, pt in hard_items()}


def hard_instance() -> Instance:
    """Chain a -> b -> c: a holds one 3 x 3 part, b and c half of the hard kit each (each half
    alone is laid out by the shelf heuristic, b + c only by CP-SAT; a + b + c is over the
    tray's area). With o_R = o_H = 30 s, d = 5 s and a long human time on a, the optimum is
    [a], [b, c] (170 s); without the kit b + c it is [a, b], [c] (180 s)."""
    half = len(SIZES) // 2
    types: list[dict[str, Any]] = [
        {"id": f"p{j}", "width": float(w), "height": float(h), "pick_time": 1.0}
        for j, (w, h) in enumerate(SIZES)
    ]
    types.append({"id": "s", "width": 3.0, "height": 3.0, "pick_time": 1.0})
    for t in types:
        t["rotatable"] = False

    def task(tid: str, parts: list[str], robot: float, human: float) -> dict[str, Any]:
        return {
            "id": tid,
            "parts": [{"type": p, "count": 1} for p in parts],
            "human_time": {"mean": human},
            "robot_time": robot,
        }

    tasks = [
        task("a", ["s"], 5.0, 50.0),
        task("b", [f"p{j}" for j in range(half)], 10.0, 10.0),
        task("c", [f"p{j}" for j in range(half, len(SIZES))], 10.0, 10.0),
    ]
    doc = document(
        "hard-kit",
        types,
        tasks,
        tray=(TRAY.width, TRAY.height),
        delivery_time=5.0,
        overhead=(30.0, 30.0),
        precedence=[["a", "b"], ["b", "c"]],
    )
    return from_dict(doc, "<hard kit>")


def slow_packing_clock(monkeypatch: Any) -> None:
    """Make the packer's and the oracle's clock jump 100 s at every reading: each packing call
    looks as if it had spent its whole wall-clock limit before CP-SAT starts (CP-SAT then gets
    its 10 ms minimum), as on a pathologically loaded machine."""
    from bilevel_kit.models import packing, packing_oracle

    now = [0.0]

    def perf_counter() -> float:
        now[0] += 100.0
        return now[0]

    clock = SimpleNamespace(perf_counter=perf_counter)
    monkeypatch.setattr(packing, "time", clock)
    monkeypatch.setattr(packing_oracle, "time", clock)


#: The modules whose clocks a reproducible solve (``deterministic=True``) no longer reads: the
#: Benders seed cuts, the cut shrinking and the quick plans (``common``), the quick plans' best
#: cut (``segment``) and the packing calls (``packing``, ``packing_oracle``: their wall-clock
#: safety nets are ten times their limit, from the start of each call).
STEP_CLOCKS = (
    "bilevel_kit.models.common",
    "bilevel_kit.models.segment",
    "bilevel_kit.models.packing",
    "bilevel_kit.models.packing_oracle",
)
#: ... and the run's own safety nets: its budget and the kit-count LP's scan.
NET_CLOCKS = (
    "bilevel_kit.models.budget",
    "bilevel_kit.models.relax",
    "bilevel_kit.models.relax.kit_lp",
)


def slow_clock(monkeypatch: Any, modules: tuple[str, ...]) -> None:
    """Make ``time.perf_counter`` jump 100 s at every reading in ``modules``: every wall-clock
    limit they compute has passed by the time they look at it."""
    import importlib
    import time

    now = [time.perf_counter()]

    def perf_counter() -> float:
        now[0] += 100.0
        return now[0]

    clock = SimpleNamespace(perf_counter=perf_counter)
    for name in modules:
        monkeypatch.setattr(importlib.import_module(name), "time", clock)
