"""The columns: convex kits within the tray area, and those that fit with their data
(package docstring, "Columns")."""

from __future__ import annotations

from collections import Counter
from collections.abc import Sequence
from dataclasses import dataclass

from ...errors import UsageError
from ...instance import Instance
from ...plan import kit_durations
from ..budget import Budget
from .lower import LowerLevel

#: Largest number of candidate kits (convex, within the tray area) (option ``max_columns``).
MAX_COLUMNS = 5000
#: Share of the time limit the kit values' packing calls may use (package docstring, Time).
LOWER_SHARE = 0.8


def enumerate_kits(instance: Instance, max_columns: int = MAX_COLUMNS) -> list[frozenset[str]]:
    """Every convex task set whose total part area fits the tray area (package docstring);
    UsageError when there are more than ``max_columns``."""
    ids = [t.id for t in instance.tasks]
    n = len(ids)
    bit = {t: 1 << i for i, t in enumerate(ids)}
    anc = [0] * n
    desc = [0] * n
    for i, t in enumerate(ids):
        for a in instance.ancestors[t]:
            anc[i] |= bit[a]
            desc[ids.index(a)] |= bit[t]
    area = [
        sum(instance.part_types[p].area * c for p, c in instance.task_by_id[t].parts) for t in ids
    ]
    cap = instance.tray.area * (1 + 1e-12)

    def convex(mask: int) -> bool:
        up = down = 0
        for i in range(n):
            if mask >> i & 1:
                up |= desc[i]
                down |= anc[i]
        return (up & down) & ~mask == 0

    seen: dict[int, float] = {}
    frontier = []
    for i in range(n):
        if area[i] <= cap:
            seen[1 << i] = area[i]
            frontier.append(1 << i)
    while frontier:
        nxt = []
        for mask in frontier:
            for i in range(n):
                if mask >> i & 1:
                    continue
                new = mask | 1 << i
                if new in seen:
                    continue
                total = seen[mask] + area[i]
                if total > cap or not convex(new):
                    continue
                seen[new] = total
                nxt.append(new)
                if len(seen) > max_columns:
                    raise UsageError(
                        f"bilevel-milp: more than {max_columns} candidate kits on "
                        f"{instance.name!r} ({n} tasks); the exact column model is for small "
                        "instances (raise max_columns at your own risk)"
                    )
        frontier = nxt
    kits = [frozenset(ids[i] for i in range(n) if mask >> i & 1) for mask in seen]
    # a kit of part-less tasks only is no kit (docs/timeline.md#part-less-tasks): they ride
    # in a kit with parts, so J is minimised over the plans the checker accepts
    return [s for s in kits if any(instance.needs_kit(t) for t in s)]


@dataclass(frozen=True)
class Column:
    tasks: frozenset[str]
    robot: float  # R_c, overhead included
    human: float  # H_c, overhead included
    fitness: float
    lo: int  # earliest position
    hi: int  # latest position


def build_columns(
    instance: Instance,
    kits: Sequence[frozenset[str]],
    lower: LowerLevel,
    budget: Budget,
    excluded: Counter[str | None] | None = None,
) -> list[Column] | None:
    """Columns (kits that fit, with their data); None when the budget runs out first.
    ``excluded`` counts the candidates left out by the scope of the proof that they do not fit
    (None: not proven, docs/formulations.md#what-optimal-means)."""
    ids = [t.id for t in instance.tasks]
    n = len(ids)
    anc = instance.ancestors
    desc: dict[str, set[str]] = {t: set() for t in ids}
    for t in ids:
        for a in anc[t]:
            desc[a].add(t)
    out = []
    lower.deadline = budget.share(LOWER_SHARE)  # packing calls leave the MILP its share
    for s in sorted(kits, key=lambda s: (len(s), sorted(instance.index[t] for t in s))):
        if budget.expired():
            return None
        val = lower.value(instance.kit_parts(s))
        if not val.fits:
            if excluded is not None:
                excluded[val.proof] += 1
            continue
        r, h = kit_durations(instance, list(s))
        anc_out = set().union(*(anc[t] for t in s)) - s
        desc_out = set().union(*(desc[t] for t in s)) - s
        # positions 0..n-1, used ones first: a kit before c exists if c has ancestors
        # outside it; the kits before c hold at most n - |c| - |descendants outside c| tasks
        out.append(Column(s, r, h, val.fitness, 1 if anc_out else 0, n - len(s) - len(desc_out)))
    return out
