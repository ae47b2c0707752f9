"""Benchmark of the greedy upper level: full plan of the table, 1 and 10 units.

Writes bench/results/greedy.csv. Goal (issue 3): the table's full plan under 2 s.
Run: python bench/bench_greedy.py [--reps 5]
"""

from __future__ import annotations

import argparse
import os
import statistics
import time
from pathlib import Path

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

from benchio import write_rows

from bilevel_kit import check, load
from bilevel_kit.heuristics.greedy_ce import GreedyCEPolicy, plan

ROOT = Path(__file__).resolve().parent.parent


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--reps", type=int, default=5)
    args = ap.parse_args()
    table = load(ROOT / "instances/hrc_table.json")
    rows = []
    for units, reps in ((1, args.reps), (10, max(1, args.reps // 2))):
        inst = table.with_overrides(units=units)
        times = []
        for rep in range(reps):
            policy = GreedyCEPolicy(inst, seed=rep)
            t0 = time.perf_counter()
            p = plan(inst, policy=policy)
            times.append(time.perf_counter() - t0)
            assert check(inst, p) == []
        st = policy.stats
        rows.append(
            {
                "instance": f"hrc_table x{units}",
                "tasks": inst.n_tasks,
                "reps": reps,
                "median_s": round(statistics.median(times), 4),
                "min_s": round(min(times), 4),
                "kits": len(p.kits),
                "epochs": st.epochs,
                "sequences": st.sequences,
                "ce_calls": st.ce_calls,
                "cache_hits": st.fitness_cache_hits,
            }
        )
        print(rows[-1])
    print(f"wrote {write_rows(ROOT / 'bench/results/greedy.csv', rows)}")


if __name__ == "__main__":
    main()
