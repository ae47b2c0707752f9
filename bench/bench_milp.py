"""Benchmark of the Pyomo/HiGHS MILP against CP-SAT (issue 7), and the exact bilevel optimum.

1. MILP vs CP-SAT time to proven optimum on 1, 2 and 5 units of the table (each solve capped
   at ``--time-limit``, default 120 s; the packing cache is cleared before every solve), with
   the ratio MILP time / CP-SAT time per instance. Writes bench/results/milp.csv.
2. ``--bilevel``: the exact optimum J* of the paper's whole-plan objective on the 12-task table
   (:mod:`bilevel_kit.models.bilevel_milp`) next to J of greedy-ce's plan under the same kit
   values. Writes bench/results/bilevel_milp.csv.

Run: PYTHONPATH=. python bench/bench_milp.py [--time-limit 120] [--units 1,2,5] [--bilevel]
"""

from __future__ import annotations

import argparse
import csv
import time
from pathlib import Path
from typing import Any

from bilevel_kit.instance import load
from bilevel_kit.models import cpsat as cs
from bilevel_kit.models import milp as ms
from bilevel_kit.models import packing_oracle as cpsat_packing
from bilevel_kit.plan import evaluate
from bilevel_kit.validate import check

ROOT = Path(__file__).resolve().parent.parent
RESULTS = ROOT / "bench" / "results"


def run(method: str, inst: Any, time_limit: float, seed: int) -> dict[str, Any]:
    """One solve from a cold packing cache; the honest makespan and the checker's verdict."""
    cpsat_packing.clear_cache()
    t0 = time.perf_counter()
    if method == "milp":
        out = ms.solve(inst, time_limit=time_limit, seed=seed)
    else:
        out = cs.solve(inst, time_limit=time_limit, seed=seed)
    wall = time.perf_counter() - t0
    makespan = evaluate(inst, out.plan).makespan if out.plan is not None else None
    return {
        "method": method,
        "status": out.status,
        "makespan": makespan,
        "bound": out.bound,
        "gap": out.extra.get("gap"),
        "time_s": round(wall, 3),
        "valid": out.plan is not None and not check(inst, out.plan),
    }


def bench_schedule(units: list[int], time_limit: float, seed: int) -> list[dict[str, Any]]:
    table = load(ROOT / "instances" / "hrc_table.json")
    rows = []
    for u in units:
        inst = table.with_overrides(units=u)
        res = {m: run(m, inst, time_limit, seed) for m in ("cpsat", "milp")}
        both = res["cpsat"]["status"] == res["milp"]["status"] == "optimal"
        agree = both and abs(res["cpsat"]["makespan"] - res["milp"]["makespan"]) < 1e-6
        ratio = res["milp"]["time_s"] / max(res["cpsat"]["time_s"], 1e-9)
        for m in ("cpsat", "milp"):
            rows.append(
                {
                    "instance": f"hrc_table x{u}",
                    "tasks": inst.n_tasks,
                    **res[m],
                    "ratio_milp_to_cpsat": round(ratio, 3),
                    "agree": agree,
                }
            )
        print(
            f"x{u}: cpsat {res['cpsat']['status']} {res['cpsat']['makespan']} in "
            f"{res['cpsat']['time_s']} s | milp {res['milp']['status']} "
            f"{res['milp']['makespan']} in {res['milp']['time_s']} s | ratio {ratio:.2f}",
            flush=True,
        )
    return rows


def bench_bilevel(time_limit: float, seed: int) -> list[dict[str, Any]]:
    from bilevel_kit.heuristics.greedy_ce import greedy_ce
    from bilevel_kit.models import bilevel_milp as kc

    inst = load(ROOT / "instances" / "hrc_table.json")
    rows = []
    for lower in ("ce", "best"):
        t0 = time.perf_counter()
        greedy = greedy_ce(inst, seed=seed)
        t_greedy = time.perf_counter() - t0
        values = kc.LowerLevel(inst, seed=seed, lower=lower)  # shared: same f for both plans
        t0 = time.perf_counter()
        out = kc.solve(inst, time_limit=time_limit, seed=seed, lower=lower, values=values)
        wall = time.perf_counter() - t0
        j_greedy = kc.paper_objective(inst, greedy.plan, values)
        row = {
            "instance": "hrc_table",
            "lower": lower,
            "status": out.status,
            "columns": out.extra.get("columns"),
            "multisets": out.extra.get("multisets"),
            "J_opt": out.extra.get("plan_objective_J"),
            "J_bound": out.extra.get("plan_objective_J_bound"),
            "J_greedy": j_greedy,
            "J_greedy_own_layouts": kc.paper_objective(inst, greedy.plan, kc.layout_fitness(inst)),
            "greedy_extra_paper_objective": greedy.extra["epoch_F_sum"],
            "J_local_search": out.extra.get("local_search_objective"),
            "makespan_opt_J": out.extra.get("makespan"),
            "makespan_greedy": evaluate(inst, greedy.plan).makespan,
            "kits_opt_J": len(out.plan.kits) if out.plan else None,
            "kits_greedy": len(greedy.plan.kits),
            "time_s": round(wall, 3),
            "lower_level_s": round(out.extra.get("lower_level_s", 0.0), 3),
            "milp_s": round(out.extra.get("milp_s", 0.0), 3),
            "greedy_s": round(t_greedy, 3),
            "valid": out.plan is not None and not check(inst, out.plan),
        }
        rows.append(row)
        print(row, flush=True)
    return rows


def write(rows: list[dict[str, Any]], path: Path) -> None:
    path.parent.mkdir(parents=True, exist_ok=True)
    with path.open("w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(rows[0]))
        w.writeheader()
        w.writerows(rows)
    print(f"wrote {path}")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--time-limit", type=float, default=120.0)
    ap.add_argument("--units", default="1,2,5")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--bilevel", action="store_true", help="also the exact bilevel optimum")
    ap.add_argument("--no-schedule", action="store_true", help="skip the MILP vs CP-SAT part")
    args = ap.parse_args()
    if not args.no_schedule:
        rows = bench_schedule([int(u) for u in args.units.split(",")], args.time_limit, args.seed)
        write(rows, RESULTS / "milp.csv")
        print("\n| instance | tasks | method | status | makespan | time (s) | MILP/CP-SAT |")
        print("|---|---|---|---|---|---|---|")
        for r in rows:
            print(
                f"| {r['instance']} | {r['tasks']} | {r['method']} | {r['status']} | "
                f"{r['makespan']} | {r['time_s']} | {r['ratio_milp_to_cpsat']} |"
            )
    if args.bilevel:
        write(bench_bilevel(max(args.time_limit, 300.0), args.seed), RESULTS / "bilevel_milp.csv")


if __name__ == "__main__":
    main()
