"""Benchmark of the cross-entropy kit arrangement (paper Algorithm 1) at paper parameters.

Kit: every part of the 28-part table kit (4 legs 152.4 x 12.7 mm, 4 feet 43 x 43, 4 connectors
41 x 41, 8 screws 14 x 6, 8 screws 8 x 6) on a 300 x 200 mm tray; 200 samples, 30 elites,
at most 100 iterations.

For each seed it times one ``arrange`` call, then the evaluation alone of the same number of
samples (``iterations`` batches of 200, drawn beforehand) with the vectorised objective:
rotated box extents plus :class:`bilevel_kit.layout.fitness.PairScorer`, in the same precision.
The ratio of the medians says how much the CE loop (sampling, projection, refit, the exact
final check) costs on top of scoring.

OpenBLAS threads are capped at 1 unless OPENBLAS_NUM_THREADS is set: on a busy 2-core machine
threaded BLAS calls measure the neighbours, not the algorithm. The setting is in the CSV.

Usage: python bench/bench_ce.py [--repeats 21] [--out bench/results/ce.csv]
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

from bilevel_kit.instance import Instance, from_dict  # noqa: E402
from bilevel_kit.layout.cross_entropy import CEParams, arrange  # noqa: E402
from bilevel_kit.layout.fitness import PairScorer, PairTable, half_extents  # noqa: E402

PARTS = {"leg": 4, "foot": 4, "connector": 4, "screw_long": 8, "screw_short": 8}
SIZES = {
    "leg": (152.4, 12.7),
    "foot": (43.0, 43.0),
    "connector": (41.0, 41.0),
    "screw_long": (14.0, 6.0),
    "screw_short": (8.0, 6.0),
}


def table_kit() -> Instance:
    """The 28-part whole-table kit on a 300 x 200 mm tray."""
    return from_dict(
        {
            "format": "bilevel-kit/1",
            "name": "table-kit-28",
            "tray": {"width": 300.0, "height": 200.0},
            "part_types": [
                {"id": k, "width": w, "height": h, "pick_time": 1.0} for k, (w, h) in SIZES.items()
            ],
            "tasks": [
                {
                    "id": "all",
                    "parts": [{"type": k, "count": v} for k, v in PARTS.items()],
                    "human_time": {"mean": 1.0},
                }
            ],
        }
    )


def eval_only_seconds(inst: Instance, batches: int, params: CEParams, seed: int) -> float:
    """Time to score ``batches`` x ``params.samples`` random layouts (drawn before timing)."""
    dt = np.float32 if params.precision == "float32" else np.float64
    types = [t for t in sorted(PARTS) for _ in range(PARTS[t])]
    w = np.array([inst.part_types[t].width for t in types], dtype=dt)[:, None]
    h = np.array([inst.part_types[t].height for t in types], dtype=dt)[:, None]
    n, S = len(types), params.samples
    rng = np.random.default_rng(seed)
    data = [
        (
            (rng.random((n, S)) * inst.tray.width).astype(dt),
            (rng.random((n, S)) * inst.tray.height).astype(dt),
            (rng.random((n, S)) * 180.0).astype(dt),
        )
        for _ in range(batches)
    ]
    scorer = PairScorer(PairTable.build(types, dt), S, dt)
    w6 = dt(inst.weights["W6"])
    t0 = time.perf_counter()
    for x, y, th in data:
        ex, ey = half_extents(w, h, th)
        dsd, z = scorer.signed(x, y, ex, ey)
        cost = dsd + w6 * z
        np.argpartition(cost, params.elite - 1)
    return time.perf_counter() - t0


def run(repeats: int, precision: str) -> dict[str, object]:
    inst = table_kit()
    params = CEParams(precision=precision)
    for s in range(2):  # warm-up
        arrange(inst, PARTS, rng=1000 + s, params=params)
    solve, evals, iters, fits, fitness, sources = [], [], [], [], [], []
    for seed in range(repeats):
        t0 = time.perf_counter()
        res = arrange(inst, PARTS, rng=seed, params=params)
        solve.append(time.perf_counter() - t0)
        evals.append(eval_only_seconds(inst, res.iterations, params, seed))
        iters.append(res.iterations)
        fits.append(res.fits)
        fitness.append(res.fitness)
        sources.append(res.source)
    med_solve = statistics.median(solve)
    med_eval = statistics.median(evals)
    return {
        "kit": "table-28",
        "parts": sum(PARTS.values()),
        "precision": precision,
        "samples": params.samples,
        "elite": params.elite,
        "max_iter": params.max_iter,
        "repeats": repeats,
        "median_iterations": statistics.median(iters),
        "median_solve_ms": round(med_solve * 1e3, 2),
        "median_eval_only_ms": round(med_eval * 1e3, 2),
        "ratio_solve_to_eval": round(med_solve / med_eval, 3),
        "median_ratio_per_seed": round(
            statistics.median(a / b for a, b in zip(solve, evals, strict=True)), 3
        ),
        "fits_rate": sum(fits) / repeats,
        "median_fitness": round(statistics.median(fitness), 1),
        "sources": ";".join(f"{s}={sources.count(s)}" for s in sorted(set(sources))),
        "openblas_threads": os.environ.get("OPENBLAS_NUM_THREADS", ""),
    }


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=21)
    ap.add_argument("--precision", choices=["float32", "float64", "both"], default="both")
    ap.add_argument("--out", type=Path, default=ROOT / "bench" / "results" / "ce.csv")
    args = ap.parse_args()
    precisions = ["float32", "float64"] if args.precision == "both" else [args.precision]
    rows = [run(args.repeats, p) for p in precisions]
    args.out.parent.mkdir(parents=True, exist_ok=True)
    with args.out.open("w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=list(rows[0]))
        writer.writeheader()
        writer.writerows(rows)
    for row in rows:
        print(", ".join(f"{k}={v}" for k, v in row.items()))
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
