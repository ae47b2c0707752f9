"""Benchmark of the convex layout polish (models/convex_layout.py) on cross-entropy layouts.

Why: ``greedy-ce --polish`` is only worth its time if polishing CE layouts gains fitness. Three
groups of kits on the table instance (instances/hrc_table.json, W6 = 10):

* ``plan``: every distinct kit of the greedy-ce plan (seeds 0..reps-1, default parameters);
* ``candidates``: every part multiset CE arranged during those greedy runs (what polishing
  inside the memoised lower level would cost);
* ``random``: random sub-multisets of the table's parts (1-4 legs/feet/connectors, 0-8 screws
  of each kind), arranged by CE with the paper's parameters.

Per kit: exact fitness before and after, absolute and relative gain
(``gain / |fitness_before|``), rounds, status and wall time of the polish (cvxpy + Clarabel;
the first call, which imports cvxpy, is made before timing). Every polished layout is re-checked
with the independent checker. Writes bench/results/polish.csv and prints a summary.

Usage: python bench/bench_polish.py [--reps 3] [--random 30] [--out bench/results/polish.csv]
"""

from __future__ import annotations

import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import argparse
import csv
import statistics
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from bilevel_kit import check, load  # noqa: E402
from bilevel_kit.heuristics.convex import exactly_valid, polish  # noqa: E402
from bilevel_kit.heuristics.cross_entropy import Arrangement, arrange  # noqa: E402
from bilevel_kit.heuristics.greedy_ce import GreedyCEPolicy, plan  # noqa: E402
from bilevel_kit.instance import Instance  # noqa: E402
from bilevel_kit.plan import Placement  # noqa: E402

FIELDS = [
    "group",
    "kit",
    "n_parts",
    "fitness_before",
    "fitness_after",
    "gain",
    "rel_gain",
    "rounds",
    "status",
    "polish_s",
]


def kit_name(layout: tuple[Placement, ...]) -> str:
    counts: dict[str, int] = {}
    for p in layout:
        counts[p.type] = counts.get(p.type, 0) + 1
    return " ".join(f"{t}={n}" for t, n in sorted(counts.items()))


def measure(inst: Instance, group: str, layout: tuple[Placement, ...], w6: float) -> dict:
    res = polish(inst, layout, w6=w6)
    tray = inst.tray
    assert exactly_valid(res.layout, tray.width, tray.height), "polish broke a layout"
    assert res.fitness_after >= res.fitness_before
    return {
        "group": group,
        "kit": kit_name(layout),
        "n_parts": len(layout),
        "fitness_before": round(res.fitness_before, 4),
        "fitness_after": round(res.fitness_after, 4),
        "gain": round(res.gain, 4),
        "rel_gain": round(res.gain / max(abs(res.fitness_before), 1e-9), 6),
        "rounds": res.rounds,
        "status": res.status,
        "polish_s": round(res.wall_time_s, 5),
    }


def greedy_rows(inst: Instance, reps: int, w6: float) -> list[dict]:
    rows: list[dict] = []
    seen_plan: set[tuple[Placement, ...]] = set()
    seen_cand: set[tuple[Placement, ...]] = set()
    for seed in range(reps):
        policy = GreedyCEPolicy(inst, seed=seed)
        p = plan(inst, policy=policy)
        for kit in p.kits:
            if kit.layout not in seen_plan and len(kit.layout) > 1:
                seen_plan.add(kit.layout)
                rows.append(measure(inst, "plan", kit.layout, w6))
        # The memoised lower level (private, read only here): every multiset CE arranged.
        arrangements: dict[object, Arrangement] = getattr(policy, "_arrangements", {})
        for arr in arrangements.values():
            if arr.fits and len(arr.layout) > 1 and arr.layout not in seen_cand:
                seen_cand.add(arr.layout)
                rows.append(measure(inst, "candidates", arr.layout, w6))
        # The polished plan must pass the checker too (tasks unchanged, layouts replaced).
        from bilevel_kit.heuristics.convex import polish_plan

        polished, _ = polish_plan(inst, p, w6)
        assert check(inst, polished) == []
    return rows


def random_rows(inst: Instance, n: int, w6: float, seed: int = 12345) -> list[dict]:
    gen = np.random.default_rng(seed)
    rows = []
    for k in range(n):
        counts = {
            "leg": int(gen.integers(1, 5)),
            "foot": int(gen.integers(1, 5)),
            "connector": int(gen.integers(1, 5)),
            "screw_long": int(gen.integers(0, 9)),
            "screw_short": int(gen.integers(0, 9)),
        }
        arr = arrange(inst, counts, rng=seed + k, w6=w6)
        if arr.fits:
            rows.append(measure(inst, "random", arr.layout, w6))
    return rows


def summary(rows: list[dict], group: str) -> str:
    sel = [r for r in rows if r["group"] == group]
    if not sel:
        return f"{group}: no kits"
    gains = [r["gain"] for r in sel]
    rel = [r["rel_gain"] for r in sel]
    secs = [r["polish_s"] for r in sel]
    rounds = [r["rounds"] for r in sel]
    statuses = sorted({r["status"] for r in sel})
    return (
        f"{group:10s} kits={len(sel):3d}  mean gain={statistics.mean(gains):9.2f}  "
        f"mean rel gain={100 * statistics.mean(rel):6.2f}%  "
        f"median rel gain={100 * statistics.median(rel):6.2f}%  "
        f"time/polish mean={statistics.mean(secs):.3f}s median={statistics.median(secs):.3f}s "
        f"max={max(secs):.3f}s  mean rounds={statistics.mean(rounds):.1f}  status={statuses}"
    )


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--reps", type=int, default=3, help="greedy-ce seeds")
    ap.add_argument("--random", type=int, default=30, help="random kits")
    ap.add_argument("--out", type=Path, default=ROOT / "bench/results/polish.csv")
    args = ap.parse_args()
    inst = load(ROOT / "instances/hrc_table.json")
    w6 = float(inst.weights["W6"])
    warm = arrange(inst, {"foot": 1, "connector": 1}, rng=0)
    polish(inst, warm.layout, w6=w6)  # imports cvxpy and warms up before timing
    t0 = time.perf_counter()
    rows = greedy_rows(inst, args.reps, w6) + random_rows(inst, args.random, w6)
    total = time.perf_counter() - t0
    args.out.parent.mkdir(parents=True, exist_ok=True)
    with open(args.out, "w", newline="") as fh:
        writer = csv.DictWriter(fh, fieldnames=FIELDS)
        writer.writeheader()
        writer.writerows(rows)
    for group in ("plan", "candidates", "random"):
        print(summary(rows, group))
    print(f"{len(rows)} polishes, every result valid and not worse; total {total:.1f}s")
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
