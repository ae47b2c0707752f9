"""Brute-force references for the exact models' tests (independent of every solver).

``segmentations`` enumerates every precedence-feasible order of an instance's tasks cut into
consecutive kits, each distinct segmentation once; ``fits`` decides a kit exactly with the
CP-SAT packer (area first; memoised per part multiset) for 0/90-degree layouts on the 1 mm grid
(the test instances' sizes are whole millimetres, so the grid is exact). Only for instances of
<= 7 tasks. The brute force is the optimum over 0/90-degree plans, which is what an exact
model's own verdict speaks of (``model_verdict``, docs/formulations.md#what-optimal-means).
With several assembly stations (docs/timeline.md#several-stations) a kit holds tasks of one
station only, so the segmentations keep the kits that do: every plan is an order cut into
kits, so this still enumerates every valid plan. The brute forces time plans with the
reference timeline (tests/reference_timeline.py, written from docs/timeline.md without the
package's evaluator) and hold the evaluator to it on every plan they enumerate.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Iterator

import numpy as np
from reference_timeline import close, step, timeline, times_of

from bilevel_kit.models import packing as pk
from bilevel_kit.objectives import OBJECTIVES
from bilevel_kit.plan import Kit, Plan, evaluate

_FITS: dict = {}
#: id(instance) -> (instance, its tray and part types as a key, its kits' answers): a brute
#: force asks about the same kits again and again
_SEEN: dict = {}


def fits(inst, kit) -> bool:
    """Does the kit fit the tray (area, then exact CP-SAT packing)?"""
    held = _SEEN.get(id(inst))
    if held is None or held[0] is not inst:
        kinds = inst.part_types.values()
        types = tuple(sorted((p.id, p.width, p.height, p.rotatable) for p in kinds))
        held = _SEEN[id(inst)] = (inst, (inst.tray, types), {})
    tasks = frozenset(kit)
    if tasks in held[2]:
        return held[2][tasks]
    counts = inst.kit_parts(kit)
    key = (*held[1], frozenset(counts.items()))
    if key not in _FITS:
        if sum(inst.part_types[p].area * c for p, c in counts.items()) > inst.tray.area:
            _FITS[key] = False
        else:
            items = [(f"{p}{j}", inst.part_types[p]) for p, c in counts.items() for j in range(c)]
            res = pk.pack(inst.tray, items, time_limit=10.0)
            assert res.status in ("feasible", "infeasible")
            _FITS[key] = res.status == "feasible"
    held[2][tasks] = _FITS[key]
    return _FITS[key]


def segmentations(inst) -> Iterator[tuple[tuple[str, ...], ...]]:
    """Every precedence-feasible permutation x every one of its 2^(n-1) cut patterns, each
    distinct segmentation (as a sequence of task sets) once."""
    ids = [t.id for t in inst.tasks]
    station = {t.id: t.station for t in inst.tasks}
    n = len(ids)
    seen = set()
    for perm in itertools.permutations(ids):
        pos = {t: k for k, t in enumerate(perm)}
        if any(pos[a] > pos[b] for a, b in inst.precedence):
            continue
        # a kit holds one station's tasks: cut wherever the station changes
        need = sum(1 << (k - 1) for k in range(1, n) if station[perm[k]] != station[perm[k - 1]])
        for mask in range(2 ** (n - 1)):
            if mask & need != need:
                continue
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


def best_makespan(
    inst, objective: str = "makespan", kitless: bool = False
) -> tuple[float, Plan | None]:
    """The least makespan over the segmentations whose kits all fit; or the least of another
    ``objective`` (``sum_completion``, ``human_idle``). The values come from the reference
    timeline (tests/reference_timeline.py, written from docs/timeline.md), and the package's
    evaluator is held to it on every plan (:func:`agrees`). A kit of part-less tasks only is
    no valid kit (docs/timeline.md#part-less-tasks); ``kitless=True`` allows it (the rule
    before)."""
    times = times_of(inst)
    needs = {t.id for t in inst.tasks if inst.needs_kit(t.id)}
    best: tuple[float, Plan | None] = (float("inf"), None)
    for kits in segmentations(inst):
        if not kitless and any(needs.isdisjoint(k) for k in kits):
            continue
        if all(fits(inst, k) for k in kits):
            plan = Plan(tuple(Kit(k) for k in kits))
            ref = timeline(times, kits)
            agrees(ref, evaluate(inst, plan), kits)
            ms = ref.objective(objective)
            if ms < best[0]:
                best = (ms, plan)
    return best


def agrees(ref, tl, kits) -> None:
    """The evaluator's timeline ``tl`` has the reference's makespan, sum of completions and
    human idle (to 1e-9 relative: the two add the same numbers in other orders)."""
    for name in ("makespan", "sum_completion", "human_idle"):
        value = OBJECTIVES[name].value(tl)
        assert close(ref.objective(name), value), (name, kits, ref.objective(name), value)


def model_verdict(out) -> tuple[bool, float | None]:
    """An exact model's own verdict and bound over the plans it models: every valid plan when
    its exclusions all hold at any angle (``status`` optimal, ``bound``), else the 0/90-degree
    plans (``optimal_axis_aligned``, ``bound_axis_aligned``); and the invariants between them:
    "optimal" only for a proof at any angle, ``bound`` never above the 0/90-degree bound."""
    extra = out.extra
    if out.status == "optimal":
        assert extra["proof_scope"] == "any angle", extra
    if extra.get("proof_scope") == "any angle" or "optimal_axis_aligned" not in extra:
        return out.status == "optimal", out.bound
    axis = extra.get("bound_axis_aligned")
    assert axis is None or out.bound <= axis + 1e-9, extra
    return bool(extra["optimal_axis_aligned"]), axis


def assert_model_optimal(out, opt: float, tol: float = 1e-9) -> None:
    """The model proved ``opt`` (the brute force over 0/90-degree plans) optimal for the
    plans it models, and its ``bound`` holds for every plan (it is at most ``opt``)."""
    import pytest

    ok, bound = model_verdict(out)
    assert ok, (out.status, out.extra)
    assert out.extra["makespan"] == pytest.approx(opt, abs=tol)
    assert bound == pytest.approx(opt, abs=tol)
    assert out.bound <= opt + tol


def assert_objective_optimal(out, opt: float, tol: float = 1e-5) -> None:
    """As :func:`assert_model_optimal` for another objective of a stations model (its
    ``objective_value`` and ``objective_bound``; ``objective_bound_axis_aligned`` for a proof
    among 0/90-degree plans)."""
    import pytest

    extra = out.extra
    if hasattr(out, "objective_name"):  # a Result of solve: the objective's numbers are its own
        value, any_bound = out.objective, out.bound
    else:  # a method's output: in its extra (methods.OBJECTIVE_KEYS)
        value, any_bound = extra["objective_value"], extra["objective_bound"]
    if out.status == "optimal":
        assert extra["proof_scope"] == "any angle", extra
        bound = any_bound
    else:
        assert extra["optimal_axis_aligned"], (out.status, extra)
        bound = extra["objective_bound_axis_aligned"]
    assert value == pytest.approx(opt, abs=tol)
    assert bound == pytest.approx(opt, abs=tol)
    assert any_bound <= opt + tol


def fits_on_grid(sizes: list[tuple[int, int, bool]], W: int, H: int) -> bool:
    """Whether the ``(w, h, rotatable)`` rectangles fit a ``W`` x ``H`` tray: exhaustive search
    over integer corners, independent of every packer (tiny trays only)."""
    occ = np.zeros((H, W), dtype=bool)

    def rec(k: int) -> bool:
        if k == len(sizes):
            return True
        w, h, r = sizes[k]
        for ww, hh in {(w, h), (h, w)} if r else {(w, h)}:
            for x in range(W - ww + 1):
                for y in range(H - hh + 1):
                    if not occ[y : y + hh, x : x + ww].any():
                        occ[y : y + hh, x : x + ww] = True
                        if rec(k + 1):
                            return True
                        occ[y : y + hh, x : x + ww] = False
        return False

    return rec(0)


def station_optima(inst, plans: dict | None = None, check: bool = True) -> dict[str, float]:
    """The least makespan, sum of the stations' completions and total human idle over every
    valid plan (kits of one station, every kit fitting: :func:`fits`), by a depth-first search
    over the kit sequences, timed kit by kit with the reference timeline's rule
    (tests/reference_timeline.py, written from docs/timeline.md without the package's
    evaluator: :func:`reference_timeline.step` on its numbers).

    A plan is a sequence of kits; the search appends, for any station with tasks left, any
    non-empty set of its remaining tasks whose predecessors are done or in the set (a kit's
    internal order does not change the timeline), so it meets every plan exactly once. Fast
    enough for 8 tasks on two or three stations (every valid plan, no pruning). ``check``:
    the package's evaluator is held to the three values on every plan (:func:`agrees`; about
    three times the search's time). ``plans``, when given, receives an optimal plan of each
    objective (its kits as task tuples)."""
    times = times_of(inst)
    ids = [t.id for t in inst.tasks]
    n = len(ids)
    sids = list(times.stations)
    where = [sids.index(times.station_of[t]) for t in ids]
    prm = [times.stations[s] for s in sids]
    r = [times.r[t] for t in ids]
    h = [times.h[t] for t in ids]
    pred = [0] * n
    for a, b in inst.precedence:
        pred[ids.index(b)] |= 1 << ids.index(a)
    S = len(sids)
    mine = [sum(1 << i for i in range(n) if where[i] == s) for s in range(S)]
    best = {"makespan": math.inf, "sum_completion": math.inf, "human_idle": math.inf}
    kits_of: dict[tuple[int, int], list[tuple[int, float, float]]] = {}

    def kits(s: int, left: int) -> list[tuple[int, float, float]]:
        """The kits station s may take next from its tasks ``left``: (mask, R, H)."""
        if (s, left) not in kits_of:
            members = [i for i in range(n) if left >> i & 1]
            out = []
            for size in range(1, len(members) + 1):
                for combo in itertools.combinations(members, size):
                    mask = sum(1 << i for i in combo)
                    if any(pred[i] & left & ~mask for i in combo):
                        continue  # a predecessor is neither done nor in the kit
                    if fits(inst, [ids[i] for i in combo]):
                        robot = times.o_r + sum(r[i] for i in combo)
                        human = prm[s].overhead_human + sum(h[i] for i in combo)
                        out.append((mask, robot, human))
            kits_of[(s, left)] = out
        return kits_of[(s, left)]

    path: list[int] = []

    def leaf(end: tuple, work: tuple) -> None:
        values = {
            "makespan": max(end),
            "sum_completion": sum(end),
            "human_idle": sum(end) - sum(work),
        }
        named = [tuple(ids[i] for i in range(n) if m >> i & 1) for m in path]
        if check:
            tl = evaluate(inst, Plan(tuple(Kit(k) for k in named)))
            for name, v in values.items():
                assert close(v, OBJECTIVES[name].value(tl)), (name, named, v)
        for name, v in values.items():
            if v < best[name]:
                best[name] = v
                if plans is not None:
                    plans[name] = named

    def dfs(left: int, free: float, end: tuple, starts: tuple, work: tuple) -> None:
        if not left:
            leaf(end, work)
            return
        for s in range(S):
            rest = left & mine[s]
            if not rest:
                continue
            for mask, R, H in kits(s, rest):
                _, _, arrive, human, done = step(prm[s], free, starts[s], end[s], R, H)
                path.append(mask)
                dfs(
                    left & ~mask,
                    arrive,
                    (*end[:s], done, *end[s + 1 :]),
                    (*starts[:s], starts[s] + (human,), *starts[s + 1 :]),
                    (*work[:s], work[s] + H, *work[s + 1 :]),
                )
                path.pop()

    dfs((1 << n) - 1, 0.0, (0.0,) * S, ((),) * S, (0.0,) * S)
    return best
