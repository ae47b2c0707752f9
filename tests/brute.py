"""Brute-force references for the exact models' tests (independent of every solver).

``segmentations`` enumerates every precedence-feasible order of an instance's tasks cut into
consecutive kits, each distinct segmentation once; ``fits`` decides a kit exactly with the
CP-SAT packer (area first; memoised per part multiset). Only for instances of <= 7 tasks.
"""

from __future__ import annotations

import itertools
from collections.abc import Iterator

from bilevel_kit.models import packing as pk
from bilevel_kit.plan import Kit, Plan, evaluate

_FITS: dict = {}


def fits(inst, kit) -> bool:
    """Does the kit fit the tray (area, then exact CP-SAT packing)?"""
    counts = inst.kit_parts(kit)
    types = tuple(sorted((p.id, p.width, p.height, p.rotatable) for p in inst.part_types.values()))
    key = (inst.tray, types, frozenset(counts.items()))
    if key not in _FITS:
        if sum(inst.part_types[p].area * c for p, c in counts.items()) > inst.tray.area:
            _FITS[key] = False
        else:
            items = [(f"{p}{j}", inst.part_types[p]) for p, c in counts.items() for j in range(c)]
            res = pk.pack(inst.tray, items, time_limit=10.0)
            assert res.status in ("feasible", "infeasible")
            _FITS[key] = res.status == "feasible"
    return _FITS[key]


def segmentations(inst) -> Iterator[tuple[tuple[str, ...], ...]]:
    """Every precedence-feasible permutation x every one of its 2^(n-1) cut patterns, each
    distinct segmentation (as a sequence of task sets) once."""
    ids = [t.id for t in inst.tasks]
    n = len(ids)
    seen = set()
    for perm in itertools.permutations(ids):
        pos = {t: k for k, t in enumerate(perm)}
        if any(pos[a] > pos[b] for a, b in inst.precedence):
            continue
        for mask in range(2 ** (n - 1)):
            kits, cur = [], [perm[0]]
            for k in range(1, n):
                if mask >> (k - 1) & 1:
                    kits.append(tuple(cur))
                    cur = []
                cur.append(perm[k])
            kits.append(tuple(cur))
            key = tuple(frozenset(k) for k in kits)
            if key not in seen:
                seen.add(key)
                yield tuple(kits)


def best_makespan(inst) -> tuple[float, Plan | None]:
    """The least makespan (one evaluator) over the segmentations whose kits all fit."""
    best: tuple[float, Plan | None] = (float("inf"), None)
    for kits in segmentations(inst):
        if all(fits(inst, k) for k in kits):
            plan = Plan(tuple(Kit(k) for k in kits))
            ms = evaluate(inst, plan).makespan
            if ms < best[0]:
                best = (ms, plan)
    return best
