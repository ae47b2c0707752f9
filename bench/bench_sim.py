"""Benchmark of the shop-floor simulation: simulated tables per second for each policy.

Each run builds 10 tables in sequence (the paper's Fig. 6 setting). Two scenarios: no supply
delay, and leg/foot feeders with MAT 60 s and MTTF 90 s. ``replicate`` shares one policy object
between the runs of a scenario, so the optimized policy's CE layouts are computed in the first
run only: the "cold" column is that first run alone, "tables_per_s" the warm runs after it.
The optimized policy uses the paper's CE parameters (200 samples, 30 elites, 100 iterations).

Writes bench/results/sim.csv. Run: python bench/bench_sim.py [--reps 10]
"""

from __future__ import annotations

import argparse
import os
import statistics
import time
from pathlib import Path

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

from benchio import write_rows

from bilevel_kit import load
from bilevel_kit.sim import POLICIES, SimParams, effective_instance, make_policy, run

ROOT = Path(__file__).resolve().parent.parent
UNITS = 10
SCENARIOS = {
    "no-delay": SimParams(units=UNITS),
    "mat60-mttf90": SimParams(units=UNITS, mat={"leg": 60.0, "foot": 60.0}, mttf=90.0),
}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--reps", type=int, default=10, help="warm runs per policy and scenario")
    args = ap.parse_args()
    table = load(ROOT / "instances/hrc_table.json")
    rows = []
    for scenario, params in SCENARIOS.items():
        for name in sorted(POLICIES):
            policy = make_policy(
                name, effective_instance(table, params), seed=params.policy_seed or 0, params=params
            )
            t0 = time.perf_counter()
            first = run(table, policy, params=params, seed=0)
            cold = time.perf_counter() - t0
            recs = []
            t0 = time.perf_counter()
            for seed in range(1, args.reps + 1):
                recs.append(run(table, policy, params=params, seed=seed))
            warm = time.perf_counter() - t0
            rows.append(
                {
                    "scenario": scenario,
                    "policy": name,
                    "units": UNITS,
                    "reps": args.reps,
                    "cold_first_run_s": round(cold, 4),
                    "warm_s_per_run": round(warm / args.reps, 5),
                    "tables_per_s": round(UNITS * args.reps / warm, 1),
                    "mean_makespan_s": round(statistics.fmean(r["makespan"] for r in recs), 1),
                    "mean_human_idle_s": round(statistics.fmean(r["human_idle"] for r in recs), 1),
                    "mean_kits": round(statistics.fmean(r["n_kits"] for r in recs), 1),
                    "mean_robot_wait_s": round(statistics.fmean(r["robot_wait"] for r in recs), 1),
                    "first_makespan_s": round(first["makespan"], 1),
                }
            )
            print(rows[-1], flush=True)
    print(f"wrote {write_rows(ROOT / 'bench/results/sim.csv', rows)}")


if __name__ == "__main__":
    main()
