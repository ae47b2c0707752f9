"""Benchmark of the cross-entropy kit arrangement (paper Algorithm 1) at paper parameters.

Kit: every part of the 28-part table kit (4 legs 152.4 x 12.7 mm, 4 feet 43 x 43, 4 connectors
41 x 41, 8 screws 14 x 6, 8 screws 8 x 6) on a 300 x 200 mm tray; 200 samples, 30 elites,
at most 100 iterations.

For each seed it times one ``arrange`` call, then the evaluation alone of the same number of
samples (``iterations`` batches of 200, drawn beforehand) with the scorer ``arrange`` uses:
the compiled kernel of :mod:`bilevel_kit.heuristics._kernels` (rotated box extents, projection,
score in one pass) or, with ``scoring=numpy`` (``BILEVEL_KIT_NO_NUMBA=1``), rotated box
extents plus :class:`bilevel_kit.fitness.PairScorer`, in the same precision. The ratio
of the medians says how much the CE loop (sampling, refit, the exact final check) costs on
top of scoring; ``ratio_solve_to_numpy_eval`` compares with the numpy scoring of the same
samples. ``*_cpu_ms`` columns are process CPU time (less sensitive to a busy machine than the
wall-clock ``*_ms`` columns).

OpenBLAS threads are capped at 1 unless OPENBLAS_NUM_THREADS is set: on a busy 2-core machine
threaded BLAS calls measure the neighbours, not the algorithm. The setting is in the CSV.

Usage: python bench/bench_ce.py [--repeats 21] [--scoring both] [--out bench/results/ce.csv]
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

import math  # noqa: E402

from bilevel_kit.fitness import PairScorer, PairTable, half_extents  # noqa: E402
from bilevel_kit.heuristics import _kernels  # noqa: E402
from bilevel_kit.heuristics.cross_entropy import CEParams, arrange  # noqa: E402
from bilevel_kit.instance import Instance, from_dict  # noqa: E402

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


def eval_only_seconds(
    inst: Instance, batches: int, params: CEParams, seed: int, compiled: bool
) -> tuple[float, float]:
    """(wall, CPU) seconds to score ``batches`` x ``params.samples`` random layouts (drawn
    before timing), with the compiled kernel or with numpy."""
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
    pairs = PairTable.build(types, dt)
    w6 = dt(inst.weights["W6"])
    kernel = _kernels.score_kernel() if compiled else None
    if kernel is not None:
        stacked = [np.concatenate(d) for d in data]
        consts = np.array(
            [math.pi / 180.0, inst.tray.width, inst.tray.height, w6, 0.0, 2.0], dtype=dt
        )
        args = (
            np.arange(n, dtype=np.int64),
            (w[:, 0] / 2).astype(dt),
            (h[:, 0] / 2).astype(dt),
            np.empty((n, S), dtype=dt),
            np.empty((n, S), dtype=dt),
            consts,
            pairs.i.astype(np.int64),
            pairs.j.astype(np.int64),
            pairs.sign.astype(dt),
        )
        cost = np.empty(S, dtype=dt)
        z = np.empty(S, dtype=dt)
        t0, c0 = time.perf_counter(), time.process_time()
        for X in stacked:
            kernel(X, n, *args, cost, z)
            np.argpartition(cost, params.elite - 1)
        return time.perf_counter() - t0, time.process_time() - c0
    scorer = PairScorer(pairs, S, dt)
    t0, c0 = time.perf_counter(), time.process_time()
    for x, y, th in data:
        ex, ey = half_extents(w, h, th)
        dsd, z = scorer.signed(x, y, ex, ey)
        cost = dsd + w6 * z
        np.argpartition(cost, params.elite - 1)
    return time.perf_counter() - t0, time.process_time() - c0


def run(repeats: int, precision: str, scoring: str) -> dict[str, object]:
    if scoring == "numpy":
        os.environ[_kernels.ENV_DISABLE] = "1"
    else:
        os.environ.pop(_kernels.ENV_DISABLE, None)
    compiled = _kernels.available()
    if scoring == "numba" and not compiled:
        raise SystemExit("numba is not installed")
    inst = table_kit()
    params = CEParams(precision=precision)
    for s in range(2):  # warm-up (and the kernel's compilation or cache load)
        arrange(inst, PARTS, rng=1000 + s, params=params)
    solve, solve_cpu, evals, evals_cpu, np_evals = [], [], [], [], []
    iters, fits, fitness, sources = [], [], [], []
    for seed in range(repeats):
        t0, c0 = time.perf_counter(), time.process_time()
        res = arrange(inst, PARTS, rng=seed, params=params)
        solve.append(time.perf_counter() - t0)
        solve_cpu.append(time.process_time() - c0)
        wall, cpu = eval_only_seconds(inst, res.iterations, params, seed, compiled)
        evals.append(wall)
        evals_cpu.append(cpu)
        np_evals.append(eval_only_seconds(inst, res.iterations, params, seed, False)[0])
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
        "scoring": "numba" if compiled else "numpy",
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
        "median_numpy_eval_ms": round(statistics.median(np_evals) * 1e3, 2),
        "ratio_solve_to_numpy_eval": round(med_solve / statistics.median(np_evals), 3),
        "median_solve_cpu_ms": round(statistics.median(solve_cpu) * 1e3, 2),
        "median_eval_only_cpu_ms": round(statistics.median(evals_cpu) * 1e3, 2),
        "fits_rate": sum(fits) / repeats,
        "median_fitness": round(statistics.median(fitness), 1),
        "sources": ";".join(f"{s}={sources.count(s)}" for s in sorted(set(sources))),
        "openblas_threads": os.environ.get("OPENBLAS_NUM_THREADS", ""),
        "load_avg_1min": round(os.getloadavg()[0], 2),
    }


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=21)
    ap.add_argument("--precision", choices=["float32", "float64", "both"], default="both")
    ap.add_argument("--scoring", choices=["numba", "numpy", "both"], default="both")
    ap.add_argument("--out", type=Path, default=ROOT / "bench" / "results" / "ce.csv")
    args = ap.parse_args()
    precisions = ["float32", "float64"] if args.precision == "both" else [args.precision]
    scorings = ["numba", "numpy"] if args.scoring == "both" else [args.scoring]
    rows = [run(args.repeats, p, sc) for sc in scorings for p in precisions]
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
